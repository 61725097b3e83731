/* fovea: temporal reprojection kernels, SSE4.1: one texel = one __m128 (r, g, b, depth). The
 * row loops and all scalar arithmetic are shared (core/reproject_tmpl.h); the accumulation
 * below does the reference's operations in the same order, so results are bit-identical. */
#include <smmintrin.h>

#include <stdint.h>

#include "reproject_dsp.h"
#include "reproject.h"
#define FV_X86_W 4
#define FV_X86_FN(name) name##_sse41
#include "x86/reproject_tmpl.h"

static inline void tap(const fv_pyr_level *L, float s, float t, float zexp, float inv_tol, acc4 *acc, float *accw)
{
    const tap_pos p = tap_at(L, s, t);
    const __m128 c00 = _mm_loadu_ps(L->rgbd + 4 * p.o00), c10 = _mm_loadu_ps(L->rgbd + 4 * p.o00 + 4);
    const __m128 c01 = _mm_loadu_ps(L->rgbd + 4 * p.o01), c11 = _mm_loadu_ps(L->rgbd + 4 * p.o01 + 4);
    /* depths in texel order 00, 01, 10, 11 */
    const __m128 d = _mm_movehl_ps(_mm_unpackhi_ps(c10, c11), _mm_unpackhi_ps(c00, c01));
    const __m128 wt = tap_weights(L, &p, d, zexp, inv_tol);
    const __m128 m00 = _mm_mul_ps(_mm_shuffle_ps(wt, wt, 0x00), c00);
    const __m128 m01 = _mm_mul_ps(_mm_shuffle_ps(wt, wt, 0x55), c01);
    const __m128 m10 = _mm_mul_ps(_mm_shuffle_ps(wt, wt, 0xaa), c10);
    const __m128 m11 = _mm_mul_ps(_mm_shuffle_ps(wt, wt, 0xff), c11);
    *acc = _mm_add_ps(*acc, _mm_add_ps(_mm_add_ps(m00, m01), _mm_add_ps(m10, m11)));
    *accw = *accw + tap_weight_sum(wt);
}

static inline uint64_t sample_mask(const float *wgt, int n)
{
    uint64_t m = 0;
    int i = 0;
    for (; i + 4 <= n; i += 4)
        m |= (uint64_t)_mm_movemask_ps(_mm_cmpeq_ps(_mm_loadu_ps(wgt + i), _mm_set1_ps(1.0f))) << i;
    for (; i < n; i++)
        m |= (uint64_t)(wgt[i] == 1.0f) << i;
    return m;
}

#define TAA_FN FV_X86_FN
#include "../reproject_tmpl.h" /* the row loops every ISA shares */

/* The fill, four pixels at a time: each lane does the reference's operations (taa_fill_px). */
static inline int fill_vec_sse41(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, float *wgt,
                              const float *hrow, const float *hw, const float B[3], int x0, float py, int ilo, int ihi)
{
    const int sx0 = x0 + t->flow_x;
    const __m128 zero = _mm_setzero_ps(), half = _mm_set1_ps(0.5f), mhalf = _mm_set1_ps(-0.5f);
    const __m128i lane = _mm_setr_epi32(0, 1, 2, 3);
    int i = ilo;
    for (; i + 4 <= ihi; i += 4) {
        const __m128 w = _mm_loadu_ps(wgt + i);
        const int sx = sx0 + i;
        const __m128 ws = _mm_loadu_ps(hw + sx);
        __m128 m = _mm_and_ps(_mm_cmpeq_ps(w, zero), _mm_cmpgt_ps(ws, zero));
        if (!_mm_movemask_ps(m))
            continue;
        const float *src = hrow + 4 * sx;
        __m128 r = _mm_loadu_ps(src), g = _mm_loadu_ps(src + 4), b = _mm_loadu_ps(src + 8), z = _mm_loadu_ps(src + 12);
        _MM_TRANSPOSE4_PS(r, g, b, z); /* now r, g, b, D of the four texels */
        if (!f->identity) {
            const __m128 D = z;
            const __m128 uc = _mm_add_ps(_mm_cvtepi32_ps(_mm_add_epi32(_mm_set1_epi32(sx), lane)), half);
            const __m128 pxc = _mm_add_ps(_mm_cvtepi32_ps(_mm_add_epi32(_mm_set1_epi32(x0 + i), lane)), half);
            const __m128 U = _mm_add_ps(_mm_set1_ps(f->T2[0]),
                                        _mm_mul_ps(D, _mm_add_ps(_mm_set1_ps(B[0]), _mm_mul_ps(uc, _mm_set1_ps(f->NX[0])))));
            const __m128 V = _mm_add_ps(_mm_set1_ps(f->T2[1]),
                                        _mm_mul_ps(D, _mm_add_ps(_mm_set1_ps(B[1]), _mm_mul_ps(uc, _mm_set1_ps(f->NX[1])))));
            z = _mm_add_ps(_mm_set1_ps(f->T2[2]),
                           _mm_mul_ps(D, _mm_add_ps(_mm_set1_ps(B[2]), _mm_mul_ps(uc, _mm_set1_ps(f->NX[2])))));
            const __m128 rz = _mm_div_ps(_mm_set1_ps(1.0f), z);
            const __m128 ex = _mm_sub_ps(_mm_mul_ps(U, rz), pxc), ey = _mm_sub_ps(_mm_mul_ps(V, rz), _mm_set1_ps(py));
            const __m128 ok = _mm_and_ps(_mm_and_ps(_mm_cmple_ps(ex, half), _mm_cmpge_ps(ex, mhalf)),
                                         _mm_and_ps(_mm_cmple_ps(ey, half), _mm_cmpge_ps(ey, mhalf)));
            m = _mm_and_ps(m, _mm_and_ps(_mm_cmpgt_ps(z, _mm_set1_ps(1e-4f)), ok));
            if (!_mm_movemask_ps(m))
                continue;
        }
        _MM_TRANSPOSE4_PS(r, g, b, z); /* back to four pixels (r, g, b, depth) */
        float *o = rgbd + 4 * i;
#define PUT(k, v) _mm_storeu_ps(o + 4 * k, _mm_blendv_ps(_mm_loadu_ps(o + 4 * k), v, _mm_shuffle_ps(m, m, k * 0x55)))
        PUT(0, r);
        PUT(1, g);
        PUT(2, b);
        PUT(3, z);
#undef PUT
        _mm_storeu_ps(wgt + i, _mm_blendv_ps(w, ws, m));
    }
    return i;
}

TAA_FILL_BLOCK(taa_fill_sse41, fill_vec_sse41)

void fv_reproject_dsp_init_sse41(fv_reproject_dsp *d)
{
    d->taa_blend = taa_blend_sse41;
    d->taa_fill = taa_fill_sse41;
}
