/* fovea: the last (n mod 4) coarse pixels of pull_row, one __m128 a pixel, for the SSE4.1 and AVX2
 * kernels (included after <immintrin.h> / <smmintrin.h>). The in-tile pulls (core/tile.c) end
 * every 16x16 tile with rows of 2 and 1 coarse pixels (levels 2 and 3): 3 of a tile's 15 rows
 * went to the C reference, a call and scalar code each. Same operations in the same order as
 * fv_pull_row_c: same bits. */
#ifndef FOVEA_X86_PULL_TAIL_H
#define FOVEA_X86_PULL_TAIL_H

#define PT_BCAST(v, i) _mm_shuffle_ps((v), (v), _MM_SHUFFLE((i), (i), (i), (i)))

/* w > 0 ? w * c : +0 (w broadcast) */
static inline __m128 pt_term(__m128 w, const float *c)
{
    return _mm_and_ps(_mm_mul_ps(w, _mm_loadu_ps(c)), _mm_cmpgt_ps(w, _mm_setzero_ps()));
}

static inline void pull_tail_sse(float *restrict dst_rgbd, float *restrict dst_wgt, const float *src0_rgbd,
                                 const float *src0_wgt, const float *src1_rgbd, const float *src1_wgt, int x, int n)
{
    for (; x < n; x++) {
        const float *a = src0_rgbd + 8 * x, *b = src1_rgbd + 8 * x;
        /* lanes 0, 1: the children's weights (8 bytes each row) */
        /* (weights are 4-byte aligned only: _mm_loadl_epi64 takes an unaligned 64-bit load, where
         * _mm_load_sd's double type is undefined behaviour there) */
        const __m128 wa = _mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(const void *)(src0_wgt + 2 * x)));
        const __m128 wb = _mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(const void *)(src1_wgt + 2 * x)));
        const __m128 cs = _mm_add_ps(wa, wb);                   /* wa0 + wb0, wa1 + wb1 */
        const __m128 sw = PT_BCAST(_mm_hadd_ps(cs, cs), 0); /* (wa0 + wb0) + (wa1 + wb1) */
        _mm_store_ss(dst_wgt + x, _mm_min_ss(sw, _mm_set1_ps(1.0f)));
        const __m128 l = _mm_add_ps(pt_term(PT_BCAST(wa, 0), a), pt_term(PT_BCAST(wb, 0), b));
        const __m128 r = _mm_add_ps(pt_term(PT_BCAST(wa, 1), a + 4), pt_term(PT_BCAST(wb, 1), b + 4));
        const __m128 q = _mm_div_ps(_mm_add_ps(l, r), sw);
        _mm_storeu_ps(dst_rgbd + 4 * x, _mm_and_ps(q, _mm_cmpgt_ps(sw, _mm_setzero_ps())));
    }
}

#endif
