/* fovea: pull-push kernels, AArch64 Advanced SIMD (one pixel = one float32x4_t). Bit-identical
 * to the C references in core/pullpush.c: same operations in the same order, true division
 * (FDIV), multiply-by-element (no FMLA: the tree is built with -ffp-contract=off). */
#include <arm_neon.h>

#include "pullpush_dsp.h"

static inline float32x4_t divmask(float32x4_t t, float32x4_t sw)
{
    const uint32x4_t pos = vcgtq_f32(sw, vdupq_n_f32(0.0f));
    return vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(vdivq_f32(t, sw)), pos));
}

/* w > 0 ? w * c : +0, w = lane `lane` of wv, pos = (wv > 0) */
#define TERM(c, wv, pos, lane)                                                                         \
    vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(vmulq_laneq_f32(vld1q_f32(c), wv, lane)),   \
                                    vdupq_laneq_u32(pos, lane)))

/* Coarse pixel k (0..3) of a group of 4: children at a, b; weights in lanes la, lb of wa/wb. */
#define PULL_PX(k, wa, wb, pa_, pb_, la, lb)                                                           \
    do {                                                                                               \
        const float *pa = a + 8 * (k), *pb = b + 8 * (k);                                              \
        const float32x4_t l = vaddq_f32(TERM(pa, wa, pa_, la), TERM(pb, wb, pb_, la));                 \
        const float32x4_t r = vaddq_f32(TERM(pa + 4, wa, pa_, lb), TERM(pb + 4, wb, pb_, lb));         \
        vst1q_f32(o + 4 * (k), divmask(vaddq_f32(l, r), vdupq_laneq_f32(sw, k)));                      \
    } while (0)

static void pull_row_neon(float *restrict dst_rgbd, float *restrict dst_wgt, const float *src0_rgbd,
                          const float *src0_wgt, const float *src1_rgbd, const float *src1_wgt, int n)
{
    const float32x4_t one = vdupq_n_f32(1.0f);
    int x = 0;
    for (; x + 4 <= n; x += 4) {
        const float *a = src0_rgbd + 8 * x, *b = src1_rgbd + 8 * x;
        const float32x4_t wal = vld1q_f32(src0_wgt + 2 * x), wah = vld1q_f32(src0_wgt + 2 * x + 4);
        const float32x4_t wbl = vld1q_f32(src1_wgt + 2 * x), wbh = vld1q_f32(src1_wgt + 2 * x + 4);
        /* (wa0 + wb0) + (wa1 + wb1) for the 4 coarse pixels */
        const float32x4_t sw = vpaddq_f32(vaddq_f32(wal, wbl), vaddq_f32(wah, wbh));
        vst1q_f32(dst_wgt + x, vminq_f32(sw, one));
        const float32x4_t zero = vdupq_n_f32(0.0f);
        const uint32x4_t pal = vcgtq_f32(wal, zero), pah = vcgtq_f32(wah, zero);
        const uint32x4_t pbl = vcgtq_f32(wbl, zero), pbh = vcgtq_f32(wbh, zero);
        float *o = dst_rgbd + 4 * x;
        PULL_PX(0, wal, wbl, pal, pbl, 0, 1);
        PULL_PX(1, wal, wbl, pal, pbl, 2, 3);
        PULL_PX(2, wah, wbh, pah, pbh, 0, 1);
        PULL_PX(3, wah, wbh, pah, pbh, 2, 3);
    }
    if (x < n)
        fv_pull_row_c(dst_rgbd + 4 * x, dst_wgt + x, src0_rgbd + 8 * x, src0_wgt + 2 * x, src1_rgbd + 8 * x,
                      src1_wgt + 2 * x, n - x);
}

/* v = near + 1/4 (far - near) */
static inline float32x4_t vlerp(const float *nr, const float *fr)
{
    const float32x4_t a = vld1q_f32(nr);
    return vaddq_f32(a, vmulq_n_f32(vsubq_f32(vld1q_f32(fr), a), 0.25f));
}

/* c = pos ? fine : 0; fine = lt1 ? c + om * (interp - c) : fine; interp = v + 1/4 (vn - v);
 * om, pos, lt1 in lane k of oms, pos, lt1 */
#define PUSH_PX(o, v, vn, k)                                                                           \
    do {                                                                                               \
        const float32x4_t ip = vaddq_f32((v), vmulq_n_f32(vsubq_f32((vn), (v)), 0.25f));              \
        const float32x4_t f = vld1q_f32(o);                                                            \
        const float32x4_t c =                                                                          \
            vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(f), vdupq_laneq_u32(pos, k)));      \
        const float32x4_t r = vaddq_f32(c, vmulq_laneq_f32(vsubq_f32(ip, c), oms, k));                 \
        vst1q_f32((o), vbslq_f32(vdupq_laneq_u32(lt1, k), r, f));                                      \
    } while (0)

/* Weights all 0 or 1 (level 0 of a ray-traced frame): w = 0 gives +0 + 1 * (interp - +0) =
 * +0 + interp, w = 1 keeps the pixel. */
#define PUSH_PX_BINARY(o, v, vn, k)                                                                    \
    do {                                                                                               \
        const float32x4_t ip = vaddq_f32((v), vmulq_n_f32(vsubq_f32((vn), (v)), 0.25f));              \
        vst1q_f32((o), vbslq_f32(vdupq_laneq_u32(lt1, k), vaddq_f32(zero, ip), vld1q_f32(o)));         \
    } while (0)

static void push_row_neon(float *restrict fine_rgbd, const float *fine_wgt, const float *coarse_near,
                          const float *coarse_far, int n)
{
    const float32x4_t one = vdupq_n_f32(1.0f), zero = vdupq_n_f32(0.0f);
    float32x4_t vp = one, v0 = one; /* v(X - 1), v(X) when `have` */
    int x = 0, have = 0;
    for (; x + 4 <= n; x += 4) {
        const int X = x >> 1; /* reads coarse X - 1 .. X + 2 <= n / 2 */
        const float32x4_t w = vld1q_f32(fine_wgt + x);
        const uint32x4_t lt1 = vcltq_f32(w, one);
        if (!vmaxvq_u32(lt1)) { /* all four kept as they are */
            have = 0;
            continue;
        }
        if (!have) {
            vp = vlerp(coarse_near + 4 * (X - 1), coarse_far + 4 * (X - 1));
            v0 = vlerp(coarse_near + 4 * X, coarse_far + 4 * X);
        }
        const float32x4_t v1 = vlerp(coarse_near + 4 * (X + 1), coarse_far + 4 * (X + 1));
        const float32x4_t v2 = vlerp(coarse_near + 4 * (X + 2), coarse_far + 4 * (X + 2));
        float *o = fine_rgbd + 4 * x;
        if (vminvq_u32(vorrq_u32(vceqq_f32(w, zero), vceqq_f32(w, one)))) {
            PUSH_PX_BINARY(o, v0, vp, 0);
            PUSH_PX_BINARY(o + 4, v0, v1, 1);
            PUSH_PX_BINARY(o + 8, v1, v0, 2);
            PUSH_PX_BINARY(o + 12, v1, v2, 3);
        } else {
            const float32x4_t oms = vsubq_f32(one, w);
            const uint32x4_t pos = vcgtq_f32(w, zero);
            PUSH_PX(o, v0, vp, 0);
            PUSH_PX(o + 4, v0, v1, 1);
            PUSH_PX(o + 8, v1, v0, 2);
            PUSH_PX(o + 12, v1, v2, 3);
        }
        vp = v1;
        v0 = v2;
        have = 1;
    }
    if (x < n) /* x is even: the tail starts on a coarse pixel boundary */
        fv_push_row_c(fine_rgbd + 4 * x, fine_wgt + x, coarse_near + 2 * x, coarse_far + 2 * x, n - x);
}

void fv_pullpush_dsp_init_neon(fv_pullpush_dsp *d)
{
    d->pull_row = pull_row_neon;
    d->push_row = push_row_neon;
}
