/* fovea: the output kernel, NEON: the indices of 4 pixels' channels in vector code, the table
 * read per channel (NEON has no gather). */
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

static void rgb8_row_neon(uint8_t *restrict dst, const float *rgbd, int n, const uint8_t *lut)
{
    int x = 0;
    for (; x + 4 <= n; x += 4) {
        const float32x4x4_t p = vld4q_f32(rgbd + 4 * x); /* r, g, b, d of 4 pixels, deinterleaved */
        uint32_t ir[4], ig[4], ib[4];
        vst1q_u32(ir, srgb_index4(p.val[0]));
        vst1q_u32(ig, srgb_index4(p.val[1]));
        vst1q_u32(ib, srgb_index4(p.val[2]));
        for (int k = 0; k < 4; k++) {
            dst[3 * (x + k) + 0] = lut[ir[k]];
            dst[3 * (x + k) + 1] = lut[ig[k]];
            dst[3 * (x + k) + 2] = lut[ib[k]];
        }
    }
    fv_rgb8_row_c(dst + 3 * x, rgbd + 4 * x, n - x, lut);
}

void fv_output_dsp_init_neon(fv_output_dsp *d) { d->rgb8_row = rgb8_row_neon; }
