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
#define TAA_OWN_BLEND
#include "../reproject_tmpl.h" /* the row loops every ISA shares */
#define VW 8
/* the taps' texels of eight lanes: per lane one 256-bit load per texel row (texels 00|10 and
 * 01|11), an 8x8 transpose to planes; weights as 64-bit pairs (00, 10) and (01, 11) */
#define TAA_VEC_TAP_LOAD
static inline void transpose8(__m256 r[8])
{
    __m256 t[8], u[8];
    for (int k = 0; k < 8; k += 2) {
        t[k] = _mm256_unpacklo_ps(r[k], r[k + 1]);
        t[k + 1] = _mm256_unpackhi_ps(r[k], r[k + 1]);
    }
    for (int k = 0; k < 8; k += 4) {
        u[k] = _mm256_shuffle_ps(t[k], t[k + 2], 0x44);
        u[k + 1] = _mm256_shuffle_ps(t[k], t[k + 2], 0xee);
        u[k + 2] = _mm256_shuffle_ps(t[k + 1], t[k + 3], 0x44);
        u[k + 3] = _mm256_shuffle_ps(t[k + 1], t[k + 3], 0xee);
    }
    for (int k = 0; k < 4; k++) {
        r[k] = _mm256_permute2f128_ps(u[k], u[k + 4], 0x20);
        r[k + 4] = _mm256_permute2f128_ps(u[k], u[k + 4], 0x31);
    }
}
static inline __m256 pairs4(const float *const *p) /* (p[k][0], p[k][1]) for k = 0..3 */
{
    const __m128 lo = _mm_loadh_pi(_mm_castpd_ps(_mm_load_sd((const double *)p[0])), (const __m64 *)p[1]);
    const __m128 hi = _mm_loadh_pi(_mm_castpd_ps(_mm_load_sd((const double *)p[2])), (const __m64 *)p[3]);
    return _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1);
}
static inline void deinterleave8(__m256 a, __m256 b, __m256 *even, __m256 *odd)
{
    *even = _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(_mm256_shuffle_ps(a, b, 0x88)), 0xd8));
    *odd = _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(_mm256_shuffle_ps(a, b, 0xdd)), 0xd8));
}
typedef float vf_ __attribute__((vector_size(32)));
#define TAA_VEC_PX_LOAD
static inline void vpx_load(float *const px[8], vf_ p[4])
{
    __m128 r0 = _mm_loadu_ps(px[0]), g0 = _mm_loadu_ps(px[1]), b0 = _mm_loadu_ps(px[2]), z0 = _mm_loadu_ps(px[3]);
    __m128 r1 = _mm_loadu_ps(px[4]), g1 = _mm_loadu_ps(px[5]), b1 = _mm_loadu_ps(px[6]), z1 = _mm_loadu_ps(px[7]);
    _MM_TRANSPOSE4_PS(r0, g0, b0, z0);
    _MM_TRANSPOSE4_PS(r1, g1, b1, z1);
    p[0] = (vf_)_mm256_insertf128_ps(_mm256_castps128_ps256(r0), r1, 1);
    p[1] = (vf_)_mm256_insertf128_ps(_mm256_castps128_ps256(g0), g1, 1);
    p[2] = (vf_)_mm256_insertf128_ps(_mm256_castps128_ps256(b0), b1, 1);
    p[3] = (vf_)_mm256_insertf128_ps(_mm256_castps128_ps256(z0), z1, 1);
}
static inline void vtap_load(const float *const t0[8], const float *const t1[8], const float *const w0[8],
                             const float *const w1[8], vf_ c[4][4], vf_ cw[4])
{
    __m256 top[8], bot[8];
    for (int k = 0; k < 8; k++) {
        top[k] = _mm256_loadu_ps(t0[k]);
        bot[k] = _mm256_loadu_ps(t1[k]);
    }
    transpose8(top);
    transpose8(bot);
    for (int ch = 0; ch < 4; ch++) {
        c[0][ch] = (vf_)top[ch];
        c[2][ch] = (vf_)top[4 + ch];
        c[1][ch] = (vf_)bot[ch];
        c[3][ch] = (vf_)bot[4 + ch];
    }
    __m256 e, o;
    deinterleave8(pairs4(w0), pairs4(w0 + 4), &e, &o);
    cw[0] = (vf_)e, cw[2] = (vf_)o;
    deinterleave8(pairs4(w1), pairs4(w1 + 4), &e, &o);
    cw[1] = (vf_)e, cw[3] = (vf_)o;
}
#define vfloor(x) ((vf)_mm256_floor_ps((__m256)(x)))
#include "../reproject_vec.h" /* the blend, eight samples at a time */

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
