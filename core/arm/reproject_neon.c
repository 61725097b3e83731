/* fovea: temporal reprojection kernels, NEON: one texel = one float32x4_t (r, g, b, depth).
 * Same operations in the same order as the reference (no fused multiply-add intrinsics; the
 * tree is built with -ffp-contract=off): bit-identical. Row loops and scalar arithmetic:
 * core/reproject_tmpl.h. */
#include <arm_neon.h>

#include <stdint.h>

#include "reproject_dsp.h"
#include "reproject.h"

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
#include "reproject_tmpl.h"

/* The fill, four pixels at a time (vld4 / vst4 de-interleave r, g, b, depth): each lane does the
 * reference's operations (taa_fill_px). */
static inline int fill_vec_neon(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, float *wgt,
                              const float *hrow, const float *hw, const float B[3], int x0, float py, int ilo, int ihi)
{
    const int sx0 = x0 + t->flow_x;
    const float32x4_t zero = vdupq_n_f32(0.0f), half = vdupq_n_f32(0.5f), mhalf = vdupq_n_f32(-0.5f);
    static const int32_t lanes[4] = {0, 1, 2, 3};
    const int32x4_t lane = vld1q_s32(lanes);
    int i = ilo;
    for (; i + 4 <= ihi; i += 4) {
        const float32x4_t w = vld1q_f32(wgt + i);
        const int sx = sx0 + i;
        const float32x4_t ws = vld1q_f32(hw + sx);
        uint32x4_t m = vandq_u32(vceqq_f32(w, zero), vcgtq_f32(ws, zero));
        if (!vmaxvq_u32(m))
            continue;
        float32x4x4_t px = vld4q_f32(hrow + 4 * sx); /* r, g, b, D of four texels */
        if (!f->identity) {
            const float32x4_t D = px.val[3];
            const float32x4_t uc = vaddq_f32(vcvtq_f32_s32(vaddq_s32(vdupq_n_s32(sx), lane)), half);
            const float32x4_t pxc = vaddq_f32(vcvtq_f32_s32(vaddq_s32(vdupq_n_s32(x0 + i), lane)), half);
            float32x4_t c[3];
            for (int k = 0; k < 3; k++)
                c[k] = vaddq_f32(vdupq_n_f32(f->T2[k]),
                                 vmulq_f32(D, vaddq_f32(vdupq_n_f32(B[k]), vmulq_f32(uc, vdupq_n_f32(f->NX[k])))));
            const float32x4_t rz = vdivq_f32(vdupq_n_f32(1.0f), c[2]);
            const float32x4_t ex = vsubq_f32(vmulq_f32(c[0], rz), pxc);
            const float32x4_t ey = vsubq_f32(vmulq_f32(c[1], rz), vdupq_n_f32(py));
            const uint32x4_t ok = vandq_u32(vandq_u32(vcleq_f32(ex, half), vcgeq_f32(ex, mhalf)),
                                            vandq_u32(vcleq_f32(ey, half), vcgeq_f32(ey, mhalf)));
            m = vandq_u32(m, vandq_u32(vcgtq_f32(c[2], vdupq_n_f32(1e-4f)), ok));
            if (!vmaxvq_u32(m))
                continue;
            px.val[3] = c[2];
        }
        float *o = rgbd + 4 * i;
        float32x4x4_t old = vld4q_f32(o);
        for (int k = 0; k < 4; k++)
            old.val[k] = vbslq_f32(m, px.val[k], old.val[k]);
        vst4q_f32(o, old);
        vst1q_f32(wgt + i, vbslq_f32(m, ws, w));
    }
    return i;
}

TAA_FILL_BLOCK(taa_fill_neon, fill_vec_neon)

void fv_reproject_dsp_init_neon(fv_reproject_dsp *d)
{
    d->taa_blend = taa_blend_neon;
    d->taa_fill = taa_fill_neon;
}
