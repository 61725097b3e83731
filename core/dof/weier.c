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
 * Every pass splits the image into bands of 16 rows; each pixel depends only on the inputs and
 * its coordinates, so the image is identical for any thread count. */
#include "dof/dof.h"
#include "base/util.h"
#include "base/clock.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "dof/weier_impl.h"

#define TILE 16
#define LOW 4          /* the near layer's reduced resolution in the periphery: 4x4 blocks */
#define NSLOT 13       /* per-thread row buffers of the fused vertical + combine pass */
#define ENH_LEVELS 3   /* contrast enhancement: levels 1..3 (footprints up to ~8 px) */
#define MAX_UP_LEVEL 5 /* periphery far blur: levels 1..5 (CoC up to 64 px) */
#define LAMBDA_STEPS 8 /* the level LUT's steps per pixel of CoC */
#define LAMBDA_N (64 * LAMBDA_STEPS + 1) /* CoCs 0 .. 64 px */


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

/* sigma (pixels) -> table index */
static inline uint8_t sig_index(float sigma)
{
    const float s = sigma * FV_DOF_SIG_STEPS + 0.5f;
    return (uint8_t)(s < (float)(FV_DOF_NSIG - 1) ? (s > 0.0f ? (int)s : 0) : FV_DOF_NSIG - 1);
}

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

static void xtaps_init(xtaps *t, int L, int w, int src_w)
{
    const float sc = 1.0f / (float)(1 << L);
    for (int x = 0; x < w; x++) {
        const float u = ((float)x + 0.5f) * sc - 0.5f, fu = floorf(u);
        t->i0[x] = fv_clampi((int)fu, 0, src_w - 1);
        t->i1[x] = fv_clampi((int)fu + 1, 0, src_w - 1);
        t->ax[x] = u - fu;
    }
}

/* Image `src` (2^L level-0 pixels a texel) bilinearly up-sampled to level-0 row y, columns
 * [0, w). Separable: the two source rows are blended once into tmp, then each pixel reads two
 * texels. */
static void upsample_row(const fv_dof_dsp *dsp, const img4 *src, int L, const xtaps *xt, int y, int w,
                         float *restrict tmp, float *restrict dst)
{
    const float sc = 1.0f / (float)(1 << L);
    const float v = ((float)y + 0.5f) * sc - 0.5f, fv = floorf(v), ay = v - fv;
    const float *ra = src->px + 4 * (ptrdiff_t)fv_clampi((int)fv, 0, src->h - 1) * src->stride;
    const float *rb = src->px + 4 * (ptrdiff_t)fv_clampi((int)fv + 1, 0, src->h - 1) * src->stride;
    for (int i = 0; i < 4 * src->w; i++)
        tmp[i] = ra[i] + ay * (rb[i] - ra[i]);
    dsp->dof_upsample_row(dst, tmp, xt->i0, xt->i1, xt->ax, w);
}

/* ---- passes ---- */

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
    int l_reach;               /* the largest radius there */
    int up_levels;             /* periphery far blur: pyramid levels 1..up_levels are read */
    const float *lambda;       /* CoC -> continuous pyramid level (LAMBDA_N entries) */
    int enh_on;                /* contrast enhancement runs */
    float *band_ms;            /* per band: worker time (ms) in the filter and the combine (pairs) */
    xtaps xt[MAX_UP_LEVEL + 1]; /* up-sampling taps by 2^L, L = 1..MAX_UP_LEVEL */
} wctx;

static inline float t_of(const wctx *x, float fx, float fy)
{
    const float dx = fx - x->v->gaze_x, dy = fy - x->v->gaze_y;
    return fv_clampf((sqrtf(dx * dx + dy * dy) - x->v->r0_px) * x->inv_tr, 0.0f, 1.0f);
}

static void coc_band(void *ctx, int band, int tid)
{
    (void)tid;
    wctx *x = ctx;
    const fv_pyr_level *l0 = &x->v->pyr->lv[0];
    const ptrdiff_t st = x->wk->stride;
    const int y0 = band * TILE, y1 = fv_mini(y0 + TILE, x->h);
    for (int y = y0; y < y1; y++)
        x->dsp->dof_coc_row(x->wk->p1[0] + y * st, l0->rgbd + 4 * (ptrdiff_t)y * l0->stride, x->w, x->K, x->dn, x->df);
    /* one sweep for the tile statistics and the quarter-resolution near source: per 4x4 block
     * the near pixels' colour sum, count and largest |c|; per tile the largest near and far c */
    const float inv_blk = 1.0f / (LOW * LOW);
    for (int by = y0 / LOW; by < (y1 + LOW - 1) / LOW; by++) {
        float *src = x->l_src + 4 * (ptrdiff_t)by * x->lw, *rr = x->l_r + (ptrdiff_t)by * x->lw;
        memset(src, 0, (size_t)x->lw * 4 * sizeof(float));
        for (int i = 0; i < x->lw; i++)
            rr[i] = 0.0f; /* the largest |c| of the block's near pixels, for now */
        for (int y = by * LOW; y < fv_mini(by * LOW + LOW, x->h); y++) {
            const float *c = x->wk->p1[0] + y * st, *p = l0->rgbd + 4 * (ptrdiff_t)y * l0->stride;
            for (int i = 0; i < x->w; i++) {
                if (!(c[i] < 0.0f))
                    continue;
                float *b = src + 4 * (i / LOW);
                b[0] += p[4 * i], b[1] += p[4 * i + 1], b[2] += p[4 * i + 2], b[3] += 1.0f;
                rr[i / LOW] = -c[i] > rr[i / LOW] ? -c[i] : rr[i / LOW];
            }
        }
        for (int i = 0; i < x->lw; i++) {
            const float cmax = rr[i], *b = src + 4 * i;
            float r = floorf(cmax * 0.5f); /* the largest near radius in pixels, capped */
            r = r < (float)FV_DOF_RMAX ? r : (float)FV_DOF_RMAX;
            /* the tile's largest near radius (first block of the tile in the band: reset) */
            float *tn = &x->t_near_own[band * x->tw + i * LOW / TILE];
            if (by == y0 / LOW && i * LOW % TILE == 0)
                *tn = 0.0f;
            *tn = r > *tn ? r : *tn;
            /* radius in whole blocks (the up-sampling adds about one); -1: no near pixel (rr[i]
             * becomes it) */
            const float rb = b[3] > 0.0f ? floorf(r / LOW) : -1.0f;
            rr[i] = rb;
            x->l_w[(ptrdiff_t)by * x->lw + i] = 1.0f / (2.0f * (rb > 0.0f ? rb : 0.0f) + 1.0f);
            for (int k = 0; k < 4; k++)
                src[4 * i + k] *= inv_blk;
        }
    }
    for (int tx = 0; tx < x->tw; tx++) {
        float fc = 0.0f;
        for (int y = y0; y < y1; y++) {
            const float *c = x->wk->p1[0] + y * st;
            for (int i = tx * TILE; i < fv_mini((tx + 1) * TILE, x->w); i++)
                fc = c[i] > fc ? c[i] : fc;
        }
        x->t_fsig_own[band * x->tw + tx] = fc * 0.25f;
    }
}

/* Each tile learns the largest near radius / far sigma of the tiles within reach. */
static void dilate_tiles(wctx *x)
{
    float rmax = 0.0f;
    for (int i = 0; i < x->tw * x->th; i++)
        rmax = x->t_near_own[i] > rmax ? x->t_near_own[i] : rmax;
    const int dn = (int)ceilf(rmax / TILE), df = (FV_DOF_RMAX + TILE - 1) / TILE;
    for (int ty = 0; ty < x->th; ty++)
        for (int tx = 0; tx < x->tw; tx++) {
            float n = 0.0f, f = 0.0f;
            for (int j = ty - dn; j <= ty + dn; j++)
                for (int i = tx - dn; i <= tx + dn; i++)
                    if (j >= 0 && j < x->th && i >= 0 && i < x->tw && x->t_near_own[j * x->tw + i] > n)
                        n = x->t_near_own[j * x->tw + i];
            for (int j = ty - df; j <= ty + df; j++)
                for (int i = tx - df; i <= tx + df; i++)
                    if (j >= 0 && j < x->th && i >= 0 && i < x->tw && x->t_fsig_own[j * x->tw + i] > f)
                        f = x->t_fsig_own[j * x->tw + i];
            x->t_near[ty * x->tw + tx] = n;
            x->t_fsig[ty * x->tw + tx] = f;
        }
    int lr = -1; /* -1: no near block at all */
    for (ptrdiff_t i = 0; i < (ptrdiff_t)x->lw * x->lh; i++)
        lr = x->l_r[i] > (float)lr ? (int)x->l_r[i] : lr;
    x->l_reach = lr;
}

/* The scatter-as-gather box of one row: out[i] = sum over samples s within `reach` whose radius
 * r[s] >= |i - s| of wgt[s] * src[s] (4 channels); the largest such radius and its box weight. */
static void near_box_row(float *restrict out, float *restrict out_r, float *restrict out_w, const float *src,
                         ptrdiff_t step, const float *r, const float *wgt, ptrdiff_t rstep, int i, int n, int reach)
{
    float acc[4] = {0, 0, 0, 0}, rmax = 0.0f;
    const int jlo = i - reach > 0 ? -reach : -i, jhi = i + reach < n ? reach : n - 1 - i;
    for (int j = jlo; j <= jhi; j++) {
        const float rs = r[(i + j) * rstep];
        if (rs < (float)(j < 0 ? -j : j)) /* not near (-1), or does not reach */
            continue;
        const float ws = wgt[(i + j) * rstep], *p = src + (i + j) * step;
        for (int c = 0; c < 4; c++)
            acc[c] += ws * p[c];
        rmax = rs > rmax ? rs : rmax;
    }
    memcpy(out, acc, sizeof acc);
    if (out_r) {
        *out_r = rmax;
        *out_w = 1.0f / (2.0f * rmax + 1.0f);
    }
}

/* Horizontal pass of one band: far_h (p4[1]) and near_h (p4[3], radius p1[2], weight p1[1]) in
 * the centre rectangle, and the band's quarter-resolution rows. */
static void hpass_band(void *ctx, int band, int tid)
{
    (void)tid;
    wctx *x = ctx;
    const fv_pyr_level *l0 = &x->v->pyr->lv[0];
    const ptrdiff_t st = x->wk->stride;
    const int y0 = band * TILE, y1 = fv_mini(y0 + TILE, x->h);
    uint8_t sig[TILE * 8];
    for (int y = y0 > x->cy0 ? y0 : x->cy0; y < y1 && y < x->cy1; y++) {
        const float *rgbd = l0->rgbd + 4 * (ptrdiff_t)y * l0->stride;
        const float *coc = x->wk->p1[0] + y * st;
        float *fh = x->wk->p4[1] + 4 * y * st;
        for (int xs = x->cx0; xs < x->cx1; xs += TILE * 8) {
            const int n = fv_mini(x->cx1 - xs, TILE * 8);
            for (int i = 0; i < n; i++) {
                const float c = coc[xs + i];
                sig[i] = sig_index(c > 0.0f ? c * 0.25f : x->t_fsig[band * x->tw + (xs + i) / TILE]);
            }
            x->dsp->dof_hgauss_row(fh, rgbd, coc, x->w, xs, n, sig, x->tab);
        }
        /* near sources of the row: premultiplied colour, radius (-1: not near), box weight
         * (p4[0]'s row is free until the fused pass) */
        float *s4 = x->wk->p4[0] + 4 * y * st, *sr = x->wk->p1[1] + y * st, *sw = x->wk->p1[2] + y * st;
        float *nh = x->wk->p4[3] + 4 * y * st, *nr = x->wk->p4[2] + 4 * y * st, *nw = nr + st;
        int prepped = 0;
        for (int tx = x->cx0 / TILE; tx * TILE < x->cx1; tx++) {
            const int reach = (int)x->t_near[band * x->tw + tx];
            if (reach <= 0)
                continue;
            if (!prepped) {
                const int lo = x->cx0 - FV_DOF_RMAX > 0 ? x->cx0 - FV_DOF_RMAX : 0;
                const int hi = fv_mini(x->cx1 + FV_DOF_RMAX, x->w);
                for (int i = lo; i < hi; i++) {
                    const float rc = floorf(-coc[i] * 0.5f);
                    const float r = coc[i] < 0.0f ? (rc < (float)FV_DOF_RMAX ? rc : (float)FV_DOF_RMAX) : -1.0f;
                    sr[i] = r;
                    sw[i] = 1.0f / (2.0f * (r > 0.0f ? r : 0.0f) + 1.0f);
                    for (int c = 0; c < 3; c++)
                        s4[4 * i + c] = rgbd[4 * i + c];
                    s4[4 * i + 3] = 1.0f;
                }
                prepped = 1;
            }
            for (int i = tx * TILE > x->cx0 ? tx * TILE : x->cx0; i < fv_mini((tx + 1) * TILE, x->cx1); i++)
                near_box_row(nh + 4 * i, nr + i, nw + i, s4, 4, sr, sw, 1, i, x->w, reach);
        }
        /* near radius / weight of the horizontal result moved into p1[1] / p1[2] for the
         * vertical pass (the per-sample arrays are no longer needed) */
        if (prepped)
            for (int tx = x->cx0 / TILE; tx * TILE < x->cx1; tx++) {
                if (!(x->t_near[band * x->tw + tx] > 0.0f))
                    continue;
                for (int i = tx * TILE > x->cx0 ? tx * TILE : x->cx0; i < fv_mini((tx + 1) * TILE, x->cx1); i++)
                    sr[i] = nr[i], sw[i] = nw[i];
            }
    }
    /* the quarter-resolution rows of this band */
    if (x->l_reach >= 0)
        for (int by = y0 / LOW; by < (y1 + LOW - 1) / LOW; by++) {
            const ptrdiff_t o = (ptrdiff_t)by * x->lw;
            for (int i = 0; i < x->lw; i++)
                near_box_row(x->l_h + 4 * (o + i), x->l_hr + o + i, x->l_hw + o + i, x->l_src + 4 * o, 4, x->l_r + o,
                             x->l_w + o, 1, i, x->lw, x->l_reach);
        }
}

/* The quarter-resolution vertical pass (rows of blocks, a band of them per task). */
static void lvpass_band(void *ctx, int band, int tid)
{
    (void)tid;
    wctx *x = ctx;
    for (int by = band * (TILE / LOW); by < fv_mini((band + 1) * (TILE / LOW), x->lh); by++)
        for (int i = 0; i < x->lw; i++)
            near_box_row(x->l_v + 4 * ((ptrdiff_t)by * x->lw + i), NULL, NULL, x->l_h + 4 * i, 4 * (ptrdiff_t)x->lw,
                         x->l_hr + i, x->l_hw + i, x->lw, by, x->lh, x->l_reach);
}

/* Per-thread row buffers of the fused pass. */
static float *slot(const wctx *x, int tid, int k) { return x->wk->rows + ((size_t)tid * NSLOT + (size_t)k) * 4 * (size_t)x->w; }

/* The periphery's blur of every out-of-focus pixel of row y with t > 0, by its own |c|: the two
 * nearest up-sampled pyramid levels, interpolated (level 0 is the sharp row). Far pixels blend
 * it into the centre's Gaussian by t; near pixels' own blur is this alone (the combine fades it
 * in by t), the quarter-resolution near layer only spreading them over their surroundings. */
static void blur_periphery(const wctx *x, int tid, int y, const float *coc, const float *trow, const float *sharp,
                           float *restrict blur)
{
    const fv_pyramid *pyr = x->v->pyr;
    int need = 0; /* the levels this row needs */
    for (int i = 0; i < x->w; i++) {
        const float a = coc[i] < 0.0f ? -coc[i] : coc[i];
        if (a > 0.0f && trow[i] > 0.0f) {
            const float l = x->lambda[fv_mini((int)(a * LAMBDA_STEPS), (LAMBDA_N - 1))];
            const int L = (int)l + (l > (float)(int)l);
            need = L > need ? L : need;
        }
    }
    need = fv_mini(need, x->up_levels);
    float *up[MAX_UP_LEVEL + 1];
    up[0] = (float *)sharp;
    float *tmp = slot(x, tid, 2);
    for (int L = 1; L <= need; L++) {
        const fv_pyr_level *lv = &pyr->lv[L];
        const img4 im = {lv->rgbd, lv->w, lv->h, lv->stride};
        up[L] = slot(x, tid, 2 + L);
        upsample_row(x->dsp, &im, L, &x->xt[L], y, x->w, tmp, up[L]);
    }
    const fv_dof_pyrblur_args pa = {.coc = coc, .t = trow, .up = (const float *const *)up, .need = need,
                                    .lambda = x->lambda, .lambda_steps = LAMBDA_STEPS, .lambda_max = (LAMBDA_N - 1)};
    x->dsp->dof_pyrblur_row(blur, &pa, 0, x->w);
}

/* The fused vertical pass and combine of one band. */
static void vcombine_band(void *ctx, int band, int tid)
{
    wctx *x = ctx;
    const fv_dof_view *v = x->v;
    const fv_pyr_level *l0 = &v->pyr->lv[0];
    const ptrdiff_t st = x->wk->stride;
    const int y0 = band * TILE, y1 = fv_mini(y0 + TILE, x->h);
    /* slots: 0 far, 1 near, 2..7 the far periphery's temporary and up-sampled levels, reused
     * afterwards by the near layer's up-sampling (3, 4) and the enhancement's levels (5..7);
     * 8 t; the enhancement's CoC-like width (9), result (10), temporary (11), ones (12) */
    float *far = slot(x, tid, 0), *near = slot(x, tid, 1), *trow = slot(x, tid, 8);
    float *enh = x->enh_on ? slot(x, tid, 10) : NULL;
    uint8_t sig[TILE * 8];
    double filter_ns = 0.0, combine_ns = 0.0;
    for (int y = y0; y < y1; y++) {
        const int64_t ta = fv_time_ns();
        const float fy = (float)y + 0.5f;
        const float *coc = x->wk->p1[0] + y * st, *sharp = l0->rgbd + 4 * (ptrdiff_t)y * l0->stride;
        /* t is 1 outside the disc of radius r1: compute it only across the disc's span */
        const float dyr = fy - v->gaze_y, r1 = v->r1_px;
        int tx0 = x->w, tx1 = x->w;
        if (dyr * dyr < r1 * r1) {
            const float half = sqrtf(r1 * r1 - dyr * dyr);
            tx0 = fv_clampi((int)floorf(v->gaze_x - half) - 1, 0, x->w);
            tx1 = fv_clampi((int)ceilf(v->gaze_x + half) + 1, 0, x->w);
        }
        for (int i = 0; i < tx0; i++)
            trow[i] = 1.0f;
        for (int i = tx0; i < tx1; i++)
            trow[i] = t_of(x, (float)i + 0.5f, fy);
        for (int i = tx1; i < x->w; i++)
            trow[i] = 1.0f;
        /* far: the centre's Gaussian (normalised), then the periphery's pyramid blended in */
        const int centre_row = y >= x->cy0 && y < x->cy1;
        if (centre_row) {
            for (int xs = x->cx0; xs < x->cx1; xs += TILE * 8) {
                const int n = fv_mini(x->cx1 - xs, TILE * 8);
                for (int i = 0; i < n; i++)
                    sig[i] = sig_index(coc[xs + i] > 0.0f ? coc[xs + i] * 0.25f : 0.0f);
                x->dsp->dof_vgauss_row(far, x->wk->p4[1], st, y, x->cy0, x->cy1, xs, n, sig, x->tab);
            }
            for (int i = x->cx0; i < x->cx1; i++)
                if (coc[i] > 0.0f && trow[i] < 1.0f && far[4 * i + 3] > 0.0f)
                    for (int k = 0; k < 3; k++)
                        far[4 * i + k] /= far[4 * i + 3];
        }
        blur_periphery(x, tid, y, coc, trow, sharp, far);
        /* near: full resolution in the centre rectangle (pixels with t < 1); the quarter-
         * resolution layer up-sampled is blended in by t in the combine */
        float *nfull = NULL;
        if (centre_row) {
            nfull = near;
            memset(near, 0, (size_t)x->w * 4 * sizeof(float));
            for (int tx = x->cx0 / TILE; tx * TILE < x->cx1; tx++) {
                const int reach = (int)x->t_near[(y / TILE) * x->tw + tx];
                if (reach <= 0)
                    continue;
                for (int i = tx * TILE > x->cx0 ? tx * TILE : x->cx0; i < fv_mini((tx + 1) * TILE, x->cx1); i++) {
                    if (!(trow[i] < 1.0f))
                        continue;
                    /* rows of the column outside the rectangle or in tiles no near sample
                     * reaches hold no near_h: stay within [cy0, cy1) and skip those tiles */
                    float acc[4] = {0, 0, 0, 0};
                    const int jlo = y - reach > x->cy0 ? -reach : x->cy0 - y;
                    const int jhi = y + reach < x->cy1 ? reach : x->cy1 - 1 - y;
                    for (int j = jlo; j <= jhi; j++) {
                        const int s = y + j;
                        if (!(x->t_near[(s / TILE) * x->tw + tx] > 0.0f))
                            continue;
                        const float *nh = x->wk->p4[3] + 4 * (s * st + i);
                        const float r = x->wk->p1[1][s * st + i];
                        if (!(nh[3] > 0.0f) || r < (float)(j < 0 ? -j : j))
                            continue;
                        const float wgt = x->wk->p1[2][s * st + i];
                        for (int c = 0; c < 4; c++)
                            acc[c] += wgt * nh[c];
                    }
                    memcpy(near + 4 * i, acc, sizeof acc);
                }
            }
        }
        float *lup = NULL;
        if (x->l_reach >= 0) {
            lup = slot(x, tid, 3);
            const img4 im = {x->l_v, x->lw, x->lh, x->lw};
            upsample_row(x->dsp, &im, 2, &x->xt[2], y, x->w, slot(x, tid, 4), lup); /* LOW = 2^2 */
        }
        if (enh) {
            /* Patney's blur, its width following the sampling footprint fp(eccentricity): the
             * periphery's own-blur kernel with a "CoC" of 2 fp (sigma fp / 2) */
            float *ecoc = slot(x, tid, 9), *ones = slot(x, tid, 12), *up[ENH_LEVELS + 1];
            float emax = 0.0f;
            for (int i = 0; i < x->w; i++) {
                ecoc[i] = 0.0f;
                ones[i] = 1.0f;
                if (!(trow[i] > 0.0f))
                    continue;
                const float dx = (float)i + 0.5f - v->gaze_x, ecc = sqrtf(dx * dx + dyr * dyr);
                const int e = (int)(ecc / v->enh_step);
                ecoc[i] = 2.0f * v->enh_fp[e < v->enh_n - 1 ? e : v->enh_n - 1];
                emax = ecoc[i] > emax ? ecoc[i] : emax;
            }
            const float lm = x->lambda[fv_mini((int)(emax * LAMBDA_STEPS), (LAMBDA_N - 1))];
            const int need = fv_mini(fv_mini((int)lm + (lm > (float)(int)lm), ENH_LEVELS), x->up_levels);
            up[0] = (float *)sharp;
            for (int L = 1; L <= need; L++) {
                const fv_pyr_level *lv = &v->pyr->lv[L];
                const img4 im = {lv->rgbd, lv->w, lv->h, lv->stride};
                up[L] = slot(x, tid, 4 + L);
                upsample_row(x->dsp, &im, L, &x->xt[L], y, x->w, slot(x, tid, 11), up[L]);
            }
            const fv_dof_pyrblur_args ea = {.coc = ecoc, .t = ones, .up = (const float *const *)up, .need = need,
                                            .lambda = x->lambda, .lambda_steps = LAMBDA_STEPS,
                                            .lambda_max = (LAMBDA_N - 1)};
            x->dsp->dof_pyrblur_row(enh, &ea, 0, x->w);
        }
        const int64_t tb = fv_time_ns();
        fv_dof_combine_args a = {.sharp = sharp, .coc = coc, .far = far, .near = nfull, .lnear = lup, .t = trow,
                                 .enh = enh, .gain = v->prm->contrast_gain};
        x->dsp->dof_combine_row(x->out + 4 * (ptrdiff_t)y * x->out_stride, &a, 0, x->w);
        const int64_t tc = fv_time_ns();
        filter_ns += (double)(tb - ta);
        combine_ns += (double)(tc - tb);
    }
    x->band_ms[2 * band] = (float)(filter_ns * 1e-6);
    x->band_ms[2 * band + 1] = (float)(combine_ns * 1e-6);
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
static size_t tables_len(int w) { return LAMBDA_N + 3 * (size_t)MAX_UP_LEVEL * (size_t)w; }

static void tables_at(float *a, int w, const float **lambda, xtaps xt[MAX_UP_LEVEL + 1])
{
    *lambda = a, a += LAMBDA_N;
    for (int L = 1; L <= MAX_UP_LEVEL; L++) {
        xt[L].i0 = (int32_t *)(void *)a, a += w; /* int32 and float have the same size */
        xt[L].i1 = (int32_t *)(void *)a, a += w;
        xt[L].ax = a, a += w;
    }
}

/* Scratch beyond the planes, allocated on first use and kept: the tables (built then), tiles,
 * the quarter-resolution layer, band times, per-thread rows. */
static int ensure_aux(fv_dof_work *wk, int threads)
{
    const int w = wk->w, h = wk->h;
    const int tw = (w + TILE - 1) / TILE, th = (h + TILE - 1) / TILE;
    const size_t lw = (size_t)(w + LOW - 1) / LOW, lh = (size_t)(h + LOW - 1) / LOW;
    const size_t aux = tables_len(w) + 4 * (size_t)tw * th + lw * lh * (4 + 1 + 1 + 4 + 1 + 1 + 4) + 2 * (size_t)th;
    if (wk->aux_len < aux) {
        free(wk->aux);
        if (!(wk->aux = malloc(aux * sizeof(float))))
            return wk->aux_len = 0, -1;
        wk->aux_len = aux;
        const float *lambda;
        xtaps xt[MAX_UP_LEVEL + 1];
        tables_at(wk->aux, w, &lambda, xt);
        lambda_init(wk->aux);
        for (int L = 1; L <= MAX_UP_LEVEL; L++) /* level L's width, ceil(w / 2^L): for L = 2 also
                                                 * the quarter-resolution layer's */
            xtaps_init(&xt[L], L, w, (w + (1 << L) - 1) >> L);
    }
    const size_t rows = (size_t)threads * NSLOT * 4 * (size_t)w;
    if (wk->rows_len < rows) {
        free(wk->rows);
        if (!(wk->rows = malloc(rows * sizeof(float))))
            return wk->rows_len = 0, -1;
        wk->rows_len = rows;
    }
    return 0;
}

void fv_dof_weier(const fv_dof_view *v, fv_dof_work *wk, float *out, ptrdiff_t out_stride, fv_pool *pool,
                  const fv_dof_dsp *dsp, fv_dof_times *t)
{
    wctx ctx = {0}, *x = &ctx;
    x->v = v, x->wk = wk, x->dsp = dsp, x->out = out, x->out_stride = out_stride, x->tab = wk->gauss;
    x->w = v->pyr->lv[0].w, x->h = v->pyr->lv[0].h;
    x->tw = (x->w + TILE - 1) / TILE, x->th = (x->h + TILE - 1) / TILE;
    if (x->w != wk->w || x->h != wk->h || ensure_aux(wk, fv_pool_threads(pool)))
        goto fail;
    x->K = v->prm->pupil_mm * 1e-3f * v->focal_px * v->blur_scale;
    x->dn = fmaxf(v->focus_m - v->prm->tolerance_m, FV_COC_MIN_DEPTH_M), x->df = v->focus_m + v->prm->tolerance_m;
    x->inv_tr = v->r1_px > v->r0_px ? 1.0f / (v->r1_px - v->r0_px) : 1e30f;
    const int nt = x->tw * x->th;
    x->lw = (x->w + LOW - 1) / LOW, x->lh = (x->h + LOW - 1) / LOW;
    const ptrdiff_t nl = (ptrdiff_t)x->lw * x->lh;
    float *a = wk->aux;
    tables_at(a, x->w, &x->lambda, x->xt);
    a += tables_len(x->w);
    x->t_near = a, x->t_fsig = a + nt, x->t_near_own = a + 2 * nt, x->t_fsig_own = a + 3 * nt, a += 4 * nt;
    x->l_src = a, a += 4 * nl;
    x->l_r = a, a += nl;
    x->l_w = a, a += nl;
    x->l_h = a, a += 4 * nl;
    x->l_hr = a, a += nl;
    x->l_hw = a, a += nl;
    x->l_v = a, a += 4 * nl;
    x->band_ms = a, a += 2 * x->th;
    /* the centre rectangle: the transition disc plus the kernels' reach */
    const float reach = v->r1_px + 2.0f * FV_DOF_RMAX;
    x->cx0 = fv_clampi((int)floorf(v->gaze_x - reach), 0, x->w), x->cx1 = fv_clampi((int)ceilf(v->gaze_x + reach), 0, x->w);
    x->cy0 = fv_clampi((int)floorf(v->gaze_y - reach), 0, x->h), x->cy1 = fv_clampi((int)ceilf(v->gaze_y + reach), 0, x->h);
    x->up_levels = fv_mini(MAX_UP_LEVEL, v->pyr->levels - 1);
    x->enh_on = v->prm->contrast_gain > 0.0f && v->enh_fp && v->enh_n > 0;
    const int64_t t0 = fv_time_ns();
    fv_pool_run(pool, x->th, coc_band, x);
    dilate_tiles(x);
    const int64_t t1 = fv_time_ns();
    fv_pool_run(pool, x->th, hpass_band, x);
    fv_pool_run(pool, x->th, lvpass_band, x);
    const int64_t t2 = fv_time_ns();
    fv_pool_run(pool, x->th, vcombine_band, x);
    const int64_t t3 = fv_time_ns();
    if (t) {
        double f = 0.0, c = 0.0;
        for (int b = 0; b < x->th; b++)
            f += x->band_ms[2 * b], c += x->band_ms[2 * b + 1];
        const double fused = (double)(t3 - t2) * 1e-6, share = f + c > 0.0 ? c / (f + c) : 0.0;
        t->coc_ms = (double)(t1 - t0) * 1e-6;
        t->filter_ms = (double)(t2 - t1) * 1e-6 + fused * (1.0 - share);
        t->combine_ms = fused * share;
    }
    return;
fail:
    /* no memory for the scratch: show the image sharp rather than nothing */
    for (int y = 0; y < v->pyr->lv[0].h; y++)
        memcpy(out + 4 * (ptrdiff_t)y * out_stride, v->pyr->lv[0].rgbd + 4 * (ptrdiff_t)y * v->pyr->lv[0].stride,
               (size_t)v->pyr->lv[0].w * 4 * sizeof(float));
    if (t)
        t->coc_ms = t->filter_ms = t->combine_ms = NAN;
}
