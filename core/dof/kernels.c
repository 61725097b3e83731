/* fovea: plain-C reference kernels of the layered depth-of-field filter (core/dof/weier.c).
 * The hand-vectorised versions (core/x86/dof_*.c, core/arm/dof_neon.c) give the same bits: the
 * 4-channel sums below are written channel by channel in the order the vector code adds. */
#include <math.h>

#include "dof/weier_impl.h"
#include "dsp.h"

static inline int clampi(int v, int lo, int hi) { return v < lo ? lo : v > hi ? hi : v; }

void fv_dof_coc_row_c(float *restrict coc, const float *rgbd, int n, float K, float dn, float df)
{
    const float inv_dn = 1.0f / dn, inv_df = 1.0f / df;
    for (int x = 0; x < n; x++) {
        const float g = rgbd[4 * x + 3] > FV_DOF_MIN_DEPTH_M ? rgbd[4 * x + 3] : FV_DOF_MIN_DEPTH_M;
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
            const int q = clampi(x + j, 0, w - 1);
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
            const float *p = src + 4 * ((ptrdiff_t)clampi(y + j, ylo, yhi - 1) * stride + x);
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

/* Five quincunx taps (or one when the offset is under 1/8 px) of the blur of diameter c. */
static void quincunx(const fv_pyramid *pyr, float c, float fx, float fy, float q[4])
{
    int L;
    float o;
    fv_dof_footprint(c, pyr->levels - 1, &L, &o);
    const fv_pyr_level *lv = &pyr->lv[L];
    q[0] = q[1] = q[2] = q[3] = 0.0f;
    fv_dof_tap_c(lv, L, fx, fy, q);
    if (o >= 0.125f) {
        fv_dof_tap_c(lv, L, fx - o, fy - o, q);
        fv_dof_tap_c(lv, L, fx + o, fy - o, q);
        fv_dof_tap_c(lv, L, fx - o, fy + o, q);
        fv_dof_tap_c(lv, L, fx + o, fy + o, q);
        for (int k = 0; k < 4; k++)
            q[k] *= 0.2f;
    }
}

void fv_dof_combine_row_c(float *restrict out, const struct fv_dof_combine_args *a, int x0, int n)
{
    const float fy = (float)a->y + 0.5f, dy = fy - a->gy;
    for (int x = x0; x < x0 + n; x++) {
        const float *s = a->sharp + 4 * x;
        float o[3] = {s[0], s[1], s[2]};
        const float c = a->coc[x], fx = (float)x + 0.5f, dx = fx - a->gx;
        const float ecc = sqrtf(dx * dx + dy * dy);
        float t = (ecc - a->r0) * a->inv_tr;
        t = t > 0.0f ? (t < 1.0f ? t : 1.0f) : 0.0f;
        if (c > 0.0f) {
            float f[3] = {0.0f, 0.0f, 0.0f}, q[4];
            if (t < 1.0f && a->far && x >= a->far_x0 && x < a->far_x1 && a->far[4 * x + 3] > 0.0f) {
                const float *p = a->far + 4 * x;
                for (int k = 0; k < 3; k++)
                    f[k] = p[k] / p[3];
            }
            if (t > 0.0f) {
                quincunx(a->pyr, c, fx, fy, q);
                for (int k = 0; k < 3; k++)
                    f[k] = f[k] + t * (q[k] - f[k]);
            }
            const float af = c < 1.0f ? c : 1.0f;
            for (int k = 0; k < 3; k++)
                o[k] = o[k] + af * (f[k] - o[k]);
        }
        if (a->has_near && a->near[4 * x + 3] > 0.0f) {
            const float *p = a->near + 4 * x;
            const float cov = p[3] < 1.0f ? p[3] : 1.0f;
            for (int k = 0; k < 3; k++)
                o[k] = o[k] + cov * (p[k] / p[3] - o[k]);
        }
        if (a->enh && t > 0.0f) {
            const float *b = a->enh + 4 * x, gt = a->gain * t;
            for (int k = 0; k < 3; k++) {
                const float v = o[k] + gt * (o[k] - b[k]);
                o[k] = v > 0.0f ? v : 0.0f;
            }
        }
        out[4 * x + 0] = o[0];
        out[4 * x + 1] = o[1];
        out[4 * x + 2] = o[2];
        out[4 * x + 3] = s[3];
    }
}

void fv_dof_init_c(fv_dsp *d)
{
    d->dof_coc_row = fv_dof_coc_row_c;
    d->dof_hgauss_row = fv_dof_hgauss_row_c;
    d->dof_vgauss_row = fv_dof_vgauss_row_c;
    d->dof_combine_row = fv_dof_combine_row_c;
}
