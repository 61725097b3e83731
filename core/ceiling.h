/* fovea: the ray stage's yardstick. Bare Embree on exactly the rays a frame casts: the same
 * pixels (every pixel, or the sampler's set for a gaze and phase), the same camera rays through
 * pixel centres, in the same 16x16 tiles claimed by the same pool, with no shading, no sampling
 * tables, no weights and no later stage. The bench times it in the same run as the real stage,
 * so the ray stage is judged as stage time / ceiling time. */
#ifndef FOVEA_CEILING_H
#define FOVEA_CEILING_H

#include "camera.h"
#include "pool.h"
#include "sampling.h"
#include "scene.h"

typedef struct fv_ceiling_opts {
    int packet;             /* 8 (rtcIntersect8) or 16 (rtcIntersect16); 0 = 16 */
    const fv_sampler *smp;  /* NULL: every pixel; else its pixels for the point of regard gx, gy */
    int gx, gy, phase;
    const uint32_t *rows;   /* NULL, or the frame's own sample bits (tile i's FV_TILE rows at
                             * [FV_TILE * i], fv_pipeline_last_rows), used instead of smp */
} fv_ceiling_opts;

/* Traces the rays and returns how many; with depth_m (w x h floats, row-major) each traced
 * pixel's first-hit distance along the view axis is written there (INFINITY on a miss; the
 * other pixels are not touched), so tests can check it casts the same rays as the real stage.
 * Without depth_m nothing is stored: the time is Embree's alone. opt may be NULL (every pixel,
 * 16-wide packets). */
long fv_ceiling_trace(const fv_scene *scene, const fv_camera *cam, fv_pool *pool, const fv_ceiling_opts *opt,
                      float *depth_m);

#endif
