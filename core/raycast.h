/* fovea: ray casting of the sampled pixels with Embree packets over screen tiles. */
#ifndef FOVEA_RAYCAST_H
#define FOVEA_RAYCAST_H

#include <math.h>

#include "camera.h"
#include "pool.h"
#include "pullpush.h"
#include "render_dsp.h"
#include "reproject.h"
#include "sampling.h"
#include "scene.h"

#define FV_TILE 16              /* screen tiles are FV_TILE x FV_TILE pixels */
#define FV_TILE_PULL_LEVELS 4   /* log2(FV_TILE): pyramid levels each tile pulls itself */
#define FV_DEPTH_MISS_M 1000.0f /* depth stored where a ray leaves the scene */

/* Background radiance (linear RGB) where rays miss. */
extern const float fv_background_rgb[3];

/* Casts a ray for every pixel the sampler selects around the point of regard (gx, gy pixels)
 * and writes colour + depth with weight 1 into level 0 of pyr; every other pixel gets weight 0
 * (its colour is left as it was: pull-push never reads it). Tiles are claimed atomically by the pool's workers. Returns the number of
 * rays cast. Each tile also pulls its pixels up to pyramid level FV_TILE_PULL_LEVELS while they
 * are in cache, so reconstruction continues with fv_pullpush_from(pyr, dsp, pool,
 * fv_raycast_pulled_levels(pyr)). */
static inline int fv_raycast_pulled_levels(const fv_pyramid *p)
{
    return p->levels - 1 < FV_TILE_PULL_LEVELS ? p->levels - 1 : FV_TILE_PULL_LEVELS;
}
/* Lane k of an 8-ray packet: a primary ray from org along dir (tnear 0, tfar infinite, all
 * masks), not hit yet. */
static inline void fv_ray8_set(struct RTCRayHit8 *rh, int k, const float org[3], const float dir[3])
{
    rh->ray.org_x[k] = org[0];
    rh->ray.org_y[k] = org[1];
    rh->ray.org_z[k] = org[2];
    rh->ray.dir_x[k] = dir[0];
    rh->ray.dir_y[k] = dir[1];
    rh->ray.dir_z[k] = dir[2];
    rh->ray.tnear[k] = 0.0f;
    rh->ray.tfar[k] = INFINITY;
    rh->ray.time[k] = 0.0f;
    rh->ray.mask[k] = ~0u;
    rh->ray.id[k] = (unsigned)k;
    rh->ray.flags[k] = 0;
    rh->hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
    rh->hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
}

typedef struct fv_raycast_opts {
    int phase;                     /* sampling pattern phase (fv_sampler_row) */
    const fv_taa_frame *taa;       /* NULL: no temporal reprojection */
    const fv_taa_params *taa_prm;  /* with taa */
    struct fv_prof *prof;          /* trace recorder (core/prof.h): a "tile" span per tile (arg: its
                                    * index) on the worker's track, "reproject" inside; NULL = off */
} fv_raycast_opts;

/* opt may be NULL (phase 0, no reprojection). With opt->taa each tile reprojects the previous
 * frame into its samples and holes (core/reproject.h) after shading and before pulling; the
 * CPU time the workers spent on that, divided by the pool's thread count, goes to *taa_ms
 * (may be NULL). */
long fv_raycast(const fv_scene *scene, const fv_camera *cam, const fv_sampler *smp, int gx, int gy,
                fv_pyramid *pyr, const fv_render_dsp *dsp, fv_pool *pool, const fv_raycast_opts *opt, double *taa_ms);

#endif
