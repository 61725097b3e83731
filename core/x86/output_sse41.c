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

/* lca_row: the radius step 4 pixels at a time (sqrt, table index and weight), the taps lane by
 * lane through the reference's own steps (no gathers here): the reference's bytes */
static void lca_row_sse41(uint8_t *restrict dst, int y, const fv_lca_geom *g, const fv_lens_lca *lca, const uint8_t *lut)
{
    const float ty = g->tan_top - ((float)y + 0.5f) * g->px_tan, uy = ty - g->cy;
    const float *own = g->img + 4 * (ptrdiff_t)y * g->stride;
    const __m128 tl = _mm_set1_ps(g->tan_left), pt = _mm_set1_ps(g->px_tan), cx = _mm_set1_ps(g->cx);
    const __m128 uy2 = _mm_set1_ps(uy * uy), steps = _mm_set1_ps((float)FV_LENS_LCA_STEPS), is = _mm_set1_ps(lca->inv_step);
    int x = 0;
    for (; x + 4 <= g->w; x += 4) {
        const __m128 xf = _mm_add_ps(_mm_cvtepi32_ps(_mm_add_epi32(_mm_set1_epi32(x), _mm_setr_epi32(0, 1, 2, 3))), _mm_set1_ps(0.5f));
        const __m128 ux = _mm_sub_ps(_mm_add_ps(tl, _mm_mul_ps(xf, pt)), cx);
        __m128 f = _mm_mul_ps(_mm_sqrt_ps(_mm_add_ps(_mm_mul_ps(ux, ux), uy2)), is);
        f = _mm_blendv_ps(steps, f, _mm_cmplt_ps(f, steps)); /* NaN: STEPS */
        const __m128i i = _mm_min_epi32(_mm_cvttps_epi32(f), _mm_set1_epi32(FV_LENS_LCA_STEPS - 1));
        float a[4], u[4];
        int32_t iv[4];
        _mm_storeu_ps(a, _mm_sub_ps(f, _mm_cvtepi32_ps(i)));
        _mm_storeu_ps(u, ux);
        _mm_storeu_si128((__m128i *)(void *)iv, i);
        for (int l = 0; l < 4; l++)
            fv_lca_finish(dst + 3 * (x + l), iv[l], a[l], u[l], uy, g, lca, own + 4 * (x + l), lut);
    }
    for (; x < g->w; x++)
        fv_lca_pixel(dst + 3 * x, x, ty, g, lca, own + 4 * x, lut);
}

void fv_output_dsp_init_sse41(fv_output_dsp *d)
{
    d->rgb8_row = rgb8_row_sse41;
    d->lca_row = lca_row_sse41;
}
