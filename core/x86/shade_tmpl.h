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
/* NRM9: the corner normals of SW lanes from their records, transposed (rows of 8 floats, then
 * element 8 on its own: only 9 floats of a record are read) */
#if FV_X86_W == 8
static inline void nrm9(const float *const *at, V c[9])
{
    V r[8];
    for (int l = 0; l < 8; l++)
        r[l] = _mm256_loadu_ps(at[l]);
    const V t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
    const V t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
    const V t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
    const V t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
    /* s_k: element k of lanes 0-3 in the low half, element k + 4 in the high half (lanes 0-3 of
     * s_k, 4-7 of s_{k+4}) */
    const V s0 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0)), s1 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
    const V s2 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0)), s3 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
    const V s4 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(1, 0, 1, 0)), s5 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(3, 2, 3, 2));
    const V s6 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(1, 0, 1, 0)), s7 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(3, 2, 3, 2));
    c[0] = _mm256_permute2f128_ps(s0, s4, 0x20), c[4] = _mm256_permute2f128_ps(s0, s4, 0x31);
    c[1] = _mm256_permute2f128_ps(s1, s5, 0x20), c[5] = _mm256_permute2f128_ps(s1, s5, 0x31);
    c[2] = _mm256_permute2f128_ps(s2, s6, 0x20), c[6] = _mm256_permute2f128_ps(s2, s6, 0x31);
    c[3] = _mm256_permute2f128_ps(s3, s7, 0x20), c[7] = _mm256_permute2f128_ps(s3, s7, 0x31);
    c[8] = _mm256_setr_ps(at[0][8], at[1][8], at[2][8], at[3][8], at[4][8], at[5][8], at[6][8], at[7][8]);
}
#else
static inline void nrm9(const float *const *at, V c[9])
{
    for (int j = 0; j < 8; j += 4) {
        V r0 = _mm_loadu_ps(at[0] + j), r1 = _mm_loadu_ps(at[1] + j), r2 = _mm_loadu_ps(at[2] + j),
          r3 = _mm_loadu_ps(at[3] + j);
        _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
        c[j] = r0, c[j + 1] = r1, c[j + 2] = r2, c[j + 3] = r3;
    }
    c[8] = _mm_setr_ps(at[0][8], at[1][8], at[2][8], at[3][8]);
}
#endif
#define NRM9 nrm9
typedef V M;
#define SHADE_FN FV_X86_FN(brdf)
#include "../shade_tmpl.h"
