/* fovea: the fovea's anti-aliasing (core/reproject_aa.c has the model and fv_taa_aa_tile_c, the
 * reference) with one pixel's r, g, b, depth as one 4-float vector: the bilinear and Catmull-Rom
 * taps, the 3x3 rectification min / max and the blend are vector ops over the channels, and the
 * projection to the previous frame runs four pixels a step. Every lane does the reference's
 * operations in the same order (no FMA: the tree builds with -ffp-contract=off; min / max with the
 * reference's a < b ? a : b and a > b ? a : b, NaN and signed zeros included; no reciprocal), so
 * the result is bit-identical (0 ulp, tests/checkasm/reproject.c). Lane 3 (depth) of the sums is
 * carried along unused; the pixel's depth is stored back unchanged.
 *
 * The includer defines, for its ISA:
 *   v4                       one pixel's 4 floats
 *   V_LD(p) V_ST(p, v)       unaligned load / store of 4 floats
 *   V_DUP(x) V_ADD V_SUB V_MUL V_DIV
 *   V_MIN(a, b) V_MAX(a, b)  a < b ? a : b, a > b ? a : b per lane
 *   V_RGB_S(c, s)            lanes 0-2 of c, lane 3 of s
 *   V_B0 .. V_B3(v)          lane k of v broadcast
 *   V_ONES(p)                1 when the 4 floats at p all == 1.0f
 *   TAA_AA_FN(name)          the ISA-suffixed name */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "reproject.h"
#include "reproject_dsp.h"

/* Catmull-Rom of level 0 (fv_taa_aa_tile_c's catmull_rom), for a pixel whose 16 texels all have
 * weight 1 (checked before): its texel (i0 - 1, j0 - 1) and the weights per axis */
typedef struct {
    const float *r; /* texel (i0 - 1, j0 - 1) */
    float wx[4], wy[4];
    int x; /* the pixel in its row */
} aa_cr;
static inline int TAA_AA_FN(aa_cr_setup)(const fv_pyr_level *H, int i0, int j0, float fx, float fy, aa_cr *c)
{
    for (int j = 0; j < 4; j++)
        if (!V_ONES(H->wgt + (ptrdiff_t)(j0 - 1 + j) * H->stride + i0 - 1))
            return 0;
    c->wx[0] = fx, c->wy[0] = fy; /* the fractions until aa_cr_weights */
    c->r = H->rgbd + 4 * ((ptrdiff_t)(j0 - 1) * H->stride + i0 - 1);
    return 1;
}
/* the weights per axis of cr[0 .. n-1] from their fractions, four pixels a step (the
 * reference's polynomials, lane by lane) */
static inline void TAA_AA_FN(aa_cr_weights)(aa_cr *cr, int n)
{
    for (int k = 0; k < n; k += 4) {
        float t[2][4];
        for (int l = 0; l < 4; l++) {
            const aa_cr *c = &cr[k + l < n ? k + l : n - 1];
            t[0][l] = c->wx[0], t[1][l] = c->wy[0];
        }
        for (int a = 0; a < 2; a++) {
            const v4 q = V_LD(t[a]);
            float w[4][4];
            V_ST(w[0], V_MUL(q, V_ADD(V_DUP(-0.5f), V_MUL(q, V_SUB(V_DUP(1.0f), V_MUL(V_DUP(0.5f), q))))));
            V_ST(w[1], V_ADD(V_DUP(1.0f), V_MUL(V_MUL(q, q), V_ADD(V_DUP(-2.5f), V_MUL(V_DUP(1.5f), q)))));
            V_ST(w[2], V_MUL(q, V_ADD(V_DUP(0.5f), V_MUL(q, V_SUB(V_DUP(2.0f), V_MUL(V_DUP(1.5f), q))))));
            V_ST(w[3], V_MUL(V_MUL(q, q), V_ADD(V_DUP(-0.5f), V_MUL(V_DUP(0.5f), q))));
            for (int l = 0; l < 4 && k + l < n; l++) {
                float *d = a ? cr[k + l].wy : cr[k + l].wx;
                d[0] = w[0][l], d[1] = w[1][l], d[2] = w[2][l], d[3] = w[3][l];
            }
        }
    }
}
/* the sum over the 16 texels, in the reference's order (a += wx[i] wy[j] texel, j outer) */
static inline v4 TAA_AA_FN(aa_cr_sum)(const aa_cr *c, ptrdiff_t stride)
{
    const v4 wxv = V_LD(c->wx);
    v4 acc = V_DUP(0.0f);
    for (int j = 0; j < 4; j++) {
        const float *r = c->r + 4 * (ptrdiff_t)j * stride;
        const v4 ww = V_MUL(wxv, V_DUP(c->wy[j])); /* wx[i] wy[j], i = 0..3 */
        acc = V_ADD(acc, V_MUL(V_B0(ww), V_LD(r)));
        acc = V_ADD(acc, V_MUL(V_B1(ww), V_LD(r + 4)));
        acc = V_ADD(acc, V_MUL(V_B2(ww), V_LD(r + 8)));
        acc = V_ADD(acc, V_MUL(V_B3(ww), V_LD(r + 12)));
    }
    return acc;
}
#ifndef AA_CR_PAIR
/* two pixels' sums interleaved: each is one chain of 16 dependent additions (the reference's
 * order), so two chains in flight hide half the latency */
static inline void TAA_AA_FN(aa_cr_pair)(const aa_cr *a, const aa_cr *b, ptrdiff_t stride, v4 *ha, v4 *hb)
{
    const v4 wxa = V_LD(a->wx), wxb = V_LD(b->wx);
    v4 acc = V_DUP(0.0f), bcc = V_DUP(0.0f);
    for (int j = 0; j < 4; j++) {
        const float *r = a->r + 4 * (ptrdiff_t)j * stride, *q = b->r + 4 * (ptrdiff_t)j * stride;
        const v4 wa = V_MUL(wxa, V_DUP(a->wy[j])), wb = V_MUL(wxb, V_DUP(b->wy[j]));
        acc = V_ADD(acc, V_MUL(V_B0(wa), V_LD(r)));
        bcc = V_ADD(bcc, V_MUL(V_B0(wb), V_LD(q)));
        acc = V_ADD(acc, V_MUL(V_B1(wa), V_LD(r + 4)));
        bcc = V_ADD(bcc, V_MUL(V_B1(wb), V_LD(q + 4)));
        acc = V_ADD(acc, V_MUL(V_B2(wa), V_LD(r + 8)));
        bcc = V_ADD(bcc, V_MUL(V_B2(wb), V_LD(q + 8)));
        acc = V_ADD(acc, V_MUL(V_B3(wa), V_LD(r + 12)));
        bcc = V_ADD(bcc, V_MUL(V_B3(wb), V_LD(q + 12)));
    }
    *ha = acc, *hb = bcc;
}
#define AA_CR_PAIR TAA_AA_FN(aa_cr_pair)
#endif

void TAA_AA_FN(fv_taa_aa_tile)(const fv_taa_frame *f, const fv_taa_aa_frame *a, const fv_pyr_level *l0, int x0,
                               int y0, int tw, int th)
{
    enum { T = 16 };
    float s[T][T][4];
    for (int y = 0; y < th; y++)
        memcpy(s[y], l0->rgbd + 4 * ((ptrdiff_t)(y0 + y) * l0->stride + x0), (size_t)tw * 4 * sizeof(float));
    const int hist = f && a->n_prev;
    const fv_pyr_level *H = hist ? &f->hist->lv[0] : NULL;
    const float *Hrgbd = H ? H->rgbd : NULL, *Hw = H ? H->wgt : NULL;
    ptrdiff_t Hs = H ? H->stride : 0;
    int hx0 = 0, hy0 = 0;
    if (hist && a->h_rgbd) {
        Hrgbd = a->h_rgbd, Hw = a->h_wgt, Hs = a->h_stride, hx0 = a->h_x0, hy0 = a->h_y0;
    }
    const float jx = a->ox - 0.5f, jy = a->oy - 0.5f;
    const int moving = hist && !f->identity, catrom = moving && !a->h_rgbd;
    for (int y = 0; y < th; y++) {
        uint8_t *ncur = a->n_cur + (ptrdiff_t)(y0 + y) * a->stride + x0;
        /* the row's places in the previous frame, four pixels a step (fv_taa_project's ops) */
        float uu[T], vv[T], zz[T];
        if (moving && !f->lens) {
            const float py = (float)(y0 + y) + a->oy;
            float rc[3]; /* M0 + py MY per row */
            for (int k = 0; k < 3; k++)
                rc[k] = f->M0[k] + py * f->MY[k];
            const v4 iota = V_LD(((const float[4]){0.0f, 1.0f, 2.0f, 3.0f}));
            for (int x = 0; x < tw; x += 4) {
                const v4 px = V_ADD(V_ADD(V_DUP((float)(x0 + x)), iota), V_DUP(a->ox));
                float dd[4];
                for (int k = 0; k < 4; k++)
                    dd[k] = s[y][x + k < tw ? x + k : tw - 1][3];
                const v4 d = V_LD(dd);
                const v4 U = V_ADD(V_DUP(f->T[0]), V_MUL(d, V_ADD(V_DUP(rc[0]), V_MUL(px, V_DUP(f->MX[0])))));
                const v4 Vv = V_ADD(V_DUP(f->T[1]), V_MUL(d, V_ADD(V_DUP(rc[1]), V_MUL(px, V_DUP(f->MX[1])))));
                const v4 Z = V_ADD(V_DUP(f->T[2]), V_MUL(d, V_ADD(V_DUP(rc[2]), V_MUL(px, V_DUP(f->MX[2])))));
                /* lanes with Z <= 0 get garbage: the z > 1e-4 test below skips them, as the reference */
                float ub[4], vb[4], zb[4];
                V_ST(ub, V_SUB(V_DIV(U, Z), V_DUP(jx)));
                V_ST(vb, V_SUB(V_DIV(Vv, Z), V_DUP(jy)));
                V_ST(zb, Z);
                for (int k = 0; k < 4 && x + k < tw; k++)
                    uu[x + k] = ub[k], vv[x + k] = vb[k], zz[x + k] = zb[k];
            }
        }
        /* 1. history per pixel: the counts, the bilinear taps, which pixels take Catmull-Rom */
        v4 hh[T];
        uint8_t nn[T];
        aa_cr cr[T];
        int ncr = 0;
        for (int x = 0; x < tw; x++) {
            int n = 0;
            v4 h = V_DUP(0.0f);
            if (hist) {
                const float d = s[y][x][3];
                float u, v, z;
                if (f->identity) {
                    u = (float)(x0 + x) + 0.5f;
                    v = (float)(y0 + y) + 0.5f;
                    z = d;
                } else if (!f->lens) {
                    u = uu[x], v = vv[x], z = zz[x];
                } else {
                    z = fv_taa_project(f, (float)(x0 + x) + a->ox, (float)(y0 + y) + a->oy, d, &u, &v);
                    u -= jx;
                    v -= jy;
                }
                if (z > 1e-4f && u >= 0.0f && u < f->prev_w && v >= 0.0f && v < f->prev_h) {
                    const int ni = (int)u, nj = (int)v;
                    const float tol = z / f->inv_depth_tol;
                    int near = 0;
                    for (int j = nj - 1; j <= nj + 1 && !near; j++) {
                        const ptrdiff_t o = (ptrdiff_t)(j - hy0) * Hs + (ni - hx0);
                        near = (Hw[o - 1] > 0.0f && fabsf(Hrgbd[4 * o - 1] - z) <= tol) ||
                               (Hw[o] > 0.0f && fabsf(Hrgbd[4 * o + 3] - z) <= tol) ||
                               (Hw[o + 1] > 0.0f && fabsf(Hrgbd[4 * o + 7] - z) <= tol);
                    }
                    const float sx = u - 0.5f, sy = v - 0.5f, fx0 = floorf(sx), fy0 = floorf(sy);
                    const int i0 = (int)fx0, j0 = (int)fy0;
                    const float fx = sx - fx0, fy = sy - fy0;
                    const float b[4] = {(1.0f - fx) * (1.0f - fy), fx * (1.0f - fy), (1.0f - fx) * fy, fx * fy};
                    const ptrdiff_t o0 = (ptrdiff_t)(j0 - hy0) * Hs + i0 - hx0, o1 = o0 + Hs;
                    const float w0 = b[0] * Hw[o0], w1 = b[1] * Hw[o0 + 1], w2 = b[2] * Hw[o1], w3 = b[3] * Hw[o1 + 1];
                    v4 acc = V_ADD(V_DUP(0.0f), V_MUL(V_DUP(w0), V_LD(Hrgbd + 4 * o0)));
                    acc = V_ADD(acc, V_MUL(V_DUP(w1), V_LD(Hrgbd + 4 * o0 + 4)));
                    acc = V_ADD(acc, V_MUL(V_DUP(w2), V_LD(Hrgbd + 4 * o1)));
                    acc = V_ADD(acc, V_MUL(V_DUP(w3), V_LD(Hrgbd + 4 * o1 + 4)));
                    const float accw = ((0.0f + w0) + w1 + w2) + w3;
                    if (near && accw > 1e-6f) {
                        n = a->n_prev[(ptrdiff_t)(int)v * a->stride + (int)u];
                        h = V_DIV(acc, V_DUP(accw));
                        if (catrom && i0 >= 1 && j0 >= 1 && (float)(i0 + 2) < f->prev_w &&
                            (float)(j0 + 2) < f->prev_h && TAA_AA_FN(aa_cr_setup)(H, i0, j0, fx, fy, &cr[ncr]))
                            cr[ncr++].x = x;
                    }
                }
            }
            n = n + 1 < FV_TAA_AA_MAX_N ? n + 1 : FV_TAA_AA_MAX_N;
            ncur[x] = nn[x] = (uint8_t)n;
            hh[x] = h;
        }
        /* 2. Catmull-Rom, two pixels at a time */
        TAA_AA_FN(aa_cr_weights)(cr, ncr);
        int k = 0;
        for (; k + 2 <= ncr; k += 2)
            AA_CR_PAIR(&cr[k], &cr[k + 1], H->stride, &hh[cr[k].x], &hh[cr[k + 1].x]);
        if (k < ncr)
            hh[cr[k].x] = TAA_AA_FN(aa_cr_sum)(&cr[k], H->stride);
        /* 3. the blend, rectified when moving */
        for (int x = 0; x < tw; x++) {
            const int n = nn[x];
            if (n == 1)
                continue;
            float *px = l0->rgbd + 4 * ((ptrdiff_t)(y0 + y) * l0->stride + x0 + x);
            const v4 h = hh[x];
            const v4 alpha = V_DUP(1.0f / (float)n), sv = V_LD(s[y][x]);
            if (f->identity) {
                V_ST(px, V_RGB_S(V_ADD(h, V_MUL(alpha, V_SUB(sv, h))), sv));
                continue;
            }
            v4 lo = sv, hi = sv;
            if (x > 0 && x + 1 < tw && y > 0 && y + 1 < th) { /* inside the tile: the 3x3 unrolled */
                for (int j = y - 1; j <= y + 1; j++) {
                    const v4 q0 = V_LD(s[j][x - 1]), q1 = V_LD(s[j][x]), q2 = V_LD(s[j][x + 1]);
                    lo = V_MIN(lo, q0), hi = V_MAX(hi, q0);
                    lo = V_MIN(lo, q1), hi = V_MAX(hi, q1);
                    lo = V_MIN(lo, q2), hi = V_MAX(hi, q2);
                }
            } else {
                const int ja = y > 0 ? y - 1 : 0, jb = y + 1 < th ? y + 1 : th - 1;
                const int ia = x > 0 ? x - 1 : 0, ib = x + 1 < tw ? x + 1 : tw - 1;
                for (int j = ja; j <= jb; j++)
                    for (int i = ia; i <= ib; i++) {
                        const v4 q = V_LD(s[j][i]);
                        lo = V_MIN(lo, q), hi = V_MAX(hi, q);
                    }
            }
            const v4 hc = V_MIN(V_MAX(h, lo), hi);
            V_ST(px, V_RGB_S(V_ADD(hc, V_MUL(alpha, V_SUB(sv, hc))), sv));
        }
    }
}
