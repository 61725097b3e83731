/* fovea: the reprojection blend vectorised across VW samples of a row (SSE4.1 and NEON: 4,
 * AVX2: 8), written once with GCC / clang vector extensions and included by each ISA file
 * after core/reproject_tmpl.h (which it defines TAA_OWN_BLEND for). The ISA file defines
 *   VW           lanes per step
 *   vfloor(x)    an exact per-lane floor of a vf (the ISA's round-down instruction)
 * Every lane does the reference's operations in the reference's order (core/reproject_tmpl.h:
 * projection, bounds, footprint, level, one bilinear tap with depth agreement, blend), so the
 * result is bit-identical to C. The flow sums stay sequential in pixel order (a float sum's
 * bits depend on its order). Samples whose footprint needs the quincunx (five taps) go through
 * the shared scalar taa_blend_px: with the rotating pattern the history is dense and almost
 * every footprint is one texel.
 * Why: the scalar per-sample chain (division, floor, address, loads, agreement, division) was
 * ~150 cycles a sample and latency-bound; across lanes the chain is paid once per VW samples. */
#include <stdint.h>
#include <string.h>

typedef float vf __attribute__((vector_size(4 * VW)));
typedef int32_t vi __attribute__((vector_size(4 * VW)));

/* m ? a : b per lane, m all-ones or zero (a comparison's result) */
static inline vf vsel(vi m, vf a, vf b) { return (vf)(((vi)a & m) | ((vi)b & ~m)); }

static inline vi vseli(vi m, vi a, vi b) { return (a & m) | (b & ~m); }

static inline unsigned vmask_bits(vi m)
{
    unsigned b = 0;
    for (int k = 0; k < VW; k++)
        b |= (unsigned)(m[k] != 0) << k;
    return b;
}

/* The texels of the lanes' taps as planes: c[q][channel], cw[q] for texels q = 00, 01, 10, 11;
 * t0[k] points at lane k's texel 00 (10 follows), t1[k] at 01 (11 follows), w0[k] / w1[k] at
 * their weights. An ISA may define TAA_VEC_TAP_LOAD with loads and transposes; this generic
 * form goes lane by lane. */
#ifndef TAA_VEC_PX_LOAD
/* the pixels (r, g, b, depth) at px[k] as four planes */
static inline void vpx_load(float *const px[VW], vf p[4])
{
    for (int k = 0; k < VW; k++)
        for (int ch = 0; ch < 4; ch++)
            p[ch][k] = px[k][ch];
}
#endif

#ifndef TAA_VEC_TAP_LOAD
static inline void vtap_load(const float *const t0[VW], const float *const t1[VW], const float *const w0[VW],
                             const float *const w1[VW], vf c[4][4], vf cw[4])
{
    for (int k = 0; k < VW; k++) {
        for (int ch = 0; ch < 4; ch++) {
            c[0][ch][k] = t0[k][ch];
            c[1][ch][k] = t1[k][ch];
            c[2][ch][k] = t0[k][4 + ch];
            c[3][ch][k] = t1[k][4 + ch];
        }
        cw[0][k] = w0[k][0];
        cw[1][k] = w1[k][0];
        cw[2][k] = w0[k][1];
        cw[3][k] = w1[k][1];
    }
}
#endif

/* A batch of up to VW samples (lanes below n), in pixel order: their pixels, centres. */
typedef struct {
    float *px[VW];
    float pxc[VW], py[VW];
    int n;
} vbatch;

static void TAA_FN(vblend_batch)(const struct fv_taa_frame *f, const struct fv_taa_tile *t, vbatch *bt,
                                 float *fdx, float *fdy, float *fn)
{
    const vf zero = {0}, one = zero + 1.0f;
    const fv_pyr_level *lv = f->hist->lv;
    for (int k = bt->n; k < VW; k++) { /* idle lanes repeat lane 0 and are masked off */
        bt->px[k] = bt->px[0];
        bt->pxc[k] = bt->pxc[0];
        bt->py[k] = bt->py[0];
    }
    const unsigned smp = (1u << bt->n) - 1u;
    vf p[4], pxc, py;
    vpx_load(bt->px, p);
    memcpy(&pxc, bt->pxc, sizeof pxc);
    memcpy(&py, bt->py, sizeof py);
    const vf d = p[3];
    vf u, v, z, rz;
    vi ok;
    if (f->identity) {
        u = pxc;
        v = py;
        z = d;
        rz = 1.0f / z;
        ok = (vi)zero == 0;
    } else {
        const vf b0 = f->M0[0] + py * f->MY[0], b1 = f->M0[1] + py * f->MY[1], b2 = f->M0[2] + py * f->MY[2];
        const vf U = f->T[0] + d * (b0 + pxc * f->MX[0]);
        const vf V = f->T[1] + d * (b1 + pxc * f->MX[1]);
        z = f->T[2] + d * (b2 + pxc * f->MX[2]);
        ok = z > 1e-4f; /* not behind the previous eye */
        rz = 1.0f / z;
        u = U * rz;
        v = V * rz;
    }
    ok &= (u >= 0.0f) & (u < f->prev_w) & (v >= 0.0f) & (v < f->prev_h);
    const unsigned act = smp & vmask_bits(ok);
    if (!act)
        return;
    const vf du = u - pxc, dv = v - py;
    for (unsigned b = act; b; b &= b - 1) { /* in pixel order, as the reference */
        const int k = __builtin_ctz(b);
        *fdx = *fdx + du[k];
        *fdy = *fdy + dv[k];
        *fn = *fn + 1.0f;
    }
    /* footprint -> level (taa_level), texel size, quincunx offset */
    const vf fp = (d * rz) * t->widen;
    vi e = ((vi)fp >> 23) - 127; /* used only where fp >= 2 > 0 */
    e = vseli(e < f->max_level, e, e - e + f->max_level);
    const vi l = (fp >= 2.0f) & e;
    const vf ts = (vf)((l + 127) << 23), inv_ts = (vf)((127 - l) << 23); /* 2^l, 2^-l */
    vf o = (fp - ts) * 0.5f;
    o = vsel(o < 0.5f * ts, o, 0.5f * ts);
    const unsigned quin = act & vmask_bits(o >= 0.125f);
    for (unsigned b = quin; b; b &= b - 1) {
        const int k = __builtin_ctz(b);
        TAA_FN(taa_blend_px)(f, t, bt->px[k], d[k], u[k], v[k], z[k], rz[k]);
    }
    const unsigned one_tap = act & ~quin;
    if (!one_tap)
        return;
    const vf inv_tol = rz * f->inv_depth_tol;
    const vf s = u * inv_ts - 0.5f, tt = v * inv_ts - 0.5f;
    const vf fs = vfloor(s), ft = vfloor(tt);
    const vi ii = __builtin_convertvector(fs, vi), jj = __builtin_convertvector(ft, vi);
    const vf fx = s - fs, fy = tt - ft, omx = 1.0f - fx, omy = 1.0f - fy;
    /* lanes without a tap read texel (0, 0) of level 0 (addressable, its border too) */
    const float *t0[VW], *t1[VW], *w0[VW], *w1[VW];
    for (int k = 0; k < VW; k++) {
        const int on = one_tap >> k & 1u;
        const fv_pyr_level *L = &lv[on ? l[k] : 0];
        const ptrdiff_t o00 = on ? (ptrdiff_t)jj[k] * L->stride + ii[k] : 0;
        t0[k] = L->rgbd + 4 * o00;
        t1[k] = t0[k] + 4 * L->stride;
        w0[k] = L->wgt + o00;
        w1[k] = w0[k] + L->stride;
    }
    vf c[4][4], cw[4];
    vtap_load(t0, t1, w0, w1, c, cw);
    const vf bw[4] = {omx * omy, omx * fy, fx * omy, fx * fy};
    vf wt[4];
#pragma GCC unroll 4
    for (int q = 0; q < 4; q++) {
        vf a = c[q][3] - z;
        a = (vf)((vi)a & 0x7fffffff); /* |depth - z| */
        a = 1.0f - a * inv_tol;
        a = vsel(a > 0.0f, a, zero);
        wt[q] = (bw[q] * cw[q]) * a;
    }
    const vf accw = zero + ((wt[0] + wt[1]) + (wt[2] + wt[3]));
    const unsigned done = one_tap & vmask_bits(accw > 0.0f); /* else: no valid history */
    if (!done)
        return;
    const vf a1 = 1.0f - accw;
    const vf alpha = vsel(a1 > t->alpha, a1, zero + t->alpha);
    vf out[3];
#pragma GCC unroll 3
    for (int ch = 0; ch < 3; ch++) {
        const vf acc = zero + ((wt[0] * c[0][ch] + wt[1] * c[1][ch]) + (wt[2] * c[2][ch] + wt[3] * c[3][ch]));
        const vf hh = acc / accw;
        out[ch] = hh + alpha * (p[ch] - hh);
    }
    (void)one;
    for (unsigned b = done; b; b &= b - 1) {
        const int k = __builtin_ctz(b);
        for (int ch = 0; ch < 3; ch++)
            bt->px[k][ch] = out[ch][k];
    }
}

/* The samples of the block are batched VW at a time across rows (the pattern is sparse in the
 * periphery: lanes of one row would mostly idle). */
static void TAA_FN(taa_blend)(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd_blk,
                              const float *wgt_blk, ptrdiff_t stride, int x0, int y0, int w, int h,
                              struct fv_taa_flow *flow)
{
    float fdx = flow->dx, fdy = flow->dy, fn = flow->n;
    vbatch bt;
    bt.n = 0;
    for (int r = 0; r < h; r++) {
        float *rgbd = rgbd_blk + 4 * r * stride;
        const float py = (float)(y0 + r) + 0.5f;
        for (uint64_t m = sample_mask(wgt_blk + r * stride, w); m; m &= m - 1) {
            const int i = __builtin_ctzll(m);
            bt.px[bt.n] = rgbd + 4 * i;
            bt.pxc[bt.n] = (float)(x0 + i) + 0.5f;
            bt.py[bt.n] = py;
            if (++bt.n == VW) {
                TAA_FN(vblend_batch)(f, t, &bt, &fdx, &fdy, &fn);
                bt.n = 0;
            }
        }
    }
    if (bt.n)
        TAA_FN(vblend_batch)(f, t, &bt, &fdx, &fdy, &fn);
    flow->dx = fdx;
    flow->dy = fdy;
    flow->n = fn;
}
