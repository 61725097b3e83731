/* fovea: temporal reprojection kernels, AVX2. The blend goes sample by sample (the shared loop
 * of core/reproject_tmpl.h) with each bilinear tap's two texel rows as one 256-bit load each;
 * the fill takes eight pixels at a time. Same operations in the same order as the reference
 * (built with -mfma but -ffp-contract=off, no FMA intrinsics): bit-identical.
 * (Blending eight samples at a time, with AVX2 gathers or with 128-bit loads and transposes,
 * measured 3.5x and 1.8x slower than this on the project's AMD EPYC machines: the taps of
 * neighbouring samples are scattered, and the per-sample chain overlaps well out of order.) */
#include <immintrin.h>

#include <stdint.h>

#include "reproject_dsp.h"
#include "reproject.h"
#define FV_X86_W 8
#define FV_X86_FN(name) name##_avx2
#include "x86/reproject_tmpl.h"

static inline void tap(const fv_pyr_level *L, float s, float t, float zexp, float inv_tol, acc4 *acc, float *accw)
{
    const tap_pos p = tap_at(L, s, t);
    const __m256 top = _mm256_loadu_ps(L->rgbd + 4 * p.o00); /* c00 | c10 */
    const __m256 bot = _mm256_loadu_ps(L->rgbd + 4 * p.o01); /* c01 | c11 */
    /* depths in texel order 00, 01, 10, 11 */
    const __m256 zw = _mm256_unpackhi_ps(top, bot); /* (c00.b, c01.b, c00.d, c01.d | c10.b, c11.b, c10.d, c11.d) */
    const __m128 d = _mm_movehl_ps(_mm256_extractf128_ps(zw, 1), _mm256_castps256_ps128(zw));
    const __m128 wt = tap_weights(L, &p, d, zexp, inv_tol);
    /* (w00 | w10) for the top row, (w01 | w11) for the bottom row, each broadcast over 4 lanes */
    const __m256 wt8 = _mm256_castps128_ps256(wt);
    const __m256 wtop = _mm256_permutevar8x32_ps(wt8, _mm256_setr_epi32(0, 0, 0, 0, 2, 2, 2, 2));
    const __m256 wbot = _mm256_permutevar8x32_ps(wt8, _mm256_setr_epi32(1, 1, 1, 1, 3, 3, 3, 3));
    const __m256 s8 = _mm256_add_ps(_mm256_mul_ps(wtop, top), _mm256_mul_ps(wbot, bot)); /* 00+01 | 10+11 */
    *acc = _mm_add_ps(*acc, _mm_add_ps(_mm256_castps256_ps128(s8), _mm256_extractf128_ps(s8, 1)));
    *accw = *accw + tap_weight_sum(wt);
}

static inline uint64_t sample_mask(const float *wgt, int n)
{
    uint64_t m = 0;
    int i = 0;
    for (; i + 8 <= n; i += 8)
        m |= (uint64_t)_mm256_movemask_ps(_mm256_cmp_ps(_mm256_loadu_ps(wgt + i), _mm256_set1_ps(1.0f), _CMP_EQ_OQ)) << i;
    for (; i < n; i++)
        m |= (uint64_t)(wgt[i] == 1.0f) << i;
    return m;
}

#define TAA_FN FV_X86_FN
#include "../reproject_tmpl.h" /* the row loops every ISA shares */

static inline __m256 pair(__m128 lo, __m128 hi) { return _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1); }

/* The fill, eight pixels at a time: each lane does the reference's operations (taa_fill_px). */
static inline int fill_vec_avx2(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, float *wgt,
                              const float *hrow, const float *hw, const float B[3], int x0, float py, int ilo, int ihi)
{
    const int sx0 = x0 + t->flow_x;
    const __m256 zero = _mm256_setzero_ps(), half = _mm256_set1_ps(0.5f), mhalf = _mm256_set1_ps(-0.5f);
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    int i = ilo;
    for (; i + 8 <= ihi; i += 8) {
        const __m256 w = _mm256_loadu_ps(wgt + i);
        const int sx = sx0 + i;
        const __m256 ws = _mm256_loadu_ps(hw + sx);
        __m256 m = _mm256_and_ps(_mm256_cmp_ps(w, zero, _CMP_EQ_OQ), _mm256_cmp_ps(ws, zero, _CMP_GT_OQ));
        if (!_mm256_movemask_ps(m))
            continue;
        const float *src = hrow + 4 * sx;
        __m128 r0 = _mm_loadu_ps(src), g0 = _mm_loadu_ps(src + 4), b0 = _mm_loadu_ps(src + 8), z0 = _mm_loadu_ps(src + 12);
        __m128 r1 = _mm_loadu_ps(src + 16), g1 = _mm_loadu_ps(src + 20), b1 = _mm_loadu_ps(src + 24),
               z1 = _mm_loadu_ps(src + 28);
        _MM_TRANSPOSE4_PS(r0, g0, b0, z0);
        _MM_TRANSPOSE4_PS(r1, g1, b1, z1);
        __m256 z = pair(z0, z1);
        if (!f->identity) {
            const __m256 D = z;
            const __m256 uc = _mm256_add_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(sx), lane)), half);
            const __m256 pxc = _mm256_add_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(x0 + i), lane)), half);
            __m256 c[3];
            for (int k = 0; k < 3; k++)
                c[k] = _mm256_add_ps(_mm256_set1_ps(f->T2[k]),
                                     _mm256_mul_ps(D, _mm256_add_ps(_mm256_set1_ps(B[k]),
                                                                    _mm256_mul_ps(uc, _mm256_set1_ps(f->NX[k])))));
            z = c[2];
            const __m256 rz = _mm256_div_ps(_mm256_set1_ps(1.0f), z);
            const __m256 ex = _mm256_sub_ps(_mm256_mul_ps(c[0], rz), pxc);
            const __m256 ey = _mm256_sub_ps(_mm256_mul_ps(c[1], rz), _mm256_set1_ps(py));
            const __m256 ok = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(ex, half, _CMP_LE_OQ), _mm256_cmp_ps(ex, mhalf, _CMP_GE_OQ)),
                                            _mm256_and_ps(_mm256_cmp_ps(ey, half, _CMP_LE_OQ), _mm256_cmp_ps(ey, mhalf, _CMP_GE_OQ)));
            m = _mm256_and_ps(m, _mm256_and_ps(_mm256_cmp_ps(z, _mm256_set1_ps(1e-4f), _CMP_GT_OQ), ok));
            if (!_mm256_movemask_ps(m))
                continue;
            z0 = _mm256_castps256_ps128(z);
            z1 = _mm256_extractf128_ps(z, 1);
        }
        _MM_TRANSPOSE4_PS(r0, g0, b0, z0); /* back to pixels (r, g, b, depth) */
        _MM_TRANSPOSE4_PS(r1, g1, b1, z1);
        float *o = rgbd + 4 * i;
        const __m256 p[4] = {pair(r0, g0), pair(b0, z0), pair(r1, g1), pair(b1, z1)}; /* pixels 0|1, 2|3, ... */
        for (int k = 0; k < 4; k++) {
            const __m256 mk = _mm256_permutevar8x32_ps(
                m, _mm256_setr_epi32(2 * k, 2 * k, 2 * k, 2 * k, 2 * k + 1, 2 * k + 1, 2 * k + 1, 2 * k + 1));
            _mm256_storeu_ps(o + 8 * k, _mm256_blendv_ps(_mm256_loadu_ps(o + 8 * k), p[k], mk));
        }
        _mm256_storeu_ps(wgt + i, _mm256_blendv_ps(w, ws, m));
    }
    return i;
}

TAA_FILL_BLOCK(taa_fill_avx2, fill_vec_avx2)

void fv_reproject_dsp_init_avx2(fv_reproject_dsp *d)
{
    d->taa_blend = taa_blend_avx2;
    d->taa_fill = taa_fill_avx2;
}
