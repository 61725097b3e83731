/* fovea: the fovea's anti-aliasing (fv_taa_aa_tile), NEON: one pixel's r, g, b, depth in one
 * float32x4_t (core/reproject_aa_tmpl.h has the design; bit-identical to fv_taa_aa_tile_c). min /
 * max as selects: vminq / vmaxq treat NaN and -0 differently from the reference's a < b ? a : b. */
#include <arm_neon.h>

typedef float32x4_t v4;
#define V_LD(p) vld1q_f32(p)
#define V_ST(p, v) vst1q_f32((p), (v))
#define V_DUP(x) vdupq_n_f32(x)
#define V_ADD vaddq_f32
#define V_SUB vsubq_f32
#define V_MUL vmulq_f32
#define V_DIV vdivq_f32
static inline v4 v_min(v4 a, v4 b) { return vbslq_f32(vcltq_f32(a, b), a, b); }
static inline v4 v_max(v4 a, v4 b) { return vbslq_f32(vcgtq_f32(a, b), a, b); }
#define V_MIN v_min
#define V_MAX v_max
#define V_RGB_S(c, s) vcopyq_laneq_f32((c), 3, (s), 3)
#define V_B0(v) vdupq_laneq_f32((v), 0)
#define V_B1(v) vdupq_laneq_f32((v), 1)
#define V_B2(v) vdupq_laneq_f32((v), 2)
#define V_B3(v) vdupq_laneq_f32((v), 3)
#define V_ONES(p) (vminvq_u32(vceqq_f32(vld1q_f32(p), vdupq_n_f32(1.0f))) != 0)
#define TAA_AA_FN(name) name##_neon
#include "reproject_aa_tmpl.h"
