/* fovea: pull-push reconstruction (Marroquim et al. 2007, as used by Weier et al. 2018).
 * Level 0 holds the sparse samples: colour + depth (r, g, b, depth_m) and a weight in [0,1]
 * (0 = no sample; the colour of a zero-weight pixel is never read, so it need not be cleared).
 * Pull averages weighted valid samples up the pyramid; push fills every hole from the
 * (bilinearly interpolated) coarser level on the way down. The filled pyramid is kept: it feeds depth of field and next frame's reprojection. */
#ifndef FOVEA_PULLPUSH_H
#define FOVEA_PULLPUSH_H

#include <stddef.h>
#include "pullpush_dsp.h"
#include "pool.h"

#define FV_PYR_MAX_LEVELS 16

typedef struct fv_pyr_level {
    int w, h;         /* valid size in pixels */
    ptrdiff_t stride; /* pixels per row (>= w) */
    float *rgbd;      /* pixel (x,y) at rgbd + 4*(y*stride + x): r, g, b, depth_m */
    float *wgt;       /* pixel (x,y) at wgt[y*stride + x] */
} fv_pyr_level;

typedef struct fv_pyramid {
    int levels; /* down to 1x1 */
    fv_pyr_level lv[FV_PYR_MAX_LEVELS];
    void *mem;
} fv_pyramid;

int fv_pyramid_init(fv_pyramid *p, int w, int h); /* 0 on success, -1 on bad size / no memory */
void fv_pyramid_free(fv_pyramid *p);
/* Level 0: weight 0 and colour/depth 0 everywhere (before writing new samples). */
void fv_pyramid_clear(fv_pyramid *p, fv_pool *pool);
/* Fills every hole of level 0 and every level above it. Deterministic for any pool size. */
void fv_pullpush(fv_pyramid *p, const fv_pullpush_dsp *dsp, fv_pool *pool);
/* The same when levels 1..pulled already hold their pull (fv_pull_block): the ray caster pulls
 * each tile up the first levels while it is still in cache. Same bits as fv_pullpush. */
void fv_pullpush_from(fv_pyramid *p, const fv_pullpush_dsp *dsp, fv_pool *pool, int pulled);
/* Pulls the block [x0, x0+w) x [y0, y0+h) of `level` (x0, y0 even; w, h reaching the level's
 * edge or even) into level + 1. Disjoint blocks may run concurrently. */
void fv_pull_block(fv_pyramid *p, const fv_pullpush_dsp *dsp, int level, int x0, int y0, int w, int h);

#endif
