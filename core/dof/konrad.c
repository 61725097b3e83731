/* fovea: the adaptive circle-of-confusion gather filter of Zhou, Chen, Pullen 2007 ("Accurate
 * depth of field simulation in real time") as Konrad ("Depth of field rendering algorithms for
 * virtual reality", sec. III.B) describes and runs it: non-separable (fv_dof_konrad).
 *
 * What the paper says: every pixel P in the window around the centre C gets a weight of three
 * factors:
 *  1. P contributes nothing unless its circle of confusion overlaps C;
 *  2. the light intensity over P's CoC, approximated as uniform: 1 / r_P^2;
 *  3. intensity leakage: if P is behind the focal plane, its weight is scaled by a factor
 *     proportional to C's CoC radius (C near the focal plane attenuates P strongly); P in front
 *     of the focal plane is unchanged.
 * Zhou approximate the filter as separable; Konrad runs the full 2D filter, and so do we.
 *
 * What we chose where it is silent:
 *  - CoC: the thin lens of the reference renderer, fv_dof_thin_lens_px (diameter, signed:
 *    positive = behind the focal plane), radius r = |CoC| / 2, capped at FV_DM_MAX_R_PX (16 px).
 *  - Factor 1: |P - C| <= r_P (centre distances, hard edge); C itself always contributes.
 *  - Factor 2: 1 / max(pi r_P^2, 1): the disc's area, but never less than the one pixel an
 *    in-focus point covers (so a sharp centre keeps the weight of a pixel, not infinity).
 *    Weights are divided by C's own factor 2, so C's weight is exactly 1 and a pixel nothing else
 *    reaches comes out bit for bit (in-focus pixels, and sharp objects in front of a far blur).
 *  - Factor 3: behind the focal plane (signed CoC > 0), P != C: min(1, r_C / r_P), i.e.
 *    proportional to r_C and 1 when C is blurred at least as much as P.
 *  - Window: the tile search radius (model_util.h), the largest r_P that can reach C.
 *  - Stages: coc (CoC, tile maxima), filter; no combine (NAN). */
#include <math.h>
#include <string.h>

#include "dof/dof.h"
#include "base/clock.h"
#include "dof/model_util.h"

typedef struct ko_job {
    const fv_dof_view *v;
    const fv_pyr_level *L;
    fv_dof_work *wk;
    float *out;
    ptrdiff_t os;
    int w, h;
    fv_dm_tiles tiles;
} ko_job;

static inline float ko_area(float r) { return fmaxf(FV_DM_PI_F * r * r, 1.0f); }

/* signed CoC radius in pixels, capped -> p1[0]; 1 / disc area (factor 2) -> p1[3] */
static void ko_coc_row(void *ctx, int y, int tid)
{
    (void)tid;
    const ko_job *j = ctx;
    float *r = j->wk->p1[0] + y * j->wk->stride, *ia = j->wk->p1[3] + y * j->wk->stride;
    for (int x = 0; x < j->w; x++) {
        const float h = 0.5f * fv_dof_thin_lens_px(j->v, fv_dm_px(j->L, x, y)[3]);
        r[x] = fminf(fmaxf(h, -FV_DM_MAX_R_PX), FV_DM_MAX_R_PX);
        ia[x] = 1.0f / ko_area(r[x]);
    }
}

static void ko_filter_row(void *ctx, int y, int tid)
{
    (void)tid;
    const ko_job *j = ctx;
    const ptrdiff_t st = j->wk->stride;
    const float *rad = j->wk->p1[0], *iar = j->wk->p1[3];
    float *o = j->out + 4 * y * j->os;
    for (int x = 0; x < j->w; x++) {
        const float *c = fv_dm_px(j->L, x, y);
        o[4 * x + 3] = c[3];
        const int R = fv_dm_tile_reach(&j->tiles, x, y);
        const float rc = fabsf(rad[y * st + x]), ac = ko_area(rc);
        float a[3] = {c[0], c[1], c[2]}, sw = 1.0f; /* C: weight exactly 1 */
        for (int dy = -R; dy <= R; dy++) {
            const int py = fv_clampi(y + dy, 0, j->h - 1);
            for (int dx = -R; dx <= R; dx++) {
                if (!dx && !dy)
                    continue;
                const int px = fv_clampi(x + dx, 0, j->w - 1);
                const float rs = rad[py * st + px], rp = fabsf(rs);
                if ((float)(dx * dx + dy * dy) > rp * rp) /* factor 1 */
                    continue;
                float wgt = ac * iar[py * st + px]; /* factor 2, relative to C's */
                if (rs > 0.0f && rc < rp)     /* factor 3 */
                    wgt *= rc / rp;
                if (!(wgt > 0.0f))
                    continue;
                const float *p = fv_dm_px(j->L, px, py);
                for (int ch = 0; ch < 3; ch++)
                    a[ch] += wgt * p[ch];
                sw += wgt;
            }
        }
        for (int ch = 0; ch < 3; ch++)
            o[4 * x + ch] = sw == 1.0f ? a[ch] : a[ch] / sw;
    }
}

void fv_dof_konrad(const fv_dof_view *v, fv_dof_work *wk, float *out, ptrdiff_t out_stride, fv_pool *pool,
                   const fv_dof_dsp *dsp, fv_dof_times *t)
{
    (void)dsp;
    ko_job j = {.v = v, .L = &v->pyr->lv[0], .wk = wk, .out = out, .os = out_stride};
    j.w = j.L->w, j.h = j.L->h;

    int64_t t0 = fv_dof_stage_begin(v, FV_STAGE_COC);
    fv_pool_run(pool, j.h, ko_coc_row, &j);
    j.tiles = (fv_dm_tiles){.rad = wk->p1[0], .stride = wk->stride, .step = 1, .nch = 1, .w = j.w, .h = j.h,
                            .tmax = wk->p1[1], .reach = (int *)wk->p1[2]};
    fv_dm_tiles_run(&j.tiles, pool);
    t->coc_ms = fv_dof_ms(t0, fv_dof_stage_end(v, FV_STAGE_COC, t0));

    t0 = fv_dof_stage_begin(v, FV_STAGE_DOF_FILTER);
    fv_pool_run(pool, j.h, ko_filter_row, &j);
    t->filter_ms = fv_dof_ms(t0, fv_dof_stage_end(v, FV_STAGE_DOF_FILTER, t0));
    t->combine_ms = NAN;
}
