/* fovea: temporal reprojection kernels, SSE4.1. The blend takes four samples a step (the design
 * of core/x86/reproject_avx2.c at four lanes; wider footprints through the shared scalar taps,
 * one texel = one __m128 (r, g, b, depth)); every lane does the reference's operations in the
 * same order, so results are bit-identical. */
#include <smmintrin.h>

#include <stdint.h>

#include "reproject_dsp.h"
#include "reproject.h"
#include "reproject_still_lane.h"
#define FV_X86_W 4
#define FV_X86_FN(name) name##_sse41
#include "x86/reproject_tmpl.h"

static inline void tap(const fv_pyr_level *L, float s, float t, float zexp, float inv_tol, acc4 *acc, float *accw)
{
    const tap_pos p = tap_at(L, s, t);
    const __m128 c00 = _mm_loadu_ps(L->rgbd + 4 * p.o00), c10 = _mm_loadu_ps(L->rgbd + 4 * p.o00 + 4);
    const __m128 c01 = _mm_loadu_ps(L->rgbd + 4 * p.o01), c11 = _mm_loadu_ps(L->rgbd + 4 * p.o01 + 4);
    /* depths in texel order 00, 01, 10, 11 */
    const __m128 d = _mm_movehl_ps(_mm_unpackhi_ps(c10, c11), _mm_unpackhi_ps(c00, c01));
    const __m128 wt = tap_weights(L, &p, d, zexp, inv_tol);
    const __m128 m00 = _mm_mul_ps(_mm_shuffle_ps(wt, wt, 0x00), c00);
    const __m128 m01 = _mm_mul_ps(_mm_shuffle_ps(wt, wt, 0x55), c01);
    const __m128 m10 = _mm_mul_ps(_mm_shuffle_ps(wt, wt, 0xaa), c10);
    const __m128 m11 = _mm_mul_ps(_mm_shuffle_ps(wt, wt, 0xff), c11);
    *acc = _mm_add_ps(*acc, _mm_add_ps(_mm_add_ps(m00, m01), _mm_add_ps(m10, m11)));
    *accw = *accw + tap_weight_sum(wt);
}

static inline uint64_t sample_mask(const float *wgt, int n)
{
    uint64_t m = 0;
    int i = 0;
    for (; i + 4 <= n; i += 4)
        m |= (uint64_t)_mm_movemask_ps(_mm_cmpeq_ps(_mm_loadu_ps(wgt + i), _mm_set1_ps(1.0f))) << i;
    for (; i < n; i++)
        m |= (uint64_t)(wgt[i] == 1.0f) << i;
    return m;
}

#define TAA_FN FV_X86_FN
#define TAA_OWN_BLEND /* four samples a step, below */
#include "../reproject_tmpl.h" /* the row loops every ISA shares */

/* four pixel vectors <-> four channel vectors */
static inline void transpose4(__m128 p0, __m128 p1, __m128 p2, __m128 p3, __m128 *c0, __m128 *c1, __m128 *c2,
                              __m128 *c3)
{
    _MM_TRANSPOSE4_PS(p0, p1, p2, p3);
    *c0 = p0, *c1 = p1, *c2 = p2, *c3 = p3;
}

typedef struct {
    __m128 R, G, B, D, u, v, z, inv_tol; /* the samples and their projection */
    int32_t off[4];                      /* each sample's pixel offset from the block */
    int32_t oi[4];                       /* level-0 offset of each single tap's texel 00 */
    unsigned sm;                         /* lanes whose single tap is pending */
} taa_group;

/* A group of four samples (core/x86/reproject_avx2.c has the eight-lane twin and the design). */
static inline unsigned group_project(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd_blk,
                                     const int32_t off[4], const int32_t xs[4], const int32_t ys[4], int n,
                                     int keep_sample, float *fdx, float *fdy, float *fn, taa_group *g)
{
#define PX(k) (rgbd_blk + 4 * (ptrdiff_t)off[k])
    __m128 R, G, B, D;
    transpose4(_mm_loadu_ps(PX(0)), _mm_loadu_ps(PX(1)), _mm_loadu_ps(PX(2)), _mm_loadu_ps(PX(3)), &R, &G, &B, &D);
    const __m128 half = _mm_set1_ps(0.5f), one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
    const __m128 pxc = _mm_add_ps(_mm_cvtepi32_ps(_mm_loadu_si128((const __m128i *)xs)), half);
    const __m128 py = _mm_add_ps(_mm_cvtepi32_ps(_mm_loadu_si128((const __m128i *)ys)), half);
    __m128 u, v, z, rz, valid;
    if (f->identity) {
        u = pxc, v = py, z = D;
        rz = _mm_div_ps(one, z);
        valid = _mm_castsi128_ps(_mm_set1_epi32(-1));
    } else {
        __m128 c[3];
        for (int k = 0; k < 3; k++) {
            const __m128 b = _mm_add_ps(_mm_set1_ps(f->M0[k]), _mm_mul_ps(py, _mm_set1_ps(f->MY[k])));
            c[k] = _mm_add_ps(_mm_set1_ps(f->T[k]), _mm_mul_ps(D, _mm_add_ps(b, _mm_mul_ps(pxc, _mm_set1_ps(f->MX[k])))));
        }
        z = c[2];
        valid = _mm_cmpgt_ps(z, _mm_set1_ps(1e-4f));
        rz = _mm_div_ps(one, z);
        u = _mm_mul_ps(c[0], rz);
        v = _mm_mul_ps(c[1], rz);
    }
    valid = _mm_and_ps(valid, _mm_and_ps(_mm_and_ps(_mm_cmpge_ps(u, zero), _mm_cmplt_ps(u, _mm_set1_ps(f->prev_w))),
                                         _mm_and_ps(_mm_cmpge_ps(v, zero), _mm_cmplt_ps(v, _mm_set1_ps(f->prev_h)))));
    const unsigned vm = (unsigned)_mm_movemask_ps(valid) & ((1u << n) - 1u);
    if (!vm)
        return 0;
    { /* the flow sums, in sample order as the reference adds them */
        float du[4], dv[4];
        _mm_storeu_ps(du, _mm_sub_ps(u, pxc));
        _mm_storeu_ps(dv, _mm_sub_ps(v, py));
        float sx = *fdx, sy = *fdy, sn = *fn;
        for (unsigned m = vm; m; m &= m - 1) {
            const int k = __builtin_ctz(m);
            sx = sx + du[k], sy = sy + dv[k], sn = sn + 1.0f;
        }
        *fdx = sx, *fdy = sy, *fn = sn;
    }
    if (keep_sample)
        return 0; /* history has no weight here: the samples stay exactly as traced */
    const __m128 fp = _mm_mul_ps(_mm_mul_ps(D, rz), _mm_set1_ps(t->widen));
    __m128 o = _mm_mul_ps(_mm_sub_ps(fp, one), half);
    o = _mm_blendv_ps(half, o, _mm_cmplt_ps(o, half)); /* o < 0.5 ? o : 0.5 */
    const __m128 single = _mm_andnot_ps(_mm_or_ps(_mm_cmpge_ps(fp, _mm_set1_ps(2.0f)), _mm_cmpge_ps(o, _mm_set1_ps(0.125f))),
                                        valid);
    const unsigned sm = (unsigned)_mm_movemask_ps(single) & vm;
    const __m128 inv_tol = _mm_mul_ps(rz, _mm_set1_ps(f->inv_depth_tol));
    if (sm != vm) { /* wider footprints: the scalar taps */
        float uu[4], vv[4], zz[4], it[4], ff[4];
        _mm_storeu_ps(uu, u), _mm_storeu_ps(vv, v), _mm_storeu_ps(zz, z), _mm_storeu_ps(it, inv_tol), _mm_storeu_ps(ff, fp);
        for (unsigned m = vm & ~sm; m; m &= m - 1) {
            const int k = __builtin_ctz(m);
            taa_pending q;
            q.px = PX(k);
            q.u = uu[k], q.v = vv[k], q.z = zz[k], q.inv_tol = it[k];
            q.l = taa_footprint(f, ff[k], &q.o);
            taa_taps(f, t, &q);
        }
    }
#undef PX
    if (!sm)
        return 0;
    const fv_pyr_level *L = &f->hist->lv[0];
    __m128i o00 = _mm_add_epi32(_mm_mullo_epi32(_mm_cvttps_epi32(_mm_floor_ps(_mm_sub_ps(v, half))), _mm_set1_epi32((int)L->stride)),
                                _mm_cvttps_epi32(_mm_floor_ps(_mm_sub_ps(u, half))));
    o00 = _mm_and_si128(o00, _mm_castps_si128(single)); /* other lanes read texel (0, 0) */
    _mm_storeu_si128((__m128i *)g->oi, o00);
    for (int k = 0; k < 4; k++) {
        const float *c = L->rgbd + 4 * (ptrdiff_t)g->oi[k], *wr = L->wgt + g->oi[k];
        _mm_prefetch((const char *)c, _MM_HINT_T0);
        _mm_prefetch((const char *)(c + 4 * L->stride), _MM_HINT_T0);
        _mm_prefetch((const char *)wr, _MM_HINT_T0);
        _mm_prefetch((const char *)(wr + L->stride), _MM_HINT_T0);
    }
    for (int k = 0; k < 4; k++)
        g->off[k] = off[k];
    g->R = R, g->G = G, g->B = B, g->D = D, g->u = u, g->v = v, g->z = z, g->inv_tol = inv_tol;
    g->sm = sm;
    return sm;
}

static inline void group_taps(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd_blk,
                              const taa_group *g)
{
    const fv_pyr_level *L = &f->hist->lv[0];
    const __m128 half = _mm_set1_ps(0.5f), one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
    const __m128 z = g->z, inv_tol = g->inv_tol;
    const int32_t *oi = g->oi;
    const __m128 s = _mm_sub_ps(g->u, half), tt = _mm_sub_ps(g->v, half);
    const __m128 fx = _mm_sub_ps(s, _mm_floor_ps(s)), fy = _mm_sub_ps(tt, _mm_floor_ps(tt));
    const __m128 omx = _mm_sub_ps(one, fx), omy = _mm_sub_ps(one, fy);
    const float *h0 = L->rgbd, *h1 = L->rgbd + 4 * L->stride;
#define T(h, k, dx) _mm_loadu_ps(h + 4 * (ptrdiff_t)oi[k] + (dx))
    __m128 c00[4], c10[4], c01[4], c11[4]; /* r, g, b, depth of each texel of the four samples */
    transpose4(T(h0, 0, 0), T(h0, 1, 0), T(h0, 2, 0), T(h0, 3, 0), &c00[0], &c00[1], &c00[2], &c00[3]);
    transpose4(T(h0, 0, 4), T(h0, 1, 4), T(h0, 2, 4), T(h0, 3, 4), &c10[0], &c10[1], &c10[2], &c10[3]);
    transpose4(T(h1, 0, 0), T(h1, 1, 0), T(h1, 2, 0), T(h1, 3, 0), &c01[0], &c01[1], &c01[2], &c01[3]);
    transpose4(T(h1, 0, 4), T(h1, 1, 4), T(h1, 2, 4), T(h1, 3, 4), &c11[0], &c11[1], &c11[2], &c11[3]);
#undef T
    const float *w0 = L->wgt, *w1 = L->wgt + L->stride;
#define PR(p, a, b) _mm_movelh_ps(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(p + oi[a]))), \
                                  _mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(p + oi[b]))))
    const __m128 q0 = PR(w0, 0, 1), q1 = PR(w0, 2, 3), q2 = PR(w1, 0, 1), q3 = PR(w1, 2, 3);
#undef PR
    const __m128 W00 = _mm_shuffle_ps(q0, q1, _MM_SHUFFLE(2, 0, 2, 0)), W10 = _mm_shuffle_ps(q0, q1, _MM_SHUFFLE(3, 1, 3, 1));
    const __m128 W01 = _mm_shuffle_ps(q2, q3, _MM_SHUFFLE(2, 0, 2, 0)), W11 = _mm_shuffle_ps(q2, q3, _MM_SHUFFLE(3, 1, 3, 1));
    const __m128 absmask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
#define AGREE(d) _mm_max_ps(_mm_sub_ps(one, _mm_mul_ps(_mm_and_ps(_mm_sub_ps(d, z), absmask), inv_tol)), zero)
    const __m128 w00 = _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(omx, omy), W00), AGREE(c00[3]));
    const __m128 w01 = _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(omx, fy), W01), AGREE(c01[3]));
    const __m128 w10 = _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(fx, omy), W10), AGREE(c10[3]));
    const __m128 w11 = _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(fx, fy), W11), AGREE(c11[3]));
#undef AGREE
    const __m128 accw = _mm_add_ps(zero, _mm_add_ps(_mm_add_ps(w00, w01), _mm_add_ps(w10, w11)));
    const __m128 ok = _mm_cmpgt_ps(accw, zero);
    const unsigned bm = (unsigned)_mm_movemask_ps(ok) & g->sm;
    if (!bm)
        return; /* no valid history: the samples stand alone */
    const __m128 alpha = _mm_max_ps(_mm_sub_ps(one, accw), _mm_set1_ps(t->alpha)); /* a1 > alpha ? a1 : alpha */
    const __m128 px[3] = {g->R, g->G, g->B};
    __m128 res[3];
    for (int c = 0; c < 3; c++) {
        const __m128 acc = _mm_add_ps(zero, _mm_add_ps(_mm_add_ps(_mm_mul_ps(w00, c00[c]), _mm_mul_ps(w01, c01[c])),
                                                       _mm_add_ps(_mm_mul_ps(w10, c10[c]), _mm_mul_ps(w11, c11[c]))));
        const __m128 hh = _mm_div_ps(acc, accw);
        res[c] = _mm_blendv_ps(px[c], _mm_add_ps(hh, _mm_mul_ps(alpha, _mm_sub_ps(px[c], hh))), ok);
    }
    __m128 pk[4];
    transpose4(res[0], res[1], res[2], g->D, &pk[0], &pk[1], &pk[2], &pk[3]);
    for (unsigned m = g->sm == 0xfu ? 0xfu : bm; m; m &= m - 1) { /* all four: those without history unchanged */
        const int k = __builtin_ctz(m);
        _mm_storeu_ps(rgbd_blk + 4 * (ptrdiff_t)g->off[k], pk[k]);
    }
}

#define TAA_GROUP_LANES 4
#define TAA_GROUP_DIST 4 /* groups (16 samples) between a group's projection and its taps */
#define TAA_GROUP_RING 8
#include "../reproject_blend_tmpl.h"

/* The fill, four pixels at a time: each lane does the reference's operations (taa_fill_px).
 * Per block, not per row (as the AVX2 fill, branch taa9): the span of whole steps, the columns'
 * uc * NX and pixel centres and the frame's constants are made once per block (the flow is the
 * block's); a row costs its B = N0 + vc NY and its steps; the rows' edges come after. B + uc NX adds
 * the reference's product: the same bits. */
#define FILL_MAX_STEPS 16 /* w <= 64 */
static void taa_fill_sse41(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd_blk, float *wgt_blk,
                           ptrdiff_t stride, int x0, int y0, int w, int h)
{
    int ilo, ihi;
    taa_fill_span(f, t, x0, w, &ilo, &ihi);
    const int sx0 = x0 + t->flow_x, nstep = ihi - ilo >= 4 ? (ihi - ilo) / 4 : 0, iend = ilo + 4 * nstep;
    const int identity = f->identity;
    const fv_pyr_level *L = &f->hist->lv[0];
    const float *hrgbd = L->rgbd, *hwgt = L->wgt;
    const ptrdiff_t hstride = L->stride;
    const float prev_h = f->prev_h;
    const float N0[3] = {f->N0[0], f->N0[1], f->N0[2]}, NY[3] = {f->NY[0], f->NY[1], f->NY[2]};
    const __m128 zero = _mm_setzero_ps(), half = _mm_set1_ps(0.5f), mhalf = _mm_set1_ps(-0.5f);
    const __m128 T20 = _mm_set1_ps(f->T2[0]), T21 = _mm_set1_ps(f->T2[1]), T22 = _mm_set1_ps(f->T2[2]);
    const __m128 zmin = _mm_set1_ps(1e-4f), one = _mm_set1_ps(1.0f);
    const __m128i lane = _mm_setr_epi32(0, 1, 2, 3);
    __m128 cu0[FILL_MAX_STEPS], cu1[FILL_MAX_STEPS], cu2[FILL_MAX_STEPS], cpx[FILL_MAX_STEPS];
    if (!identity)
        for (int s = 0; s < nstep; s++) {
            const int i = ilo + 4 * s;
            const __m128 uc = _mm_add_ps(_mm_cvtepi32_ps(_mm_add_epi32(_mm_set1_epi32(sx0 + i), lane)), half);
            cu0[s] = _mm_mul_ps(uc, _mm_set1_ps(f->NX[0]));
            cu1[s] = _mm_mul_ps(uc, _mm_set1_ps(f->NX[1]));
            cu2[s] = _mm_mul_ps(uc, _mm_set1_ps(f->NX[2]));
            cpx[s] = _mm_add_ps(_mm_cvtepi32_ps(_mm_add_epi32(_mm_set1_epi32(x0 + i), lane)), half);
        }
    for (int r = 0; r < h; r++) {
        float *rgbd = rgbd_blk + 4 * r * stride, *wgt = wgt_blk + r * stride;
        const int sy = y0 + r + t->flow_y;
        if (!(sy >= 0 && (float)sy < prev_h))
            continue;
        const float vc = (float)sy + 0.5f;
        const __m128 B0 = _mm_set1_ps(N0[0] + vc * NY[0]), B1 = _mm_set1_ps(N0[1] + vc * NY[1]),
                     B2 = _mm_set1_ps(N0[2] + vc * NY[2]);
        const ptrdiff_t ho = (ptrdiff_t)sy * hstride;
        const float *hw = hwgt + ho, *hrow = hrgbd + 4 * ho;
        const __m128 pyv = _mm_set1_ps((float)(y0 + r) + 0.5f);
        for (int s = 0; s < nstep; s++) {
            const int i = ilo + 4 * s, sx = sx0 + i;
            const __m128 wv = _mm_loadu_ps(wgt + i);
            const __m128 ws = _mm_loadu_ps(hw + sx);
            __m128 m = _mm_and_ps(_mm_cmpeq_ps(wv, zero), _mm_cmpgt_ps(ws, zero));
            if (!_mm_movemask_ps(m))
                continue;
            const float *src = hrow + 4 * sx;
            __m128 r0 = _mm_loadu_ps(src), g0 = _mm_loadu_ps(src + 4), b0 = _mm_loadu_ps(src + 8), z = _mm_loadu_ps(src + 12);
            _MM_TRANSPOSE4_PS(r0, g0, b0, z); /* now r, g, b, D of the four texels */
            if (!identity) {
                const __m128 D = z;
                const __m128 U = _mm_add_ps(T20, _mm_mul_ps(D, _mm_add_ps(B0, cu0[s])));
                const __m128 V = _mm_add_ps(T21, _mm_mul_ps(D, _mm_add_ps(B1, cu1[s])));
                z = _mm_add_ps(T22, _mm_mul_ps(D, _mm_add_ps(B2, cu2[s])));
                const __m128 rz = _mm_div_ps(one, z);
                const __m128 ex = _mm_sub_ps(_mm_mul_ps(U, rz), cpx[s]), ey = _mm_sub_ps(_mm_mul_ps(V, rz), pyv);
                const __m128 ok = _mm_and_ps(_mm_and_ps(_mm_cmple_ps(ex, half), _mm_cmpge_ps(ex, mhalf)),
                                             _mm_and_ps(_mm_cmple_ps(ey, half), _mm_cmpge_ps(ey, mhalf)));
                m = _mm_and_ps(m, _mm_and_ps(_mm_cmpgt_ps(z, zmin), ok));
                if (!_mm_movemask_ps(m))
                    continue;
            }
            _MM_TRANSPOSE4_PS(r0, g0, b0, z); /* back to four pixels (r, g, b, depth) */
            float *o = rgbd + 4 * i;
#define PUT(k, v) _mm_storeu_ps(o + 4 * k, _mm_blendv_ps(_mm_loadu_ps(o + 4 * k), v, _mm_shuffle_ps(m, m, k * 0x55)))
            PUT(0, r0);
            PUT(1, g0);
            PUT(2, b0);
            PUT(3, z);
#undef PUT
            _mm_storeu_ps(wgt + i, _mm_blendv_ps(wv, ws, m));
        }
    }
    if (ilo == 0 && iend == w)
        return;
    /* the rows' edges outside the whole steps, pixel by pixel (each pixel's fill is independent) */
    for (int r = 0; r < h; r++) {
        const float *hw, *hrow;
        float B[3];
        if (!(hrow = taa_fill_setup(f, t, y0 + r, &hw, B)))
            continue;
        float *rgbd = rgbd_blk + 4 * r * stride, *wgt = wgt_blk + r * stride;
        const float py = (float)(y0 + r) + 0.5f;
        taa_fill_px(f, t, rgbd, wgt, hrow, hw, B, x0, py, 0, ilo);
        taa_fill_px(f, t, rgbd, wgt, hrow, hw, B, x0, py, iend, w);
    }
}

/* ------------------------------------------------------------------ the still head's blend */

/* taa_still (reproject_dsp.h): four samples a step, the reference lane's operations per lane
 * (ordered compares: a NaN lane takes the C branch's side). */
static void taa_still_sse41(float *s, const float *h, ptrdiff_t plane, int n, float widen, float alpha,
                            float inv_depth_tol, uint8_t *wide)
{
    const __m128 one = _mm_set1_ps(1.0f), two = _mm_set1_ps(2.0f), zero = _mm_setzero_ps();
    const __m128 vw = _mm_set1_ps(widen), va = _mm_set1_ps(alpha), vt = _mm_set1_ps(inv_depth_tol);
    const __m128 absmask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    int k = 0;
    for (; k + 4 <= n; k += 4) {
        const __m128 d = _mm_loadu_ps(s + 3 * plane + k);
        const __m128 rz = _mm_div_ps(one, d);
        const __m128 wm = _mm_cmpge_ps(_mm_mul_ps(_mm_mul_ps(d, rz), vw), two);
        const int bits = _mm_movemask_ps(wm);
        for (int i = 0; i < 4; i++)
            wide[k + i] = (uint8_t)(bits >> i & 1);
        const __m128 dd = _mm_and_ps(_mm_sub_ps(_mm_loadu_ps(h + 3 * plane + k), d), absmask);
        __m128 a = _mm_sub_ps(one, _mm_mul_ps(dd, _mm_mul_ps(rz, vt)));
        a = _mm_and_ps(a, _mm_cmpgt_ps(a, zero));
        const __m128 w = _mm_mul_ps(_mm_loadu_ps(h + 4 * plane + k), a);
        const __m128 ok = _mm_andnot_ps(wm, _mm_cmpgt_ps(w, zero));
        if (!_mm_movemask_ps(ok))
            continue;
        const __m128 a1 = _mm_sub_ps(one, w);
        const __m128 al = _mm_blendv_ps(va, a1, _mm_cmpgt_ps(a1, va));
        for (int c = 0; c < 3; c++) {
            const __m128 sc = _mm_loadu_ps(s + c * plane + k);
            const __m128 hc = _mm_div_ps(_mm_add_ps(zero, _mm_mul_ps(w, _mm_loadu_ps(h + c * plane + k))), w);
            const __m128 o = _mm_add_ps(hc, _mm_mul_ps(al, _mm_sub_ps(sc, hc)));
            _mm_storeu_ps(s + c * plane + k, _mm_blendv_ps(sc, o, ok));
        }
    }
    for (; k < n; k++)
        taa_still_lane(s, h, plane, k, widen, alpha, inv_depth_tol, wide);
}

void fv_reproject_dsp_init_sse41(fv_reproject_dsp *d)
{
    d->taa_blend = taa_blend_sse41;
    d->taa_fill = taa_fill_sse41;
    d->taa_still = taa_still_sse41;
    d->taa_aa = fv_taa_aa_tile_sse41; /* core/x86/reproject_aa_sse41.c */
}
