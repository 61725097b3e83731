/* fovea eye tracker kernels, SSE4.1 (+SSSE3). Exact: integer arithmetic, same results as the C
 * references in core/eyetrack/eyetrack_ref.c for every input. */
#include <smmintrin.h>

#include "eyetrack/eyetrack_dsp.h"

static void down2_row_sse41(uint8_t *restrict dst, const uint8_t *a, const uint8_t *b, int n)
{
    const __m128i ones = _mm_set1_epi8(1), two = _mm_set1_epi16(2);
    int x = 0;
    for (; x + 16 <= n; x += 16) {
        /* maddubs(u8, 1): the sum of each horizontal pair as 16 bits */
        const __m128i a0 = _mm_maddubs_epi16(_mm_loadu_si128((const __m128i *)(a + 2 * x)), ones);
        const __m128i a1 = _mm_maddubs_epi16(_mm_loadu_si128((const __m128i *)(a + 2 * x + 16)), ones);
        const __m128i b0 = _mm_maddubs_epi16(_mm_loadu_si128((const __m128i *)(b + 2 * x)), ones);
        const __m128i b1 = _mm_maddubs_epi16(_mm_loadu_si128((const __m128i *)(b + 2 * x + 16)), ones);
        const __m128i s0 = _mm_srli_epi16(_mm_add_epi16(_mm_add_epi16(a0, b0), two), 2);
        const __m128i s1 = _mm_srli_epi16(_mm_add_epi16(_mm_add_epi16(a1, b1), two), 2);
        _mm_storeu_si128((__m128i *)(dst + x), _mm_packus_epi16(s0, s1));
    }
    if (x < n)
        fv_et_down2_row_c(dst + x, a + 2 * x, b + 2 * x, n - x);
}

static void integral_row_sse41(uint32_t *restrict dst, const uint32_t *above, const uint8_t *src, int n)
{
    __m128i run = _mm_setzero_si128(); /* prefix so far, broadcast */
    int x = 0;
    for (; x + 8 <= n; x += 8) {
        __m128i v = _mm_cvtepu8_epi16(_mm_loadl_epi64((const __m128i *)(src + x)));
        /* inclusive prefix sum of 8 x 16 bits (at most 8 * 255) */
        v = _mm_add_epi16(v, _mm_slli_si128(v, 2));
        v = _mm_add_epi16(v, _mm_slli_si128(v, 4));
        v = _mm_add_epi16(v, _mm_slli_si128(v, 8));
        const __m128i lo = _mm_add_epi32(_mm_cvtepu16_epi32(v), run);
        const __m128i hi = _mm_add_epi32(_mm_cvtepu16_epi32(_mm_srli_si128(v, 8)), run);
        run = _mm_shuffle_epi32(hi, 0xff);
        _mm_storeu_si128((__m128i *)(dst + x), _mm_add_epi32(lo, _mm_loadu_si128((const __m128i *)(above + x))));
        _mm_storeu_si128((__m128i *)(dst + x + 4), _mm_add_epi32(hi, _mm_loadu_si128((const __m128i *)(above + x + 4))));
    }
    uint32_t r = (uint32_t)_mm_cvtsi128_si32(run);
    for (; x < n; x++) {
        r += src[x];
        dst[x] = above[x] + r;
    }
}

static int thresh_row_sse41(uint8_t *restrict dst, const uint8_t *src, int n, int t)
{
    if (t > 255 || t <= 0) /* nothing / everything passes: no 8-bit compare for these */
        return fv_et_thresh_row_c(dst, src, n, t);
    const __m128i tv = _mm_set1_epi8((char)t);
    int x = 0, count = 0;
    for (; x + 16 <= n; x += 16) {
        const __m128i s = _mm_loadu_si128((const __m128i *)(src + x));
        const __m128i m = _mm_cmpeq_epi8(_mm_max_epu8(s, tv), s); /* s >= t, unsigned */
        _mm_storeu_si128((__m128i *)(dst + x), m);
        count += __builtin_popcount((unsigned)_mm_movemask_epi8(m));
    }
    if (x < n)
        count += fv_et_thresh_row_c(dst + x, src + x, n - x, t);
    return count;
}

/* The box sums are below 2^31, so the signed conversion is the C reference's unsigned one. */
static float box_score_row_sse41(float *restrict dst, const uint32_t *it, const uint32_t *ib, int din,
                                 const uint32_t *ot, const uint32_t *ob, int dout, int n, float inv_a, float inv_r,
                                 float dark)
{
#define L(p) _mm_loadu_si128((const __m128i *)(p))
    const __m128 va = _mm_set1_ps(inv_a), vr = _mm_set1_ps(inv_r), vd = _mm_set1_ps(dark);
    __m128 vm = _mm_set1_ps(-__builtin_inff());
    if (n < 4)
        return fv_et_box_score_row_c(dst, it, ib, din, ot, ob, dout, n, inv_a, inv_r, dark);
    /* the last block overlaps the one before it: it stores the same values again, and the
     * maximum does not mind */
    for (int x = 0;; x += 4) {
        if (x > n - 4)
            x = n - 4;
        const __m128i si = _mm_add_epi32(_mm_sub_epi32(L(ib + x + din), L(it + x + din)), _mm_sub_epi32(L(it + x), L(ib + x)));
        const __m128i so = _mm_sub_epi32(
            _mm_add_epi32(_mm_sub_epi32(L(ob + x + dout), L(ot + x + dout)), _mm_sub_epi32(L(ot + x), L(ob + x))), si);
        const __m128 mi = _mm_mul_ps(_mm_cvtepi32_ps(si), va), mo = _mm_mul_ps(_mm_cvtepi32_ps(so), vr);
        const __m128 s = _mm_sub_ps(_mm_sub_ps(mo, mi), _mm_sub_ps(mi, vd));
        _mm_storeu_ps(dst + x, s);
        vm = _mm_max_ps(vm, s);
        if (x == n - 4)
            break;
    }
#undef L
    vm = _mm_max_ps(vm, _mm_movehl_ps(vm, vm));
    vm = _mm_max_ss(vm, _mm_shuffle_ps(vm, vm, 1));
    return _mm_cvtss_f32(vm);
}

/* 3x3 box: nine widened loads per 16 pixels (columns x - 1, x, x + 1 of three rows), the sum
 * (at most 2295) times 3641 by pmulhrsw, which rounds exactly as the reference's + 16384 >> 15 */
static void box3_row_sse41(uint8_t *restrict dst, const uint8_t *r0, const uint8_t *r1, const uint8_t *r2, int n)
{
    const __m128i k = _mm_set1_epi16(3641), z = _mm_setzero_si128();
    const uint8_t *rows[3] = { r0, r1, r2 };
    if (n > 0)
        dst[0] = fv_et_box3_px(r0, r1, r2, n, 0);
    int x = 1;
    for (; x + 17 <= n; x += 16) { /* reads columns x - 1 .. x + 16 */
        __m128i lo = z, hi = z;
        for (int r = 0; r < 3; r++)
            for (int d = -1; d <= 1; d++) {
                const __m128i v = _mm_loadu_si128((const __m128i *)(rows[r] + x + d));
                lo = _mm_add_epi16(lo, _mm_unpacklo_epi8(v, z));
                hi = _mm_add_epi16(hi, _mm_unpackhi_epi8(v, z));
            }
        _mm_storeu_si128((__m128i *)(dst + x), _mm_packus_epi16(_mm_mulhrs_epi16(lo, k), _mm_mulhrs_epi16(hi, k)));
    }
    for (; x < n; x++)
        dst[x] = fv_et_box3_px(r0, r1, r2, n, x);
}

void fv_eyetrack_dsp_init_sse41(fv_eyetrack_dsp *d)
{
    d->et_down2_row = down2_row_sse41;
    d->et_integral_row = integral_row_sse41;
    d->et_thresh_row = thresh_row_sse41;
    d->et_box_score_row = box_score_row_sse41;
    d->et_box3_row = box3_row_sse41;
}
