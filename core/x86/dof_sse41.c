/* fovea: depth-of-field kernels, SSE4.1 (core/x86/dof_tmpl.h has the pieces and why they give
 * the bits of the C references in core/dof/dof_ref.c). The CoC takes 4 pixels at a time (true
 * division, the reference's selects); the Gaussians 4 output pixels at a time, one pixel per
 * vector, so 4 independent add chains overlap where the reference waits on one. The up-sampling
 * and the periphery's level blend take one pixel a vector (their per-pixel scalars 4 at a time). */
#define FV_X86_W 4
#define FV_X86_FN(name) name##_sse41
#include "x86/dof_tmpl.h"

static void coc_row_sse41(float *restrict coc, const float *rgbd, int n, float K, float dn, float df)
{
    const dof_coc4_k k = dof_coc4_setup(K, dn, df);
    int x = 0;
    for (; x + 4 <= n; x += 4)
        _mm_storeu_ps(coc + x, dof_coc4(dof_depth4(rgbd + 4 * x), &k));
    if (x < n)
        fv_dof_coc_row_c(coc + x, rgbd + 4 * x, n - x, K, dn, df);
}

static void combine_row_sse41(float *restrict out, const fv_dof_combine_args *a, int x0, int n)
{
    dof_combine_row_x86(out, a, x0, n);
}

static void upsample_row_sse41(float *restrict dst, const float *tmp, int L, int sw, int x0, int n)
{
    dof_upsample_row_x86(dst, tmp, L, sw, x0, n);
}

static void pyrblur_row_sse41(float *restrict blur, const fv_dof_pyrblur_args *a, int x0, int n)
{
    dof_pyrblur_row_x86(blur, a, x0, n);
}

static void nearblk_row_sse41(float *restrict sum, float *restrict ext, const float *coc, const float *rgbd, int n)
{
    int b = 0;
    for (; 4 * b + 4 <= n; b++)
        dof_nearblk4(sum + 4 * b, ext + 2 * b, coc + 4 * b, rgbd + 16 * b);
    if (4 * b < n)
        fv_dof_nearblk_row_c(sum + 4 * b, ext + 2 * b, coc + 4 * b, rgbd + 16 * b, n - 4 * b);
}

static void nearbox_row_sse41(float *restrict out, float *restrict out_r, float *restrict out_w, const float *src,
                              const float *r, const float *wgt, int w, int x0, int n, int reach)
{
    for (int i = x0; i < x0 + n;)
        if (i >= reach && i + 3 + reach < w && i + 4 <= x0 + n)
            dof_nearbox4(out, out_r, out_w, src, r, wgt, i, reach), i += 4;
        else /* the row's ends */
            fv_dof_nearbox_row_c(out, out_r, out_w, src, r, wgt, w, i, 1, reach), i++;
}

static void periph_row_sse41(float *restrict out, const float *sharp, const float *coc, const float *half,
                             const float *lnear, int x0, int n)
{
    dof_periph_row_x86(out, sharp, coc, half, lnear, x0, n);
}

/* 4 texels a step: the pair sums as even + odd lanes (a0 + a1, ..., the reference's additions; a
 * float add commutes bit for bit; shuffles are cheaper than hadd); |x| by clearing the sign bit,
 * exact like fabsf */
static inline __m128 hcoc_pairs(const float *c, __m128 abs)
{
    const __m128 a = _mm_and_ps(_mm_loadu_ps(c), abs), b = _mm_and_ps(_mm_loadu_ps(c + 4), abs);
    return _mm_add_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0)), _mm_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1)));
}

static void hcoc_row_sse41(float *restrict hc, const float *ca, const float *cb, int n)
{
    const __m128 abs = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff)), q = _mm_set1_ps(0.25f);
    int u = 0;
    for (; u + 4 <= n; u += 4)
        _mm_storeu_ps(hc + u, _mm_mul_ps(q, _mm_add_ps(hcoc_pairs(ca + 2 * u, abs), hcoc_pairs(cb + 2 * u, abs))));
    if (u < n)
        fv_dof_hcoc_row_c(hc + u, ca + 2 * u, cb + 2 * u, n - u);
}

/* 4 blocks a step: the blocks' min CoC (even lanes of ext) and counts (lane 3 of each sum) by
 * shuffles; floor by roundps, the caps and selects as the reference's (min/max_ps return the
 * second operand where the compare is false, the reference's choice), true division */
static void nearfin_row_sse41(float *restrict rad, float *restrict rb, float *restrict wgt, float *restrict sum,
                              const float *ext, int n, float inv)
{
    const __m128 half = _mm_set1_ps(0.5f), rmax = _mm_set1_ps((float)FV_DOF_RMAX), q = _mm_set1_ps(0.25f);
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f), two = _mm_set1_ps(2.0f), m1 = _mm_set1_ps(-1.0f);
    const __m128 vinv = _mm_set1_ps(inv), sgn = _mm_set1_ps(-0.0f);
    int i = 0;
    for (; i + 4 <= n; i += 4) {
        const __m128 e = _mm_shuffle_ps(_mm_loadu_ps(ext + 2 * i), _mm_loadu_ps(ext + 2 * i + 4), _MM_SHUFFLE(2, 0, 2, 0));
        float *s = sum + 4 * i;
        const __m128 s0 = _mm_loadu_ps(s), s1 = _mm_loadu_ps(s + 4), s2 = _mm_loadu_ps(s + 8), s3 = _mm_loadu_ps(s + 12);
        const __m128 cnt = _mm_shuffle_ps(_mm_shuffle_ps(s0, s1, _MM_SHUFFLE(3, 3, 3, 3)),
                                          _mm_shuffle_ps(s2, s3, _MM_SHUFFLE(3, 3, 3, 3)), _MM_SHUFFLE(2, 0, 2, 0));
        /* -e 0.5 as the reference: the sign flipped exactly, then the multiply */
        const __m128 r = _mm_min_ps(_mm_floor_ps(_mm_mul_ps(_mm_xor_ps(e, sgn), half)), rmax);
        const __m128 b = _mm_blendv_ps(m1, _mm_floor_ps(_mm_mul_ps(r, q)), _mm_cmpgt_ps(cnt, zero));
        _mm_storeu_ps(rad + i, r);
        _mm_storeu_ps(rb + i, b);
        _mm_storeu_ps(wgt + i, _mm_div_ps(one, _mm_add_ps(_mm_mul_ps(two, _mm_max_ps(b, zero)), one)));
        _mm_storeu_ps(s, _mm_mul_ps(s0, vinv));
        _mm_storeu_ps(s + 4, _mm_mul_ps(s1, vinv));
        _mm_storeu_ps(s + 8, _mm_mul_ps(s2, vinv));
        _mm_storeu_ps(s + 12, _mm_mul_ps(s3, vinv));
    }
    if (i < n)
        fv_dof_nearfin_row_c(rad + i, rb + i, wgt + i, sum + 4 * i, ext + 2 * i, n - i, inv);
}

void fv_dof_dsp_init_sse41(fv_dof_dsp *d)
{
    d->dof_nearfin_row = nearfin_row_sse41;
    d->dof_hcoc_row = hcoc_row_sse41;
    d->dof_periph_row = periph_row_sse41;
    d->dof_nearbox_row = nearbox_row_sse41;
    d->dof_nearblk_row = nearblk_row_sse41;
    d->dof_upsample_row = upsample_row_sse41;
    d->dof_pyrblur_row = pyrblur_row_sse41;
    d->dof_coc_row = coc_row_sse41;
    d->dof_hgauss_row = hgauss_row_sse41;
    d->dof_vgauss_row = vgauss_row_sse41;
    d->dof_combine_row = combine_row_sse41;
}
