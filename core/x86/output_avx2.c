/* fovea: the output kernel, AVX2: 8 pixels a step, sRGB computed instead of looked up (the
 * table gathers bound the old version): v^(5/12) as 2^(5e/12), e the exponent (a permute from 9
 * constants), times a cubic in the mantissa m in [1, 2) (relative error 1.1e-4, 0.03 of a step
 * of 255); within 1 of the reference's table bytes (the table itself rounds v to 1/4096 first,
 * up to 0.4 of a step), exactly 0 for v <= 0 or NaN and 255 for v >= 1 (output_dsp.h). The 24
 * colour values of 8 pixels are permuted into 3 vectors first (the depth is never converted). */
#include <immintrin.h>
#include <string.h>

#include "output_dsp.h"

/* 1.055 * 2^(5 (k - 9) / 12), k = e + 9 for the exponents e = -9 .. -1 of [2^-9, 1) */
static const float k_pow2[9] = {7.841334415e-02f, 1.046692569e-01f, 1.397166956e-01f,
                                1.864994135e-01f, 2.489468500e-01f, 3.323041769e-01f,
                                4.435728590e-01f, 5.920987305e-01f, 7.903569831e-01f};

/* 255 sRGB(v) + 0.5 truncated, as 32-bit integers (0 .. 256: the packs saturate 256 to 255) */
static inline __m256i srgb8(__m256 v)
{
    /* [0, 1 - ulp]; NaN -> 0 (max returns its second operand on NaN) */
    v = _mm256_min_ps(_mm256_max_ps(v, _mm256_setzero_ps()), _mm256_set1_ps(0x1.fffffep-1f));
    const __m256i bits = _mm256_castps_si256(v);
    /* e + 9; below 2^-9 (the linear part's) any lane value: the permute reads its low 3 bits */
    const __m256i k = _mm256_sub_epi32(_mm256_srli_epi32(bits, 23), _mm256_set1_epi32(127 - 9));
    const __m256 m = _mm256_castsi256_ps(
        _mm256_or_si256(_mm256_and_si256(bits, _mm256_set1_epi32(0x007fffff)), _mm256_set1_epi32(0x3f800000)));
    __m256 p = _mm256_fmadd_ps(_mm256_set1_ps(2.373281530e-02f), m, _mm256_set1_ps(-1.733108596e-01f));
    p = _mm256_fmadd_ps(p, m, _mm256_set1_ps(6.886010604e-01f));
    p = _mm256_fmadd_ps(p, m, _mm256_set1_ps(4.610837899e-01f));
    __m256 t = _mm256_permutevar8x32_ps(_mm256_loadu_ps(k_pow2), k);
    t = _mm256_blendv_ps(t, _mm256_set1_ps(k_pow2[8]), _mm256_castsi256_ps(_mm256_cmpeq_epi32(k, _mm256_set1_epi32(8))));
    const __m256 gam = _mm256_fmsub_ps(t, p, _mm256_set1_ps(0.055f));
    const __m256 lin = _mm256_mul_ps(v, _mm256_set1_ps(12.92f));
    const __m256 s = _mm256_blendv_ps(gam, lin, _mm256_cmp_ps(v, _mm256_set1_ps(0.0031308f), _CMP_LE_OQ));
    return _mm256_cvttps_epi32(_mm256_fmadd_ps(s, _mm256_set1_ps(255.0f), _mm256_set1_ps(0.5f)));
}

static inline __m256 perm(__m256 v, int a, int b, int c, int d, int e, int f, int g, int h)
{
    return _mm256_permutevar8x32_ps(v, _mm256_setr_epi32(a, b, c, d, e, f, g, h));
}

static void rgb8_row_avx2(uint8_t *restrict dst, const float *rgbd, int n, const uint8_t *lut)
{
    int x = 0;
    for (; x + 8 <= n; x += 8) {
        const float *p = rgbd + 4 * x;
        /* pixels 0-1, 2-3, 4-5, 6-7 as r g b d r g b d; the 24 colour values in order as
         * X = r0 g0 b0 r1 g1 b1 r2 g2, Y = b2 r3 g3 b3 r4 g4 b4 r5, Z = g5 b5 r6 g6 b6 r7 g7 b7
         * (the depth lanes are not computed) */
        const __m256 A = _mm256_loadu_ps(p), B = _mm256_loadu_ps(p + 8);
        const __m256 C = _mm256_loadu_ps(p + 16), D = _mm256_loadu_ps(p + 24);
        const __m256i X = srgb8(_mm256_blend_ps(perm(A, 0, 1, 2, 4, 5, 6, 0, 0), perm(B, 0, 0, 0, 0, 0, 0, 0, 1), 0xc0));
        const __m256i Y = srgb8(_mm256_blend_ps(perm(B, 2, 4, 5, 6, 0, 0, 0, 0), perm(C, 0, 0, 0, 0, 0, 1, 2, 4), 0xf0));
        const __m256i Z = srgb8(_mm256_blend_ps(perm(C, 5, 6, 0, 0, 0, 0, 0, 0), perm(D, 0, 0, 0, 1, 2, 4, 5, 6), 0xfc));
        /* per 128-bit lane the packs give X0-3 Y0-3 Z0-3 Z0-3 | X4-7 Y4-7 Z4-7 Z4-7 (4-byte groups) */
        const __m256i b = _mm256_packus_epi16(_mm256_packus_epi32(X, Y), _mm256_packus_epi32(Z, Z));
        const __m256i o = _mm256_permutevar8x32_epi32(b, _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7));
        _mm_storeu_si128((__m128i *)(void *)(dst + 3 * x), _mm256_castsi256_si128(o));
        _mm_storel_epi64((__m128i *)(void *)(dst + 3 * x + 16), _mm256_extracti128_si256(o, 1));
    }
    fv_rgb8_row_c(dst + 3 * x, rgbd + 4 * x, n - x, lut);
}

/* lca_row, 8 pixels a step: the same operations as the reference lane by lane (floor by
 * vroundps, gathers for the ratio tables, the texels and the sRGB table), so the same bytes */
static inline __m256i lca_lut(__m256 v, const uint8_t *lut)
{
    const __m256 gt0 = _mm256_cmp_ps(v, _mm256_setzero_ps(), _CMP_GT_OQ), lt1 = _mm256_cmp_ps(v, _mm256_set1_ps(1.0f), _CMP_LT_OQ);
    const __m256i t = _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(v, _mm256_set1_ps((float)FV_SRGB_LUT)), _mm256_set1_ps(0.5f)));
    __m256i i = _mm256_blendv_epi8(_mm256_set1_epi32(FV_SRGB_LUT), t, _mm256_castps_si256(lt1));
    i = _mm256_and_si256(i, _mm256_castps_si256(gt0));
    return _mm256_and_si256(_mm256_i32gather_epi32((const int *)(const void *)lut, i, 1), _mm256_set1_epi32(0xff));
}

static inline __m256 lca_sample(const fv_lca_geom *g, __m256 fx, __m256 fy, int c)
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    const __m256 wm = _mm256_set1_ps((float)(g->w - 1)), hm = _mm256_set1_ps((float)(g->h - 1));
    const __m256 x0f = _mm256_floor_ps(fx), y0f = _mm256_floor_ps(fy);
    const __m256 ax = _mm256_sub_ps(fx, x0f), ay = _mm256_sub_ps(fy, y0f);
    /* min(max(v, 0), n - 1): max returns its second operand on NaN, as fv_lca_clamp */
    const __m256i x0 = _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(x0f, zero), wm));
    const __m256i x1 = _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(_mm256_add_ps(x0f, one), zero), wm));
    const __m256i y0 = _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(y0f, zero), hm));
    const __m256i y1 = _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(_mm256_add_ps(y0f, one), zero), hm));
    const __m256i st = _mm256_set1_epi32((int)g->stride), cc = _mm256_set1_epi32(c);
    const __m256i r0 = _mm256_mullo_epi32(y0, st), r1 = _mm256_mullo_epi32(y1, st);
    /* 4 (y stride + x) + c: an image below 2^29 pixels (the callers' sizes are far below) */
    const __m256i i00 = _mm256_add_epi32(_mm256_slli_epi32(_mm256_add_epi32(r0, x0), 2), cc);
    const __m256i i10 = _mm256_add_epi32(_mm256_slli_epi32(_mm256_add_epi32(r0, x1), 2), cc);
    const __m256i i01 = _mm256_add_epi32(_mm256_slli_epi32(_mm256_add_epi32(r1, x0), 2), cc);
    const __m256i i11 = _mm256_add_epi32(_mm256_slli_epi32(_mm256_add_epi32(r1, x1), 2), cc);
    const __m256 t00 = _mm256_i32gather_ps(g->img, i00, 4), t10 = _mm256_i32gather_ps(g->img, i10, 4);
    const __m256 t01 = _mm256_i32gather_ps(g->img, i01, 4), t11 = _mm256_i32gather_ps(g->img, i11, 4);
    const __m256 a = _mm256_add_ps(t00, _mm256_mul_ps(ax, _mm256_sub_ps(t10, t00)));
    const __m256 b = _mm256_add_ps(t01, _mm256_mul_ps(ax, _mm256_sub_ps(t11, t01)));
    return _mm256_add_ps(a, _mm256_mul_ps(ay, _mm256_sub_ps(b, a)));
}

static void lca_row_avx2(uint8_t *restrict dst, int y, const fv_lca_geom *g, const fv_lens_lca *lca, const uint8_t *lut)
{
    const float ty = g->tan_top - ((float)y + 0.5f) * g->px_tan;
    const float *own = g->img + 4 * (ptrdiff_t)y * g->stride;
    const __m256 uy = _mm256_set1_ps(ty - g->cy), cx = _mm256_set1_ps(g->cx), cy = _mm256_set1_ps(g->cy);
    const __m256 tl = _mm256_set1_ps(g->tan_left), tt = _mm256_set1_ps(g->tan_top), pt = _mm256_set1_ps(g->px_tan);
    const __m256 inv = _mm256_set1_ps(g->inv_px), half = _mm256_set1_ps(0.5f), steps = _mm256_set1_ps((float)FV_LENS_LCA_STEPS);
    const __m256 uy2 = _mm256_mul_ps(uy, uy);
    /* the bytes r, g, b of a pixel's 32-bit lane to 3 packed bytes: 12 per 128-bit half */
    const __m256i pack = _mm256_setr_epi8(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1, 0, 1, 2, 4, 5, 6, 8, 9,
                                          10, 12, 13, 14, -1, -1, -1, -1);
    int x = 0;
    for (; x + 8 <= g->w; x += 8) {
        const __m256 xf = _mm256_add_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(x), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7))), half);
        const __m256 ux = _mm256_sub_ps(_mm256_add_ps(tl, _mm256_mul_ps(xf, pt)), cx);
        __m256 f = _mm256_mul_ps(_mm256_sqrt_ps(_mm256_add_ps(_mm256_mul_ps(ux, ux), uy2)), _mm256_set1_ps(lca->inv_step));
        f = _mm256_blendv_ps(steps, f, _mm256_cmp_ps(f, steps, _CMP_LT_OQ)); /* f < STEPS ? f : STEPS (NaN: STEPS) */
        __m256i i = _mm256_cvttps_epi32(f);
        i = _mm256_min_epi32(i, _mm256_set1_epi32(FV_LENS_LCA_STEPS - 1));
        const __m256 a = _mm256_sub_ps(f, _mm256_cvtepi32_ps(i));
        __m256i out = _mm256_slli_epi32(lca_lut(_mm256_i32gather_ps(own + 4 * x + 1, _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28), 4), lut), 8);
        for (int ch = 0; ch < 2; ch++) {
            const float *t = lca->ratio[ch];
            const __m256 t0 = _mm256_i32gather_ps(t, i, 4), t1 = _mm256_i32gather_ps(t + 1, i, 4);
            const __m256 s = _mm256_add_ps(t0, _mm256_mul_ps(a, _mm256_sub_ps(t1, t0)));
            const __m256 qx = _mm256_add_ps(cx, _mm256_mul_ps(ux, s)), qy = _mm256_add_ps(cy, _mm256_mul_ps(uy, s));
            const __m256 fx = _mm256_sub_ps(_mm256_mul_ps(_mm256_sub_ps(qx, tl), inv), half);
            const __m256 fy = _mm256_sub_ps(_mm256_mul_ps(_mm256_sub_ps(tt, qy), inv), half);
            const __m256i v = lca_lut(lca_sample(g, fx, fy, ch ? 2 : 0), lut);
            out = _mm256_or_si256(out, ch ? _mm256_slli_epi32(v, 16) : v);
        }
        const __m256i b = _mm256_shuffle_epi8(out, pack);
        uint8_t tmp[32];
        _mm256_storeu_si256((__m256i *)(void *)tmp, b);
        memcpy(dst + 3 * x, tmp, 12);
        memcpy(dst + 3 * x + 12, tmp + 16, 12);
    }
    for (; x < g->w; x++)
        fv_lca_pixel(dst + 3 * x, x, ty, g, lca, own + 4 * x, lut);
}

void fv_output_dsp_init_avx2(fv_output_dsp *d)
{
    d->rgb8_row = rgb8_row_avx2;
    d->lca_row = lca_row_avx2;
}
