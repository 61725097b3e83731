/* fovea: the layered filter's band pipeline (issue 14): the CoC pass, the centre's horizontal
 * pass and the fused pass run as one job over bands of 16 rows, each band's fused pass a few bands
 * behind its CoC work, so the level 0 rows it reads (29.5 MB an eye at 1280x1440, read two or
 * three times a frame before) come from cache the second time.
 *
 * Task k (of th + 4, claimed in order by fv_pool_run's counter):
 *   1. k < th: the CoC pass of band k (fvw_coc_band) and its quarter-resolution horizontal rows
 *      (fvw_lhpass_band, each block row to its own largest radius);
 *   2. j = k - 2: the quarter-resolution vertical pass of band j, once step 1 is done for every
 *      band up to k (its block rows read up to LREACH_MAX = 6 block rows away: bands j-2 .. j+2);
 *      then, if band j holds centre rows, tile row j's dilation (reads tile rows j-2 .. j+2) and
 *      band j's horizontal pass;
 *   3. the fused pass of band b = k - 3 if none of its rows is in the centre rectangle, once step 2
 *      is done up to b + 1 (the near layer up-sampled reads block rows up to 4 b + 4, the half-
 *      resolution blur's halo the half-resolution CoC of band b + 1);
 *   4. the fused pass of the centre band b = k - 4, once step 2 is done up to b + 2 (the vertical
 *      Gaussian's and near box's reach, 24 rows).
 * The near reach: a tile's dilation spans ceil(rmax / 16) tiles, rmax the frame's largest near
 * radius (fvw_dilate_tiles), and a tile it marks runs the near box even for radius-0 near pixels
 * (their own colour in the transition ring), so the span must be the frame's. rmax <= FV_DOF_RMAX
 * = 24: once a tile row up to j + 2 has a radius above 16 the span is 2 tiles whatever follows;
 * until then step 2 guesses 1 tile (right whenever the frame's radii stay at or below 16, the
 * usual case: 4 px on the range at medium; with no near pixel at all every dilation is 0). After
 * the job fvw_pipe_settle drops a guessed band's horizontal pass if the frame's span is 2, and
 * the fused pass of every centre band within 2 bands of one (conservative: the guess changes only
 * a band's own radius-0 pixels); the passes after the job make them again, as before. Nothing the
 * free bands read depends on it (no full-resolution near or far layer outside the centre
 * rectangle).
 *
 * A task waits only for steps of tasks with a smaller index, which were claimed before it and run
 * on other threads (fv_pool_run runs every claimed item to its end), so the job always makes
 * progress, on one thread in plain order. Which step runs where is a function of the frame, and
 * each band's data too (the per-row reach in steps 1-2 is exact: the near box kernels skip taps
 * beyond a source's radius), so the output is the same for any thread count and the same as the
 * passes one after another (prm.band_passes). */
#include "dof/weier_passes.h"

#include "base/clock.h"

/* the fused pass of a free band runs PIPE_LAG tasks after its CoC work, a centre band's one more */
#define PIPE_LAG 3

int fvw_pipe_free(const fvw_ctx *x, int band) { return band < x->pc0 || band >= x->pc1; }

/* the counter of step bit (PIPE_COC, PIPE_LV, PIPE_H), NULL for the other bits */
static int *upto_of(fvw_ctx *x, int bit)
{
    return bit == PIPE_COC ? &x->coc_upto : bit == PIPE_LV ? &x->lv_upto : bit == PIPE_H ? &x->h_upto : NULL;
}

/* marks step `bit` of band done (with `extra` bits) and advances that step's counter over the
 * bands done in order */
static void pipe_done(fvw_ctx *x, int band, int bit, int extra)
{
    pthread_mutex_lock(&x->pmu);
    x->pflag[band] |= bit | extra;
    int *upto = upto_of(x, bit);
    if (upto) {
        while (*upto < x->th && (x->pflag[*upto] & bit))
            ++*upto;
        pthread_cond_broadcast(&x->pcv);
    }
    pthread_mutex_unlock(&x->pmu);
}

/* waits until step `bit` is done for every band up to `band` (clamped to the last) */
static void pipe_wait(fvw_ctx *x, int band, int bit)
{
    band = band < x->th - 1 ? band : x->th - 1;
    pthread_mutex_lock(&x->pmu);
    const int *upto = upto_of(x, bit);
    while (*upto <= band)
        pthread_cond_wait(&x->pcv, &x->pmu);
    pthread_mutex_unlock(&x->pmu);
}

/* the near reach is 2 tiles for sure: a tile row up to j + 2 (step 1 is done up to there) has a
 * near radius above 16 */
static int reach_known(const fvw_ctx *x, int j)
{
    for (int ty = 0; ty <= j + 2 && ty < x->th; ty++)
        for (int tx = 0; tx < x->tw; tx++)
            if (x->t_near_own[ty * x->tw + tx] > (float)TILE)
                return 1;
    return 0;
}

void fvw_pipe_settle(fvw_ctx *x)
{
    /* a guessed reach of 1 tile was right unless the frame's is 2 (a reach of 0: no tile has a near
     * radius, so any dilation gives 0s) */
    for (int j = x->pc0; j < x->pc1; j++)
        if ((x->pflag[j] & PIPE_HP) && !(x->pflag[j] & PIPE_D2) && x->near_tiles > 1)
            x->pflag[j] &= ~PIPE_HP;
    /* a fused band is kept if every horizontal pass it read (bands b-2 .. b+2) is */
    for (int b = x->pc0; b < x->pc1; b++)
        for (int j = b - 2 > x->pc0 ? b - 2 : x->pc0; j <= b + 2 && j < x->pc1; j++)
            if (!(x->pflag[j] & PIPE_HP))
                x->pflag[b] &= ~PIPE_FUSED;
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
        pipe_done(x, k, PIPE_COC, 0);
    }
    const int j = k - 2;
    if (j >= 0 && j < x->th) {
        pipe_wait(x, j + 2, PIPE_COC);
        int64_t t0 = fv_time_ns();
        fvw_lvpass_band(x, j, tid);
        pipe_done(x, j, PIPE_LV, 0);
        int made = 0;
        if (!fvw_pipe_free(x, j)) {
            const int dn = reach_known(x, j) ? 2 : 1;
            fvw_dilate_row(x, j, dn);
            fvw_hpass_band(x, j, tid);
            made = PIPE_HP | (dn == 2 ? PIPE_D2 : 0);
        }
        x->band_ms[BAND_MS * j + 5] += (float)((double)(fv_time_ns() - t0) * 1e-6);
        pipe_done(x, j, PIPE_H, made);
    }
    const int b = k - PIPE_LAG;
    if (b >= 0 && b < x->th && fvw_pipe_free(x, b)) {
        pipe_wait(x, b + 1, PIPE_LV);
        const int64_t t0 = prof ? fv_time_ns() : 0;
        fvw_vcombine_band(x, b, tid);
        if (prof)
            fv_prof_span(prof, tid, tid, "dof fused band", t0, fv_time_ns(), b);
        pipe_done(x, b, PIPE_FUSED, 0);
    }
    const int c = k - PIPE_LAG - 1;
    if (c >= 0 && c < x->th && !fvw_pipe_free(x, c)) {
        pipe_wait(x, c + 2, PIPE_H); /* implies PIPE_LV up to c + 2 */
        const int64_t t0 = prof ? fv_time_ns() : 0;
        fvw_vcombine_band(x, c, tid);
        if (prof)
            fv_prof_span(prof, tid, tid, "dof fused band", t0, fv_time_ns(), c);
        pipe_done(x, c, PIPE_FUSED, 0);
    }
}
