/* fovea: the packet shading kernel, NEON: 4 lanes a vector, the body of core/shade_tmpl.h.
 * Bit-identical to the C reference (IEEE operations in its order: vdivq / vsqrtq, no FMA). */
/* the template's loops over x, y, z peeled (as -O3 would): at -O2 gcc kept them as loops over
 * arrays of vectors on the stack (brdf_lights 2720 -> 2196 instructions a packet, brdf 1372 -> 890) */
#if defined(__GNUC__) && !defined(__clang__) /* clang -O2 unrolls them already */
#pragma GCC optimize("peel-loops")
#endif
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
/* the corner normals of 4 lanes from their records: 4x4 transposes of elements 0-3 and 4-7, then
 * element 8 on its own (only 9 floats of a record are read) */
static inline void nrm9(const float *const *at, V c[9])
{
    for (int j = 0; j < 8; j += 4) {
        const float32x4x2_t p01 = vtrnq_f32(vld1q_f32(at[0] + j), vld1q_f32(at[1] + j));
        const float32x4x2_t p23 = vtrnq_f32(vld1q_f32(at[2] + j), vld1q_f32(at[3] + j));
        c[j] = vcombine_f32(vget_low_f32(p01.val[0]), vget_low_f32(p23.val[0]));
        c[j + 1] = vcombine_f32(vget_low_f32(p01.val[1]), vget_low_f32(p23.val[1]));
        c[j + 2] = vcombine_f32(vget_high_f32(p01.val[0]), vget_high_f32(p23.val[0]));
        c[j + 3] = vcombine_f32(vget_high_f32(p01.val[1]), vget_high_f32(p23.val[1]));
    }
    const float e8[4] = {at[0][8], at[1][8], at[2][8], at[3][8]};
    c[8] = vld1q_f32(e8);
}
#define NRM9 nrm9
#define SHADE_FN brdf_neon
#include "shade_tmpl.h"

void fv_shade_dsp_init_neon(fv_shade_dsp *d) { d->brdf = brdf_neon; }
