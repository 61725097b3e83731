/* fovea: the temporal reprojection kernels' plain-C references (contracts in reproject_dsp.h):
 * the row loops are in reproject_tmpl.h, shared with every ISA version, which differ only in the
 * 4-channel texel accumulation below. Also the table's init. */
#include <math.h>
#include <stdint.h>

#include "reproject.h"
#include "reproject_dsp.h"
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

/* The still head in place (reproject.h): plain C, a few operations per sample (the projection
 * is the identity, the level-0 tap one saved texel). The level-0 single tap is tap() with
 * fx = fy = 0 (b00 = 1, the other three texels weigh +0), written out on the saved texel. */
void fv_taa_still_tile(const fv_taa_frame *f, const fv_taa_params *prm, const struct fv_sampler *smp, int gx, int gy,
                       const fv_pyr_level *l0, int x0, int y0, int tw, int th, const uint32_t *rows, float keep,
                       const fv_taa_still_hist *h)
{
    fv_taa_tile t;
    const float cx = (float)x0 + 0.5f * (float)tw, cy = (float)y0 + 0.5f * (float)th;
    fv_taa_tile_setup(&t, prm, fv_sampler_probability(smp, cx - (float)gx, cy - (float)gy) * keep, smp->prm.p_min,
                      smp->phases);
    if (t.alpha >= 1.0f)
        return; /* samples as traced (the blend's keep_sample), holes hold the history */
    int k = 0;
    for (int y = 0; y < th; y++) {
        float *row = l0->rgbd + 4 * ((ptrdiff_t)(y0 + y) * l0->stride + x0);
        const float py = (float)(y0 + y) + 0.5f;
        for (uint32_t r = rows[y]; r; r &= r - 1, k++) {
            const int i = __builtin_ctz(r);
            float *px = row + 4 * i;
            const float d = px[3], rz = 1.0f / d;
            float o;
            const int l = taa_footprint(f, (d * rz) * t.widen, &o);
            const float inv_tol = rz * f->inv_depth_tol;
            if (l > 0) { /* the history's coarser levels are not overwritten: the blend's taps */
                const taa_pending q = {px, (float)(x0 + i) + 0.5f, py, d, inv_tol, o, l};
                taa_taps(f, &t, &q);
                continue;
            }
            const float *c = h->rgbd[k];
            float a = 1.0f - fabsf(c[3] - d) * inv_tol;
            a = a > 0.0f ? a : 0.0f;
            const float w = h->wgt[k] * a;
            if (!(w > 0.0f))
                continue; /* no valid history: the sample stands alone */
            acc4 acc;
            for (int ch = 0; ch < 4; ch++)
                acc.c[ch] = 0.0f + w * c[ch];
            const float a1 = 1.0f - w;
            out_blend(px, acc, w, a1 > t.alpha ? a1 : t.alpha);
        }
    }
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
