/* fovea: depth-of-field-driven sampling (issue 15 item 4; Liu et al.'s "Russian roulette on the
 * DoF sampling distribution", eq. (10)-(11), with a density that falls with the CoC's area
 * instead of Liu's depth-linear eq. (10)).
 *
 * Per tile, after the acuity sampler has set its bits and before the rays are cast, every set
 * bit survives with a keep-probability q, so a pixel the DoF filter will blur over a CoC of
 * c pixels is sampled at density
 *     d(c) = min(p, max(d(c_cap), 1 / ((min(c, c_cap) / kappa)^2 + 1/3))),   q = d / p,
 * p the acuity model's probability (fv_sampler_probability) at the 4x4 block's pixel farthest
 * from the gaze (the block's lowest p). With kappa = 2 (default), 1 / d is the texel area 4^L
 * of the pyramid level L the layered filter reads at that CoC (core/dof/weier.c matches the
 * level's variance (3 4^L - 1) / 12 to the disc's c^2 / 16, so 4^L = c^2 / 4 + 1/3; sigma =
 * c / 4 in the fovea's Gaussian is that level's blur too): one sample per texel the filter
 * reads, never fewer than the filter's largest CoC c_cap needs, never more than the acuity
 * sampler gives. CoCs up to kappa sqrt(1/p - 1/3) (d(c) >= p) keep every acuity sample: the
 * in-focus part of the fovea (c <= 1.63 px at kappa 2) stays fully sampled, its blurred part and
 * the transition ring are thinned like the periphery (c > 4.3 px there at p_min 0.2).
 *
 * The expected CoC comes before the frame is traced: the previous frame's reconstructed depth
 * (the reprojection history, level FV_DOFSAMP_LEVEL, mapped to this view through the tile's flow
 * and the inverse camera mapping) and the focus the eye can have this frame: between last frame's
 * accommodated focus and last frame's target (the eye accommodates from one towards the other),
 * widened by Weier's tracking tolerance t. c is Weier's eq. (3), which simplifies to
 * c = k_m focal_px e_scale |1/d_bound - 1/g| (docs/dof.md): the smallest CoC of the models (the
 * others have no tolerance band), so no model blurs less than assumed. The CoC of each 4x4
 * block is the smallest over its 3x3 texel neighbourhood, so a misregistered depth edge keeps
 * the in-focus side dense.
 *
 * The roulette (eq. (11): keep when eps < q) draws eps per pixel and frame, the same bytes for
 * any thread count, a different subset every frame (the history accumulates them), always an
 * even dither (no clumps, no holes): in Weier's periphery (S_out, outside r1) eps is the
 * pixel's rank in S_out's lattice dither (fv_sampler_lattice / p_min), elsewhere (the fovea, the
 * transition's Halton points, Liu's pattern) the R2 lattice's value at the pixel; both shifted
 * by the frame times the golden ratio. Kept samples keep weight 1: pull-push normalises its
 * weights (so the kept set's expected weight per acuity sample, q / q, is unbiased) and the
 * reprojection's blend recognises samples by weight 1; each tile reports its mean keep
 * probability instead, for the reprojection's history density. Pure: no OS calls. */
#ifndef FOVEA_SAMPLING_DOF_H
#define FOVEA_SAMPLING_DOF_H

#include <stddef.h>
#include <stdint.h>

#include "reproject.h"
#include "sampling.h"

/* The history level the CoC is read from: 4x4-pixel texels, thinned per 4x4 block. */
#define FV_DOFSAMP_LEVEL 2

typedef struct fv_dofsamp_params {
    int enabled;     /* --dof-sampling on|off: default 1 (acts only with DoF on and a history) */
    float kappa;     /* the density's CoC scale, default 2: one sample per texel of the pyramid level
                      * the filter reads (1 / d = (c / kappa)^2 + 1/3); larger: denser */
    float coc_cap_px; /* the largest CoC the filter applies (Weier: far sigma 8 px = c / 4), 32 */
} fv_dofsamp_params;

void fv_dofsamp_params_default(fv_dofsamp_params *p);

/* One eye's frame: what every tile reads. */
typedef struct fv_dofsamp_frame {
    const fv_taa_frame *taa;   /* the history and the camera mappings */
    const fv_sampler *smp;     /* the acuity sampler in force */
    int gx, gy;                /* its point of regard, pixels */
    float lo_dpt, hi_dpt;      /* dioptres seen sharp: [1 / (far + t), 1 / (near - t)] */
    float px_per_dpt;          /* CoC pixels per dioptre of defocus: k_m focal_px e_scale */
    float kappa, coc_cap_px;
    uint32_t seed;             /* the frame number, hashed with each pixel */
    int phase;                 /* the sampler's pattern phase this frame (fv_sampler_row) */
    float *map;                /* defocus (dioptres outside the sharp band) of every history texel
                                * of level map_level, border included: map_w x map_h */
    int map_w, map_h, map_level;
} fv_dofsamp_frame;

/* focus_a_m, focus_b_m: the focus range the eye can have this frame (either order);
 * tolerance_m: Weier's t; px_per_dpt: k_m focal_px e_scale; frame: the eye's frame number;
 * phase: the sampler's pattern phase. */
void fv_dofsamp_frame_setup(fv_dofsamp_frame *f, const fv_dofsamp_params *prm, const fv_taa_frame *taa,
                            const fv_sampler *smp, int gx, int gy, float focus_a_m, float focus_b_m,
                            float tolerance_m, float px_per_dpt, uint32_t frame, int phase);

/* The expected CoC diameter in pixels at view depth depth_m (>= 0: the magnitude). */
float fv_dofsamp_coc_px(const fv_dofsamp_frame *f, float depth_m);
/* The sampling density the DoF needs at CoC c_px: 1 / ((min(c, c_cap) / kappa)^2 + 1/3), at
 * most 1. */
float fv_dofsamp_density(const fv_dofsamp_frame *f, float c_px);
/* The keep-probability of an acuity sample of probability p at CoC c_px: min(1, density / p). */
float fv_dofsamp_keep(const fv_dofsamp_frame *f, float p, float c_px);

/* The defocus map: computed once per frame from the history (sequential reads; the tiles then
 * read 6 x 6 of it from cache instead of missing on the history six times each).
 * fv_dofsamp_map_len: floats it needs for this history; attach: the buffer (after setup); rows:
 * fills map rows [j0, j1) (0 .. map_h; any split, e.g. bands over a pool). Then the tiles. */
size_t fv_dofsamp_map_len(const fv_pyramid *hist);
void fv_dofsamp_map_attach(fv_dofsamp_frame *f, float *map);
void fv_dofsamp_map_rows(const fv_dofsamp_frame *f, int j0, int j1);

/* Thins the tile [x0, x0+tw) x [y0, y0+th) (tw, th <= 16): bit x of rows[y] (pixel x0+x, y0+y)
 * survives when hash < q 2^32. Returns the tile's mean keep-probability over its pixels
 * (1 when nothing is thinned). */
float fv_dofsamp_tile(const fv_dofsamp_frame *f, int x0, int y0, int tw, int th, uint32_t rows[16]);

#endif
