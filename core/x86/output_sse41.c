/* fovea: the output kernel, SSE4.1: one pixel a vector; the indices in vector code, the table
 * read per channel (SSE4.1 has no gather). */
#include <smmintrin.h>

#include "output_dsp.h"

/* the indices of fv_srgb_index for the 4 lanes of v (the 4th lane is unused) */
static inline __m128i srgb_index4(__m128 v)
{
    const __m128 t = _mm_add_ps(_mm_mul_ps(v, _mm_set1_ps((float)FV_SRGB_LUT)), _mm_set1_ps(0.5f));
    __m128i i = _mm_cvttps_epi32(t);
    i = _mm_blendv_epi8(_mm_set1_epi32(FV_SRGB_LUT), i, _mm_castps_si128(_mm_cmplt_ps(v, _mm_set1_ps(1.0f))));
    return _mm_and_si128(i, _mm_castps_si128(_mm_cmpgt_ps(v, _mm_setzero_ps())));
}

static void rgb8_row_sse41(uint8_t *restrict dst, const float *rgbd, int n, const uint8_t *lut)
{
    for (int x = 0; x < n; x++) {
        const __m128i i = srgb_index4(_mm_loadu_ps(rgbd + 4 * x));
        dst[3 * x + 0] = lut[_mm_cvtsi128_si32(i)];
        dst[3 * x + 1] = lut[_mm_extract_epi32(i, 1)];
        dst[3 * x + 2] = lut[_mm_extract_epi32(i, 2)];
    }
}

void fv_output_dsp_init_sse41(fv_output_dsp *d) { d->rgb8_row = rgb8_row_sse41; }
