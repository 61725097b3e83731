/* fovea: the output kernel, NEON: the indices of 8 pixels' channels in vector code, the table
 * read per channel (NEON has no gather), the bytes assembled in registers. */
#include <arm_neon.h>

#include "output_dsp.h"

static inline uint32x4_t srgb_index4(float32x4_t v)
{
    const float32x4_t t = vaddq_f32(vmulq_f32(v, vdupq_n_f32((float)FV_SRGB_LUT)), vdupq_n_f32(0.5f));
    /* vcvtq truncates like (int); lanes it would saturate are replaced below */
    const uint32x4_t i = vreinterpretq_u32_s32(vcvtq_s32_f32(t));
    const uint32x4_t lt1 = vcltq_f32(v, vdupq_n_f32(1.0f)), gt0 = vcgtq_f32(v, vdupq_n_f32(0.0f));
    return vandq_u32(vbslq_u32(lt1, i, vdupq_n_u32(FV_SRGB_LUT)), gt0);
}

/* 8 table bytes of one channel (indices lo, hi: pixels 0-3, 4-7) as one 64-bit word: a byte load and
 * an OR a pixel, no stores of single bytes */
static inline uint8x8_t lut8(const uint8_t *lut, uint32x4_t lo, uint32x4_t hi)
{
    const uint64_t w = (uint64_t)lut[vgetq_lane_u32(lo, 0)] | (uint64_t)lut[vgetq_lane_u32(lo, 1)] << 8 |
                       (uint64_t)lut[vgetq_lane_u32(lo, 2)] << 16 | (uint64_t)lut[vgetq_lane_u32(lo, 3)] << 24 |
                       (uint64_t)lut[vgetq_lane_u32(hi, 0)] << 32 | (uint64_t)lut[vgetq_lane_u32(hi, 1)] << 40 |
                       (uint64_t)lut[vgetq_lane_u32(hi, 2)] << 48 | (uint64_t)lut[vgetq_lane_u32(hi, 3)] << 56;
    return vcreate_u8(w);
}

/* 8 pixels a step: indices in vector code, the table bytes gathered into a word per channel, one
 * interleaving 24-byte store (ST3) */
static void rgb8_row_neon(uint8_t *restrict dst, const float *rgbd, int n, const uint8_t *lut)
{
    int x = 0;
    for (; x + 8 <= n; x += 8) {
        const float32x4x4_t p = vld4q_f32(rgbd + 4 * x), q = vld4q_f32(rgbd + 4 * x + 16); /* r, g, b, d */
        const uint8x8x3_t o = {{lut8(lut, srgb_index4(p.val[0]), srgb_index4(q.val[0])),
                                lut8(lut, srgb_index4(p.val[1]), srgb_index4(q.val[1])),
                                lut8(lut, srgb_index4(p.val[2]), srgb_index4(q.val[2]))}};
        vst3_u8(dst + 3 * x, o);
    }
    fv_rgb8_row_c(dst + 3 * x, rgbd + 4 * x, n - x, lut);
}

/* lca_row: the radius step 4 pixels at a time (sqrt, table index and weight), the taps lane by
 * lane through the reference's own steps (no gathers): the reference's bytes */
static void lca_row_neon(uint8_t *restrict dst, int y, const fv_lca_geom *g, const fv_lens_lca *lca, const uint8_t *lut)
{
    const float ty = g->tan_top - ((float)y + 0.5f) * g->px_tan, uy = ty - g->cy;
    const float *own = g->img + 4 * (ptrdiff_t)y * g->stride;
    const float32x4_t tl = vdupq_n_f32(g->tan_left), pt = vdupq_n_f32(g->px_tan), cx = vdupq_n_f32(g->cx);
    const float32x4_t uy2 = vdupq_n_f32(uy * uy), steps = vdupq_n_f32((float)FV_LENS_LCA_STEPS), is = vdupq_n_f32(lca->inv_step);
    static const int32_t lane[4] = {0, 1, 2, 3};
    int x = 0;
    for (; x + 4 <= g->w; x += 4) {
        const float32x4_t xf = vaddq_f32(vcvtq_f32_s32(vaddq_s32(vdupq_n_s32(x), vld1q_s32(lane))), vdupq_n_f32(0.5f));
        const float32x4_t ux = vsubq_f32(vaddq_f32(tl, vmulq_f32(xf, pt)), cx);
        float32x4_t f = vmulq_f32(vsqrtq_f32(vaddq_f32(vmulq_f32(ux, ux), uy2)), is);
        f = vbslq_f32(vcltq_f32(f, steps), f, steps); /* NaN: STEPS */
        const int32x4_t i = vminq_s32(vcvtq_s32_f32(f), vdupq_n_s32(FV_LENS_LCA_STEPS - 1));
        float a[4], u[4];
        int32_t iv[4];
        vst1q_f32(a, vsubq_f32(f, vcvtq_f32_s32(i)));
        vst1q_f32(u, ux);
        vst1q_s32(iv, i);
        for (int l = 0; l < 4; l++)
            fv_lca_finish(dst + 3 * (x + l), iv[l], a[l], u[l], uy, g, lca, own + 4 * (x + l), lut);
    }
    for (; x < g->w; x++)
        fv_lca_pixel(dst + 3 * x, x, ty, g, lca, own + 4 * x, lut);
}

void fv_output_dsp_init_neon(fv_output_dsp *d)
{
    d->rgb8_row = rgb8_row_neon;
    d->lca_row = lca_row_neon;
}
