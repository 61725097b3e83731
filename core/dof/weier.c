/* fovea: Weier et al. 2018's layered depth-of-field filter (sec. 3.2, after Bukowski et al. 2013
 * and Mulder and van Liere 2000), one eye.
 *
 * CoC (stage "coc"): the signed tracking-aware thin-lens CoC of eq. (3) per pixel, in pixels:
 *   c = K (1/d - 1/g), K = k E d_i = pupil_m * focal_px * preset scale, d = the nearer bound of
 *   [d_o - t, d_o + t] (exactly 0 inside), which is eq. (3) simplified (docs/dof.md). Per 16x16
 *   tile the largest near radius and far sigma (dilated: what can reach the tile), and the
 *   near layer's quarter-resolution source (below).
 *
 * Filter (stage "dof_filter"): three layers, two separable passes.
 *   far  (c > 0). Centre and transition (eccentricity < r1): a Gaussian of sigma = c / 4 (the
 *        disc of diameter c has that standard deviation per axis) gathering ONLY far-field
 *        samples, so in-focus foreground never bleeds into the far layer; pixels in focus carry
 *        their tile's largest far sigma through the horizontal pass so that far pixels above and
 *        below gather across them. Periphery: the reconstruction pyramid, read at the level the
 *        CoC selects (level L up-sampled bilinearly has a standard deviation of about 2^L / 2),
 *        interpolated between the two nearest levels to the disc's variance. Weier reads one level
 *        with five quincunx taps per pixel; up-sampling whole rows of two levels gives a smoother
 *        result at a fraction of the cost (measured in docs/dof.md). Across the transition
 *        region both are computed and blended linearly in eccentricity (Weier's vertical pass).
 *        Beyond the transition disc (one ray per ~5 pixels there) the levels >= 1 part runs on
 *        the level 1 grid with a 2x2-mean |c| (fvw_hblur_band) and each row reads it up-sampled as
 *        its level 1, so a pixel below level 1 still mixes its own sharp colour at full resolution
 *        (tests/test_dof.c bounds the difference to the full-resolution path). There (t = 1) one
 *        kernel, dof_periph_row, does it all per pixel: the half-resolution row up-sampled by 2
 *        with fixed taps, the own-blur weight min(|c|, 1) min(3 c^2 / 44, 1) in closed form (the
 *        combine's min(1, |c|) times the level-0..1 interpolation), the near layer, the combine.
 *   near (c < 0): scatter-as-gather box: a near sample of radius r = min(floor(|c| / 2), 24)
 *        covers 2r + 1 pixels with weight 1 / (2r + 1) each, so it spreads over whatever lies
 *        around it (the focused background included) and the sum of the weights is the layer's
 *        coverage (Bukowski's alpha); the vertical pass spreads each horizontal result over its
 *        rows the same way. Full resolution around the gaze; in the periphery the same filter
 *        runs at quarter resolution on 4x4 blocks (Bukowski's reduced-resolution buffers, where
 *        acuity cannot tell), blended across the transition region like the far layer.
 *   focused: the sharp image itself.
 *
 * Combine (stage "combine"): sharp -> far layer by min(1, c) (a CoC of one pixel is fully
 * blurred), near layer alpha-blended with its coverage, then optionally Patney et al. 2016's
 * contrast enhancement in the transition and periphery: out + gain t (out - blur), the blur read
 * from the pyramid like the periphery's own blur, its width following the sampling footprint
 * 1 / sqrt(p) at the pixel's eccentricity (sigma = footprint / 2).
 *
 * The filter's vertical pass and the combine run fused per row (the layers never go to memory
 * as full images); their times are the workers' time in each, scaled to the pass's wall time.
 * Pass order: CoC (+ per-block statistics, kernel dof_nearblk_row, and the half-resolution
 * periphery's 2x2-mean CoC; the CoC plane kept only for the centre rectangle's rows) ->
 * horizontal pass (centre rectangle; near boxes by dof_nearbox_row) -> quarter-resolution
 * vertical pass -> fused pass per band: the band's rows of the periphery's half-resolution blur
 * (with a half row of halo), then per row the CoC recomputed outside the centre rectangle, the
 * vertical pass, the combine (dof_periph_row beyond the disc) and the output. With contrast
 * enhancement (or prm.chain_periphery / hblur_pass) the half-resolution blur is a pass of its own
 * over the whole image, before the fused pass.
 * On the default path these passes run as one band pipeline (weier_pipe.c): each band's fused
 * pass a few bands behind its CoC work, so that level 0 is read from memory once; the centre's
 * bands with a guessed tile dilation, made again after it if the guess was wrong (prm.band_passes:
 * the passes one after another, the same bits).
 * Every pass splits the image into bands of 16 rows; each pixel depends only on the inputs and
 * its coordinates, so the image is identical for any thread count.
 *
 * Files, one per stage: this one is the driver (scratch, constant tables, the order of the
 * passes, stage times); weier_coc.c the CoC pass, weier_filter.c the blur passes, combine.c the
 * combine, weier_pipe.c the band pipeline; weier_passes.h is their shared context. */
#include "dof/weier_passes.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "base/util.h"

void fv_dof_gauss_tab_init(fv_dof_gauss_tab *t)
{
    /* sigma in steps of 1/FV_DOF_SIG_STEPS px; radius ceil(3 sigma) (at least 1) */
    for (int s = 0; s < FV_DOF_NSIG; s++) {
        const double sig = (double)s / FV_DOF_SIG_STEPS;
        int r = (int)ceil(3.0 * sig);
        r = r < 1 ? 1 : r > FV_DOF_RMAX ? FV_DOF_RMAX : r;
        t->rad[s] = r;
        double sum = 0.0;
        for (int j = 0; j <= FV_DOF_RMAX; j++) {
            double g = 0.0;
            if (j <= r)
                g = s == 0 ? (j == 0 ? 1.0 : 0.0) : exp(-0.5 * (double)j * j / (sig * sig));
            t->w[s][j] = (float)g;
            sum += j ? 2.0 * (double)t->w[s][j] : (double)t->w[s][j];
        }
        t->inv[s] = (float)(1.0 / sum);
    }
}

/* CoC -> continuous level: interpolating two levels mixes their variances, so match the
 * variance c^2 / 16 of the disc. Level L up-sampled bilinearly to pixel centres has about the
 * box's (4^L - 1) / 12 plus the tent's 4^L / 6 averaged over phases, (3 4^L - 1) / 12 per axis
 * for L >= 1 (sigma ~ 2^L / 2); level 0 is the sharp image, variance 0. */
static void lambda_init(float *lambda)
{
    for (int i = 0; i < LAMBDA_N; i++) {
        const float c = (float)i / LAMBDA_STEPS, var = c * c * (1.0f / 16.0f);
        float lo = 0.0f, l = 0.0f;
        for (int L = 1; L <= MAX_UP_LEVEL; L++) {
            const float hi = (3.0f * (float)(1 << (2 * L)) - 1.0f) / 12.0f;
            if (var < hi) {
                l = (float)(L - 1) + (var - lo) / (hi - lo);
                break;
            }
            lo = hi, l = (float)L;
        }
        lambda[i] = l;
    }
}

/* The constant tables at the start of aux (the level LUT, then the up-sampling taps of levels
 * 1..MAX_UP_LEVEL for the work's width), followed by the per-frame scratch. */
static int half_w(int w) { return (w + 1) / 2; } /* the pyramid's level 1 */

static size_t tables_len(int w)
{
    return 2 * (size_t)LAMBDA_N + 3 * (size_t)MAX_UP_LEVEL * (size_t)w + 3 * (size_t)(MAX_UP_LEVEL - 1) * half_w(w);
}

static void taps_at(xtaps *t, float **a, int n)
{
    t->i0 = (int32_t *)(void *)*a, *a += n; /* int32 and float have the same size */
    t->i1 = (int32_t *)(void *)*a, *a += n;
    t->ax = *a, *a += n;
}

static void tables_at(float *a, int w, const float **lambda, const float **lambda_h, xtaps xt[MAX_UP_LEVEL + 1],
                      xtaps xh[MAX_UP_LEVEL])
{
    *lambda = a, a += LAMBDA_N;
    *lambda_h = a, a += LAMBDA_N;
    for (int L = 1; L <= MAX_UP_LEVEL; L++)
        taps_at(&xt[L], &a, w);
    for (int L = 1; L < MAX_UP_LEVEL; L++)
        taps_at(&xh[L], &a, half_w(w));
}

/* Scratch beyond the planes, allocated on first use and kept: the tables (built then), tiles,
 * the quarter-resolution layer, band times, per-thread rows. */
static int ensure_aux(fv_dof_work *wk, int threads, int hblur)
{
    const int w = wk->w, h = wk->h;
    const int tw = (w + TILE - 1) / TILE, th = (h + TILE - 1) / TILE;
    const size_t lw = (size_t)(w + LOW - 1) / LOW, lh = (size_t)(h + LOW - 1) / LOW;
    const size_t aux = tables_len(w) + 4 * (size_t)tw * th + lw * lh * (4 + 1 + 1 + 4 + 1 + 1 + 4) + 5 * lh + (BAND_MS + 1) * (size_t)th +
                       (hblur ? 5 : 1) * (size_t)half_w(w) * (size_t)half_w(h);
    if (wk->aux_len < aux) {
        free(wk->aux);
        if (!(wk->aux = malloc(aux * sizeof(float))))
            return wk->aux_len = 0, -1;
        wk->aux_len = aux;
        const float *lambda, *lambda_h;
        xtaps xt[MAX_UP_LEVEL + 1], xh[MAX_UP_LEVEL];
        tables_at(wk->aux, w, &lambda, &lambda_h, xt, xh);
        lambda_init(wk->aux);
        for (int i = 0; i < LAMBDA_N; i++) /* the half grid's level 0 is level 1 */
            wk->aux[LAMBDA_N + i] = fmaxf(wk->aux[i] - 1.0f, 0.0f);
        for (int L = 1; L <= MAX_UP_LEVEL; L++) /* level L's width, ceil(w / 2^L): for L = 2 also
                                                 * the quarter-resolution layer's */
            fvw_xtaps_init(&xt[L], L, w, (w + (1 << L) - 1) >> L);
        for (int L = 1; L < MAX_UP_LEVEL; L++) /* level L + 1 onto the level 1 grid */
            fvw_xtaps_init(&xh[L], L, half_w(w), (half_w(w) + (1 << L) - 1) >> L);
    }
    size_t rows = (size_t)threads * (NSLOT * 4 * (size_t)w + HBAND_ROWS * 4 * (size_t)half_w(w));
    if (rows < 8 * (size_t)w + (size_t)tw * th) /* the tile dilation's temporary after slots 0, 1 */
        rows = 8 * (size_t)w + (size_t)tw * th;
    if (wk->rows_len < rows) {
        free(wk->rows);
        if (!(wk->rows = malloc(rows * sizeof(float))))
            return wk->rows_len = 0, -1;
        wk->rows_len = rows;
    }
    return 0;
}

/* after the band pipeline: band pc0 + i unless the pipeline made it */
static void fvw_hpass_centre(void *ctx, int i, int tid)
{
    fvw_ctx *x = ctx;
    if (!(x->pflag[x->pc0 + i] & PIPE_HP))
        fvw_hpass_band(x, x->pc0 + i, tid);
}
static void fvw_vcombine_centre(void *ctx, int i, int tid)
{
    fvw_ctx *x = ctx;
    if (!(x->pflag[x->pc0 + i] & PIPE_FUSED))
        fvw_vcombine_band(x, x->pc0 + i, tid);
}

void fv_dof_weier(const fv_dof_view *v, fv_dof_work *wk, float *out, ptrdiff_t out_stride, fv_pool *pool,
                  const fv_dof_dsp *dsp, fv_dof_times *t)
{
    fvw_ctx ctx = {0}, *x = &ctx;
    x->v = v, x->wk = wk, x->dsp = dsp, x->out = out, x->out_stride = out_stride, x->tab = wk->gauss;
    x->w = v->pyr->lv[0].w, x->h = v->pyr->lv[0].h;
    x->tw = (x->w + TILE - 1) / TILE, x->th = (x->h + TILE - 1) / TILE;
    x->hw = half_w(x->w), x->hh = half_w(x->h);
    x->up_levels = fv_mini(MAX_UP_LEVEL, v->pyr->levels - 1);
    x->half_on = !v->prm->full_res_periphery && x->up_levels >= 1 && v->pyr->lv[1].w == x->hw && v->pyr->lv[1].h == x->hh;
    x->enh_on = v->prm->contrast_gain > 0.0f && v->enh_fp && v->enh_n > 0;
    x->hblur_fused = x->half_on && !x->enh_on && !v->prm->chain_periphery && !v->prm->hblur_pass;
    /* the whole half-resolution image (7.4 MB at 1280x1440) only for the paths that still make it */
    if (x->w != wk->w || x->h != wk->h || (!out && !v->conv) || ensure_aux(wk, fv_pool_threads(pool), !x->hblur_fused))
        goto fail;
    x->K = v->prm->pupil_mm * 1e-3f * v->focal_px * v->blur_scale;
    x->dn = fmaxf(v->focus_m - v->prm->tolerance_m, FV_COC_MIN_DEPTH_M), x->df = v->focus_m + v->prm->tolerance_m;
    x->inv_tr = v->r1_px > v->r0_px ? 1.0f / (v->r1_px - v->r0_px) : 1e30f;
    const int nt = x->tw * x->th;
    x->lw = (x->w + LOW - 1) / LOW, x->lh = (x->h + LOW - 1) / LOW;
    const ptrdiff_t nl = (ptrdiff_t)x->lw * x->lh;
    float *a = wk->aux;
    tables_at(a, x->w, &x->lambda, &x->lambda_h, x->xt, x->xh);
    a += tables_len(x->w);
    x->t_near = a, x->t_fsig = a + nt, x->t_near_own = a + 2 * nt, x->t_fsig_own = a + 3 * nt, a += 4 * nt;
    x->l_src = a, a += 4 * nl;
    x->l_r = a, a += nl;
    x->l_w = a, a += nl;
    x->l_h = a, a += 4 * nl;
    x->l_hr = a, a += nl;
    x->l_hw = a, a += nl;
    x->l_v = a, a += 4 * nl;
    x->l_span = (int32_t *)(void *)a, a += 2 * x->lh; /* int32 and float have the same size */
    x->l_nn = (int32_t *)(void *)a, a += 2 * x->lh;
    x->l_rowr = (int32_t *)(void *)a, a += x->lh;
    x->band_ms = a, a += BAND_MS * x->th;
    x->pflag = (int32_t *)(void *)a, a += x->th;
    x->hcoc = a, a += (ptrdiff_t)x->hw * x->hh;
    x->hblur = x->hblur_fused ? NULL : a; /* last: allocated only when needed */
    /* the centre rectangle: the transition disc plus the kernels' reach */
    const float reach = v->r1_px + 2.0f * FV_DOF_RMAX;
    x->cx0 = fv_clampi((int)floorf(v->gaze_x - reach), 0, x->w), x->cx1 = fv_clampi((int)ceilf(v->gaze_x + reach), 0, x->w);
    x->cy0 = fv_clampi((int)floorf(v->gaze_y - reach), 0, x->h), x->cy1 = fv_clampi((int)ceilf(v->gaze_y + reach), 0, x->h);
    x->hband = wk->rows + (size_t)fv_pool_threads(pool) * NSLOT * 4 * (size_t)x->w;
    /* the band pipeline (weier_pipe.c) on the default path: the bands [pc0, pc1) hold the centre
     * rectangle's rows (horizontal pass, fused a band later than the others) */
    x->pipe = x->hblur_fused && !v->prm->band_passes;
    x->pc0 = x->pc1 = 0;
    if (x->cy0 < x->cy1)
        x->pc0 = x->cy0 / TILE, x->pc1 = (x->cy1 + TILE - 1) / TILE;
    memset(x->band_ms, 0, BAND_MS * (size_t)x->th * sizeof(float));
    const int64_t t0 = fv_dof_stage_begin(v, FV_STAGE_COC);
    if (x->pipe) {
        /* the CoC, horizontal, quarter-resolution and fused passes in one job (its span is the
         * coc stage's; the stage times below split it by the workers' measured shares) */
        memset(x->pflag, 0, (size_t)x->th * sizeof(int32_t));
        x->coc_upto = x->lv_upto = x->h_upto = 0;
        pthread_mutex_init(&x->pmu, NULL);
        pthread_cond_init(&x->pcv, NULL);
        fv_pool_run(pool, x->th + 4, fvw_pipe_task, x);
        pthread_cond_destroy(&x->pcv);
        pthread_mutex_destroy(&x->pmu);
    } else
        fv_pool_run(pool, x->th, fvw_coc_band, x);
    const int64_t tp = fv_time_ns();
    fvw_dilate_tiles(x);
    if (x->pipe)
        fvw_pipe_settle(x);
    const int64_t t1 = fv_dof_stage_end(v, FV_STAGE_COC, t0);
    /* the combine (and with v->conv the conversion to the display format) runs fused into the
     * vertical pass: one dof_filter span holds them, and each one's share of the fused time is
     * the workers' measured share */
    const int64_t tf = fv_dof_stage_begin(v, FV_STAGE_DOF_FILTER);
    int64_t t2;
    if (x->pipe) { /* the centre's bands the pipeline's guess got wrong (none, usually) */
        const int nc = x->pc1 - x->pc0;
        fv_pool_run(pool, nc, fvw_hpass_centre, x);
        t2 = fv_time_ns();
        fv_pool_run(pool, nc, fvw_vcombine_centre, x);
    } else {
        fv_pool_run(pool, x->th, fvw_hpass_band, x);
        fv_pool_run(pool, x->th, fvw_lvpass_band, x);
        fv_pool_run(pool, x->th, fvw_hblur_band, x);
        t2 = fv_time_ns();
        fv_pool_run(pool, x->th, fvw_vcombine_band, x);
    }
    const int64_t t3 = fv_dof_stage_end(v, FV_STAGE_DOF_FILTER, tf);
    if (t) {
        /* per phase the workers' shares: [0] the pipeline (band pipeline only), [1] the fused
         * pass after it (or the only one) */
        double f[2] = {0}, c[2] = {0}, o[2] = {0}, k[2] = {0}, kp = 0.0, lp = 0.0;
        for (int b = 0; b < x->th; b++) {
            const float *m = x->band_ms + BAND_MS * b;
            const int ph = x->pipe && (x->pflag[b] & PIPE_FUSED) ? 0 : 1;
            f[ph] += m[0], c[ph] += m[1], o[ph] += m[2], k[ph] += m[3];
            kp += m[4], lp += m[5];
        }
        double coc = 0.0, filter = 0.0, comb = 0.0, outp = 0.0;
        if (x->pipe) {
            const double wall = (double)(tp - t0) * 1e-6, all = f[0] + c[0] + o[0] + k[0] + kp + lp;
            if (all > 0.0)
                coc += wall * (k[0] + kp) / all, filter += wall * (f[0] + lp) / all, comb += wall * c[0] / all,
                    outp += wall * o[0] / all;
            else
                coc += wall;
            coc += (double)(t1 - tp) * 1e-6; /* the tile dilation */
        } else
            coc += (double)(t1 - t0) * 1e-6;
        const double fused = (double)(t3 - t2) * 1e-6, all = f[1] + c[1] + o[1] + k[1];
        /* the CoC rows the fused pass recomputes belong to the coc stage */
        coc += all > 0.0 ? fused * k[1] / all : 0.0;
        filter += (double)(t2 - tf) * 1e-6 + (all > 0.0 ? fused * f[1] / all : fused);
        comb += all > 0.0 ? fused * c[1] / all : 0.0;
        outp += all > 0.0 ? fused * o[1] / all : 0.0;
        t->coc_ms = coc, t->filter_ms = filter, t->combine_ms = comb;
        t->output_ms = v->conv ? outp : NAN;
    }
    return;
fail:
    /* no memory for the scratch: show the image sharp rather than nothing (without a float
     * image the pipeline converts level 0 itself) */
    for (int y = 0; out && y < v->pyr->lv[0].h; y++)
        memcpy(out + 4 * (ptrdiff_t)y * out_stride, v->pyr->lv[0].rgbd + 4 * (ptrdiff_t)y * v->pyr->lv[0].stride,
               (size_t)v->pyr->lv[0].w * 4 * sizeof(float));
    if (t)
        t->coc_ms = t->filter_ms = t->combine_ms = t->output_ms = NAN; /* the pipeline converts */
}

