/* fovea: the layered depth-of-field filter's passes (core/dof/weier*.c, combine.c), private to
 * them: the per-frame context, the constants and the pieces the files share. */
#ifndef FOVEA_DOF_WEIER_PASSES_H
#define FOVEA_DOF_WEIER_PASSES_H

#include <math.h>
#include <pthread.h>
#include <stddef.h>
#include <stdint.h>

#include "base/util.h"
#include "dof/dof.h"
#include "dof/weier_impl.h"

#define TILE 16
#define LOW 4          /* the near layer's reduced resolution in the periphery: 4x4 blocks */
#define NSLOT 16       /* per-thread row buffers of the fused vertical + combine pass */
#define ENH_LEVELS 3   /* contrast enhancement: levels 1..3 (footprints up to ~8 px) */
#define MAX_UP_LEVEL 5 /* periphery far blur: levels 1..5 (CoC up to 64 px) */
#define LAMBDA_STEPS 8 /* the level LUT's steps per pixel of CoC */
#define LAMBDA_N (64 * LAMBDA_STEPS + 1) /* CoCs 0 .. 64 px */

/* An image of 4 floats a pixel (a pyramid level, or the quarter-resolution near layer). */
typedef struct {
    const float *px;
    int w, h;
    ptrdiff_t stride;
} img4;

/* Horizontal taps of a bilinear up-sampling by 2^L to level-0 pixel centres, per column x:
 * texels i0, i1 and the weight of i1 (borders clamp). Built once per frame. */
typedef struct {
    int32_t *i0, *i1;
    float *ax;
} xtaps;


typedef struct {
    const fv_dof_view *v;
    fv_dof_work *wk;
    const fv_dof_dsp *dsp;
    const fv_dof_gauss_tab *tab;
    float *out;
    ptrdiff_t out_stride;
    int w, h, tw, th;
    float K;                   /* CoC scale: pupil_m * focal_px * blur_scale */
    float dn, df;              /* the in-focus range [d_o - t, d_o + t] */
    float inv_tr;              /* 1 / (r1 - r0) */
    float *t_near, *t_fsig;    /* per tile, dilated: the largest near radius / far sigma that reach it */
    float *t_near_own, *t_fsig_own;
    int cx0, cx1, cy0, cy1;    /* the centre rectangle: full-resolution layers (t < 1 plus reach) */
    /* quarter-resolution near layer (the periphery) */
    int lw, lh;                /* its size */
    float *l_src, *l_r, *l_w;  /* source: premultiplied (rgb, coverage) / radius / box weight */
    float *l_h, *l_hr, *l_hw;  /* after the horizontal pass */
    float *l_v;                /* after the vertical pass */
    int32_t *l_nn;             /* per block row: the blocks [l_nn[2 by], l_nn[2 by + 1]) holding a pixel that is not near */
    int32_t *l_span;           /* per row of l_v: its texels [l_span[2 by], l_span[2 by + 1]) that are not all 0 */
    int l_reach;               /* the largest radius there */
    int near_tiles;            /* the tile dilation's near reach in tiles (fvw_dilate_tiles) */
    int up_levels;             /* periphery far blur: pyramid levels 1..up_levels are read */
    const float *lambda;       /* CoC -> continuous pyramid level (LAMBDA_N entries) */
    int enh_on;                /* contrast enhancement runs */
    float *band_ms;            /* per band (BAND_MS each): worker time (ms) in the fused pass's filter, combine,
                                * output and recomputed CoC rows, the CoC pass, the quarter-resolution passes */
    xtaps xt[MAX_UP_LEVEL + 1]; /* up-sampling taps by 2^L, L = 1..MAX_UP_LEVEL */
    /* the periphery's far blur at half resolution (the level 1 grid), up-sampled once per row */
    int half_on;               /* level 1 exists: the periphery outside the transition disc uses it */
    int hw, hh;                /* level 1's size */
    float *hblur;              /* hw x hh x 4: level 1 blurred by the half-resolution CoC */
    float *hcoc;               /* hw x hh: that CoC, the 2x2 mean of |c| (written by the CoC pass) */
    int hblur_fused;           /* the fused path makes each band's half rows itself (fvw_hband), no hblur image */
    float *hband;              /* the per-thread band rows of it, after the row slots */
    const float *lambda_h;     /* CoC -> continuous level - 1 (>= 0), for the half grid */
    xtaps xh[MAX_UP_LEVEL];    /* up-sampling taps by 2^k to the half grid, k = 1..MAX_UP_LEVEL - 1 */
    /* the band pipeline (fvw_pipe_task): the CoC, horizontal, quarter-resolution and fused passes
     * in one job, each band's fused pass a few bands behind its CoC work, so that level 0 is read
     * from memory once */
    int pipe;                  /* on (the default path: hblur_fused and not prm.band_passes) */
    int pc0, pc1;              /* the bands [pc0, pc1) hold a centre row: horizontal pass, fused a band later */
    int32_t *l_rowr;           /* per block row: its largest block radius l_r, at least 0 */
    int32_t *pflag;            /* per band: PIPE_* bits of the steps done (under pmu) */
    int coc_upto, lv_upto, h_upto; /* the bands [0, n) have PIPE_COC / PIPE_LV / PIPE_H */
    pthread_mutex_t pmu;       /* guards pflag and the three counters */
    pthread_cond_t pcv;        /* a counter moved */
} fvw_ctx;

#define BAND_MS 6
#define PIPE_COC 1   /* CoC pass and quarter-resolution horizontal rows */
#define PIPE_LV 2    /* quarter-resolution vertical pass */
#define PIPE_H 4     /* the centre's step (made or skipped): tile dilation and horizontal pass */
#define PIPE_HP 8    /* ... made in the pipeline */
#define PIPE_FUSED 16 /* the fused pass made in the pipeline */
#define PIPE_D2 32   /* the centre's step took the near reach as 2 tiles (known), else 1 (guessed) */
#define LREACH_MAX (FV_DOF_RMAX / LOW) /* the largest block radius: floor(FV_DOF_RMAX / 4) */


static inline float fvw_t_of(const fvw_ctx *x, float fx, float fy)
{
    const float dx = fx - x->v->gaze_x, dy = fy - x->v->gaze_y;
    return fv_clampf((sqrtf(dx * dx + dy * dy) - x->v->r0_px) * x->inv_tr, 0.0f, 1.0f);
}


/* The columns [*a, *b) of a row at height fy (pixel centre) that the transition disc (radius r1
 * around the gaze) covers, with a pixel to spare each side; empty (*a = *b = w) off the disc.
 * Pixels outside it have t = 1. */
static inline void fvw_disc_span(const fvw_ctx *x, float fy, int *a, int *b)
{
    const float dyr = fy - x->v->gaze_y, r1 = x->v->r1_px;
    *a = *b = x->w;
    if (dyr * dyr < r1 * r1) {
        const float half = sqrtf(r1 * r1 - dyr * dyr);
        *a = fv_clampi((int)floorf(x->v->gaze_x - half) - 1, 0, x->w);
        *b = fv_clampi((int)ceilf(x->v->gaze_x + half) + 1, 0, x->w);
    }
}

/* sigma (pixels) -> table index */
static inline uint8_t fvw_sig_index(float sigma)
{
    const float s = sigma * FV_DOF_SIG_STEPS + 0.5f;
    return (uint8_t)(s < (float)(FV_DOF_NSIG - 1) ? (s > 0.0f ? (int)s : 0) : FV_DOF_NSIG - 1);
}


/* Rows whose CoC the CoC pass keeps in the plane p1[0]: the centre rectangle's (the horizontal
 * pass reads them); the fused pass recomputes the others from level 0. */
static inline int fvw_coc_kept(const fvw_ctx *x, int y) { return y >= x->cy0 && y < x->cy1; }

/* Per-thread row buffers of the fused pass. */
static inline float *fvw_slot(const fvw_ctx *x, int tid, int k) { return x->wk->rows + ((size_t)tid * NSLOT + (size_t)k) * 4 * (size_t)x->w; }


/* Per-thread rows of the half-resolution blur for one band of the fused pass (HBAND_ROWS x hw x 4
 * floats, after the row slots): the band's TILE / 2 half rows and one of halo each side. */
#define HBAND_ROWS (TILE / 2 + 2)
static inline float *fvw_hband(const fvw_ctx *x, int tid) { return x->hband + (size_t)tid * HBAND_ROWS * 4 * (size_t)x->hw; }

/* weier_filter.c: up-sampling helpers */
void fvw_xtaps_init(xtaps *t, int L, int w, int src_w);
void fvw_upsample_row(const fv_dof_dsp *dsp, const img4 *src, int L, const xtaps *xt, int y, int xa, int xb,
                      float *restrict tmp, float *restrict dst);
/* weier_coc.c: stage "coc" (bands of TILE rows; then the tiles' reach) */
void fvw_coc_band(void *ctx, int band, int tid);
void fvw_dilate_tiles(fvw_ctx *x);
void fvw_dilate_row(fvw_ctx *x, int ty, int dn); /* tile row ty with near reach dn tiles (the band pipeline) */
/* weier_filter.c: stage "dof_filter" (bands); the vertical pass runs the combine row by row */
void fvw_hpass_band(void *ctx, int band, int tid);
void fvw_lvpass_band(void *ctx, int band, int tid);
void fvw_lhpass_band(fvw_ctx *x, int band);
void fvw_hblur_band(void *ctx, int band, int tid);
void fvw_vcombine_band(void *ctx, int band, int tid);
/* weier_pipe.c: the band pipeline, task k of x->th + 4 (fv_pool_run) */
void fvw_pipe_task(void *ctx, int k, int tid);
void fvw_pipe_settle(fvw_ctx *x); /* after the job and fvw_dilate_tiles: drops the centre's guessed work if wrong */
int fvw_pipe_free(const fvw_ctx *x, int band); /* band has no centre row */
/* combine.c: stage "combine", one row */
void fvw_enhance_row(const fvw_ctx *x, int tid, int y, const float *sharp, const float *trow, float *restrict enh);
void fvw_combine_row(const fvw_ctx *x, float *restrict dst, const float *sharp, const float *coc, const float *far, const float *near,
                     const float *lnear, const float *trow, const float *enh, int xa, int xb);

#endif
