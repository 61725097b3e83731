/* fovea: pull-push kernels, AVX2 (two pixels = one __m256). Bit-identical to the C references
 * in core/pullpush.c: same operations in the same order, true division, no FMA (the file is
 * built with -mfma but -ffp-contract=off, and only separate mul/add intrinsics are used). */
#include <immintrin.h>

#include "pullpush_dsp.h"
#include "x86/pull_tail.h"

static inline __m256i pair_idx(int k) /* lanes 0-3 <- element 2k, lanes 4-7 <- element 2k+1 */
{
    return _mm256_setr_epi32(2 * k, 2 * k, 2 * k, 2 * k, 2 * k + 1, 2 * k + 1, 2 * k + 1, 2 * k + 1);
}

/* w > 0 ? w * c : +0 for two pixels, w = the weights' pair selected by idx */
static inline __m256 term(__m256 w8, __m256i idx, const float *c)
{
    const __m256 w = _mm256_permutevar8x32_ps(w8, idx);
    return _mm256_and_ps(_mm256_mul_ps(w, _mm256_loadu_ps(c)), _mm256_cmp_ps(w, _mm256_setzero_ps(), _CMP_GT_OQ));
}

/* Per-column vertical sum p(wa, a) + p(wb, b) of two children pixels per row (a, b: 2 pixels). */
static inline __m256 vsum(const float *a, const float *b, __m256 wa, __m256 wb, __m256i idx)
{
    return _mm256_add_ps(term(wa, idx, a), term(wb, idx, b));
}

static inline __m256 divmask(__m256 t, __m256 sw)
{
    return _mm256_and_ps(_mm256_div_ps(t, sw), _mm256_cmp_ps(sw, _mm256_setzero_ps(), _CMP_GT_OQ));
}

static void pull_row_avx2(float *restrict dst_rgbd, float *restrict dst_wgt, const float *src0_rgbd,
                          const float *src0_wgt, const float *src1_rgbd, const float *src1_wgt, int n)
{
    const __m256i i0 = pair_idx(0), i1 = pair_idx(1), i2 = pair_idx(2), i3 = pair_idx(3);
    const __m128 one = _mm_set1_ps(1.0f);
    int x = 0;
    for (; x + 4 <= n; x += 4) { /* 4 coarse pixels from 8 fine pixels of each row */
        const float *a = src0_rgbd + 8 * x, *b = src1_rgbd + 8 * x;
        const __m256 wa = _mm256_loadu_ps(src0_wgt + 2 * x), wb = _mm256_loadu_ps(src1_wgt + 2 * x);
        /* sw = (wa0 + wb0) + (wa1 + wb1): lanes 0,1 = coarse 0,1; lanes 4,5 = coarse 2,3 */
        const __m256 cs = _mm256_add_ps(wa, wb);
        const __m256 h = _mm256_hadd_ps(cs, cs);
        const __m128 sw4 = _mm256_castps256_ps128(
            _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(h), _MM_SHUFFLE(3, 1, 2, 0))));
        _mm_storeu_ps(dst_wgt + x, _mm_min_ps(sw4, one));
        const __m256 t0 = vsum(a, b, wa, wb, i0);           /* columns 0, 1 */
        const __m256 t1 = vsum(a + 8, b + 8, wa, wb, i1);   /* columns 2, 3 */
        const __m256 t2 = vsum(a + 16, b + 16, wa, wb, i2); /* columns 4, 5 */
        const __m256 t3 = vsum(a + 24, b + 24, wa, wb, i3); /* columns 6, 7 */
        /* left column + right column: coarse pixels (0, 1) and (2, 3) */
        const __m256 s01 = _mm256_add_ps(_mm256_permute2f128_ps(t0, t1, 0x20), _mm256_permute2f128_ps(t0, t1, 0x31));
        const __m256 s23 = _mm256_add_ps(_mm256_permute2f128_ps(t2, t3, 0x20), _mm256_permute2f128_ps(t2, t3, 0x31));
        const __m256 sw01 = _mm256_permutevar8x32_ps(h, _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1));
        const __m256 sw23 = _mm256_permutevar8x32_ps(h, _mm256_setr_epi32(4, 4, 4, 4, 5, 5, 5, 5));
        _mm256_storeu_ps(dst_rgbd + 4 * x, divmask(s01, sw01));
        _mm256_storeu_ps(dst_rgbd + 4 * x + 8, divmask(s23, sw23));
    }
    pull_tail_sse(dst_rgbd, dst_wgt, src0_rgbd, src0_wgt, src1_rgbd, src1_wgt, x, n);
}

/* v = near + 1/4 (far - near) for two coarse pixels */
static inline __m256 vlerp(const float *nr, const float *fr, __m256 q)
{
    const __m256 a = _mm256_loadu_ps(nr);
    return _mm256_add_ps(a, _mm256_mul_ps(q, _mm256_sub_ps(_mm256_loadu_ps(fr), a)));
}

/* Two fine pixels: interp = p + 1/4 (nb - p); c = pos ? fine : 0; where lt1: fine = c + om (interp - c) */
static inline void push2(float *o, __m256 p, __m256 nb, __m256 w8, __m256i idx, __m256 q)
{
    const __m256 one = _mm256_set1_ps(1.0f);
    const __m256 w = _mm256_permutevar8x32_ps(w8, idx);
    const __m256 om = _mm256_sub_ps(one, w);
    const __m256 pos = _mm256_cmp_ps(w, _mm256_setzero_ps(), _CMP_GT_OQ);
    const __m256 lt1 = _mm256_cmp_ps(w, one, _CMP_LT_OQ);
    const __m256 ip = _mm256_add_ps(p, _mm256_mul_ps(q, _mm256_sub_ps(nb, p)));
    const __m256 c = _mm256_and_ps(_mm256_loadu_ps(o), pos);
    _mm256_maskstore_ps(o, _mm256_castps_si256(lt1), _mm256_add_ps(c, _mm256_mul_ps(om, _mm256_sub_ps(ip, c))));
}

/* Same for a group whose weights are all 0 or 1 (level 0 of a ray-traced frame): w = 0 gives
 * +0 + 1 * (interp - +0) = +0 + interp, w = 1 keeps the pixel; no need to read the colour. */
static inline void push2_binary(float *o, __m256 p, __m256 nb, __m256 lt8, __m256i idx, __m256 q)
{
    const __m256 ip = _mm256_add_ps(p, _mm256_mul_ps(q, _mm256_sub_ps(nb, p)));
    _mm256_maskstore_ps(o, _mm256_castps_si256(_mm256_permutevar8x32_ps(lt8, idx)),
                        _mm256_add_ps(_mm256_setzero_ps(), ip));
}

static void push_row_avx2(float *restrict fine_rgbd, const float *fine_wgt, const float *coarse_near,
                          const float *coarse_far, int n)
{
    const __m256 q = _mm256_set1_ps(0.25f), one = _mm256_set1_ps(1.0f);
    const __m256i i0 = pair_idx(0), i1 = pair_idx(1), i2 = pair_idx(2), i3 = pair_idx(3);
    int x = 0;
    for (; x + 8 <= n; x += 8) { /* fine x .. x+7 under coarse X .. X+3; reads coarse X-1 .. X+4 <= n/2 */
        const __m256 w8 = _mm256_loadu_ps(fine_wgt + x);
        const __m256 lt8 = _mm256_cmp_ps(w8, one, _CMP_LT_OQ);
        if (!_mm256_movemask_ps(lt8))
            continue; /* all eight kept as they are (dense fovea): no colour traffic at all */
        const int X = x >> 1;
        const __m256 va = vlerp(coarse_near + 4 * (X - 1), coarse_far + 4 * (X - 1), q); /* v(X-1), v(X)   */
        const __m256 vb = vlerp(coarse_near + 4 * (X + 1), coarse_far + 4 * (X + 1), q); /* v(X+1), v(X+2) */
        const __m256 vc = vlerp(coarse_near + 4 * (X + 3), coarse_far + 4 * (X + 3), q); /* v(X+3), v(X+4) */
        /* fine 2X: v(X) toward v(X-1); 2X+1: v(X) toward v(X+1); ... */
        const __m256 p0 = _mm256_permute2f128_ps(va, va, 0x11), n0 = _mm256_permute2f128_ps(va, vb, 0x20);
        const __m256 p1 = _mm256_permute2f128_ps(vb, vb, 0x00), n1 = _mm256_permute2f128_ps(va, vb, 0x31);
        const __m256 p2 = _mm256_permute2f128_ps(vb, vb, 0x11), n2 = _mm256_permute2f128_ps(vb, vc, 0x20);
        const __m256 p3 = _mm256_permute2f128_ps(vc, vc, 0x00), n3 = _mm256_permute2f128_ps(vb, vc, 0x31);
        float *o = fine_rgbd + 4 * x;
        const __m256 binary = _mm256_or_ps(_mm256_cmp_ps(w8, _mm256_setzero_ps(), _CMP_EQ_OQ),
                                           _mm256_cmp_ps(w8, one, _CMP_EQ_OQ));
        if (_mm256_movemask_ps(binary) == 0xff) {
            push2_binary(o, p0, n0, lt8, i0, q);
            push2_binary(o + 8, p1, n1, lt8, i1, q);
            push2_binary(o + 16, p2, n2, lt8, i2, q);
            push2_binary(o + 24, p3, n3, lt8, i3, q);
        } else {
            push2(o, p0, n0, w8, i0, q);
            push2(o + 8, p1, n1, w8, i1, q);
            push2(o + 16, p2, n2, w8, i2, q);
            push2(o + 24, p3, n3, w8, i3, q);
        }
    }
    if (x < n) /* x is even: the tail starts on a coarse pixel boundary */
        fv_push_row_c(fine_rgbd + 4 * x, fine_wgt + x, coarse_near + 2 * x, coarse_far + 2 * x, n - x);
}

void fv_pullpush_dsp_init_avx2(fv_pullpush_dsp *d)
{
    d->pull_row = pull_row_avx2;
    d->push_row = push_row_avx2;
}
