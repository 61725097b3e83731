/* fovea: the output stage's kernel (one table per module; core/cpu.h has the pattern). C
 * reference: core/output_ref.c.
 *
 * rgb8_row: linear RGB floats to sRGB-encoded bytes through a table, for x in [0, n) and c in
 *   {r, g, b}: with v = rgbd[4x + c] (the 4th float, depth, is never read),
 *     i = v > 0 ? (v < 1 ? (int)(v * FV_SRGB_LUT + 0.5f) : FV_SRGB_LUT) : 0   (NaN: 0)
 *     dst[3x + c] = lut[i]
 *   lut holds FV_SRGB_LUT + 1 entries and must be readable FV_SRGB_LUT_PAD bytes past them
 *   (vector gathers read whole words). SSE4.1 and NEON give the reference's bytes for any
 *   table. AVX2 computes sRGB instead of reading the table, so it takes only the sRGB table of
 *   fv_srgb_lut_init: within 1 of the reference's bytes (measured over every float in
 *   [-1.5, 1.5]: 0.83 % of them differ, by 1), exactly 0 for v <= 0 or NaN, 255 for v >= 1.
 *
 * lca_row: one display row y with the lens's lateral chromatic aberration resampled (core/lens.h):
 *   for x in [0, g->w), with the pixel's panel point tx = tan_left + ((float)x + 0.5f) px_tan,
 *   ty = tan_top - ((float)y + 0.5f) px_tan, u = (tx - cx, ty - cy), r = sqrtf(ux ux + uy uy),
 *   f = min(r inv_step, STEPS), i = min((int)f, STEPS - 1), a = f - i, and per channel c in
 *   {red (table 0), blue (table 1)}: s = ratio[i] + a (ratio[i + 1] - ratio[i]), q = c + u s,
 *   the image's channel bilinear at pixel coordinates ((qx - tan_left) inv_px - 0.5,
 *   (tan_top - qy) inv_px - 0.5) (texel indices floorf'd and clamped to the image, each clamp
 *   as min(max(v, 0), n - 1) with NaN -> 0; a + ax (b - a) across, then down); green is the
 *   pixel's own; each channel through the table as rgb8_row's reference: dst[3x + c] =
 *   lut[fv_srgb_index(v)]. Reads any pixel of the image (w x h, stride pixels of 4 floats), the
 *   two ratio tables, lut[0, FV_SRGB_LUT + FV_SRGB_LUT_PAD]; writes dst[0, 3 w). Every ISA
 *   version gives the reference's bytes (the same IEEE operations in the same order, no FMA). */
#ifndef FOVEA_OUTPUT_DSP_H
#define FOVEA_OUTPUT_DSP_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "cpu.h"
#include "lens.h"

#define FV_SRGB_LUT 4096   /* steps of the linear [0, 1] -> sRGB table */
#define FV_SRGB_LUT_PAD 3  /* bytes past the last entry a gather may read */

typedef void (*fv_rgb8_row_fn)(uint8_t *restrict dst, const float *rgbd, int n, const uint8_t *lut);

/* the display's pixel grid in panel (tangent) units and the image lca_row samples */
typedef struct fv_lca_geom {
    float tan_left, tan_top, px_tan, inv_px; /* inv_px = 1 / px_tan */
    float cx, cy;                            /* the lens centre */
    const float *img;                        /* linear RGB + depth, 4 floats a pixel */
    ptrdiff_t stride;                        /* pixels */
    int w, h;
} fv_lca_geom;
typedef void (*fv_lca_row_fn)(uint8_t *restrict dst, int y, const fv_lca_geom *g, const fv_lens_lca *lca,
                              const uint8_t *lut);

typedef struct fv_output_dsp {
    fv_rgb8_row_fn rgb8_row;
    fv_lca_row_fn lca_row;
} fv_output_dsp;

void fv_output_dsp_init(fv_output_dsp *d, unsigned isa_mask);

/* The table the output stage uses: lut[i] = round(255 sRGB(i / FV_SRGB_LUT)), i in
 * [0, FV_SRGB_LUT], then FV_SRGB_LUT_PAD zero bytes. */
void fv_srgb_lut_init(uint8_t lut[FV_SRGB_LUT + 1 + FV_SRGB_LUT_PAD]);

/* ---- internal: reference and per-ISA fillers ---- */
void fv_rgb8_row_c(uint8_t *restrict dst, const float *rgbd, int n, const uint8_t *lut);
void fv_lca_row_c(uint8_t *restrict dst, int y, const fv_lca_geom *g, const fv_lens_lca *lca, const uint8_t *lut);
static inline int fv_srgb_index(float v)
{
    return v > 0.0f ? (v < 1.0f ? (int)(v * FV_SRGB_LUT + 0.5f) : FV_SRGB_LUT) : 0;
}
/* lca_row's pixel x (the ISA versions' tails) */
static inline float fv_lca_clamp(float v, float hi)
{
    v = v > 0.0f ? v : 0.0f; /* NaN -> 0, as fmaxf(v, 0) */
    return v < hi ? v : hi;
}
static inline float fv_lca_sample(const fv_lca_geom *g, float fx, float fy, int c)
{
    const float x0f = floorf(fx), y0f = floorf(fy), ax = fx - x0f, ay = fy - y0f;
    const float wm = (float)(g->w - 1), hm = (float)(g->h - 1);
    const int x0 = (int)fv_lca_clamp(x0f, wm), x1 = (int)fv_lca_clamp(x0f + 1.0f, wm);
    const int y0 = (int)fv_lca_clamp(y0f, hm), y1 = (int)fv_lca_clamp(y0f + 1.0f, hm);
    const float *r0 = g->img + 4 * (ptrdiff_t)y0 * g->stride, *r1 = g->img + 4 * (ptrdiff_t)y1 * g->stride;
    const float a = r0[4 * x0 + c] + ax * (r0[4 * x1 + c] - r0[4 * x0 + c]);
    const float b = r1[4 * x0 + c] + ax * (r1[4 * x1 + c] - r1[4 * x0 + c]);
    return a + ay * (b - a);
}
/* the pixel after its radius step: i, a of the ratio tables and ux, uy (the versions that
 * vectorise the radius and take the taps lane by lane) */
static inline void fv_lca_finish(uint8_t *o, int i, float a, float ux, float uy, const fv_lca_geom *g,
                                 const fv_lens_lca *lca, const float *own, const uint8_t *lut)
{
    for (int ch = 0; ch < 2; ch++) {
        const float *t = lca->ratio[ch], s = t[i] + a * (t[i + 1] - t[i]);
        const float qx = g->cx + ux * s, qy = g->cy + uy * s;
        const float v = fv_lca_sample(g, (qx - g->tan_left) * g->inv_px - 0.5f, (g->tan_top - qy) * g->inv_px - 0.5f, ch ? 2 : 0);
        o[ch ? 2 : 0] = lut[fv_srgb_index(v)];
    }
    o[1] = lut[fv_srgb_index(own[1])];
}
static inline void fv_lca_pixel(uint8_t *o, int x, float ty, const fv_lca_geom *g, const fv_lens_lca *lca,
                                const float *own, const uint8_t *lut)
{
    const float tx = g->tan_left + ((float)x + 0.5f) * g->px_tan, ux = tx - g->cx, uy = ty - g->cy;
    float f = sqrtf(ux * ux + uy * uy) * lca->inv_step;
    f = f < (float)FV_LENS_LCA_STEPS ? f : (float)FV_LENS_LCA_STEPS;
    int i = (int)f;
    i = i < FV_LENS_LCA_STEPS ? i : FV_LENS_LCA_STEPS - 1;
    fv_lca_finish(o, i, f - (float)i, ux, uy, g, lca, own, lut);
}
#if defined(__x86_64__)
void fv_output_dsp_init_sse41(fv_output_dsp *d);
void fv_output_dsp_init_avx2(fv_output_dsp *d);
#elif defined(__aarch64__)
void fv_output_dsp_init_neon(fv_output_dsp *d);
#endif

#endif
