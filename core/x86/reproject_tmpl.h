/* fovea: the 128-bit pieces shared by the SSE4.1 and AVX2 reprojection kernels (x86 template:
 * core/x86/reproject_sse41.c and reproject_avx2.c each include it once after defining FV_X86_W,
 * their vector width in floats, and FV_X86_FN(name); each is built with its own ISA flags).
 * Operation order as the reference's tap (core/reproject_ref.c, core/reproject_tmpl.h). */
#if !defined(FV_X86_W) || !defined(FV_X86_FN)
#error "define FV_X86_W and FV_X86_FN before including x86/reproject_tmpl.h"
#endif

#include <smmintrin.h>
#include <stddef.h>

#include "pullpush.h"

typedef __m128 acc4;

static inline acc4 acc_zero(void) { return _mm_setzero_ps(); }

/* A bilinear tap at level coordinates (s, t): the offsets of texels 00 and 01 (10 and 11 follow
 * each) and the bilinear weights in texel order 00, 01, 10, 11. */
typedef struct {
    ptrdiff_t o00, o01;
    __m128 b;
} tap_pos;

static inline tap_pos tap_at(const fv_pyr_level *L, float s, float t)
{
    const __m128 st = _mm_floor_ps(_mm_setr_ps(s, t, 0.0f, 0.0f));
    const float fs = _mm_cvtss_f32(st), ft = _mm_cvtss_f32(_mm_shuffle_ps(st, st, 1));
    const int i = (int)fs, j = (int)ft;
    const float fx = s - fs, fy = t - ft, omx = 1.0f - fx, omy = 1.0f - fy;
    tap_pos p;
    p.o00 = (ptrdiff_t)j * L->stride + i;
    p.o01 = p.o00 + L->stride;
    p.b = _mm_mul_ps(_mm_setr_ps(omx, omx, fx, fx), _mm_setr_ps(omy, fy, omy, fy));
    return p;
}

/* wt = (b * confidence) * max(0, 1 - |d - zexp| * inv_tol), d the texels' depths (order 00, 01,
 * 10, 11). */
static inline __m128 tap_weights(const fv_pyr_level *L, const tap_pos *p, __m128 d, float zexp, float inv_tol)
{
    const __m128 w = _mm_setr_ps(L->wgt[p->o00], L->wgt[p->o01], L->wgt[p->o00 + 1], L->wgt[p->o01 + 1]);
    const __m128 absmask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 a = _mm_max_ps(_mm_sub_ps(_mm_set1_ps(1.0f),
                                           _mm_mul_ps(_mm_and_ps(_mm_sub_ps(d, _mm_set1_ps(zexp)), absmask),
                                                      _mm_set1_ps(inv_tol))),
                                _mm_setzero_ps());
    return _mm_mul_ps(_mm_mul_ps(p->b, w), a);
}

/* (wt00 + wt01) + (wt10 + wt11) */
static inline float tap_weight_sum(__m128 wt)
{
    const __m128 h = _mm_add_ps(wt, _mm_shuffle_ps(wt, wt, _MM_SHUFFLE(2, 3, 0, 1))); /* lanes 0, 2: the pairs */
    return _mm_cvtss_f32(_mm_add_ss(h, _mm_movehl_ps(h, h)));
}

static inline void out_blend(float *px, acc4 acc, float accw, float alpha)
{
    const __m128 p = _mm_loadu_ps(px);
    const __m128 h = _mm_div_ps(acc, _mm_set1_ps(accw));
    const __m128 r = _mm_add_ps(h, _mm_mul_ps(_mm_set1_ps(alpha), _mm_sub_ps(p, h)));
    _mm_storeu_ps(px, _mm_blend_ps(r, p, 8)); /* depth stays the sample's */
}
