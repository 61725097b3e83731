/* fovea: plain-C reference kernels of the layered depth-of-field filter (core/dof/weier.c;
 * contracts in dof_dsp.h) and the table's init.
 * The hand-vectorised versions (core/x86/dof_*.c, core/arm/dof_neon.c) give the same bits: the
 * 4-channel sums below are written channel by channel in the order the vector code adds. */
#include <math.h>

#include "dof/weier_impl.h"
#include "base/util.h"
#include "dof/dof_dsp.h"


void fv_dof_coc_row_c(float *restrict coc, const float *rgbd, int n, float K, float dn, float df)
{
    const float inv_dn = 1.0f / dn, inv_df = 1.0f / df;
    for (int x = 0; x < n; x++) {
        const float g = rgbd[4 * x + 3] > FV_COC_MIN_DEPTH_M ? rgbd[4 * x + 3] : FV_COC_MIN_DEPTH_M;
        const float ig = 1.0f / g;
        /* near of d_n: K (1/g - 1/d_n) negated; far of d_f: K (1/d_f - 1/g); else 0 */
        coc[x] = g < dn ? K * (inv_dn - ig) : g > df ? K * (inv_df - ig) : 0.0f;
    }
}

void fv_dof_hgauss_row_c(float *restrict dst, const float *rgbd, const float *coc, int w, int x0, int n,
                         const uint8_t *sig, const struct fv_dof_gauss_tab *tab)
{
    for (int i = 0; i < n; i++) {
        const int x = x0 + i, s = sig[i], R = tab->rad[s];
        float a0 = 0.0f, a1 = 0.0f, a2 = 0.0f, a3 = 0.0f;
        for (int j = -R; j <= R; j++) {
            const int q = fv_clampi(x + j, 0, w - 1);
            if (!(coc[q] > 0.0f))
                continue; /* only far-field samples enter the far layer */
            const float g = tab->w[s][j < 0 ? -j : j];
            a0 += g * rgbd[4 * q + 0];
            a1 += g * rgbd[4 * q + 1];
            a2 += g * rgbd[4 * q + 2];
            a3 += g;
        }
        const float inv = tab->inv[s];
        dst[4 * x + 0] = a0 * inv;
        dst[4 * x + 1] = a1 * inv;
        dst[4 * x + 2] = a2 * inv;
        dst[4 * x + 3] = a3 * inv;
    }
}

void fv_dof_vgauss_row_c(float *restrict dst, const float *src, ptrdiff_t stride, int y, int ylo, int yhi, int x0,
                         int n, const uint8_t *sig, const struct fv_dof_gauss_tab *tab)
{
    for (int i = 0; i < n; i++) {
        const int x = x0 + i, s = sig[i], R = tab->rad[s];
        float a0 = 0.0f, a1 = 0.0f, a2 = 0.0f, a3 = 0.0f;
        for (int j = -R; j <= R; j++) {
            const float *p = src + 4 * ((ptrdiff_t)fv_clampi(y + j, ylo, yhi - 1) * stride + x);
            const float g = tab->w[s][j < 0 ? -j : j];
            a0 += g * p[0];
            a1 += g * p[1];
            a2 += g * p[2];
            a3 += g * p[3];
        }
        dst[4 * x + 0] = a0;
        dst[4 * x + 1] = a1;
        dst[4 * x + 2] = a2;
        dst[4 * x + 3] = a3;
    }
}

void fv_dof_combine_row_c(float *restrict out, const struct fv_dof_combine_args *a, int x0, int n)
{
    for (int x = x0; x < x0 + n; x++) {
        const float *s = a->sharp + 4 * x;
        float o0 = s[0], o1 = s[1], o2 = s[2];
        const float c = a->coc[x];
        const float t = a->t[x];
        /* towards the pixel's own blur: the far layer, fully from a CoC of one pixel on; a near
         * pixel's pyramid blur in the periphery, faded in by t */
        float ab = 0.0f;
        if (c > 0.0f)
            ab = c < 1.0f ? c : 1.0f;
        else if (c < 0.0f && t > 0.0f)
            ab = t * (-c < 1.0f ? -c : 1.0f);
        if (ab > 0.0f) {
            const float *f = a->far + 4 * x;
            o0 = o0 + ab * (f[0] - o0);
            o1 = o1 + ab * (f[1] - o1);
            o2 = o2 + ab * (f[2] - o2);
        }
        /* the near layer: full resolution, blended by t towards the quarter-resolution one,
         * which only spreads near pixels over the others (a near pixel has its own blur above) */
        float n0 = 0.0f, n1 = 0.0f, n2 = 0.0f, n3 = 0.0f;
        if (a->near) {
            const float *p = a->near + 4 * x;
            n0 = p[0], n1 = p[1], n2 = p[2], n3 = p[3];
        }
        if (a->lnear && t > 0.0f) {
            const float s = c < 0.0f ? 0.0f : 1.0f, *q = a->lnear + 4 * x;
            n0 = n0 + t * (s * q[0] - n0);
            n1 = n1 + t * (s * q[1] - n1);
            n2 = n2 + t * (s * q[2] - n2);
            n3 = n3 + t * (s * q[3] - n3);
        }
        if (n3 > 0.0f) { /* over the image by its coverage */
            const float cov = n3 < 1.0f ? n3 : 1.0f;
            o0 = o0 + cov * (n0 / n3 - o0);
            o1 = o1 + cov * (n1 / n3 - o1);
            o2 = o2 + cov * (n2 / n3 - o2);
        }
        if (a->enh) {
            const float g = a->gain * t, *b = a->enh + 4 * x;
            if (g > 0.0f) {
                const float v0 = o0 + g * (o0 - b[0]), v1 = o1 + g * (o1 - b[1]), v2 = o2 + g * (o2 - b[2]);
                o0 = v0 > 0.0f ? v0 : 0.0f;
                o1 = v1 > 0.0f ? v1 : 0.0f;
                o2 = v2 > 0.0f ? v2 : 0.0f;
            }
        }
        out[4 * x + 0] = o0;
        out[4 * x + 1] = o1;
        out[4 * x + 2] = o2;
        out[4 * x + 3] = s[3];
    }
}

void fv_dof_upsample_row_c(float *restrict dst, const float *tmp, int L, int sw, int x0, int n)
{
    /* pixel x's left texel j = floor((2x + 1 - s) / 2s) and weight a = ((2x + 1 - s) - 2s j) / 2s,
     * s = 2^L: the integer form of floor(u), u - floor(u) for u = (x + 0.5) / s - 0.5 (exact:
     * a has at most L + 1 fraction bits) */
    const int s2 = 2 << L;
    const float inv = 1.0f / (float)s2;
    for (int i = 0; i < n; i++) {
        const int m = 2 * (x0 + i) + 1 - (1 << L) + s2; /* + 2s: m >= 0, the shift floors */
        const int j = (m >> (L + 1)) - 1;
        const float a = (float)(m & (s2 - 1)) * inv;
        const float *p0 = tmp + 4 * (ptrdiff_t)fv_clampi(j, 0, sw - 1), *p1 = tmp + 4 * (ptrdiff_t)fv_clampi(j + 1, 0, sw - 1);
        for (int c = 0; c < 4; c++)
            dst[4 * i + c] = p0[c] + a * (p1[c] - p0[c]);
    }
}

void fv_dof_pyrblur_row_c(float *restrict blur, const struct fv_dof_pyrblur_args *a, int x0, int n)
{
    for (int i = x0; i < x0 + n; i++) {
        const float c = a->coc[i], t = a->t[i], m = c < 0.0f ? -c : c;
        if (!(m > 0.0f && t > 0.0f))
            continue;
        const int li = (int)(m * (float)a->lambda_steps);
        float l = a->lambda[li < a->lambda_max ? li : a->lambda_max];
        l = l < (float)a->need ? l : (float)a->need;
        const int L0 = (int)l, L1 = L0 < a->need ? L0 + 1 : L0;
        const float f = l - (float)L0, *u0 = a->up[L0] + 4 * i, *u1 = a->up[L1] + 4 * i;
        float *b = blur + 4 * i;
        /* far pixels in the transition blend into the centre's Gaussian already in blur */
        const int mix = c > 0.0f && t < 1.0f;
        for (int k = 0; k < 4; k++) {
            const float pv = u0[k] + f * (u1[k] - u0[k]);
            b[k] = mix ? b[k] + t * (pv - b[k]) : pv;
        }
    }
}

void fv_dof_nearblk_row_c(float *restrict sum, float *restrict ext, const float *coc, const float *rgbd, int n)
{
    for (int b = 0; 4 * b < n; b++) {
        float q[4][4] = {{0.0f}}, lo = ext[2 * b], hi = ext[2 * b + 1];
        for (int k = 0; k < 4 && 4 * b + k < n; k++) {
            const int i = 4 * b + k;
            const float c = coc[i];
            if (c < 0.0f)
                q[k][0] = rgbd[4 * i], q[k][1] = rgbd[4 * i + 1], q[k][2] = rgbd[4 * i + 2], q[k][3] = 1.0f;
            lo = c < lo ? c : lo;
            hi = c > hi ? c : hi;
        }
        for (int j = 0; j < 4; j++)
            sum[4 * b + j] += (q[0][j] + q[2][j]) + (q[1][j] + q[3][j]);
        ext[2 * b] = lo + 0.0f, ext[2 * b + 1] = hi + 0.0f;
    }
}

void fv_dof_nearbox_row_c(float *restrict out, float *restrict out_r, float *restrict out_w, const float *src,
                          const float *r, const float *wgt, int w, int x0, int n, int reach)
{
    for (int i = x0; i < x0 + n; i++) {
        float acc[4] = {0.0f, 0.0f, 0.0f, 0.0f}, rmax = 0.0f;
        const int jlo = i - reach > 0 ? -reach : -i, jhi = i + reach < w ? reach : w - 1 - i;
        for (int j = jlo; j <= jhi; j++) {
            const float rs = r[i + j];
            if (rs < (float)(j < 0 ? -j : j)) /* not near (-1), or does not reach */
                continue;
            const float ws = wgt[i + j], *p = src + 4 * (ptrdiff_t)(i + j);
            for (int c = 0; c < 4; c++)
                acc[c] += ws * p[c];
            rmax = rs > rmax ? rs : rmax;
        }
        for (int c = 0; c < 4; c++)
            out[4 * (ptrdiff_t)i + c] = acc[c];
        out_r[i] = rmax;
        out_w[i] = 1.0f / (2.0f * rmax + 1.0f);
    }
}

void fv_dof_hcoc_row_c(float *restrict hc, const float *ca, const float *cb, int n)
{
    for (int u = 0; u < n; u++)
        hc[u] = 0.25f * ((fabsf(ca[2 * u]) + fabsf(ca[2 * u + 1])) + (fabsf(cb[2 * u]) + fabsf(cb[2 * u + 1])));
}

void fv_dof_nearfin_row_c(float *restrict rad, float *restrict rb, float *restrict wgt, float *restrict sum,
                          const float *ext, int n, float inv)
{
    for (int i = 0; i < n; i++) {
        float r = floorf(-ext[2 * i] * 0.5f);
        r = r < (float)FV_DOF_RMAX ? r : (float)FV_DOF_RMAX;
        const float b = sum[4 * i + 3] > 0.0f ? floorf(r / 4.0f) : -1.0f;
        rad[i] = r, rb[i] = b;
        wgt[i] = 1.0f / (2.0f * (b > 0.0f ? b : 0.0f) + 1.0f);
        for (int k = 0; k < 4; k++)
            sum[4 * i + k] *= inv;
    }
}

void fv_dof_periph_row_c(float *restrict out, const float *sharp, const float *coc, const float *half,
                         const float *lnear, int x0, int n)
{
    for (int x = x0; x < x0 + n; x++) {
        const float *s = sharp + 4 * (ptrdiff_t)x, c = coc[x], m = c < 0.0f ? -c : c;
        const float *h0 = half + 4 * (ptrdiff_t)(x >> 1), *h1 = h0 + ((x & 1) ? 4 : -4);
        const float ab = m < 1.0f ? m : 1.0f, l = m * m * FV_DOF_L1_SLOPE, w = ab * (l < 1.0f ? l : 1.0f);
        float o[3];
        for (int k = 0; k < 3; k++) {
            const float u = 0.75f * h0[k] + 0.25f * h1[k];
            o[k] = w > 0.0f ? s[k] + w * (u - s[k]) : s[k];
        }
        if (lnear && !(c < 0.0f)) {
            const float *q = lnear + 4 * (ptrdiff_t)x;
            if (q[3] > 0.0f) {
                const float cov = q[3] < 1.0f ? q[3] : 1.0f;
                for (int k = 0; k < 3; k++)
                    o[k] = o[k] + cov * (q[k] / q[3] - o[k]);
            }
        }
        out[4 * (ptrdiff_t)x + 0] = o[0];
        out[4 * (ptrdiff_t)x + 1] = o[1];
        out[4 * (ptrdiff_t)x + 2] = o[2];
        out[4 * (ptrdiff_t)x + 3] = s[3];
    }
}

void fv_dof_dsp_init(fv_dof_dsp *d, unsigned isa_mask)
{
    const unsigned isas = isa_mask & fv_cpu_isas();
    d->dof_upsample_row = fv_dof_upsample_row_c;
    d->dof_pyrblur_row = fv_dof_pyrblur_row_c;
    d->dof_coc_row = fv_dof_coc_row_c;
    d->dof_hgauss_row = fv_dof_hgauss_row_c;
    d->dof_vgauss_row = fv_dof_vgauss_row_c;
    d->dof_combine_row = fv_dof_combine_row_c;
    d->dof_nearblk_row = fv_dof_nearblk_row_c;
    d->dof_nearbox_row = fv_dof_nearbox_row_c;
    d->dof_periph_row = fv_dof_periph_row_c;
    d->dof_hcoc_row = fv_dof_hcoc_row_c;
    d->dof_nearfin_row = fv_dof_nearfin_row_c;
#if defined(__x86_64__)
    if (isas & FV_ISA_SSE41)
        fv_dof_dsp_init_sse41(d);
    if (isas & FV_ISA_AVX2)
        fv_dof_dsp_init_avx2(d);
#elif defined(__aarch64__)
    if (isas & FV_ISA_NEON)
        fv_dof_dsp_init_neon(d);
#else
    (void)isas;
#endif
}
