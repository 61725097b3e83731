/* fovea: depth-of-field kernels, SSE4.1 (core/x86/dof_x86.h has the pieces and why they give
 * the bits of the C references in core/dof/kernels.c). The CoC takes 4 pixels at a time (true
 * division, the reference's selects); the Gaussians 4 output pixels at a time, one pixel per
 * vector, so 4 independent add chains overlap where the reference waits on one. */
#include "x86/dof_x86.h"

static void coc_row_sse41(float *restrict coc, const float *rgbd, int n, float K, float dn, float df)
{
    const dof_coc4_k k = dof_coc4_setup(K, dn, df);
    int x = 0;
    for (; x + 4 <= n; x += 4)
        _mm_storeu_ps(coc + x, dof_coc4(dof_depth4(rgbd + 4 * x), &k));
    if (x < n)
        fv_dof_coc_row_c(coc + x, rgbd + 4 * x, n - x, K, dn, df);
}

static void hgauss_row_sse41(float *restrict dst, const float *rgbd, const float *coc, int w, int x0, int n,
                             const uint8_t *sig, const fv_dof_gauss_tab *tab)
{
    _Alignas(16) float m[4 * (DOF_CH + 2 * FV_DOF_RMAX)];
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
        for (; i + 4 <= cn; i += 4) {
            const uint8_t *s = sg + i;
            const float *const wt[4] = {tab->w[s[0]], tab->w[s[1]], tab->w[s[2]], tab->w[s[3]]};
            const int R = dof_maxi(dof_maxi(tab->rad[s[0]], tab->rad[s[1]]), dof_maxi(tab->rad[s[2]], tab->rad[s[3]]));
            __m128 a[4];
            dof_g4(a, mc + 4 * i, 4, wt, R);
            for (int k = 0; k < 4; k++)
                _mm_storeu_ps(d + 4 * (i + k), _mm_mul_ps(a[k], _mm_set1_ps(tab->inv[s[k]])));
        }
        for (; i < cn; i++)
            _mm_storeu_ps(d + 4 * i, _mm_mul_ps(dof_g1(mc + 4 * i, tab->w[sg[i]], tab->rad[sg[i]]),
                                                _mm_set1_ps(tab->inv[sg[i]])));
    }
}

static void vgauss_row_sse41(float *restrict dst, const float *src, ptrdiff_t stride, int y, int ylo, int yhi,
                             int x0, int n, const uint8_t *sig, const fv_dof_gauss_tab *tab)
{
    int i = 0;
    for (; i + 4 <= n; i += 4) {
        const uint8_t *s = sig + i;
        const float *const wt[4] = {tab->w[s[0]], tab->w[s[1]], tab->w[s[2]], tab->w[s[3]]};
        const int R = dof_maxi(dof_maxi(tab->rad[s[0]], tab->rad[s[1]]), dof_maxi(tab->rad[s[2]], tab->rad[s[3]]));
        dof_vg4(dst + 4 * (ptrdiff_t)(x0 + i), src + 4 * (ptrdiff_t)(x0 + i), stride, y, ylo, yhi, wt, R);
    }
    for (; i < n; i++)
        dof_vg1(dst + 4 * (ptrdiff_t)(x0 + i), src + 4 * (ptrdiff_t)(x0 + i), stride, y, ylo, yhi, tab->w[sig[i]],
                tab->rad[sig[i]]);
}

static void combine_row_sse41(float *restrict out, const fv_dof_combine_args *a, int x0, int n)
{
    dof_combine_row_x86(out, a, x0, n);
}

void fv_dof_init_sse41(fv_dsp *d)
{
    d->dof_coc_row = coc_row_sse41;
    d->dof_hgauss_row = hgauss_row_sse41;
    d->dof_vgauss_row = vgauss_row_sse41;
    d->dof_combine_row = combine_row_sse41;
}
