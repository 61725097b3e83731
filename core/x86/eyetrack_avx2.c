/* fovea eye tracker kernels, AVX2. Exact: integer arithmetic, same results as the C references
 * in core/eyetrack/eyetrack_ref.c for every input. */
#include <immintrin.h>

#include "eyetrack/eyetrack_dsp.h"

static void down2_row_avx2(uint8_t *restrict dst, const uint8_t *a, const uint8_t *b, int n)
{
    const __m256i ones = _mm256_set1_epi8(1), two = _mm256_set1_epi16(2);
    int x = 0;
    for (; x + 32 <= n; x += 32) {
        const __m256i a0 = _mm256_maddubs_epi16(_mm256_loadu_si256((const __m256i *)(a + 2 * x)), ones);
        const __m256i a1 = _mm256_maddubs_epi16(_mm256_loadu_si256((const __m256i *)(a + 2 * x + 32)), ones);
        const __m256i b0 = _mm256_maddubs_epi16(_mm256_loadu_si256((const __m256i *)(b + 2 * x)), ones);
        const __m256i b1 = _mm256_maddubs_epi16(_mm256_loadu_si256((const __m256i *)(b + 2 * x + 32)), ones);
        const __m256i s0 = _mm256_srli_epi16(_mm256_add_epi16(_mm256_add_epi16(a0, b0), two), 2);
        const __m256i s1 = _mm256_srli_epi16(_mm256_add_epi16(_mm256_add_epi16(a1, b1), two), 2);
        /* packus works per 128-bit lane: put the four quarters back in order */
        const __m256i p = _mm256_permute4x64_epi64(_mm256_packus_epi16(s0, s1), _MM_SHUFFLE(3, 1, 2, 0));
        _mm256_storeu_si256((__m256i *)(dst + x), p);
    }
    if (x < n)
        fv_et_down2_row_c(dst + x, a + 2 * x, b + 2 * x, n - x);
}

static void integral_row_avx2(uint32_t *restrict dst, const uint32_t *above, const uint8_t *src, int n)
{
    /* 16 pixels a step as u16 (the sum of 8 bytes, <= 2040, fits): the prefix within groups of 4
     * by 64-bit shifts (not shuffles), then word 3 of each 128-bit lane added to its words 4-7
     * (one byte shuffle): each lane holds its 8 pixels' prefix. Widened to two rows of 8 u32, each
     * row's total is broadcast from its last element; those broadcasts do not depend on the
     * running sum, so the chain carried from step to step is one add (it had been an add and a
     * lane permute every 8 pixels, the scalar loop's speed). Integer adds mod 2^32 in any order:
     * the same bits as the C reference. */
    const __m256i up4 = _mm256_setr_epi8(-1, -1, -1, -1, -1, -1, -1, -1, 6, 7, 6, 7, 6, 7, 6, 7, /* lane 0 */
                                         -1, -1, -1, -1, -1, -1, -1, -1, 6, 7, 6, 7, 6, 7, 6, 7);
    const __m256i last = _mm256_set1_epi32(7);
    __m256i run = _mm256_setzero_si256();
    int x = 0;
    /* 32 pixels an iteration (two independent 16-pixel halves: less loop overhead a pixel); the
     * running sum's chain is two adds a half (run + the first row's total, + the second's) */
#define INTEGRAL16(o)                                                                                                \
    do {                                                                                                             \
        __m256i w = _mm256_cvtepu8_epi16(_mm_loadu_si128((const __m128i *)(src + x + (o))));                         \
        w = _mm256_add_epi16(w, _mm256_slli_epi64(w, 16));                                                           \
        w = _mm256_add_epi16(w, _mm256_slli_epi64(w, 32));                                                           \
        w = _mm256_add_epi16(w, _mm256_shuffle_epi8(w, up4));                                                        \
        const __m256i lo = _mm256_cvtepu16_epi32(_mm256_castsi256_si128(w));                                         \
        const __m256i hi = _mm256_cvtepu16_epi32(_mm256_extracti128_si256(w, 1));                                    \
        const __m256i r1 = _mm256_add_epi32(run, _mm256_permutevar8x32_epi32(lo, last));                             \
        _mm256_storeu_si256((__m256i *)(dst + x + (o)),                                                              \
                            _mm256_add_epi32(_mm256_add_epi32(lo, _mm256_loadu_si256((const __m256i *)(above + x + (o)))), run)); \
        _mm256_storeu_si256((__m256i *)(dst + x + (o) + 8),                                                          \
                            _mm256_add_epi32(_mm256_add_epi32(hi, _mm256_loadu_si256((const __m256i *)(above + x + (o) + 8))), r1)); \
        run = _mm256_add_epi32(r1, _mm256_permutevar8x32_epi32(hi, last));                                           \
    } while (0)
    for (; x + 32 <= n; x += 32) {
        INTEGRAL16(0);
        INTEGRAL16(16);
    }
    if (x + 16 <= n) {
        INTEGRAL16(0);
        x += 16;
    }
#undef INTEGRAL16
    uint32_t r = (uint32_t)_mm256_cvtsi256_si32(run);
    for (; x < n; x++) {
        r += src[x];
        dst[x] = above[x] + r;
    }
}

static int thresh_row_avx2(uint8_t *restrict dst, const uint8_t *src, int n, int t)
{
    if (t > 255 || t <= 0)
        return fv_et_thresh_row_c(dst, src, n, t);
    const __m256i tv = _mm256_set1_epi8((char)t);
    int x = 0, count = 0;
    for (; x + 32 <= n; x += 32) {
        const __m256i s = _mm256_loadu_si256((const __m256i *)(src + x));
        const __m256i m = _mm256_cmpeq_epi8(_mm256_max_epu8(s, tv), s);
        _mm256_storeu_si256((__m256i *)(dst + x), m);
        count += __builtin_popcount((unsigned)_mm256_movemask_epi8(m));
    }
    if (x + 16 <= n) { /* short rows (the glint window of a small crop) */
        const __m128i s = _mm_loadu_si128((const __m128i *)(src + x));
        const __m128i m = _mm_cmpeq_epi8(_mm_max_epu8(s, _mm256_castsi256_si128(tv)), s);
        _mm_storeu_si128((__m128i *)(dst + x), m);
        count += __builtin_popcount((unsigned)_mm_movemask_epi8(m));
        x += 16;
    }
    if (x < n)
        count += fv_et_thresh_row_c(dst + x, src + x, n - x, t);
    return count;
}

/* The box sums are below 2^31, so the signed conversion is the C reference's unsigned one. */
static float box_score_row_avx2(float *restrict dst, const uint32_t *it, const uint32_t *ib, int din,
                                const uint32_t *ot, const uint32_t *ob, int dout, int n, float inv_a, float inv_r,
                                float dark)
{
#define L(p) _mm256_loadu_si256((const __m256i *)(p))
    const __m256 va = _mm256_set1_ps(inv_a), vr = _mm256_set1_ps(inv_r), vd = _mm256_set1_ps(dark);
    __m256 vm = _mm256_set1_ps(-__builtin_inff());
    if (n < 8)
        return fv_et_box_score_row_c(dst, it, ib, din, ot, ob, dout, n, inv_a, inv_r, dark);
    /* the last block overlaps the one before it: it stores the same values again, and the
     * maximum does not mind */
    for (int x = 0;; x += 8) {
        if (x > n - 8)
            x = n - 8;
        const __m256i si =
            _mm256_add_epi32(_mm256_sub_epi32(L(ib + x + din), L(it + x + din)), _mm256_sub_epi32(L(it + x), L(ib + x)));
        const __m256i so = _mm256_sub_epi32(_mm256_add_epi32(_mm256_sub_epi32(L(ob + x + dout), L(ot + x + dout)),
                                                             _mm256_sub_epi32(L(ot + x), L(ob + x))),
                                            si);
        const __m256 mi = _mm256_mul_ps(_mm256_cvtepi32_ps(si), va), mo = _mm256_mul_ps(_mm256_cvtepi32_ps(so), vr);
        const __m256 s = _mm256_sub_ps(_mm256_sub_ps(mo, mi), _mm256_sub_ps(mi, vd));
        _mm256_storeu_ps(dst + x, s);
        vm = _mm256_max_ps(vm, s);
        if (x == n - 8)
            break;
    }
#undef L
    __m128 h = _mm_max_ps(_mm256_castps256_ps128(vm), _mm256_extractf128_ps(vm, 1));
    h = _mm_max_ps(h, _mm_movehl_ps(h, h));
    h = _mm_max_ss(h, _mm_shuffle_ps(h, h, 1));
    return _mm_cvtss_f32(h);
}

/* 3x3 box: 16 pixels a step as 16-bit lanes (nine widened loads), pmulhrsw by 3641 (the
 * reference's + 16384 >> 15), packed back in order */
static void box3_row_avx2(uint8_t *restrict dst, const uint8_t *r0, const uint8_t *r1, const uint8_t *r2, int n)
{
    const __m256i k = _mm256_set1_epi16(3641);
    const uint8_t *rows[3] = { r0, r1, r2 };
    if (n > 0)
        dst[0] = fv_et_box3_px(r0, r1, r2, n, 0);
    int x = 1;
    for (; x + 17 <= n; x += 16) { /* reads columns x - 1 .. x + 16 */
        __m256i s = _mm256_setzero_si256();
        for (int r = 0; r < 3; r++)
            for (int d = -1; d <= 1; d++)
                s = _mm256_add_epi16(s, _mm256_cvtepu8_epi16(_mm_loadu_si128((const __m128i *)(rows[r] + x + d))));
        const __m256i q = _mm256_mulhrs_epi16(s, k);
        /* packus per 128-bit lane: [q0-7 q0-7 | q8-15 q8-15] -> quarters 0 and 2 */
        const __m256i p = _mm256_permute4x64_epi64(_mm256_packus_epi16(q, q), _MM_SHUFFLE(3, 1, 2, 0));
        _mm_storeu_si128((__m128i *)(dst + x), _mm256_castsi256_si128(p));
    }
    for (; x < n; x++)
        dst[x] = fv_et_box3_px(r0, r1, r2, n, x);
}

void fv_eyetrack_dsp_init_avx2(fv_eyetrack_dsp *d)
{
    d->et_down2_row = down2_row_avx2;
    d->et_integral_row = integral_row_avx2;
    d->et_thresh_row = thresh_row_avx2;
    d->et_box_score_row = box_score_row_avx2;
    d->et_box3_row = box3_row_avx2;
}
