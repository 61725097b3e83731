/* fovea: the x86 vector operations of the packet shading kernel (core/shade_tmpl.h has the body
 * and the list): core/x86/shade_sse41.c and shade_avx2.c each include this once after defining
 * FV_X86_W (4 or 8 floats) and FV_X86_FN(name), built with their own ISA flags. Blends are
 * and/andnot/or; every arithmetic operation is an IEEE one (-ffp-contract=off: no FMA). */
#if !defined(FV_X86_W) || !defined(FV_X86_FN)
#error "define FV_X86_W and FV_X86_FN before including x86/shade_tmpl.h"
#endif

#include <immintrin.h>

#include "shade_dsp.h"

#define SW FV_X86_W
#if FV_X86_W == 8
typedef __m256 V;
#define VLD(p) _mm256_loadu_ps(p)
#define VST(p, v) _mm256_storeu_ps(p, v)
#define VS(x) _mm256_set1_ps(x)
#define VADD _mm256_add_ps
#define VSUB _mm256_sub_ps
#define VMUL _mm256_mul_ps
#define VDIV _mm256_div_ps
#define VSQRT _mm256_sqrt_ps
#define VNEG(a) _mm256_xor_ps(a, _mm256_set1_ps(-0.0f))
#define VGT(a, b) _mm256_cmp_ps(a, b, _CMP_GT_OQ)
#define VGE(a, b) _mm256_cmp_ps(a, b, _CMP_GE_OQ)
#define VLT(a, b) _mm256_cmp_ps(a, b, _CMP_LT_OQ)
#define MAND _mm256_and_ps
#define VSEL(m, a, b) _mm256_blendv_ps(b, a, m)
#define MBITS(m) _mm256_movemask_ps(m)
#else
typedef __m128 V;
#define VLD(p) _mm_loadu_ps(p)
#define VST(p, v) _mm_storeu_ps(p, v)
#define VS(x) _mm_set1_ps(x)
#define VADD _mm_add_ps
#define VSUB _mm_sub_ps
#define VMUL _mm_mul_ps
#define VDIV _mm_div_ps
#define VSQRT _mm_sqrt_ps
#define VNEG(a) _mm_xor_ps(a, _mm_set1_ps(-0.0f))
#define VGT(a, b) _mm_cmpgt_ps(a, b)
#define VGE(a, b) _mm_cmpge_ps(a, b)
#define VLT(a, b) _mm_cmplt_ps(a, b)
#define MAND _mm_and_ps
#define VSEL(m, a, b) _mm_blendv_ps(b, a, m)
#define MBITS(m) _mm_movemask_ps(m)
#endif
typedef V M;
#define SHADE_FN FV_X86_FN(brdf)
#include "../shade_tmpl.h"
