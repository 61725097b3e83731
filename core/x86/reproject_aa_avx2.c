/* fovea: the fovea's anti-aliasing (fv_taa_aa_tile), AVX2: the SSE4.1 design (one pixel's r, g,
 * b, depth in one __m128; core/reproject_aa_tmpl.h) in VEX encoding: a pixel's taps are four
 * floats wide, so two pixels per 256-bit vector would only add shuffles. Bit-identical to
 * fv_taa_aa_tile_c. */
#include <smmintrin.h>

typedef __m128 v4;
#define V_LD(p) _mm_loadu_ps(p)
#define V_ST(p, v) _mm_storeu_ps((p), (v))
#define V_DUP(x) _mm_set1_ps(x)
#define V_ADD _mm_add_ps
#define V_SUB _mm_sub_ps
#define V_MUL _mm_mul_ps
#define V_DIV _mm_div_ps
#define V_MIN _mm_min_ps /* a < b ? a : b, as minf (NaN and +-0 included) */
#define V_MAX _mm_max_ps /* a > b ? a : b */
#define V_RGB_S(c, s) _mm_blend_ps((c), (s), 0x8)
#define V_B0(v) _mm_shuffle_ps((v), (v), 0x00)
#define V_B1(v) _mm_shuffle_ps((v), (v), 0x55)
#define V_B2(v) _mm_shuffle_ps((v), (v), 0xaa)
#define V_B3(v) _mm_shuffle_ps((v), (v), 0xff)
#define V_ONES(p) (_mm_movemask_ps(_mm_cmpeq_ps(_mm_loadu_ps(p), _mm_set1_ps(1.0f))) == 0xf)
#define TAA_AA_FN(name) name##_avx2
#include "reproject_aa_tmpl.h"
