/* fovea: the ray-generation kernel, NEON: 8 lanes a step (two vectors). The reference's
 * operations in its order (no FMA): exact. */
#include <arm_neon.h>

#include "raygen_dsp.h"

static inline void rays4(const fv_raygen_cam *c, uint32x4_t p, int x0, int y0, float *dx, float *dy, float *dz)
{
    const int32x4_t xi = vaddq_s32(vreinterpretq_s32_u32(vandq_u32(p, vdupq_n_u32(15))), vdupq_n_s32(x0));
    const int32x4_t yi = vaddq_s32(vreinterpretq_s32_u32(vshrq_n_u32(p, 4)), vdupq_n_s32(y0));
    const float32x4_t hx = vdupq_n_f32(c->ox), hy = vdupq_n_f32(c->oy), s = vdupq_n_f32(c->px_tan);
    const float32x4_t tx = vaddq_f32(vdupq_n_f32(c->tan_left), vmulq_f32(vaddq_f32(vcvtq_f32_s32(xi), hx), s));
    const float32x4_t ty = vsubq_f32(vdupq_n_f32(c->tan_top), vmulq_f32(vaddq_f32(vcvtq_f32_s32(yi), hy), s));
    float *d[3] = {dx, dy, dz};
    for (int k = 0; k < 3; k++)
        vst1q_f32(d[k], vsubq_f32(vaddq_f32(vmulq_f32(tx, vdupq_n_f32(c->right[k])), vmulq_f32(ty, vdupq_n_f32(c->up[k]))),
                                  vdupq_n_f32(c->back[k])));
}

static void camera_rays_neon(const fv_raygen_cam *c, const uint8_t *px, int x0, int y0, float *dx, float *dy, float *dz,
                             int n)
{
    for (int i = 0; i < n; i += 8) {
        const uint16x8_t p16 = vmovl_u8(vld1_u8(px + i));
        rays4(c, vmovl_u16(vget_low_u16(p16)), x0, y0, dx + i, dy + i, dz + i);
        rays4(c, vmovl_u16(vget_high_u16(p16)), x0, y0, dx + i + 4, dy + i + 4, dz + i + 4);
    }
}

void fv_raygen_dsp_init_neon(fv_raygen_dsp *d) { d->camera_rays = camera_rays_neon; }
