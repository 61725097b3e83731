/* fovea: the temporal reprojection kernels (one table per module, dav1d style; core/cpu.h has
 * the pattern and the contract every ISA version keeps). C references: core/reproject_ref.c,
 * with the row loops every ISA shares in core/reproject_tmpl.h. */
#ifndef FOVEA_REPROJECT_DSP_H
#define FOVEA_REPROJECT_DSP_H

#include <stddef.h>
#include <stdint.h>

#include "cpu.h"

/* Temporal reprojection (core/reproject.h has the model), on a block of level 0: pixels
 * x0 .. x0+w-1 (w <= 64) of rows y0 .. y0+h-1; rgbd / wgt point at pixel (x0, y0), rows are
 * stride pixels apart. One call per tile, so the per-call set-up is paid once.
 * taa_blend: every pixel with weight 1 (a sample) is blended with its reprojected history (none
 *   is when the tile's alpha >= 1: the samples come back bit for bit); the sums of its flow to
 *   the previous frame are added to *flow in row-major pixel order. Other pixels untouched.
 * taa_fill: every pixel with weight 0 (a hole) takes valid history, if any: colour, depth in
 *   this frame's view, weight = the history's confidence in (0, 1]. Others untouched.
 * Both read the history pyramid only at texels [-1, w] x [-1, h] of a level (its border).
 * Every ISA version gives the reference's bits: the SIMD blends (eight samples a step with AVX2,
 * four with SSE4.1 and NEON) do each lane's operations in the reference's order (no FMA, no
 * reciprocal estimates; selects where vmax would treat NaN differently), add the flow sums in
 * sample order, and hand footprints wider than one texel to the shared scalar taps
 * (core/reproject_tmpl.h). Bound: 0 ulp, checked by tests/checkasm/reproject.c. */
struct fv_taa_frame;
struct fv_taa_tile;
struct fv_taa_flow;
typedef void (*fv_taa_blend_fn)(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd,
                                const float *wgt, ptrdiff_t stride, int x0, int y0, int w, int h,
                                struct fv_taa_flow *flow);
typedef void (*fv_taa_fill_fn)(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, float *wgt,
                               ptrdiff_t stride, int x0, int y0, int w, int h);
/* taa_still: the still head's level-0 blend (reproject.h, fv_taa_still_*) of n samples held in
 *   planes `plane` floats apart (SoA): s = the samples' r, g, b, depth (r, g, b rewritten where
 *   blended), h = their saved history texels' r, g, b, depth, weight. Per sample k:
 *     rz = 1 / depth, fp = (depth rz) widen
 *     fp >= 2: wide[k] = 1, sample untouched (its footprint reads coarser levels: the caller's taps)
 *     else wide[k] = 0; a = max(0, 1 - |h.depth - depth| (rz inv_depth_tol)), w = h.weight a;
 *       where w > 0: al = max(1 - w, alpha), hc = (0 + w h.c) / w, s.c = hc + al (s.c - hc)
 *   (the blend's single level-0 tap with fx = fy = 0). Bound: 0 ulp (the ops in this order, no
 *   FMA, no reciprocal estimate; core/reproject_still_lane.h is the reference lane). */
typedef void (*fv_taa_still_fn)(float *s, const float *h, ptrdiff_t plane, int n, float widen, float alpha,
                                float inv_depth_tol, uint8_t *wide);
/* taa_aa: the fovea's anti-aliasing of one tile (reproject.h, fv_taa_aa_*; tw, th <= 16):
 *   accumulates an eligible tile's jittered samples (level 0 at (x0, y0), all weight 1) with its
 *   history; f NULL or a->n_prev NULL (no history yet): the samples stay as traced with count 1.
 *   Writes the tile's counts. Bound: 0 ulp (each pixel's r, g, b, depth one vector, the
 *   reference's ops in its order; core/reproject_aa_tmpl.h). */
struct fv_taa_aa_frame;
struct fv_pyr_level;
typedef void (*fv_taa_aa_fn)(const struct fv_taa_frame *f, const struct fv_taa_aa_frame *a,
                             const struct fv_pyr_level *l0, int x0, int y0, int tw, int th);
typedef struct fv_reproject_dsp {
    fv_taa_blend_fn taa_blend;
    fv_taa_fill_fn taa_fill;
    fv_taa_still_fn taa_still;
    fv_taa_aa_fn taa_aa;
} fv_reproject_dsp;

/* Fills d with the best kernels allowed by isa_mask & fv_cpu_isas() (FV_ISA_C: the references);
 * every allowed ISA overwrites the entries it implements, lowest first. */
void fv_reproject_dsp_init(fv_reproject_dsp *d, unsigned isa_mask);

/* ---- internal: references and per-ISA fillers (each sets every entry it has) ---- */
void fv_taa_blend_c(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, const float *wgt,
                    ptrdiff_t stride, int x0, int y0, int w, int h, struct fv_taa_flow *flow);
void fv_taa_fill_c(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, float *wgt,
                   ptrdiff_t stride, int x0, int y0, int w, int h);
void fv_taa_still_c(float *s, const float *h, ptrdiff_t plane, int n, float widen, float alpha, float inv_depth_tol,
                    uint8_t *wide);
void fv_taa_aa_tile_c(const struct fv_taa_frame *f, const struct fv_taa_aa_frame *a, const struct fv_pyr_level *l0,
                      int x0, int y0, int tw, int th);
#if defined(__x86_64__)
void fv_taa_aa_tile_sse41(const struct fv_taa_frame *f, const struct fv_taa_aa_frame *a,
                          const struct fv_pyr_level *l0, int x0, int y0, int tw, int th);
void fv_taa_aa_tile_avx2(const struct fv_taa_frame *f, const struct fv_taa_aa_frame *a, const struct fv_pyr_level *l0,
                         int x0, int y0, int tw, int th);
void fv_reproject_dsp_init_sse41(fv_reproject_dsp *d);
void fv_reproject_dsp_init_avx2(fv_reproject_dsp *d);
#elif defined(__aarch64__)
void fv_taa_aa_tile_neon(const struct fv_taa_frame *f, const struct fv_taa_aa_frame *a, const struct fv_pyr_level *l0,
                         int x0, int y0, int tw, int th);
void fv_reproject_dsp_init_neon(fv_reproject_dsp *d);
#endif

#endif
