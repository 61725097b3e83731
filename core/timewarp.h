/* fovea: timewarp, the display path's late correction. A rendered frame (8-bit RGB and a 16-bit
 * inverse depth plane, from a source camera) is warped to the camera of the newest head pose
 * right before a refresh. The reference is a backward warp per display pixel (fixed-point
 * iteration on the source's depth; the kernel and its contract: timewarp_dsp.h), disocclusions
 * filled from the farther surface beside the hole. The warp used (fv_tw_warp_rows) is a block
 * warp over it: 16x16 display blocks whose every pixel's reference tap is provably within
 * FV_TW_BLOCK_POS_PX of one translation per row are resampled at it (tw_spans); the other
 * blocks run the per-pixel kernel. The display path runs fv_tw_warp_rows_bounded: the per-pixel
 * kernel within a budget, grid cells beyond it (its cost does not grow with the frame's age). OS-free. */
#ifndef FOVEA_TIMEWARP_H
#define FOVEA_TIMEWARP_H

#include <stddef.h>
#include <stdint.h>

#include "camera.h"
#include "timewarp_dsp.h"

/* The mapping from display camera pixels to source camera pixels (cameras of equal size; with a
 * lens, the pinhole part: fv_tw_map_set_lens). tol: the disocclusion tolerance (0.05 = 5 % in
 * inverse depth). */
void fv_tw_setup(fv_tw_map *m, const fv_camera *display, const fv_camera *source, float tol);

/* ---- with a lens ----
 * Both cameras have the lens l was built from (fv_lens_map_init). The display pixel p then shows
 * the source pixel F^-1(H(F(p), w)) (H: the pinhole warp at the display inverse depth w). The warp
 * cuts the display into FV_TW_LENS_CELL squares and gives each the map with the lens linearised
 * around it (fv_lens_map_fold: F at the cell centre, F^-1 where the centre lands at the depth the
 * source shows there), so the block warp's planner, its proof and the per-pixel kernels run as
 * they are, on that map. The linearisation's error against the exact map is FV_TW_LENS_ERR_PX
 * (the example profile, 1280 x 1440, the head turning 30 deg/s for one and two refreshes of
 * 90 Hz and moving 2 mm a refresh: measured 0.055 and 0.118 px; tests/test_lens_reproject.c
 * measures every pixel); the block warp's FV_TW_BLOCK_POS_PX comes on top. Cells of 64 (the
 * blocks' size: one map per block) cost the warp of a pair 0.1 ms of planning over the lensless
 * warp; cells of 32 halve the error (0.023 / 0.049 px) but plan four times as many blocks (+1.2 ms,
 * docs/headset.md). */
#define FV_TW_LENS_CELL 64
#define FV_TW_LENS_ERR_PX 0.15f
struct fv_lens_map;
void fv_tw_map_set_lens(fv_tw_map *m, const struct fv_lens_map *l);
/* The map of the cell [X0, X1) x [Y0, Y1) (m with its lens folded in; lens NULL). */
void fv_tw_cell_map(const fv_tw_map *m, const fv_tw_src *src, int X0, int X1, int Y0, int Y1, fv_tw_map *out);

/* The 16-bit inverse depth of an image of (r, g, b, depth_m) floats (fv_pipeline_depth): round
 * (FV_TW_INVD_PER_M / depth_m), clamped to [0, 65535] (nearer than 6.25 cm: the nearest). */
void fv_tw_pack_invd(uint16_t *dst, ptrdiff_t dst_stride, const float *rgbd, ptrdiff_t rgbd_stride, int w, int h);

/* ---- the block warp ----
 * Display block rows of FV_TW_BLOCK_H rows are cut into blocks of FV_TW_BLOCK_W columns; a block
 * that cannot be translated is cut into quarters, down to FV_TW_BLOCK_MIN pixels a side, and a
 * part that still cannot runs the per-pixel kernel. A block is translated when the planner proves that, for each of its pixels, the
 * reference's bilinear tap position (before its 7-bit weight truncation, after its clamp to the
 * source) lies within FV_TW_BLOCK_POS_PX, per axis, of the block's tap: each row is translated
 * (fv_tw_block_row), the source position clamped to the source the same way.
 * The proof: the source's inverse depth over the rectangle R that the display depths [0, G] can
 * reach from the block (R from the 8 projections of the corners at w = 0 and G: a projective map
 * of a box with positive Z lies in the hull of its vertices' images) gives a display depth range
 * [lo, hi]; hi <= G means every fetch of the reference's iteration (w1 at q(0), w2 at q(w1))
 * lands in R, so its tap is at q(p, w) for some w in [lo, hi]; q(p, w) for those w lies on the
 * segment between q(p, lo) and q(p, hi); q(p, w) - p is the bilinear blend of the corners'
 * offsets up to the homography's curvature term (h^2 / 8 |q''|, |q''| <= 2 |D'| (|N'| + |q| |D'|)
 * / D^2 for q = N / D); a row's translation blends the middles of the top and bottom edges'
 * offset ranges (both corners, w = lo and hi), so the larger half spread of an edge, the
 * curvature term and the rounding to 1/64 bound the rest; clamping to the source shrinks
 * distances. A superset of R (the tiles of fv_tw_tiles) keeps the proof.
 * Values: a translated pixel differs from the reference's by at most
 * 2 (FV_TW_BLOCK_POS_PX + 1/128) x (the largest minus the least of the source channel over the
 * 4x4 pixels around the reference's tap) + 1 level (tests/checkasm/timewarp.c checks it).
 * Disocclusions: within a translated block every reference tap lies within 2 FV_TW_BLOCK_POS_PX
 * of the others, so a disocclusion there is narrower than half a pixel; they are not counted
 * (the count is the per-pixel kernel's over the other blocks). */
#define FV_TW_BLOCK_W 64
#define FV_TW_BLOCK_H 64
#define FV_TW_BLOCK_MIN 8    /* the smallest side of a part */
#define FV_TW_BLOCK_SPLIT 64 /* entries a block may become ((FV_TW_BLOCK_W / FV_TW_BLOCK_MIN)^2) */
#define FV_TW_BLOCK_POS_PX 0.25f
#define FV_TW_TILE 8 /* the side of a tile of fv_tw_tiles; its coarse level: 4 x 4 tiles */

typedef struct fv_tw_block {
    int x0, x1, y0, y1; /* display pixels [x0, x1) x [y0, y1) */
    int fast;           /* 1: translated; 0: the per-pixel kernel */
    float u0, v0, u1, v1; /* the translation (source minus display position) of its first and last row */
    int64_t qu, qv, dqu, dqv; /* the first row's in 1/2^22 px and the step a row (fv_tw_block_row) */
    float err_px;       /* the planner's bound on the position error (translated blocks) */
    int inner;          /* translated and every row's taps inside the source (no clamping): the warp's
                         * short path, the same bytes */
    int grid;           /* translated without a proof: a cell of the bounded warp's grid fallback
                         * (fv_tw_warp_rows_bounded) */
} fv_tw_block;
/* Row y's translation of a translated block, its rows' linear blend of the first's and the last's
 * (in fixed point, within 2^-16 px) rounded to 1/64: display pixel (x, y) resamples the source at (x + ox + fx / 64, y + oy + fy / 64). */
void fv_tw_block_row(const fv_tw_block *b, int y, int *ox, int *oy, int *fx, int *fy);

/* The least and greatest inverse depth of each FV_TW_TILE square of a source (lohi[2 (ty tw + tx)]
 * and the next), and of each 4 x 4 of those (lohi4, for large footprints), built once per
 * rendered frame so the display path need not read the depth. */
typedef struct fv_tw_tiles {
    uint16_t *lohi, *lohi4;
    int tw, th;   /* tiles a row, rows of tiles */
    int tw4, th4; /* the coarse level's */
} fv_tw_tiles;
/* lohi must hold 2 tw th elements, tw = ceil(w / FV_TW_TILE), th = ceil(h / FV_TW_TILE); lohi4
 * 2 ceil(tw / 4) ceil(th / 4) */
void fv_tw_tiles_build(const fv_timewarp_dsp *d, fv_tw_tiles *t, const fv_tw_src *src);

/* Plans display block row by (rows [by FV_TW_BLOCK_H, + FV_TW_BLOCK_H) clipped to the source):
 * its blocks from column bx0 FV_TW_BLOCK_W on, nb of FV_TW_BLOCK_W (the last one clipped), into
 * out (at most FV_TW_BLOCK_SPLIT nb entries; they tile the blocks, and those covering a row come
 * in column order). Returns the entries.
 * tiles: NULL reads the depth plane itself. *guess carries the depth guess G from block to block
 * (0 at the row's start): a row planned in pieces plans as it does whole. */
int fv_tw_plan_blocks(const fv_timewarp_dsp *d, const fv_tw_map *m, const fv_tw_src *src, const fv_tw_tiles *tiles,
                      int by, int bx0, int nb, fv_tw_block *out, float *guess);

/* Warps rows [y0, y1) of the display image (rows of dst_stride bytes, src->w pixels each) with
 * the block warp (tiles: NULL, or src's). Returns the disoccluded pixels (of the per-pixel blocks). */
long fv_tw_warp_rows(const fv_timewarp_dsp *d, uint8_t *dst, ptrdiff_t dst_stride, int y0, int y1, const fv_tw_map *m,
                     const fv_tw_src *src, const fv_tw_tiles *tiles);
/* ---- the bounded warp (the display path: its cost must not depend on the frame's age) ----
 * A frame far from the display's pose (a slow renderer, a fast head) fails the block proof almost
 * everywhere and the per-pixel kernel (~5.5 ns a pixel with AVX2: ~20 ms a pair) would set the
 * display rate. fv_tw_warp_rows_bounded gives the per-pixel kernel at most budget_px pixels of
 * the rows, shared out over the block rows in proportion to their pixels (what a block row leaves
 * goes to the next); within a group of blocks the failed parts with the largest position bound
 * get it first (depth edges with parallax, where a translation shows most). The other failed
 * parts are cut into FV_TW_GRID_W x FV_TW_GRID_H cells, each translated without a proof, as a grid warp with a
 * depth per vertex: its first and last row's translation is the reference's tap (three
 * fixed-point steps, the farther surface where they disagree) at the middle of its top and
 * bottom row. Its error: the homography's change over half a cell (a turn's stretch: ~0.8 px at
 * the panel's edge for a 3 degree turn) and, across a depth edge inside the cell, the parallax
 * between the two surfaces; no disocclusion fill there. Cost: the planning, the translated
 * resample (memory speed) and the budget. budget_px = LONG_MAX is fv_tw_warp_rows (the same
 * bytes). stats (NULL: not wanted) adds the pixels that ran per pixel and those of grid cells. */
#ifndef FV_TW_GRID_W
#define FV_TW_GRID_W 16 /* columns of a grid cell */
#endif
#ifndef FV_TW_GRID_H
#define FV_TW_GRID_H 16 /* its rows */
#endif
#define FV_TW_GRID_MIN 16 /* the bounded warp's smallest proven part (FV_TW_BLOCK_MIN otherwise) */
typedef struct fv_tw_warp_stats {
    long pixel_px, grid_px;
} fv_tw_warp_stats;
long fv_tw_warp_rows_bounded(const fv_timewarp_dsp *d, uint8_t *dst, ptrdiff_t dst_stride, int y0, int y1,
                             const fv_tw_map *m, const fv_tw_src *src, const fv_tw_tiles *tiles, long budget_px,
                             fv_tw_warp_stats *stats);

/* The same rows with the per-pixel kernel everywhere (the reference the block warp is held to). */
long fv_tw_warp_rows_pixel(const fv_timewarp_dsp *d, uint8_t *dst, ptrdiff_t dst_stride, int y0, int y1,
                           const fv_tw_map *m, const fv_tw_src *src);

/* Bytes a plane must have past its last pixel / element for the kernels' word reads. */
#define FV_TW_RGB_PAD 16
#define FV_TW_INVD_PAD 32

#endif

/* ---- a rendered stereo frame kept for the warp (one mailbox slot of the headset) ---- */
struct fv_pipeline;
typedef struct fv_tw_frame {
    int w, h;               /* per eye */
    uint8_t *rgb[2];        /* left, right: display bytes, w * 3 a row, FV_TW_RGB_PAD past the end */
    uint16_t *invd[2];      /* w a row, FV_TW_INVD_PAD bytes past the end */
    fv_camera cam[2];       /* the cameras they were rendered from */
    fv_lens_map lmap[2];    /* their lens in pixel units (cameras with a lens), built at capture */
    fv_tw_tiles tiles[2];   /* of invd, built at capture */
} fv_tw_frame;

int fv_tw_frame_alloc(fv_tw_frame *f, int w, int h); /* 0, or -1 out of memory */
void fv_tw_frame_free(fv_tw_frame *f);
/* After fv_pipeline_render of eye e (0 left, 1 right): keep its display bytes, inverse depth (and
 * its tiles) and camera. */
void fv_tw_frame_capture(fv_tw_frame *f, const struct fv_pipeline *pl, int e);
/* Warps eye e of f to camera `display` (same size and lens) into dst (rows of dst_stride bytes).
 * Returns the disoccluded pixels. */
long fv_tw_frame_warp(const fv_timewarp_dsp *d, const fv_tw_frame *f, int e, const fv_camera *display, uint8_t *dst,
                      ptrdiff_t dst_stride, float tol);
/* The same with the bounded warp (fv_tw_warp_rows_bounded). */
long fv_tw_frame_warp_bounded(const fv_timewarp_dsp *d, const fv_tw_frame *f, int e, const fv_camera *display,
                              uint8_t *dst, ptrdiff_t dst_stride, float tol, long budget_px, fv_tw_warp_stats *stats);

/* The warp's image quality: luma PSNR (dB) of `warped` against `ref` (a frame rendered directly
 * at the display camera), both w x h 8-bit RGB rows of w * 3 bytes, over the pixels the warp
 * (map m, source src) did not fill as disocclusions; *disocc_frac gets the disoccluded fraction.
 * INFINITY when identical, NAN when every pixel is disoccluded or out of memory. */
double fv_tw_psnr_outside_holes(const uint8_t *warped, const uint8_t *ref, const fv_tw_map *m, const fv_tw_src *src,
                                double *disocc_frac);
