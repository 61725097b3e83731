/* fovea: the layered filter's band pipeline (issue 14): the CoC pass and the fused pass of the
 * bands outside the centre rectangle's rows run as one job, band k's CoC work a few bands ahead of
 * the fused pass that reads the same level 0 rows, so those rows come from cache the second time
 * (level 0 is 29.5 MB an eye at 1280x1440; read twice before).
 *
 * Task k (of th + PIPE_LAG, claimed in order by fv_pool_run's counter):
 *   1. k < th: the CoC pass of band k (fvw_coc_band) and its quarter-resolution horizontal rows
 *      (fvw_lhpass_band, each block row to its own largest radius);
 *   2. the quarter-resolution vertical pass of band k - 2, once step 1 is done for every band up
 *      to k (its block rows read up to LREACH_MAX = 6 block rows away: bands k - 4 .. k);
 *   3. the fused pass of band b = k - 3 if no row of it is in the centre rectangle, once step 2
 *      is done up to b + 1 (the near layer up-sampled reads block rows up to 4 b + 4, the half-
 *      resolution blur's halo the half-resolution CoC of band b + 1).
 * The centre's bands wait for the whole frame: their tile dilation reaches as far as the frame's
 * largest near radius (fvw_dilate_tiles), and a tile it marks runs the near box even for radius-0
 * near pixels, so a narrower dilation would change bits. Nothing the free bands read depends on
 * it (no full-resolution near or far layer outside the centre rectangle).
 *
 * A task waits only for steps of tasks with a smaller index, which were claimed before it and are
 * running on other threads (fv_pool_run runs every claimed item to its end), so the job always
 * makes progress, on one thread in plain order. Each band's data is a function of the frame only
 * (the per-row reach in steps 1-2 is exact: the near box kernels skip taps beyond a source's
 * radius, so any reach at least the largest radius gives the same bits), so the output is the same
 * for any thread count and the same as the passes one after another (prm.band_passes). */
#include "dof/weier_passes.h"

#include "base/clock.h"

#define PIPE_LAG 3

int fvw_pipe_free(const fvw_ctx *x, int band) { return band < x->pc0 || band >= x->pc1; }

/* marks step `bit` of band done and advances that step's counter over the bands done in order */
static void pipe_done(fvw_ctx *x, int band, int bit)
{
    pthread_mutex_lock(&x->pmu);
    x->pflag[band] |= bit;
    int *upto = bit == PIPE_COC ? &x->coc_upto : &x->lv_upto;
    while (*upto < x->th && (x->pflag[*upto] & bit))
        ++*upto;
    pthread_cond_broadcast(&x->pcv);
    pthread_mutex_unlock(&x->pmu);
}

/* waits until step `bit` is done for every band up to `band` (clamped to the last) */
static void pipe_wait(fvw_ctx *x, int band, int bit)
{
    band = band < x->th - 1 ? band : x->th - 1;
    pthread_mutex_lock(&x->pmu);
    const int *upto = bit == PIPE_COC ? &x->coc_upto : &x->lv_upto;
    while (*upto <= band)
        pthread_cond_wait(&x->pcv, &x->pmu);
    pthread_mutex_unlock(&x->pmu);
}

void fvw_pipe_task(void *ctx, int k, int tid)
{
    fvw_ctx *x = ctx;
    fv_prof *prof = x->v->prof;
    if (k < x->th) {
        const int64_t t0 = fv_time_ns();
        fvw_coc_band(x, k, tid);
        const int64_t t1 = fv_time_ns();
        fvw_lhpass_band(x, k);
        const int64_t t2 = fv_time_ns();
        x->band_ms[BAND_MS * k + 4] = (float)((double)(t1 - t0) * 1e-6);
        x->band_ms[BAND_MS * k + 5] = (float)((double)(t2 - t1) * 1e-6);
        if (prof)
            fv_prof_span(prof, tid, tid, "dof coc band", t0, t2, k);
        pipe_done(x, k, PIPE_COC);
    }
    const int j = k - 2;
    if (j >= 0 && j < x->th) {
        pipe_wait(x, j + 2, PIPE_COC);
        const int64_t t0 = fv_time_ns();
        fvw_lvpass_band(x, j, tid);
        x->band_ms[BAND_MS * j + 5] += (float)((double)(fv_time_ns() - t0) * 1e-6);
        pipe_done(x, j, PIPE_LV);
    }
    const int b = k - PIPE_LAG;
    if (b >= 0 && b < x->th && fvw_pipe_free(x, b)) {
        pipe_wait(x, b + 1, PIPE_LV);
        const int64_t t0 = prof ? fv_time_ns() : 0;
        fvw_vcombine_band(x, b, tid);
        if (prof)
            fv_prof_span(prof, tid, tid, "dof fused band", t0, fv_time_ns(), b);
    }
}
