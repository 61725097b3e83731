/* fovea: temporal reprojection (TAA) of the previous frame's reconstruction pyramid
 * (Weier et al. 2018 §3.1; disocclusion rejection after Yang et al. 2009).
 *
 * Runs inside each ray-casting tile, after its samples are shaded and before the tile pulls
 * itself up the pyramid (the tile driver, core/tile.c), so the tile is still in cache:
 *   1. blend: every sample cast this frame is moved to world space with its depth, projected
 *      into the previous frame, and blended with the previous pyramid read over the sample's
 *      footprint (ray differential: d / z' previous pixels, widened by 1/sqrt of the local
 *      density of the history) at the matching level, with five quincunx taps when the
 *      footprint is wider than a texel (one tap otherwise). Each texel of a tap counts with its
 *      bilinear weight x its confidence (pyramid weight) x its depth agreement
 *      max(0, 1 - |d_texel - z'| / (tol z')), so history from another surface is rejected
 *      texel by texel. With H = the mean confidence of the taps, the new sample's weight is
 *      max(alpha, 1 - H): alpha is the user minimum per frame of history, compounded over the
 *      frames between two samples of a pixel (1 - (1 - alpha_min)^(1/rate)).
 *   2. fill: a pixel without a new sample takes the previous frame's texel at the tile's mean
 *      sample flow (rounded to whole pixels, so a row reads one contiguous run of history),
 *      kept only if that texel's own world point reprojects to within half a pixel of the
 *      pixel's centre (so disoccluded pixels are left to pull-push, and repeated fills never
 *      blur); its confidence becomes the pixel's pull-push weight and its depth is converted to
 *      this frame's view.
 * With a rotating sampling pattern (fv_sampling_params.rotate) the history of a static scene
 * converges to a sample at every pixel.
 *
 * Coordinates: continuous pixel coordinates with pixel (x, y) covering [x, x+1) x [y, y+1)
 * (centre x + 0.5); a camera maps (px, py, view depth d) to the world point
 * eye + d * dir(px, py), dir with a view-axis component of 1 (fv_camera_ray). */
#ifndef FOVEA_REPROJECT_H
#define FOVEA_REPROJECT_H

#include <stdint.h>

#include "camera.h"
#include "pullpush.h"
#include "reproject_dsp.h"

typedef struct fv_taa_params {
    int enabled;     /* default 1 (foveated rendering only) */
    float alpha_min; /* minimum weight of a new sample per frame of history, default 0.3 */
    float depth_tol; /* relative depth tolerance of history texels, default 0.03 */
    int fill;        /* fill pixels without a sample from valid history, default 1 */
    int fovea_aa;    /* anti-aliasing in the fovea (jittered rays accumulated), default 1 */
    int in_place;    /* head still (identical cameras): render over the history's level 0 in place
                      * instead of copying it (fv_taa_still_*), default 1 */
} fv_taa_params;

void fv_taa_params_default(fv_taa_params *p);

/* Per-frame constants of the kernels. (U, V, Z) = T + d * (M0 + px * MX + py * MY) gives the
 * previous frame's pixel (U / Z, V / Z) and view depth Z of the current pixel (px, py) at view
 * depth d; the N matrices map back (previous pixel and depth -> current). */
typedef struct fv_taa_frame {
    const fv_pyramid *hist; /* the previous frame's filled pyramid */
    float T[3], M0[3], MX[3], MY[3];
    float T2[3], N0[3], NX[3], NY[3];
    float prev_w, prev_h;   /* previous level-0 size */
    float inv_depth_tol;    /* 1 / relative depth tolerance */
    int max_level;          /* coarsest pyramid level a footprint may read */
    int identity;           /* the cameras are equal: the mapping is exactly the identity */
    /* The cameras' lens (fv_taa_frame_set_lens), NULL = none. With it, the rows above map pinhole
     * coordinates (fv_lens_map): pixel p's ray is the pinhole ray of F(p), and a previous pinhole
     * point Q is previous pixel F^-1(Q). The kernels never read it: fv_taa_tile_run hands them a
     * per-tile frame whose rows fold the lens in (core/reproject_lens.c). */
    const fv_lens_map *lens;
} fv_taa_frame;

/* Per-tile constants. */
typedef struct fv_taa_tile {
    float widen;          /* footprint scale 1/sqrt(history density), >= 1 */
    float alpha;          /* minimum weight of a new sample in this tile (>= 1: samples kept as traced) */
    int flow_x, flow_y;   /* fill: the history texel of pixel (x, y) is (x + flow_x, y + flow_y) */
} fv_taa_tile;

/* Sums a blend row reports for the tile's mean flow. */
typedef struct fv_taa_flow {
    float dx, dy; /* sums of (U/Z - px), (V/Z - py) over samples that hit the previous image */
    float n;
} fv_taa_flow;

void fv_taa_frame_setup(fv_taa_frame *f, const fv_camera *cur, const fv_camera *prev, const fv_pyramid *hist,
                        float depth_tol);

/* ---- with a lens (core/reproject_lens.c) ----
 * Both cameras must have the lens that m was built from (fv_lens_map_init; same size, frustum and
 * profile, as the pipeline's eyes always have). An identity frame stays the identity (pixel to the
 * same pixel, lens or not) and keeps lens NULL. fv_taa_project then maps exactly: F, the rows, F^-1.
 * The kernels get, per tile, the lens linearised around the tile: F at the tile centre p0 and F^-1
 * at p0's projection (at fv_taa_lens_tile_depth) for the blend; for the fill, F at the
 * tile centre moved by the tile's flow and F^-1 at its projection. Affine maps before the rows and
 * after the division fold into the rows, so a tile's map is again (U, V, Z) = T + d (M0 + px MX + py
 * MY) and the kernels run unchanged. Error against the exact map: second order in the distance to
 * the linearisation point, first order in the motion (an identity motion is exact):
 * FV_TAA_LENS_ERR_PX over 16 x 16 tiles of a 1280 x 1440 eye with the example profile, the head
 * turning 30 deg/s for one or two 90 Hz frames and moving 2 mm sideways a frame, tiles with depths
 * 0.7 .. 50 m (measured, blend / fill rows: 0.016 / 0.019 px for one frame, 0.033 / 0.040 px for
 * two; tests/test_lens_reproject.c checks every pixel). */
#define FV_TAA_LENS_ERR_PX 0.05f
void fv_taa_frame_set_lens(fv_taa_frame *f, const fv_lens_map *m);
/* The depth a tile's map is linearised at: the harmonic mean of the depths of the samples (weight
 * 1) among pixels (1 + 4i, 1 + 4j) of the tile [x0, x0+tw) x [y0, y0+th) of level 0; 1000 m (a miss)
 * when none. */
float fv_taa_lens_tile_depth(const fv_pyr_level *l0, int x0, int y0, int tw, int th);
/* The blend's tile frame t: f's lens folded into the rows around current pixel (cx, cy) at view
 * depth d_m. */
void fv_taa_lens_tile_blend(const fv_taa_frame *f, fv_taa_frame *t, float cx, float cy, float d_m);
/* The fill's rows of t (T2, N*) around previous pixel (hx, hy) at previous view depth d_m. */
void fv_taa_lens_tile_fill(const fv_taa_frame *f, fv_taa_frame *t, float hx, float hy, float d_m);

/* Tile constants from the acuity model's sampling probability p at the tile (per frame) and the
 * pattern's phase count K: a rotating pattern samples a pixel every 1/p frames and its history
 * holds min(1, K p) of the pixels; a static one samples the same pixels every frame. */
void fv_taa_tile_setup(fv_taa_tile *t, const fv_taa_params *prm, float p, float p_min, int phases);

/* Reprojects one tile [x0, x0+tw) x [y0, y0+th) of the current level 0 (samples written, holes
 * at weight 0): tile constants from the acuity model at the tile centre (gaze at pixel gx, gy),
 * the blend row by row, then the fill at the tile's mean sample flow (rounded; where no sample
 * reached the previous image, the flow of a far point at the tile centre). */
struct fv_sampler;
void fv_taa_tile_run(const fv_taa_frame *f, const fv_taa_params *prm, const struct fv_sampler *smp, int gx, int gy,
                     const fv_pyr_level *l0, const fv_reproject_dsp *dsp, int x0, int y0, int tw, int th);
/* The same for a tile whose samples were thinned to a share `keep` of the acuity sampler's
 * (DoF-driven sampling, core/sampling_dof.h): the tile's sampling probability is p * keep. */
void fv_taa_tile_run_keep(const fv_taa_frame *f, const fv_taa_params *prm, const struct fv_sampler *smp, int gx,
                          int gy, const fv_pyr_level *l0, const fv_reproject_dsp *dsp, int x0, int y0, int tw, int th,
                          float keep);

/* ---- the still head in place (docs/reproject.md, "The still head in place") ----
 * With identical cameras the fill copies every history texel to its own pixel and a sample's
 * level-0 tap reads only its own pixel's texel. So the frame renders into the history's level 0
 * itself (the pipeline swaps the two pyramids' level-0 planes; the coarser levels stay double
 * buffered): holes keep their history (colour, depth, confidence: what the fill would write),
 * and each tile saves its samples' history texels before its rays overwrite them. Per sample,
 * with the footprint of fv_taa_tile_run's blend: level 0 -> the saved texel as a single tap
 * (the same bits as the blend when the footprint is one texel, the default rotating pattern;
 * where DoF-driven thinning or a static pattern widens it to a level-0 quincunx, the single tap
 * replaces the five: neighbours' level 0 is being overwritten by other tiles); level >= 1 ->
 * the blend's taps on the history's untouched coarser levels (the same bits). */
#define FV_TAA_STILL_MAX_PX 256 /* tiles up to 16 x 16 */
typedef struct fv_taa_still_hist {
    float h[5][FV_TAA_STILL_MAX_PX]; /* the samples' history texels' r, g, b, depth, weight, in
                                      * row-major sample order (taa_still's h planes) */
} fv_taa_still_hist;
/* Saves the history texels (level 0 = the history) of the samples of rows (bit x - x0 of
 * rows[y - y0]) before the tile's rays are cast over them. tw * th <= FV_TAA_STILL_MAX_PX. */
void fv_taa_still_save(const fv_pyr_level *l0, int x0, int y0, int tw, int th, const uint32_t *rows,
                       fv_taa_still_hist *h);
/* Blends the tile's samples (rows, cast over the history in place) with their saved history h;
 * the other pixels are left as they are (the history: the fill's result). f->identity must hold;
 * keep as fv_taa_tile_run_keep's. */
void fv_taa_still_tile(const fv_taa_frame *f, const fv_taa_params *prm, const struct fv_sampler *smp, int gx, int gy,
                       const fv_pyr_level *l0, const fv_reproject_dsp *dsp, int x0, int y0, int tw, int th,
                       const uint32_t *rows, float keep, const fv_taa_still_hist *h);

/* Prefetches the level-0 history that fv_taa_tile_run of the tile [x0, x0+tw) x [y0, y0+th) will
 * read, guessing the tile's motion from the history's depth at coarse_level (the level where the
 * tile is one texel). Call it before the tile's rays are cast, so the lines arrive meanwhile. */
void fv_taa_prefetch(const fv_taa_frame *f, int coarse_level, int x0, int y0, int tw, int th);

/* ---- anti-aliasing in the fovea (core/reproject_aa.c has the model) ----
 * Tiles whose every pixel is sampled every frame trace their rays through (ox, oy) inside the
 * pixels, a new point each frame (fv_sampling_jitter), and accumulate them here instead of
 * fv_taa_tile_run: history h (reprojected, confidence-weighted bilinear, clamped to the 3x3
 * neighbourhood of this frame's samples) and the sample s give h + (s - h) / n, n the pixel's
 * accumulated sample count (1 without history, at most FV_TAA_AA_MAX_N). */
#define FV_TAA_AA_MAX_N 16
typedef struct fv_taa_aa_frame {
    const uint8_t *n_prev; /* the history's sample counts (w x h, stride bytes a row); NULL: none */
    uint8_t *n_cur;        /* this frame's: written for every tile (0 outside the AA tiles) */
    ptrdiff_t stride;
    float ox, oy;          /* this frame's ray position inside the AA tiles' pixels, [0, 1) */
    /* The still head in place: the history's level 0 over the tiles that may take the AA, with
     * the ring of one pixel they read, copied before the tiles overwrite it (fv_taa_aa_snapshot):
     * texel (x, y) at h_rgbd + 4 ((y - h_y0) h_stride + x - h_x0). h_rgbd NULL: f->hist's level 0. */
    const float *h_rgbd, *h_wgt;
    ptrdiff_t h_stride;
    int h_x0, h_y0;
} fv_taa_aa_frame;

/* 1 when the tile [x0, x0+tw) x [y0, y0+th) takes the anti-aliasing: every pixel has a sample in
 * rows (this frame's final bits, bit x - x0 of rows[y - y0]) and the acuity model samples every
 * pixel of it every frame (probability 1 at its corner pixels; gaze at pixel gx, gy). */
struct fv_sampler;
int fv_taa_aa_tile_eligible(const struct fv_sampler *smp, int gx, int gy, int x0, int y0, int tw, int th,
                            const uint32_t *rows);
/* The accumulation of an eligible tile itself is the dsp table's taa_aa (reproject_dsp.h). */
/* The still head in place: copies h0 (the history's level 0) over every tile of a w x h image
 * cut into tile x tile tiles that may take the anti-aliasing (probability 1 at its corner pixels,
 * as fv_taa_aa_tile_eligible tests) plus one pixel around (within the level's border) into *buf
 * (grown as needed, *cap floats) and points a's h_* view at it. 0, or -1 when out of memory. */
int fv_taa_aa_snapshot(fv_taa_aa_frame *a, const fv_pyr_level *h0, const struct fv_sampler *smp, int gx, int gy,
                       int tile, float **buf, size_t *cap);
/* Any other tile: its counts are 0. */
void fv_taa_aa_clear(const fv_taa_aa_frame *a, int x0, int y0, int tw, int th);

/* The mapping itself, for tests and tools: current pixel (px, py) at depth d -> previous pixel
 * (*u, *v); returns the previous view depth (<= 0: behind the previous eye). */
float fv_taa_project(const fv_taa_frame *f, float px, float py, float d, float *u, float *v);
/* its lens part (internal: fv_taa_project calls it when f->lens) */
float fv_taa_project_lens(const fv_taa_frame *f, float px, float py, float d, float *u, float *v);

#endif
