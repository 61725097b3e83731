/* fovea: the packet shading kernel, NEON: 4 lanes a vector, the body of core/shade_tmpl.h.
 * Bit-identical to the C reference (IEEE operations in its order: vdivq / vsqrtq, no FMA). */
#include <arm_neon.h>

#include "shade_dsp.h"

#define SW 4
typedef float32x4_t V;
typedef uint32x4_t M;
#define VLD(p) vld1q_f32(p)
#define VST(p, v) vst1q_f32(p, v)
#define VS(x) vdupq_n_f32(x)
#define VADD vaddq_f32
#define VSUB vsubq_f32
#define VMUL vmulq_f32
#define VDIV vdivq_f32
#define VSQRT vsqrtq_f32
#define VNEG vnegq_f32
#define VGT vcgtq_f32
#define VGE vcgeq_f32
#define VLT vcltq_f32
#define MAND vandq_u32
#define VSEL(m, a, b) vbslq_f32(m, a, b)
static inline int mbits(uint32x4_t m)
{
    static const uint32_t bit[4] = {1, 2, 4, 8};
    return (int)vaddvq_u32(vandq_u32(m, vld1q_u32(bit)));
}
#define MBITS mbits
#define SHADE_FN brdf_neon
#include "shade_tmpl.h"

void fv_shade_dsp_init_neon(fv_shade_dsp *d) { d->brdf = brdf_neon; }
