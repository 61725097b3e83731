/* fovea: depth-of-field kernels, AVX2 (built with -mavx2 -mfma but -ffp-contract=off and no FMA
 * intrinsics). The CoC takes 8 pixels at a time; the Gaussians 8 output pixels at a time as four
 * 256-bit accumulators of two pixels each (each 128-bit half with its own pixel's weights), the
 * rest with the 128-bit pieces of core/x86/dof_x86.h, which also has why the bits are the
 * references'. The combine is the 128-bit one (per-pixel control flow), VEX-encoded. */
#include <immintrin.h>

#include "x86/dof_x86.h"

static void coc_row_avx2(float *restrict coc, const float *rgbd, int n, float K, float dn, float df)
{
    const __m256 vK = _mm256_set1_ps(K), idn = _mm256_set1_ps(1.0f / dn), idf = _mm256_set1_ps(1.0f / df);
    const __m256 vdn = _mm256_set1_ps(dn), vdf = _mm256_set1_ps(df), one = _mm256_set1_ps(1.0f);
    const __m256 lo = _mm256_set1_ps(FV_DOF_MIN_DEPTH_M);
    const __m256i order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
    int x = 0;
    for (; x + 8 <= n; x += 8) {
        const float *p = rgbd + 4 * x;
        /* depths: (d0 d2 d4 d6 | d1 d3 d5 d7), then in order */
        const __m256 h0 = _mm256_unpackhi_ps(_mm256_loadu_ps(p), _mm256_loadu_ps(p + 8));
        const __m256 h1 = _mm256_unpackhi_ps(_mm256_loadu_ps(p + 16), _mm256_loadu_ps(p + 24));
        const __m256 d = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(h0, h1, _MM_SHUFFLE(3, 2, 3, 2)), order);
        const __m256 g = _mm256_max_ps(d, lo); /* d > min ? d : min */
        const __m256 ig = _mm256_div_ps(one, g);
        const __m256 nr = _mm256_mul_ps(vK, _mm256_sub_ps(idn, ig));
        const __m256 fr = _mm256_and_ps(_mm256_mul_ps(vK, _mm256_sub_ps(idf, ig)), _mm256_cmp_ps(g, vdf, _CMP_GT_OQ));
        _mm256_storeu_ps(coc + x, _mm256_blendv_ps(fr, nr, _mm256_cmp_ps(g, vdn, _CMP_LT_OQ)));
    }
    if (x + 4 <= n) {
        const dof_coc4_k k = dof_coc4_setup(K, dn, df);
        _mm_storeu_ps(coc + x, dof_coc4(dof_depth4(rgbd + 4 * x), &k));
        x += 4;
    }
    if (x < n)
        fv_dof_coc_row_c(coc + x, rgbd + 4 * x, n - x, K, dn, df);
}

/* weights of a pixel pair: wa[k] in the low half, wb[k] in the high half */
static inline __m256 wpair(const float *wa, const float *wb, int k)
{
    return _mm256_blend_ps(_mm256_broadcast_ss(wa + k), _mm256_broadcast_ss(wb + k), 0xf0);
}

static inline int rad8(const fv_dof_gauss_tab *tab, const uint8_t *s)
{
    int R = 0;
    for (int k = 0; k < 8; k++)
        R = dof_maxi(R, tab->rad[s[k]]);
    return R;
}

/* 8 neighbouring pixels at p (contiguous), the block's largest radius R; tap j at p + 4 j. */
static inline void g8(__m256 a[4], const float *p0, const float *const wt[8], int R)
{
    __m256 a0 = _mm256_setzero_ps(), a1 = a0, a2 = a0, a3 = a0;
    for (int j = -R; j <= R; j++) {
        const int k = j < 0 ? -j : j;
        const float *p = p0 + 4 * (ptrdiff_t)j;
        a0 = _mm256_add_ps(a0, _mm256_mul_ps(wpair(wt[0], wt[1], k), _mm256_loadu_ps(p)));
        a1 = _mm256_add_ps(a1, _mm256_mul_ps(wpair(wt[2], wt[3], k), _mm256_loadu_ps(p + 8)));
        a2 = _mm256_add_ps(a2, _mm256_mul_ps(wpair(wt[4], wt[5], k), _mm256_loadu_ps(p + 16)));
        a3 = _mm256_add_ps(a3, _mm256_mul_ps(wpair(wt[6], wt[7], k), _mm256_loadu_ps(p + 24)));
    }
    a[0] = a0, a[1] = a1, a[2] = a2, a[3] = a3;
}

static void hgauss_row_avx2(float *restrict dst, const float *rgbd, const float *coc, int w, int x0, int n,
                            const uint8_t *sig, const fv_dof_gauss_tab *tab)
{
    _Alignas(32) float m[4 * (DOF_CH + 2 * FV_DOF_RMAX)];
    for (int c0 = 0; c0 < n; c0 += DOF_CH) {
        const int cn = n - c0 < DOF_CH ? n - c0 : DOF_CH;
        const uint8_t *sg = sig + c0;
        int Rc = 0;
        for (int i = 0; i < cn; i++)
            Rc = dof_maxi(Rc, tab->rad[sg[i]]);
        dof_mask_row(m, rgbd, coc, w, x0 + c0 - Rc, cn + 2 * Rc);
        const float *mc = m + 4 * Rc; /* output pixel c0 + i at mc + 4 i */
        float *d = dst + 4 * (ptrdiff_t)(x0 + c0);
        int i = 0;
        for (; i + 8 <= cn; i += 8) {
            const uint8_t *s = sg + i;
            const float *const wt[8] = {tab->w[s[0]], tab->w[s[1]], tab->w[s[2]], tab->w[s[3]],
                                        tab->w[s[4]], tab->w[s[5]], tab->w[s[6]], tab->w[s[7]]};
            __m256 a[4];
            g8(a, mc + 4 * i, wt, rad8(tab, s));
            for (int k = 0; k < 4; k++) {
                const __m256 inv = _mm256_setr_m128(_mm_set1_ps(tab->inv[s[2 * k]]), _mm_set1_ps(tab->inv[s[2 * k + 1]]));
                _mm256_storeu_ps(d + 4 * (i + 2 * k), _mm256_mul_ps(a[k], inv));
            }
        }
        if (i + 4 <= cn) {
            const uint8_t *s = sg + i;
            const float *const wt[4] = {tab->w[s[0]], tab->w[s[1]], tab->w[s[2]], tab->w[s[3]]};
            const int R = dof_maxi(dof_maxi(tab->rad[s[0]], tab->rad[s[1]]), dof_maxi(tab->rad[s[2]], tab->rad[s[3]]));
            __m128 a[4];
            dof_g4(a, mc + 4 * i, 4, wt, R);
            for (int k = 0; k < 4; k++)
                _mm_storeu_ps(d + 4 * (i + k), _mm_mul_ps(a[k], _mm_set1_ps(tab->inv[s[k]])));
            i += 4;
        }
        for (; i < cn; i++)
            _mm_storeu_ps(d + 4 * i, _mm_mul_ps(dof_g1(mc + 4 * i, tab->w[sg[i]], tab->rad[sg[i]]),
                                                _mm_set1_ps(tab->inv[sg[i]])));
    }
}

static void vgauss_row_avx2(float *restrict dst, const float *src, ptrdiff_t stride, int y, int ylo, int yhi,
                            int x0, int n, const uint8_t *sig, const fv_dof_gauss_tab *tab)
{
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        const uint8_t *s = sig + i;
        const float *const wt[8] = {tab->w[s[0]], tab->w[s[1]], tab->w[s[2]], tab->w[s[3]],
                                    tab->w[s[4]], tab->w[s[5]], tab->w[s[6]], tab->w[s[7]]};
        const int R = rad8(tab, s);
        const float *col = src + 4 * (ptrdiff_t)(x0 + i);
        __m256 a0 = _mm256_setzero_ps(), a1 = a0, a2 = a0, a3 = a0;
        for (int j = -R; j <= R; j++) {
            const int k = j < 0 ? -j : j;
            const float *p = col + 4 * (ptrdiff_t)dof_clampi(y + j, ylo, yhi - 1) * stride;
            a0 = _mm256_add_ps(a0, _mm256_mul_ps(wpair(wt[0], wt[1], k), _mm256_loadu_ps(p)));
            a1 = _mm256_add_ps(a1, _mm256_mul_ps(wpair(wt[2], wt[3], k), _mm256_loadu_ps(p + 8)));
            a2 = _mm256_add_ps(a2, _mm256_mul_ps(wpair(wt[4], wt[5], k), _mm256_loadu_ps(p + 16)));
            a3 = _mm256_add_ps(a3, _mm256_mul_ps(wpair(wt[6], wt[7], k), _mm256_loadu_ps(p + 24)));
        }
        float *o = dst + 4 * (ptrdiff_t)(x0 + i);
        _mm256_storeu_ps(o, a0);
        _mm256_storeu_ps(o + 8, a1);
        _mm256_storeu_ps(o + 16, a2);
        _mm256_storeu_ps(o + 24, a3);
    }
    if (i + 4 <= n) {
        const uint8_t *s = sig + i;
        const float *const wt[4] = {tab->w[s[0]], tab->w[s[1]], tab->w[s[2]], tab->w[s[3]]};
        const int R = dof_maxi(dof_maxi(tab->rad[s[0]], tab->rad[s[1]]), dof_maxi(tab->rad[s[2]], tab->rad[s[3]]));
        dof_vg4(dst + 4 * (ptrdiff_t)(x0 + i), src + 4 * (ptrdiff_t)(x0 + i), stride, y, ylo, yhi, wt, R);
        i += 4;
    }
    for (; i < n; i++)
        dof_vg1(dst + 4 * (ptrdiff_t)(x0 + i), src + 4 * (ptrdiff_t)(x0 + i), stride, y, ylo, yhi, tab->w[sig[i]],
                tab->rad[sig[i]]);
}

static void combine_row_avx2(float *restrict out, const fv_dof_combine_args *a, int x0, int n)
{
    dof_combine_row_x86(out, a, x0, n);
}

void fv_dof_init_avx2(fv_dsp *d)
{
    d->dof_coc_row = coc_row_avx2;
    d->dof_hgauss_row = hgauss_row_avx2;
    d->dof_vgauss_row = vgauss_row_avx2;
    d->dof_combine_row = combine_row_avx2;
}
