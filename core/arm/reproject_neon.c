/* fovea: temporal reprojection kernels, NEON. The blend takes four samples a step (the design
 * of core/x86/reproject_avx2.c at four lanes: single level-0 taps in SoA form, wider footprints
 * through the shared scalar taps, where one texel = one float32x4_t (r, g, b, depth)).
 * Same operations in the same order as the reference (no fused multiply-add intrinsics; the
 * tree is built with -ffp-contract=off): bit-identical. Row loops and scalar arithmetic:
 * core/reproject_tmpl.h. */
#include <arm_neon.h>

#include <stdint.h>

#include "reproject_dsp.h"
#include "reproject.h"
#include "reproject_still_lane.h"

typedef float32x4_t acc4;

static inline acc4 acc_zero(void) { return vdupq_n_f32(0.0f); }

static inline void tap(const fv_pyr_level *L, float s, float t, float zexp, float inv_tol, acc4 *acc, float *accw)
{
    const float32x2_t st = vrndm_f32(vset_lane_f32(t, vdup_n_f32(s), 1));
    const float fs = vget_lane_f32(st, 0), ft = vget_lane_f32(st, 1);
    const int i = (int)fs, j = (int)ft;
    const float fx = s - fs, fy = t - ft, omx = 1.0f - fx, omy = 1.0f - fy;
    const ptrdiff_t o00 = (ptrdiff_t)j * L->stride + i, o01 = o00 + L->stride;
    const float32x4_t c00 = vld1q_f32(L->rgbd + 4 * o00), c10 = vld1q_f32(L->rgbd + 4 * o00 + 4);
    const float32x4_t c01 = vld1q_f32(L->rgbd + 4 * o01), c11 = vld1q_f32(L->rgbd + 4 * o01 + 4);
    /* lanes in texel order 00, 01, 10, 11 */
    const float bx[4] = {omx, omx, fx, fx}, by[4] = {omy, fy, omy, fy};
    const float wl[4] = {L->wgt[o00], L->wgt[o01], L->wgt[o00 + 1], L->wgt[o01 + 1]};
    const float32x4_t b = vmulq_f32(vld1q_f32(bx), vld1q_f32(by));
    float32x4_t d = vdupq_laneq_f32(c00, 3);
    d = vcopyq_laneq_f32(d, 1, c01, 3);
    d = vcopyq_laneq_f32(d, 2, c10, 3);
    d = vcopyq_laneq_f32(d, 3, c11, 3);
    /* max(0, x) written as a compare + select: identical to the reference's x > 0 ? x : 0 */
    const float32x4_t a0 = vsubq_f32(vdupq_n_f32(1.0f), vmulq_f32(vabsq_f32(vsubq_f32(d, vdupq_n_f32(zexp))), vdupq_n_f32(inv_tol)));
    const float32x4_t a = vbslq_f32(vcgtq_f32(a0, vdupq_n_f32(0.0f)), a0, vdupq_n_f32(0.0f));
    const float32x4_t wt = vmulq_f32(vmulq_f32(b, vld1q_f32(wl)), a);
    const float32x4_t m00 = vmulq_laneq_f32(c00, wt, 0), m01 = vmulq_laneq_f32(c01, wt, 1);
    const float32x4_t m10 = vmulq_laneq_f32(c10, wt, 2), m11 = vmulq_laneq_f32(c11, wt, 3);
    *acc = vaddq_f32(*acc, vaddq_f32(vaddq_f32(m00, m01), vaddq_f32(m10, m11)));
    const float32x2_t h = vpadd_f32(vget_low_f32(wt), vget_high_f32(wt)); /* w00+w01, w10+w11 */
    *accw = *accw + (vget_lane_f32(h, 0) + vget_lane_f32(h, 1));
}

static inline void out_blend(float *px, acc4 acc, float accw, float alpha)
{
    const float32x4_t p = vld1q_f32(px);
    const float32x4_t h = vdivq_f32(acc, vdupq_n_f32(accw));
    const float32x4_t r = vaddq_f32(h, vmulq_f32(vdupq_n_f32(alpha), vsubq_f32(p, h)));
    vst1q_f32(px, vcopyq_laneq_f32(r, 3, p, 3)); /* depth stays the sample's */
}

static inline uint64_t sample_mask(const float *wgt, int n)
{
    static const uint32_t bits[4] = {1, 2, 4, 8};
    const uint32x4_t bv = vld1q_u32(bits);
    uint64_t m = 0;
    int i = 0;
    for (; i + 4 <= n; i += 4)
        m |= (uint64_t)vaddvq_u32(vandq_u32(vceqq_f32(vld1q_f32(wgt + i), vdupq_n_f32(1.0f)), bv)) << i;
    for (; i < n; i++)
        m |= (uint64_t)(wgt[i] == 1.0f) << i;
    return m;
}

#define TAA_FN(name) name##_neon
#define TAA_OWN_BLEND /* four samples a step, below */
#include "reproject_tmpl.h"

/* four pixel vectors <-> four channel vectors (a 4x4 transpose) */
static inline void transpose4(float32x4_t p0, float32x4_t p1, float32x4_t p2, float32x4_t p3, float32x4_t *c0,
                              float32x4_t *c1, float32x4_t *c2, float32x4_t *c3)
{
    const float32x4_t a0 = vtrn1q_f32(p0, p1), a1 = vtrn2q_f32(p0, p1);
    const float32x4_t a2 = vtrn1q_f32(p2, p3), a3 = vtrn2q_f32(p2, p3);
    *c0 = vreinterpretq_f32_f64(vtrn1q_f64(vreinterpretq_f64_f32(a0), vreinterpretq_f64_f32(a2)));
    *c1 = vreinterpretq_f32_f64(vtrn1q_f64(vreinterpretq_f64_f32(a1), vreinterpretq_f64_f32(a3)));
    *c2 = vreinterpretq_f32_f64(vtrn2q_f64(vreinterpretq_f64_f32(a0), vreinterpretq_f64_f32(a2)));
    *c3 = vreinterpretq_f32_f64(vtrn2q_f64(vreinterpretq_f64_f32(a1), vreinterpretq_f64_f32(a3)));
}

static inline unsigned lane_bits(uint32x4_t m)
{
    static const uint32_t bits[4] = {1, 2, 4, 8};
    return vaddvq_u32(vandq_u32(m, vld1q_u32(bits)));
}

/* x > y ? x : y, NaN-exact like the reference's ternaries (vmaxq would propagate a NaN) */
static inline float32x4_t sel_gt(float32x4_t x, float32x4_t y) { return vbslq_f32(vcgtq_f32(x, y), x, y); }

typedef struct {
    float32x4_t R, G, B, D, u, v, z, inv_tol; /* the samples and their projection */
    int32_t off[4];                           /* each sample's pixel offset from the block */
    int32_t oi[4];                            /* level-0 offset of each single tap's texel 00 */
    unsigned sm;                              /* lanes whose single tap is pending */
} taa_group;

/* A group of four samples (core/x86/reproject_avx2.c has the eight-lane twin and the design):
 * projection and flow sums in sample order; single level-0 taps left pending in g with their
 * history prefetched; wider footprints through the scalar taps at once. */
static inline unsigned group_project(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd_blk,
                                     const int32_t off[4], const int32_t xs[4], const int32_t ys[4], int n,
                                     int keep_sample, float *fdx, float *fdy, float *fn, taa_group *g)
{
#define PX(k) (rgbd_blk + 4 * (ptrdiff_t)off[k])
    float32x4_t R, G, B, D;
    transpose4(vld1q_f32(PX(0)), vld1q_f32(PX(1)), vld1q_f32(PX(2)), vld1q_f32(PX(3)), &R, &G, &B, &D);
    const float32x4_t half = vdupq_n_f32(0.5f), one = vdupq_n_f32(1.0f), zero = vdupq_n_f32(0.0f);
    const float32x4_t pxc = vaddq_f32(vcvtq_f32_s32(vld1q_s32(xs)), half), py = vaddq_f32(vcvtq_f32_s32(vld1q_s32(ys)), half);
    float32x4_t u, v, z, rz;
    uint32x4_t valid;
    if (f->identity) {
        u = pxc, v = py, z = D;
        rz = vdivq_f32(one, z);
        valid = vdupq_n_u32(~0u);
    } else {
        float32x4_t c[3];
        for (int k = 0; k < 3; k++) {
            const float32x4_t b = vaddq_f32(vdupq_n_f32(f->M0[k]), vmulq_f32(py, vdupq_n_f32(f->MY[k])));
            c[k] = vaddq_f32(vdupq_n_f32(f->T[k]), vmulq_f32(D, vaddq_f32(b, vmulq_f32(pxc, vdupq_n_f32(f->MX[k])))));
        }
        z = c[2];
        valid = vcgtq_f32(z, vdupq_n_f32(1e-4f));
        rz = vdivq_f32(one, z);
        u = vmulq_f32(c[0], rz);
        v = vmulq_f32(c[1], rz);
    }
    valid = vandq_u32(valid, vandq_u32(vandq_u32(vcgeq_f32(u, zero), vcltq_f32(u, vdupq_n_f32(f->prev_w))),
                                       vandq_u32(vcgeq_f32(v, zero), vcltq_f32(v, vdupq_n_f32(f->prev_h)))));
    const unsigned vm = lane_bits(valid) & ((1u << n) - 1u);
    if (!vm)
        return 0;
    { /* the flow sums, in sample order as the reference adds them */
        float du[4], dv[4];
        vst1q_f32(du, vsubq_f32(u, pxc));
        vst1q_f32(dv, vsubq_f32(v, py));
        float sx = *fdx, sy = *fdy, sn = *fn;
        for (unsigned m = vm; m; m &= m - 1) {
            const int k = __builtin_ctz(m);
            sx = sx + du[k], sy = sy + dv[k], sn = sn + 1.0f;
        }
        *fdx = sx, *fdy = sy, *fn = sn;
    }
    if (keep_sample)
        return 0; /* history has no weight here: the samples stay exactly as traced */
    const float32x4_t fp = vmulq_f32(vmulq_f32(D, rz), vdupq_n_f32(t->widen));
    float32x4_t o = vmulq_f32(vsubq_f32(fp, one), half);
    o = vbslq_f32(vcltq_f32(o, half), o, half); /* o < 0.5 ? o : 0.5 */
    const uint32x4_t wide = vorrq_u32(vcgeq_f32(fp, vdupq_n_f32(2.0f)), vcgeq_f32(o, vdupq_n_f32(0.125f)));
    const unsigned sm = lane_bits(vbicq_u32(valid, wide)) & vm;
    const float32x4_t inv_tol = vmulq_f32(rz, vdupq_n_f32(f->inv_depth_tol));
    if (sm != vm) { /* wider footprints: the scalar taps */
        float uu[4], vv[4], zz[4], it[4], ff[4];
        vst1q_f32(uu, u), vst1q_f32(vv, v), vst1q_f32(zz, z), vst1q_f32(it, inv_tol), vst1q_f32(ff, fp);
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
    int32x4_t o00 = vaddq_s32(vmulq_s32(vcvtq_s32_f32(vrndmq_f32(vsubq_f32(v, half))), vdupq_n_s32((int32_t)L->stride)),
                              vcvtq_s32_f32(vrndmq_f32(vsubq_f32(u, half))));
    const uint32x4_t single_lanes = vtstq_u32(vdupq_n_u32(sm), (uint32x4_t){1, 2, 4, 8});
    o00 = vandq_s32(o00, vreinterpretq_s32_u32(single_lanes)); /* other lanes read texel (0, 0) */
    vst1q_s32(g->oi, o00);
    for (int k = 0; k < 4; k++) {
        const float *c = L->rgbd + 4 * (ptrdiff_t)g->oi[k], *wr = L->wgt + g->oi[k];
        __builtin_prefetch(c);
        __builtin_prefetch(c + 4 * L->stride);
        __builtin_prefetch(wr);
        __builtin_prefetch(wr + L->stride);
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
    const float32x4_t half = vdupq_n_f32(0.5f), one = vdupq_n_f32(1.0f), zero = vdupq_n_f32(0.0f);
    const float32x4_t z = g->z, inv_tol = g->inv_tol;
    const int32_t *oi = g->oi;
    const float32x4_t s = vsubq_f32(g->u, half), tt = vsubq_f32(g->v, half);
    const float32x4_t fx = vsubq_f32(s, vrndmq_f32(s)), fy = vsubq_f32(tt, vrndmq_f32(tt));
    const float32x4_t omx = vsubq_f32(one, fx), omy = vsubq_f32(one, fy);
    const float *h0 = L->rgbd, *h1 = L->rgbd + 4 * L->stride;
#define T(h, k, dx) vld1q_f32(h + 4 * (ptrdiff_t)oi[k] + (dx))
    float32x4_t c00[4], c10[4], c01[4], c11[4]; /* r, g, b, depth of each texel of the four samples */
    transpose4(T(h0, 0, 0), T(h0, 1, 0), T(h0, 2, 0), T(h0, 3, 0), &c00[0], &c00[1], &c00[2], &c00[3]);
    transpose4(T(h0, 0, 4), T(h0, 1, 4), T(h0, 2, 4), T(h0, 3, 4), &c10[0], &c10[1], &c10[2], &c10[3]);
    transpose4(T(h1, 0, 0), T(h1, 1, 0), T(h1, 2, 0), T(h1, 3, 0), &c01[0], &c01[1], &c01[2], &c01[3]);
    transpose4(T(h1, 0, 4), T(h1, 1, 4), T(h1, 2, 4), T(h1, 3, 4), &c11[0], &c11[1], &c11[2], &c11[3]);
#undef T
    const float *w0 = L->wgt, *w1 = L->wgt + L->stride;
    const float32x4_t q0 = vcombine_f32(vld1_f32(w0 + oi[0]), vld1_f32(w0 + oi[1]));
    const float32x4_t q1 = vcombine_f32(vld1_f32(w0 + oi[2]), vld1_f32(w0 + oi[3]));
    const float32x4_t q2 = vcombine_f32(vld1_f32(w1 + oi[0]), vld1_f32(w1 + oi[1]));
    const float32x4_t q3 = vcombine_f32(vld1_f32(w1 + oi[2]), vld1_f32(w1 + oi[3]));
    const float32x4_t W00 = vuzp1q_f32(q0, q1), W10 = vuzp2q_f32(q0, q1);
    const float32x4_t W01 = vuzp1q_f32(q2, q3), W11 = vuzp2q_f32(q2, q3);
#define AGREE(d) sel_gt(vsubq_f32(one, vmulq_f32(vabsq_f32(vsubq_f32(d, z)), inv_tol)), zero)
    const float32x4_t w00 = vmulq_f32(vmulq_f32(vmulq_f32(omx, omy), W00), AGREE(c00[3]));
    const float32x4_t w01 = vmulq_f32(vmulq_f32(vmulq_f32(omx, fy), W01), AGREE(c01[3]));
    const float32x4_t w10 = vmulq_f32(vmulq_f32(vmulq_f32(fx, omy), W10), AGREE(c10[3]));
    const float32x4_t w11 = vmulq_f32(vmulq_f32(vmulq_f32(fx, fy), W11), AGREE(c11[3]));
#undef AGREE
    const float32x4_t accw = vaddq_f32(zero, vaddq_f32(vaddq_f32(w00, w01), vaddq_f32(w10, w11)));
    const uint32x4_t ok = vcgtq_f32(accw, zero);
    const unsigned bm = lane_bits(ok) & g->sm;
    if (!bm)
        return; /* no valid history: the samples stand alone */
    const float32x4_t alpha = sel_gt(vsubq_f32(one, accw), vdupq_n_f32(t->alpha)); /* a1 > alpha ? a1 : alpha */
    const float32x4_t px[3] = {g->R, g->G, g->B};
    float32x4_t res[3];
    for (int c = 0; c < 3; c++) {
        const float32x4_t acc = vaddq_f32(zero, vaddq_f32(vaddq_f32(vmulq_f32(w00, c00[c]), vmulq_f32(w01, c01[c])),
                                                          vaddq_f32(vmulq_f32(w10, c10[c]), vmulq_f32(w11, c11[c]))));
        const float32x4_t hh = vdivq_f32(acc, accw);
        res[c] = vbslq_f32(ok, vaddq_f32(hh, vmulq_f32(alpha, vsubq_f32(px[c], hh))), px[c]);
    }
    float32x4_t pk[4];
    transpose4(res[0], res[1], res[2], g->D, &pk[0], &pk[1], &pk[2], &pk[3]);
    for (unsigned m = g->sm == 0xfu ? 0xfu : bm; m; m &= m - 1) { /* all four: those without history unchanged */
        const int k = __builtin_ctz(m);
        vst1q_f32(rgbd_blk + 4 * (ptrdiff_t)g->off[k], pk[k]);
    }
}

#define TAA_GROUP_LANES 4
#define TAA_GROUP_DIST 4 /* groups (16 samples) between a group's projection and its taps */
#define TAA_GROUP_RING 8
#include "../reproject_blend_tmpl.h"

/* The fill, four pixels at a time (vld4 / vst4 de-interleave r, g, b, depth): each lane does the
 * reference's operations (taa_fill_px). Per block, not per row (as the x86 fills, branch taa9):
 * the span of whole steps, the columns' uc * NX and pixel centres and the frame's constants are
 * made once per block (the flow is the block's); a row costs its B = N0 + vc NY and its steps; the
 * rows' edges come after. B + uc NX adds the reference's product: the same bits. */
#define FILL_MAX_STEPS 16 /* w <= 64 */
static void taa_fill_neon(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd_blk, float *wgt_blk,
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
    const float32x4_t zero = vdupq_n_f32(0.0f), half = vdupq_n_f32(0.5f), mhalf = vdupq_n_f32(-0.5f);
    const float32x4_t T20 = vdupq_n_f32(f->T2[0]), T21 = vdupq_n_f32(f->T2[1]), T22 = vdupq_n_f32(f->T2[2]);
    const float32x4_t zmin = vdupq_n_f32(1e-4f), one = vdupq_n_f32(1.0f);
    static const int32_t lanes[4] = {0, 1, 2, 3};
    const int32x4_t lane = vld1q_s32(lanes);
    float32x4_t cu0[FILL_MAX_STEPS], cu1[FILL_MAX_STEPS], cu2[FILL_MAX_STEPS], cpx[FILL_MAX_STEPS];
    if (!identity)
        for (int s = 0; s < nstep; s++) {
            const int i = ilo + 4 * s;
            const float32x4_t uc = vaddq_f32(vcvtq_f32_s32(vaddq_s32(vdupq_n_s32(sx0 + i), lane)), half);
            cu0[s] = vmulq_f32(uc, vdupq_n_f32(f->NX[0]));
            cu1[s] = vmulq_f32(uc, vdupq_n_f32(f->NX[1]));
            cu2[s] = vmulq_f32(uc, vdupq_n_f32(f->NX[2]));
            cpx[s] = vaddq_f32(vcvtq_f32_s32(vaddq_s32(vdupq_n_s32(x0 + i), lane)), half);
        }
    for (int r = 0; r < h; r++) {
        float *rgbd = rgbd_blk + 4 * r * stride, *wgt = wgt_blk + r * stride;
        const int sy = y0 + r + t->flow_y;
        if (!(sy >= 0 && (float)sy < prev_h))
            continue;
        const float vc = (float)sy + 0.5f;
        const float32x4_t B0 = vdupq_n_f32(N0[0] + vc * NY[0]), B1 = vdupq_n_f32(N0[1] + vc * NY[1]),
                          B2 = vdupq_n_f32(N0[2] + vc * NY[2]);
        const ptrdiff_t ho = (ptrdiff_t)sy * hstride;
        const float *hw = hwgt + ho, *hrow = hrgbd + 4 * ho;
        const float32x4_t pyv = vdupq_n_f32((float)(y0 + r) + 0.5f);
        for (int s = 0; s < nstep; s++) {
            const int i = ilo + 4 * s, sx = sx0 + i;
            const float32x4_t wv = vld1q_f32(wgt + i);
            const float32x4_t ws = vld1q_f32(hw + sx);
            uint32x4_t m = vandq_u32(vceqq_f32(wv, zero), vcgtq_f32(ws, zero));
            if (!vmaxvq_u32(m))
                continue;
            float32x4x4_t px = vld4q_f32(hrow + 4 * sx); /* r, g, b, D of four texels */
            if (!identity) {
                const float32x4_t D = px.val[3];
                const float32x4_t U = vaddq_f32(T20, vmulq_f32(D, vaddq_f32(B0, cu0[s])));
                const float32x4_t V = vaddq_f32(T21, vmulq_f32(D, vaddq_f32(B1, cu1[s])));
                const float32x4_t z = vaddq_f32(T22, vmulq_f32(D, vaddq_f32(B2, cu2[s])));
                const float32x4_t rz = vdivq_f32(one, z);
                const float32x4_t ex = vsubq_f32(vmulq_f32(U, rz), cpx[s]);
                const float32x4_t ey = vsubq_f32(vmulq_f32(V, rz), pyv);
                const uint32x4_t ok = vandq_u32(vandq_u32(vcleq_f32(ex, half), vcgeq_f32(ex, mhalf)),
                                                vandq_u32(vcleq_f32(ey, half), vcgeq_f32(ey, mhalf)));
                m = vandq_u32(m, vandq_u32(vcgtq_f32(z, zmin), ok));
                if (!vmaxvq_u32(m))
                    continue;
                px.val[3] = z;
            }
            float *o = rgbd + 4 * i;
            float32x4x4_t old = vld4q_f32(o);
            old.val[0] = vbslq_f32(m, px.val[0], old.val[0]);
            old.val[1] = vbslq_f32(m, px.val[1], old.val[1]);
            old.val[2] = vbslq_f32(m, px.val[2], old.val[2]);
            old.val[3] = vbslq_f32(m, px.val[3], old.val[3]);
            vst4q_f32(o, old);
            vst1q_f32(wgt + i, vbslq_f32(m, ws, wv));
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
 * (vdivq is IEEE division; compares are false for NaN, selects instead of vmax). */
static void taa_still_neon(float *s, const float *h, ptrdiff_t plane, int n, float widen, float alpha,
                           float inv_depth_tol, uint8_t *wide)
{
    const float32x4_t one = vdupq_n_f32(1.0f), two = vdupq_n_f32(2.0f), zero = vdupq_n_f32(0.0f);
    const float32x4_t vw = vdupq_n_f32(widen), va = vdupq_n_f32(alpha), vt = vdupq_n_f32(inv_depth_tol);
    int k = 0;
    for (; k + 4 <= n; k += 4) {
        const float32x4_t d = vld1q_f32(s + 3 * plane + k);
        const float32x4_t rz = vdivq_f32(one, d);
        const uint32x4_t wm = vcgeq_f32(vmulq_f32(vmulq_f32(d, rz), vw), two);
        const uint16x4_t w16 = vmovn_u32(vshrq_n_u32(wm, 31));
        const uint8x8_t w8 = vmovn_u16(vcombine_u16(w16, w16));
        vst1_lane_u32((uint32_t *)(void *)(wide + k), vreinterpret_u32_u8(w8), 0);
        const float32x4_t dd = vabsq_f32(vsubq_f32(vld1q_f32(h + 3 * plane + k), d));
        float32x4_t a = vsubq_f32(one, vmulq_f32(dd, vmulq_f32(rz, vt)));
        a = vbslq_f32(vcgtq_f32(a, zero), a, zero);
        const float32x4_t w = vmulq_f32(vld1q_f32(h + 4 * plane + k), a);
        const uint32x4_t ok = vbicq_u32(vcgtq_f32(w, zero), wm);
        if (!vmaxvq_u32(ok))
            continue;
        const float32x4_t a1 = vsubq_f32(one, w);
        const float32x4_t al = vbslq_f32(vcgtq_f32(a1, va), a1, va);
        for (int c = 0; c < 3; c++) {
            const float32x4_t sc = vld1q_f32(s + c * plane + k);
            const float32x4_t hc = vdivq_f32(vaddq_f32(zero, vmulq_f32(w, vld1q_f32(h + c * plane + k))), w);
            const float32x4_t o = vaddq_f32(hc, vmulq_f32(al, vsubq_f32(sc, hc)));
            vst1q_f32(s + c * plane + k, vbslq_f32(ok, o, sc));
        }
    }
    for (; k < n; k++)
        taa_still_lane(s, h, plane, k, widen, alpha, inv_depth_tol, wide);
}

void fv_reproject_dsp_init_neon(fv_reproject_dsp *d)
{
    d->taa_blend = taa_blend_neon;
    d->taa_fill = taa_fill_neon;
    d->taa_still = taa_still_neon;
    d->taa_aa = fv_taa_aa_tile_neon; /* core/arm/reproject_aa_neon.c */
}
