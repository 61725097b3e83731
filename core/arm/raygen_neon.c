/* fovea: the ray-generation kernel, NEON: 8 lanes a step (two vectors). The reference's
 * operations in its order (no FMA): exact. The camera is read into registers once a call: the
 * stores through dx/dy/dz could alias *c, so reading it per step made gcc reload (and re-dup)
 * every coefficient for every vector (288 -> ~130 instructions a packet of 16). */
#include <arm_neon.h>

#include "raygen_dsp.h"

typedef struct cam_regs {
    float32x4_t tl, tt, ox, oy, back[3];
    float s, right[3], up[3];
    int32x4_t x0, y0;
} cam_regs;

static inline void rays4(const cam_regs *r, uint32x4_t p, float *dx, float *dy, float *dz)
{
    const int32x4_t xi = vaddq_s32(vreinterpretq_s32_u32(vandq_u32(p, vdupq_n_u32(15))), r->x0);
    const int32x4_t yi = vaddq_s32(vreinterpretq_s32_u32(vshrq_n_u32(p, 4)), r->y0);
    const float32x4_t tx = vaddq_f32(r->tl, vmulq_n_f32(vaddq_f32(vcvtq_f32_s32(xi), r->ox), r->s));
    const float32x4_t ty = vsubq_f32(r->tt, vmulq_n_f32(vaddq_f32(vcvtq_f32_s32(yi), r->oy), r->s));
    vst1q_f32(dx, vsubq_f32(vaddq_f32(vmulq_n_f32(tx, r->right[0]), vmulq_n_f32(ty, r->up[0])), r->back[0]));
    vst1q_f32(dy, vsubq_f32(vaddq_f32(vmulq_n_f32(tx, r->right[1]), vmulq_n_f32(ty, r->up[1])), r->back[1]));
    vst1q_f32(dz, vsubq_f32(vaddq_f32(vmulq_n_f32(tx, r->right[2]), vmulq_n_f32(ty, r->up[2])), r->back[2]));
}

static void camera_rays_neon(const fv_raygen_cam *c, const uint8_t *px, int x0, int y0, float *dx, float *dy, float *dz,
                             int n)
{
    const cam_regs r = {
        .tl = vdupq_n_f32(c->tan_left),
        .tt = vdupq_n_f32(c->tan_top),
        .ox = vdupq_n_f32(c->ox),
        .oy = vdupq_n_f32(c->oy),
        .back = {vdupq_n_f32(c->back[0]), vdupq_n_f32(c->back[1]), vdupq_n_f32(c->back[2])},
        .s = c->px_tan,
        .right = {c->right[0], c->right[1], c->right[2]},
        .up = {c->up[0], c->up[1], c->up[2]},
        .x0 = vdupq_n_s32(x0),
        .y0 = vdupq_n_s32(y0),
    };
    for (int i = 0; i < n; i += 8) {
        const uint16x8_t p16 = vmovl_u8(vld1_u8(px + i));
        rays4(&r, vmovl_u16(vget_low_u16(p16)), dx + i, dy + i, dz + i);
        rays4(&r, vmovl_high_u16(p16), dx + i + 4, dy + i + 4, dz + i + 4);
    }
}

void fv_raygen_dsp_init_neon(fv_raygen_dsp *d) { d->camera_rays = camera_rays_neon; }
