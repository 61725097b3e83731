/* fovea eye tracker kernels, AArch64 Advanced SIMD. Exact: integer arithmetic, same results as
 * the C references in core/eyetrack/eyetrack_ref.c for every input. */
#include <arm_neon.h>

#include "eyetrack/eyetrack_dsp.h"

static void down2_row_neon(uint8_t *restrict dst, const uint8_t *a, const uint8_t *b, int n)
{
    int x = 0;
    for (; x + 16 <= n; x += 16) {
        /* pairwise widening adds of both rows, then (s + 2) >> 2 narrowed */
        const uint16x8_t s0 = vpadalq_u8(vpaddlq_u8(vld1q_u8(a + 2 * x)), vld1q_u8(b + 2 * x));
        const uint16x8_t s1 = vpadalq_u8(vpaddlq_u8(vld1q_u8(a + 2 * x + 16)), vld1q_u8(b + 2 * x + 16));
        vst1q_u8(dst + x, vcombine_u8(vrshrn_n_u16(s0, 2), vrshrn_n_u16(s1, 2)));
    }
    if (x < n)
        fv_et_down2_row_c(dst + x, a + 2 * x, b + 2 * x, n - x);
}

static void integral_row_neon(uint32_t *restrict dst, const uint32_t *above, const uint8_t *src, int n)
{
    const uint16x8_t z = vdupq_n_u16(0);
    uint32x4_t run = vdupq_n_u32(0);
    int x = 0;
    for (; x + 8 <= n; x += 8) {
        uint16x8_t v = vmovl_u8(vld1_u8(src + x));
        v = vaddq_u16(v, vextq_u16(z, v, 7)); /* + v shifted up one lane */
        v = vaddq_u16(v, vextq_u16(z, v, 6));
        v = vaddq_u16(v, vextq_u16(z, v, 4));
        const uint32x4_t lo = vaddq_u32(vmovl_u16(vget_low_u16(v)), run);
        const uint32x4_t hi = vaddq_u32(vmovl_u16(vget_high_u16(v)), run);
        run = vdupq_laneq_u32(hi, 3);
        vst1q_u32(dst + x, vaddq_u32(lo, vld1q_u32(above + x)));
        vst1q_u32(dst + x + 4, vaddq_u32(hi, vld1q_u32(above + x + 4)));
    }
    uint32_t r = vgetq_lane_u32(run, 0);
    for (; x < n; x++) {
        r += src[x];
        dst[x] = above[x] + r;
    }
}

static int thresh_row_neon(uint8_t *restrict dst, const uint8_t *src, int n, int t)
{
    if (t > 255 || t <= 0)
        return fv_et_thresh_row_c(dst, src, n, t);
    const uint8x16_t tv = vdupq_n_u8((uint8_t)t);
    int x = 0, count = 0;
    for (; x + 16 <= n; x += 16) {
        const uint8x16_t m = vcgeq_u8(vld1q_u8(src + x), tv);
        vst1q_u8(dst + x, m);
        count += vaddlvq_u8(vshrq_n_u8(m, 7));
    }
    if (x < n)
        count += fv_et_thresh_row_c(dst + x, src + x, n - x, t);
    return count;
}

static float box_score_row_neon(float *restrict dst, const uint32_t *it, const uint32_t *ib, int din,
                                const uint32_t *ot, const uint32_t *ob, int dout, int n, float inv_a, float inv_r,
                                float dark)
{
    const float32x4_t va = vdupq_n_f32(inv_a), vr = vdupq_n_f32(inv_r), vd = vdupq_n_f32(dark);
    float32x4_t vm = vdupq_n_f32(-__builtin_inff());
    if (n < 4)
        return fv_et_box_score_row_c(dst, it, ib, din, ot, ob, dout, n, inv_a, inv_r, dark);
    /* the last block overlaps the one before it: it stores the same values again, and the
     * maximum does not mind */
    for (int x = 0;; x += 4) {
        if (x > n - 4)
            x = n - 4;
        const uint32x4_t si = vaddq_u32(vsubq_u32(vld1q_u32(ib + x + din), vld1q_u32(it + x + din)),
                                        vsubq_u32(vld1q_u32(it + x), vld1q_u32(ib + x)));
        const uint32x4_t so = vsubq_u32(vaddq_u32(vsubq_u32(vld1q_u32(ob + x + dout), vld1q_u32(ot + x + dout)),
                                                  vsubq_u32(vld1q_u32(ot + x), vld1q_u32(ob + x))),
                                        si);
        const float32x4_t mi = vmulq_f32(vcvtq_f32_u32(si), va), mo = vmulq_f32(vcvtq_f32_u32(so), vr);
        const float32x4_t s = vsubq_f32(vsubq_f32(mo, mi), vsubq_f32(mi, vd));
        vst1q_f32(dst + x, s);
        vm = vmaxq_f32(vm, s);
        if (x == n - 4)
            break;
    }
    return vmaxvq_f32(vm);
}

/* 3x3 box: 16 pixels a step, widening adds of the nine shifted loads, vqrdmulh by 3641 ((2 s k
 * + 2^15) >> 16 = the reference's (s k + 16384) >> 15; s <= 2295 never saturates) */
static void box3_row_neon(uint8_t *restrict dst, const uint8_t *r0, const uint8_t *r1, const uint8_t *r2, int n)
{
    const uint8_t *rows[3] = { r0, r1, r2 };
    if (n > 0)
        dst[0] = fv_et_box3_px(r0, r1, r2, n, 0);
    int x = 1;
    for (; x + 17 <= n; x += 16) { /* reads columns x - 1 .. x + 16 */
        uint16x8_t lo = vdupq_n_u16(0), hi = vdupq_n_u16(0);
        for (int r = 0; r < 3; r++)
            for (int d = -1; d <= 1; d++) {
                const uint8x16_t v = vld1q_u8(rows[r] + x + d);
                lo = vaddw_u8(lo, vget_low_u8(v));
                hi = vaddw_u8(hi, vget_high_u8(v));
            }
        const int16x8_t ql = vqrdmulhq_n_s16(vreinterpretq_s16_u16(lo), 3641);
        const int16x8_t qh = vqrdmulhq_n_s16(vreinterpretq_s16_u16(hi), 3641);
        vst1q_u8(dst + x, vcombine_u8(vqmovun_s16(ql), vqmovun_s16(qh)));
    }
    for (; x < n; x++)
        dst[x] = fv_et_box3_px(r0, r1, r2, n, x);
}

void fv_eyetrack_dsp_init_neon(fv_eyetrack_dsp *d)
{
    d->et_down2_row = down2_row_neon;
    d->et_integral_row = integral_row_neon;
    d->et_thresh_row = thresh_row_neon;
    d->et_box_score_row = box_score_row_neon;
    d->et_box3_row = box3_row_neon;
}
