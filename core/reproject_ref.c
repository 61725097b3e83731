/* fovea: the temporal reprojection kernels' plain-C references (contracts in reproject_dsp.h):
 * the row loops are in reproject_tmpl.h, shared with every ISA version, which differ only in the
 * 4-channel texel accumulation below. Also the table's init. */
#include <math.h>
#include <stdint.h>

#include "reproject.h"
#include "reproject_dsp.h"
#include "reproject_still_lane.h"
#include "sampling.h"

typedef struct {
    float c[4];
} acc4;

static inline acc4 acc_zero(void)
{
    acc4 a = {{0.0f, 0.0f, 0.0f, 0.0f}};
    return a;
}

static inline void tap(const fv_pyr_level *L, float s, float t, float zexp, float inv_tol, acc4 *acc, float *accw)
{
    const float fs = floorf(s), ft = floorf(t);
    const int i = (int)fs, j = (int)ft;
    const float fx = s - fs, fy = t - ft, omx = 1.0f - fx, omy = 1.0f - fy;
    const ptrdiff_t o00 = (ptrdiff_t)j * L->stride + i, o01 = o00 + L->stride;
    const float *c00 = L->rgbd + 4 * o00, *c10 = c00 + 4, *c01 = L->rgbd + 4 * o01, *c11 = c01 + 4;
    const float b00 = omx * omy, b01 = omx * fy, b10 = fx * omy, b11 = fx * fy;
    float a00 = 1.0f - fabsf(c00[3] - zexp) * inv_tol, a01 = 1.0f - fabsf(c01[3] - zexp) * inv_tol;
    float a10 = 1.0f - fabsf(c10[3] - zexp) * inv_tol, a11 = 1.0f - fabsf(c11[3] - zexp) * inv_tol;
    a00 = a00 > 0.0f ? a00 : 0.0f;
    a01 = a01 > 0.0f ? a01 : 0.0f;
    a10 = a10 > 0.0f ? a10 : 0.0f;
    a11 = a11 > 0.0f ? a11 : 0.0f;
    const float w00 = (b00 * L->wgt[o00]) * a00, w01 = (b01 * L->wgt[o01]) * a01;
    const float w10 = (b10 * L->wgt[o00 + 1]) * a10, w11 = (b11 * L->wgt[o01 + 1]) * a11;
    for (int c = 0; c < 4; c++)
        acc->c[c] = acc->c[c] + ((w00 * c00[c] + w01 * c01[c]) + (w10 * c10[c] + w11 * c11[c]));
    *accw = *accw + ((w00 + w01) + (w10 + w11));
}

static inline void out_blend(float *px, acc4 acc, float accw, float alpha)
{
    for (int c = 0; c < 3; c++) {
        const float h = acc.c[c] / accw;
        px[c] = h + alpha * (px[c] - h);
    }
}

static inline uint64_t sample_mask(const float *wgt, int n)
{
    uint64_t m = 0;
    for (int i = 0; i < n; i++)
        m |= (uint64_t)(wgt[i] == 1.0f) << i;
    return m;
}

#define TAA_FN(name) name##_c
#include "reproject_tmpl.h"

void fv_taa_blend_c(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, const float *wgt,
                    ptrdiff_t stride, int x0, int y0, int w, int h, struct fv_taa_flow *flow)
{
    taa_blend_c(f, t, rgbd, wgt, stride, x0, y0, w, h, flow);
}

/* The still head in place (reproject.h): the tile's samples gathered into planes for the
 * taa_still kernel (level-0 footprints, nearly all), the rest through the blend's scalar taps on
 * the history's coarser levels, which no tile overwrites. */
void fv_taa_still_tile(const fv_taa_frame *f, const fv_taa_params *prm, const struct fv_sampler *smp, int gx, int gy,
                       const fv_pyr_level *l0, const fv_reproject_dsp *dsp, int x0, int y0, int tw, int th,
                       const uint32_t *rows, float keep, const fv_taa_still_hist *h)
{
    fv_taa_tile t;
    const float cx = (float)x0 + 0.5f * (float)tw, cy = (float)y0 + 0.5f * (float)th;
    fv_taa_tile_setup(&t, prm, fv_sampler_probability(smp, cx - (float)gx, cy - (float)gy) * keep, smp->prm.p_min,
                      smp->phases);
    if (t.alpha >= 1.0f)
        return; /* samples as traced (the blend's keep_sample), holes hold the history */
    enum { P = FV_TAA_STILL_MAX_PX };
    float s[4][P];
    float *px[P];
    uint8_t wide[P], xy[P][2];
    int n = 0;
    for (int y = 0; y < th; y++) {
        float *row = l0->rgbd + 4 * ((ptrdiff_t)(y0 + y) * l0->stride + x0);
        for (uint32_t r = rows[y]; r; r &= r - 1, n++) {
            const int i = __builtin_ctz(r);
            float *p = px[n] = row + 4 * i;
            xy[n][0] = (uint8_t)i, xy[n][1] = (uint8_t)y;
            s[0][n] = p[0], s[1][n] = p[1], s[2][n] = p[2], s[3][n] = p[3];
        }
    }
    dsp->taa_still(&s[0][0], &h->h[0][0], P, n, t.widen, t.alpha, f->inv_depth_tol, wide);
    for (int k = 0; k < n; k++) {
        float *p = px[k];
        if (!wide[k]) {
            p[0] = s[0][k], p[1] = s[1][k], p[2] = s[2][k];
            continue;
        }
        /* a footprint of two texels or more: the blend's taps (the coarser levels are the
         * history's); a one-level pyramid has none, its single texel is the saved one */
        const float d = p[3], rz = 1.0f / d;
        float o;
        const int l = taa_footprint(f, (d * rz) * t.widen, &o);
        if (l == 0) {
            uint8_t unused;
            float one[4][1] = {{p[0]}, {p[1]}, {p[2]}, {d}}, hk[5][1];
            for (int c = 0; c < 5; c++)
                hk[c][0] = h->h[c][k];
            fv_taa_still_c(&one[0][0], &hk[0][0], 1, 1, 1.0f, t.alpha, f->inv_depth_tol, &unused);
            p[0] = one[0][0], p[1] = one[1][0], p[2] = one[2][0];
            continue;
        }
        const taa_pending q = {p, (float)(x0 + xy[k][0]) + 0.5f, (float)(y0 + xy[k][1]) + 0.5f, d,
                               rz * f->inv_depth_tol, o, l};
        taa_taps(f, &t, &q);
    }
}

void fv_taa_still_c(float *s, const float *h, ptrdiff_t plane, int n, float widen, float alpha, float inv_depth_tol,
                    uint8_t *wide)
{
    for (int k = 0; k < n; k++)
        taa_still_lane(s, h, plane, k, widen, alpha, inv_depth_tol, wide);
}

/* no vector body: the scalar form does every pixel */
static inline int no_vec(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, float *wgt,
                         const float *hrow, const float *hw, const float B[3], int x0, float py, int ilo, int ihi)
{
    (void)f, (void)t, (void)rgbd, (void)wgt, (void)hrow, (void)hw, (void)B, (void)x0, (void)py, (void)ihi;
    return ilo;
}
TAA_FILL_BLOCK(fill_c, no_vec)

void fv_taa_fill_c(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, float *wgt,
                   ptrdiff_t stride, int x0, int y0, int w, int h)
{
    fill_c(f, t, rgbd, wgt, stride, x0, y0, w, h);
}

void fv_reproject_dsp_init(fv_reproject_dsp *d, unsigned isa_mask)
{
    const unsigned isas = isa_mask & fv_cpu_isas();
    d->taa_blend = fv_taa_blend_c;
    d->taa_fill = fv_taa_fill_c;
    d->taa_still = fv_taa_still_c;
    d->taa_aa = fv_taa_aa_tile_c;
#if defined(__x86_64__)
    if (isas & FV_ISA_SSE41)
        fv_reproject_dsp_init_sse41(d);
    if (isas & FV_ISA_AVX2)
        fv_reproject_dsp_init_avx2(d);
#elif defined(__aarch64__)
    if (isas & FV_ISA_NEON)
        fv_reproject_dsp_init_neon(d);
#else
    (void)isas;
#endif
}
