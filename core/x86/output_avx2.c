/* fovea: the output kernel, AVX2: 8 pixels a step, sRGB computed instead of looked up (the
 * table gathers bound the old version): v^(5/12) as 2^(5e/12), e the exponent (a permute from 9
 * constants), times a cubic in the mantissa m in [1, 2) (relative error 1.1e-4, 0.03 of a step
 * of 255); within 1 of the reference's table bytes (the table itself rounds v to 1/4096 first,
 * up to 0.4 of a step), exactly 0 for v <= 0 or NaN and 255 for v >= 1 (output_dsp.h). The depth
 * lanes are computed and dropped by the shuffles. */
#include <immintrin.h>
#include <string.h>

#include "output_dsp.h"

/* 1.055 * 2^(5 (k - 9) / 12), k = e + 9 for the exponents e = -9 .. -1 of [2^-9, 1) */
static const float k_pow2[9] = {7.841334415e-02f, 1.046692569e-01f, 1.397166956e-01f,
                                1.864994135e-01f, 2.489468500e-01f, 3.323041769e-01f,
                                4.435728590e-01f, 5.920987305e-01f, 7.903569831e-01f};

/* 255 sRGB(v) + 0.5 truncated, as 32-bit integers (0 .. 256: the packs saturate 256 to 255) */
static inline __m256i srgb8(__m256 v)
{
    /* [0, 1 - ulp]; NaN -> 0 (max returns its second operand on NaN) */
    v = _mm256_min_ps(_mm256_max_ps(v, _mm256_setzero_ps()), _mm256_set1_ps(0x1.fffffep-1f));
    const __m256i bits = _mm256_castps_si256(v);
    /* e + 9; below 2^-9 (the linear part's) any lane value: the permute reads its low 3 bits */
    const __m256i k = _mm256_sub_epi32(_mm256_srli_epi32(bits, 23), _mm256_set1_epi32(127 - 9));
    const __m256 m = _mm256_castsi256_ps(
        _mm256_or_si256(_mm256_and_si256(bits, _mm256_set1_epi32(0x007fffff)), _mm256_set1_epi32(0x3f800000)));
    __m256 p = _mm256_fmadd_ps(_mm256_set1_ps(2.373281530e-02f), m, _mm256_set1_ps(-1.733108596e-01f));
    p = _mm256_fmadd_ps(p, m, _mm256_set1_ps(6.886010604e-01f));
    p = _mm256_fmadd_ps(p, m, _mm256_set1_ps(4.610837899e-01f));
    __m256 t = _mm256_permutevar8x32_ps(_mm256_loadu_ps(k_pow2), k);
    t = _mm256_blendv_ps(t, _mm256_set1_ps(k_pow2[8]), _mm256_castsi256_ps(_mm256_cmpeq_epi32(k, _mm256_set1_epi32(8))));
    const __m256 gam = _mm256_fmsub_ps(t, p, _mm256_set1_ps(0.055f));
    const __m256 lin = _mm256_mul_ps(v, _mm256_set1_ps(12.92f));
    const __m256 s = _mm256_blendv_ps(gam, lin, _mm256_cmp_ps(v, _mm256_set1_ps(0.0031308f), _CMP_LE_OQ));
    return _mm256_cvttps_epi32(_mm256_fmadd_ps(s, _mm256_set1_ps(255.0f), _mm256_set1_ps(0.5f)));
}

static void rgb8_row_avx2(uint8_t *restrict dst, const float *rgbd, int n, const uint8_t *lut)
{
    const __m128i keep = _mm_setr_epi8(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1); /* drop d */
    int x = 0;
    for (; x + 8 <= n; x += 8) {
        const float *p = rgbd + 4 * x;
        /* a: pixels 0 | 1 (one per 128-bit lane), b: 2 | 3, c: 4 | 5, d: 6 | 7 */
        const __m256i a = srgb8(_mm256_loadu_ps(p)), b = srgb8(_mm256_loadu_ps(p + 8));
        const __m256i c = srgb8(_mm256_loadu_ps(p + 16)), d = srgb8(_mm256_loadu_ps(p + 24));
        /* the packs work per 128-bit lane: lane 0 ends as pixels 0 2 4 6, lane 1 as 1 3 5 7 */
        const __m256i bytes = _mm256_packus_epi16(_mm256_packus_epi32(a, b), _mm256_packus_epi32(c, d));
        const __m128i even = _mm256_castsi256_si128(bytes), odd = _mm256_extracti128_si256(bytes, 1);
        const __m128i k0 = _mm_shuffle_epi8(_mm_unpacklo_epi32(even, odd), keep); /* pixels 0-3 */
        const __m128i k1 = _mm_shuffle_epi8(_mm_unpackhi_epi32(even, odd), keep); /* pixels 4-7 */
        const int32_t t0 = _mm_extract_epi32(k0, 2), t1 = _mm_extract_epi32(k1, 2);
        _mm_storel_epi64((__m128i *)(void *)(dst + 3 * x), k0);
        memcpy(dst + 3 * x + 8, &t0, 4);
        _mm_storel_epi64((__m128i *)(void *)(dst + 3 * x + 12), k1);
        memcpy(dst + 3 * x + 20, &t1, 4);
    }
    fv_rgb8_row_c(dst + 3 * x, rgbd + 4 * x, n - x, lut);
}

void fv_output_dsp_init_avx2(fv_output_dsp *d) { d->rgb8_row = rgb8_row_avx2; }
