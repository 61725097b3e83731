/* fovea: the output kernel, AVX2: 8 pixels a step, the table read with word gathers (its
 * padding makes the 4-byte reads at the last entries safe), the bytes packed and the depth
 * bytes dropped with shuffles. */
#include <immintrin.h>
#include <string.h>

#include "output_dsp.h"

static inline __m256i srgb_index8(__m256 v)
{
    const __m256 t = _mm256_add_ps(_mm256_mul_ps(v, _mm256_set1_ps((float)FV_SRGB_LUT)), _mm256_set1_ps(0.5f));
    __m256i i = _mm256_cvttps_epi32(t);
    const __m256 lt1 = _mm256_cmp_ps(v, _mm256_set1_ps(1.0f), _CMP_LT_OQ);
    const __m256 gt0 = _mm256_cmp_ps(v, _mm256_setzero_ps(), _CMP_GT_OQ);
    i = _mm256_blendv_epi8(_mm256_set1_epi32(FV_SRGB_LUT), i, _mm256_castps_si256(lt1));
    return _mm256_and_si256(i, _mm256_castps_si256(gt0));
}

/* two pixels' r, g, b, d table bytes in the low byte of each 32-bit lane */
static inline __m256i lookup8(const float *p, const uint8_t *lut)
{
    const __m256i i = srgb_index8(_mm256_loadu_ps(p));
    return _mm256_and_si256(_mm256_i32gather_epi32((const int *)(const void *)lut, i, 1), _mm256_set1_epi32(0xff));
}

static void rgb8_row_avx2(uint8_t *restrict dst, const float *rgbd, int n, const uint8_t *lut)
{
    const __m128i keep = _mm_setr_epi8(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1); /* drop d */
    int x = 0;
    for (; x + 8 <= n; x += 8) {
        const float *p = rgbd + 4 * x;
        /* a: pixels 0 | 1 (one per 128-bit lane), b: 2 | 3, c: 4 | 5, d: 6 | 7 */
        const __m256i a = lookup8(p, lut), b = lookup8(p + 8, lut), c = lookup8(p + 16, lut), d = lookup8(p + 24, lut);
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
