/* fovea: pull-push kernels, SSE4.1 (one pixel = one __m128). Bit-identical to the C
 * references in core/pullpush.c: same operations in the same order, true division. */
#include <smmintrin.h>

#include "pullpush_dsp.h"
#include "x86/pull_tail.h"

#define BCAST(v, i) _mm_shuffle_ps((v), (v), _MM_SHUFFLE((i), (i), (i), (i)))

/* w > 0 ? w * c : +0 (w broadcast) */
static inline __m128 term(__m128 w, const float *c)
{
    return _mm_and_ps(_mm_mul_ps(w, _mm_loadu_ps(c)), _mm_cmpgt_ps(w, _mm_setzero_ps()));
}

/* Coarse pixel from its four children; wa0.. are the children's weights broadcast. */
static inline __m128 pull_px(const float *a, const float *b, __m128 wa0, __m128 wa1, __m128 wb0, __m128 wb1,
                             __m128 sw)
{
    const __m128 l = _mm_add_ps(term(wa0, a), term(wb0, b));
    const __m128 r = _mm_add_ps(term(wa1, a + 4), term(wb1, b + 4));
    const __m128 q = _mm_div_ps(_mm_add_ps(l, r), sw);
    return _mm_and_ps(q, _mm_cmpgt_ps(sw, _mm_setzero_ps()));
}

static void pull_row_sse41(float *restrict dst_rgbd, float *restrict dst_wgt, const float *src0_rgbd,
                           const float *src0_wgt, const float *src1_rgbd, const float *src1_wgt, int n)
{
    const __m128 one = _mm_set1_ps(1.0f);
    int x = 0;
    for (; x + 4 <= n; x += 4) {
        const float *a = src0_rgbd + 8 * x, *b = src1_rgbd + 8 * x;
        const __m128 wal = _mm_loadu_ps(src0_wgt + 2 * x), wah = _mm_loadu_ps(src0_wgt + 2 * x + 4);
        const __m128 wbl = _mm_loadu_ps(src1_wgt + 2 * x), wbh = _mm_loadu_ps(src1_wgt + 2 * x + 4);
        /* (wa0 + wb0) + (wa1 + wb1) for the 4 coarse pixels */
        const __m128 sw = _mm_hadd_ps(_mm_add_ps(wal, wbl), _mm_add_ps(wah, wbh));
        _mm_storeu_ps(dst_wgt + x, _mm_min_ps(sw, one));
        float *o = dst_rgbd + 4 * x;
        _mm_storeu_ps(o, pull_px(a, b, BCAST(wal, 0), BCAST(wal, 1), BCAST(wbl, 0), BCAST(wbl, 1), BCAST(sw, 0)));
        _mm_storeu_ps(o + 4, pull_px(a + 8, b + 8, BCAST(wal, 2), BCAST(wal, 3), BCAST(wbl, 2), BCAST(wbl, 3),
                                     BCAST(sw, 1)));
        _mm_storeu_ps(o + 8, pull_px(a + 16, b + 16, BCAST(wah, 0), BCAST(wah, 1), BCAST(wbh, 0), BCAST(wbh, 1),
                                     BCAST(sw, 2)));
        _mm_storeu_ps(o + 12, pull_px(a + 24, b + 24, BCAST(wah, 2), BCAST(wah, 3), BCAST(wbh, 2),
                                      BCAST(wbh, 3), BCAST(sw, 3)));
    }
    pull_tail_sse(dst_rgbd, dst_wgt, src0_rgbd, src0_wgt, src1_rgbd, src1_wgt, x, n);
}

/* v = near + 1/4 (far - near) */
static inline __m128 vlerp(const float *nr, const float *fr, __m128 q)
{
    const __m128 a = _mm_loadu_ps(nr);
    return _mm_add_ps(a, _mm_mul_ps(q, _mm_sub_ps(_mm_loadu_ps(fr), a)));
}

/* c = pos ? fine : 0; fine = lt1 ? c + om * (interp - c) : fine; interp = v + 1/4 (vn - v) */
static inline void push_px(float *o, __m128 v, __m128 vn, __m128 om, __m128 pos, __m128 lt1, __m128 q)
{
    const __m128 ip = _mm_add_ps(v, _mm_mul_ps(q, _mm_sub_ps(vn, v)));
    const __m128 f = _mm_loadu_ps(o);
    const __m128 c = _mm_and_ps(f, pos);
    _mm_storeu_ps(o, _mm_blendv_ps(f, _mm_add_ps(c, _mm_mul_ps(om, _mm_sub_ps(ip, c))), lt1));
}

static void push_row_sse41(float *restrict fine_rgbd, const float *fine_wgt, const float *coarse_near,
                           const float *coarse_far, int n)
{
    const __m128 q = _mm_set1_ps(0.25f), one = _mm_set1_ps(1.0f);
    __m128 vp = q, v0 = q; /* v(X - 1), v(X) when `have` */
    int x = 0, have = 0;
    for (; x + 4 <= n; x += 4) {
        const int X = x >> 1; /* reads coarse X - 1 .. X + 2 <= n / 2 */
        const __m128 w = _mm_loadu_ps(fine_wgt + x);
        const __m128 lt1 = _mm_cmplt_ps(w, one);
        if (!_mm_movemask_ps(lt1)) { /* all four kept as they are */
            have = 0;
            continue;
        }
        if (!have) {
            vp = vlerp(coarse_near + 4 * (X - 1), coarse_far + 4 * (X - 1), q);
            v0 = vlerp(coarse_near + 4 * X, coarse_far + 4 * X, q);
        }
        const __m128 v1 = vlerp(coarse_near + 4 * (X + 1), coarse_far + 4 * (X + 1), q);
        const __m128 v2 = vlerp(coarse_near + 4 * (X + 2), coarse_far + 4 * (X + 2), q);
        const __m128 om = _mm_sub_ps(one, w), pos = _mm_cmpgt_ps(w, _mm_setzero_ps());
        float *o = fine_rgbd + 4 * x;
        push_px(o, v0, vp, BCAST(om, 0), BCAST(pos, 0), BCAST(lt1, 0), q);
        push_px(o + 4, v0, v1, BCAST(om, 1), BCAST(pos, 1), BCAST(lt1, 1), q);
        push_px(o + 8, v1, v0, BCAST(om, 2), BCAST(pos, 2), BCAST(lt1, 2), q);
        push_px(o + 12, v1, v2, BCAST(om, 3), BCAST(pos, 3), BCAST(lt1, 3), q);
        vp = v1;
        v0 = v2;
        have = 1;
    }
    if (x < n) /* x is even: the tail starts on a coarse pixel boundary */
        fv_push_row_c(fine_rgbd + 4 * x, fine_wgt + x, coarse_near + 2 * x, coarse_far + 2 * x, n - x);
}

void fv_pullpush_dsp_init_sse41(fv_pullpush_dsp *d)
{
    d->pull_row = pull_row_sse41;
    d->push_row = push_row_sse41;
}
