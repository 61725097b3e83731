/* fovea: small pieces shared by the alternative DoF models (hussain.c, mantiuk.c, konrad.c,
 * liu.c); internal to core/dof. Work is split into rows (or rows of tiles) through the pool, and
 * every value depends only on its coordinates, so results are identical for any thread count. */
#ifndef FOVEA_DOF_MODEL_UTIL_H
#define FOVEA_DOF_MODEL_UTIL_H

#include <math.h>
#include <stdint.h>

#include "base/util.h"
#include "dof.h"

/* Level 0 pixel (x, y): r, g, b, depth_m. */
static inline const float *fv_dm_px(const fv_pyr_level *L, int x, int y)
{
    return L->rgbd + 4 * ((ptrdiff_t)y * L->stride + x);
}

/* The scatter-as-gather models (konrad, liu) look for pixels whose CoC disc covers the centre.
 * Radii are capped at FV_DM_MAX_R_PX so that a pixel's candidates lie in its 16x16 tile and the 8
 * around it; each tile's search radius is the largest radius found there (an in-focus
 * neighbourhood costs one copy per pixel). */
#define FV_DM_TILE 16
#define FV_DM_PI_F 3.14159265358979323846f
#define FV_DM_MAX_R_PX 16.0f

typedef struct fv_dm_tiles {
    const float *rad;   /* radii (any sign; |.| is used), pixel (x, y) at rad[(y*stride + x)*step + c] */
    ptrdiff_t stride;   /* pixels per row */
    int step, nch;      /* floats per pixel, channels read (c < nch) */
    int w, h, tw, th;   /* image and tile grid */
    float *tmax;        /* tw x th: largest |radius| in the tile */
    int *reach;         /* tw x th: search radius in whole pixels (0 = nothing reaches the tile) */
} fv_dm_tiles;

static inline void fv_dm_tile_max_task(void *ctx, int ty, int tid)
{
    (void)tid;
    fv_dm_tiles *t = ctx;
    const int y0 = ty * FV_DM_TILE, y1 = y0 + FV_DM_TILE < t->h ? y0 + FV_DM_TILE : t->h;
    for (int tx = 0; tx < t->tw; tx++) {
        const int x0 = tx * FV_DM_TILE, x1 = x0 + FV_DM_TILE < t->w ? x0 + FV_DM_TILE : t->w;
        float m = 0.0f;
        for (int y = y0; y < y1; y++)
            for (int x = x0; x < x1; x++)
                for (int c = 0; c < t->nch; c++) {
                    const float r = fabsf(t->rad[((ptrdiff_t)y * t->stride + x) * t->step + c]);
                    m = r > m ? r : m;
                }
        t->tmax[ty * t->tw + tx] = m;
    }
}

static inline void fv_dm_tile_reach_task(void *ctx, int ty, int tid)
{
    (void)tid;
    fv_dm_tiles *t = ctx;
    for (int tx = 0; tx < t->tw; tx++) {
        float m = 0.0f;
        for (int j = ty - 1; j <= ty + 1; j++)
            for (int i = tx - 1; i <= tx + 1; i++)
                if (j >= 0 && j < t->th && i >= 0 && i < t->tw)
                    m = t->tmax[j * t->tw + i] > m ? t->tmax[j * t->tw + i] : m;
        t->reach[ty * t->tw + tx] = (int)ceilf(m);
    }
}

/* Fills t->tmax and t->reach (the caller sets the other fields; tw, th are derived here). */
static inline void fv_dm_tiles_run(fv_dm_tiles *t, fv_pool *pool)
{
    t->tw = (t->w + FV_DM_TILE - 1) / FV_DM_TILE;
    t->th = (t->h + FV_DM_TILE - 1) / FV_DM_TILE;
    fv_pool_run(pool, t->th, fv_dm_tile_max_task, t);
    fv_pool_run(pool, t->th, fv_dm_tile_reach_task, t);
}

static inline int fv_dm_tile_reach(const fv_dm_tiles *t, int x, int y)
{
    return t->reach[(y / FV_DM_TILE) * t->tw + x / FV_DM_TILE];
}

#endif
