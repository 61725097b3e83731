/* fovea: depth-of-field kernels, SSE4.1 (core/x86/dof_x86.h has the pieces and why they give
 * the bits of the C references in core/dof/kernels.c). The CoC takes 4 pixels at a time (true
 * division, the reference's selects); the Gaussians 4 output pixels at a time, one pixel per
 * vector, so 4 independent add chains overlap where the reference waits on one. The up-sampling
 * and the periphery's level blend take one pixel a vector (their per-pixel scalars 4 at a time). */
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
    ptrdiff_t offs[2 * FV_DOF_RMAX + 1], *off = offs + FV_DOF_RMAX;
    dof_offsets_h(off, FV_DOF_RMAX);
    for (int c0 = 0; c0 < n; c0 += DOF_CH) {
        const int cn = n - c0 < DOF_CH ? n - c0 : DOF_CH, Rc = dof_span_rad(sig + c0, cn, tab);
        dof_mask_row(m, rgbd, coc, w, x0 + c0 - Rc, cn + 2 * Rc);
        /* output pixel c0 + i from m + 4 (Rc + i) */
        dof_gauss_4(dst + 4 * (ptrdiff_t)(x0 + c0), m + 4 * Rc, off, cn, sig + c0, tab, 1);
    }
}

static void vgauss_row_sse41(float *restrict dst, const float *src, ptrdiff_t stride, int y, int ylo, int yhi,
                             int x0, int n, const uint8_t *sig, const fv_dof_gauss_tab *tab)
{
    ptrdiff_t offs[2 * FV_DOF_RMAX + 1], *off = offs + FV_DOF_RMAX;
    const int R = dof_span_rad(sig, n, tab);
    dof_offsets_v(off, R, stride, y, ylo, yhi);
    dof_gauss_4(dst + 4 * (ptrdiff_t)x0, src + 4 * (ptrdiff_t)x0, off, n, sig, tab, 0);
}

static void combine_row_sse41(float *restrict out, const fv_dof_combine_args *a, int x0, int n)
{
    dof_combine_row_x86(out, a, x0, n);
}

static void upsample_row_sse41(float *restrict dst, const float *tmp, const int32_t *i0, const int32_t *i1,
                               const float *ax, int n)
{
    dof_upsample_row_x86(dst, tmp, i0, i1, ax, n);
}

static void pyrblur_row_sse41(float *restrict blur, const fv_dof_pyrblur_args *a, int x0, int n)
{
    dof_pyrblur_row_x86(blur, a, x0, n);
}

void fv_dof_init_sse41(fv_dsp *d)
{
    d->dof_upsample_row = upsample_row_sse41;
    d->dof_pyrblur_row = pyrblur_row_sse41;
    d->dof_coc_row = coc_row_sse41;
    d->dof_hgauss_row = hgauss_row_sse41;
    d->dof_vgauss_row = vgauss_row_sse41;
    d->dof_combine_row = combine_row_sse41;
}
