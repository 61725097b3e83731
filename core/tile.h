/* fovea: the tile driver (llvmpipe's "rasterise" step): the per-eye image is cut into
 * FV_TILE x FV_TILE screen tiles claimed atomically by the pool's workers, and each tile runs
 * the stages that can stay in its cache, in order:
 *   sampling pattern (core/sampling.c) -> ray casting and shading (core/raycast.c)
 *   -> temporal reprojection (core/reproject.c) -> its pulls up the pyramid (core/pullpush.c).
 * The frame's remaining stages (pull-push above the tile levels, depth of field, output) run
 * over the whole image in core/pipeline.c. Each tile writes only its own pixels, so the image
 * is identical for any thread count. */
#ifndef FOVEA_TILE_H
#define FOVEA_TILE_H

#include "camera.h"
#include "render_dsp.h"
#include "pool.h"
#include "pullpush.h"
#include "reproject.h"
#include "sampling.h"
#include "scene.h"

#define FV_TILE 16            /* screen tiles are FV_TILE x FV_TILE pixels */
#define FV_TILE_PULL_LEVELS 4 /* log2(FV_TILE): pyramid levels each tile pulls itself */

/* The pyramid levels the tiles have pulled: reconstruction continues with
 * fv_pullpush_from(pyr, dsp, pool, fv_tile_pulled_levels(pyr)). */
static inline int fv_tile_pulled_levels(const fv_pyramid *p)
{
    return p->levels - 1 < FV_TILE_PULL_LEVELS ? p->levels - 1 : FV_TILE_PULL_LEVELS;
}

struct fv_dofsamp_frame;
typedef struct fv_tile_opts {
    int phase;                    /* sampling pattern phase (fv_sampler_row) */
    const fv_taa_frame *taa;      /* NULL: no temporal reprojection */
    const fv_taa_params *taa_prm; /* with taa */
    struct fv_prof *prof;         /* trace recorder (core/prof.h): a "tile" span per tile (arg: its
                                   * index) on the worker's track, "reproject" inside; NULL = off */
    const struct fv_dofsamp_frame *dofs; /* DoF-driven thinning of the sampler's bits
                                          * (core/sampling_dof.h); NULL = off */
    uint32_t *rows_out;           /* NULL, or every tile's final sample bits: tile i's rows at
                                   * rows_out + FV_TILE * i (the bench's ceiling retraces them) */
    int64_t *shade_ns;            /* NULL: shading not timed (no clock reads); else set to the
                                   * workers' summed time shading hits in this pass (ns) */
    const fv_taa_aa_frame *aa;    /* anti-aliasing in the fovea (core/reproject_aa.c); NULL = off */
    int still;                    /* with taa (identical cameras): level 0 of pyr is the history's,
                                   * rendered over in place (fv_taa_still_*, core/reproject.h); the
                                   * AA reads aa's snapshot */
} fv_tile_opts;

/* Runs every tile of the eye image: the sampler's pixels around the point of regard (gx, gy
 * pixels) get a ray each and weight 1 in level 0 of pyr, every other pixel weight 0 (its colour
 * is left as it was: pull-push never reads it); with opt->taa the tile then reprojects the
 * previous frame into its samples and holes; last it pulls itself up FV_TILE_PULL_LEVELS levels
 * while in cache. opt may be NULL (phase 0, no reprojection). Returns the rays cast; the CPU
 * time the workers spent reprojecting, divided by the pool's thread count, goes to *taa_ms
 * (NAN without reprojection; taa_ms may be NULL). */
long fv_tile_pass(const fv_scene *scene, const fv_camera *cam, const fv_sampler *smp, int gx, int gy, fv_pyramid *pyr,
                  const fv_render_dsp *dsp, fv_pool *pool, const fv_tile_opts *opt, double *taa_ms);

/* An eye's tile pass's arguments and results (fv_tile_pass_post / _wait): rays and taa_ms as
 * fv_tile_pass returns and sets them (taa_ms: the eye's reprojection time over the pool's
 * threads), tile_ms the workers' time in its tiles, summed. */
typedef struct fv_tile_eye {
    const fv_camera *cam;
    int gx, gy;
    fv_pyramid *pyr;
    fv_tile_opts opt;
    long rays;      /* out */
    double taa_ms;  /* out */
    double tile_ms; /* out */
} fv_tile_eye;
/* One eye's tile pass as the pool's background job (fv_pool_post): it runs on idle workers while
 * the caller runs other (foreground) jobs that touch none of its data, and is finished by
 * fv_tile_pass_wait (the caller takes the tiles left), which fills eye's outputs and frees the
 * handle. NULL when out of memory (nothing posted). */
typedef struct fv_tile_async fv_tile_async;
fv_tile_async *fv_tile_pass_post(const fv_scene *scene, const fv_sampler *smp, const fv_render_dsp *dsp, fv_pool *pool,
                                 const fv_tile_eye *eye);
void fv_tile_pass_wait(fv_tile_async *a, fv_pool *pool, fv_tile_eye *eye);

#endif
