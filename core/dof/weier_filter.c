/* fovea: the layered filter's blur passes (stage "dof_filter"): the horizontal pass of the far
 * and near layers, the quarter-resolution near layer, the periphery's pyramid blur and the
 * fused vertical pass, which hands each finished row to the combine (combine.c). */
#include "dof/weier_passes.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "base/clock.h"
#include "base/util.h"

void fvw_xtaps_init(xtaps *t, int L, int w, int src_w)
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
void fvw_upsample_row(const fv_dof_dsp *dsp, const img4 *src, int L, const xtaps *xt, int y, int w,
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
void fvw_hpass_band(void *ctx, int band, int tid)
{
    (void)tid;
    fvw_ctx *x = ctx;
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
                sig[i] = fvw_sig_index(c > 0.0f ? c * 0.25f : x->t_fsig[band * x->tw + (xs + i) / TILE]);
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
void fvw_lvpass_band(void *ctx, int band, int tid)
{
    (void)tid;
    fvw_ctx *x = ctx;
    for (int by = band * (TILE / LOW); by < fv_mini((band + 1) * (TILE / LOW), x->lh); by++)
        for (int i = 0; i < x->lw; i++)
            near_box_row(x->l_v + 4 * ((ptrdiff_t)by * x->lw + i), NULL, NULL, x->l_h + 4 * i, 4 * (ptrdiff_t)x->lw,
                         x->l_hr + i, x->l_hw + i, x->lw, by, x->lh, x->l_reach);
}

/* The periphery's blur of every out-of-focus pixel of row y with t > 0, by its own |c|: the two
 * nearest up-sampled pyramid levels, interpolated (level 0 is the sharp row). Far pixels blend
 * it into the centre's Gaussian by t; near pixels' own blur is this alone (the combine fades it
 * in by t), the quarter-resolution near layer only spreading them over their surroundings. */
void fvw_blur_periphery(const fvw_ctx *x, int tid, int y, const float *coc, const float *trow, const float *sharp,
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
    float *tmp = fvw_slot(x, tid, 2);
    for (int L = 1; L <= need; L++) {
        const fv_pyr_level *lv = &pyr->lv[L];
        const img4 im = {lv->rgbd, lv->w, lv->h, lv->stride};
        up[L] = fvw_slot(x, tid, 2 + L);
        fvw_upsample_row(x->dsp, &im, L, &x->xt[L], y, x->w, tmp, up[L]);
    }
    const fv_dof_pyrblur_args pa = {.coc = coc, .t = trow, .up = (const float *const *)up, .need = need,
                                    .lambda = x->lambda, .lambda_steps = LAMBDA_STEPS, .lambda_max = (LAMBDA_N - 1)};
    x->dsp->dof_pyrblur_row(blur, &pa, 0, x->w);
}

/* The fused vertical pass and combine of one band. */
void fvw_vcombine_band(void *ctx, int band, int tid)
{
    fvw_ctx *x = ctx;
    const fv_dof_view *v = x->v;
    const fv_pyr_level *l0 = &v->pyr->lv[0];
    const ptrdiff_t st = x->wk->stride;
    const int y0 = band * TILE, y1 = fv_mini(y0 + TILE, x->h);
    /* slots: 0 far, 1 near, 2..7 the far periphery's temporary and up-sampled levels, reused
     * afterwards by the near layer's up-sampling (3, 4) and the enhancement's levels (5..7);
     * 8 t; the enhancement's CoC-like width (9), result (10), temporary (11), ones (12) */
    float *far = fvw_slot(x, tid, 0), *near = fvw_slot(x, tid, 1), *trow = fvw_slot(x, tid, 8);
    float *enh = x->enh_on ? fvw_slot(x, tid, 10) : NULL;
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
            trow[i] = fvw_t_of(x, (float)i + 0.5f, fy);
        for (int i = tx1; i < x->w; i++)
            trow[i] = 1.0f;
        /* far: the centre's Gaussian (normalised), then the periphery's pyramid blended in */
        const int centre_row = y >= x->cy0 && y < x->cy1;
        if (centre_row) {
            for (int xs = x->cx0; xs < x->cx1; xs += TILE * 8) {
                const int n = fv_mini(x->cx1 - xs, TILE * 8);
                for (int i = 0; i < n; i++)
                    sig[i] = fvw_sig_index(coc[xs + i] > 0.0f ? coc[xs + i] * 0.25f : 0.0f);
                x->dsp->dof_vgauss_row(far, x->wk->p4[1], st, y, x->cy0, x->cy1, xs, n, sig, x->tab);
            }
            for (int i = x->cx0; i < x->cx1; i++)
                if (coc[i] > 0.0f && trow[i] < 1.0f && far[4 * i + 3] > 0.0f)
                    for (int k = 0; k < 3; k++)
                        far[4 * i + k] /= far[4 * i + 3];
        }
        fvw_blur_periphery(x, tid, y, coc, trow, sharp, far);
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
            lup = fvw_slot(x, tid, 3);
            const img4 im = {x->l_v, x->lw, x->lh, x->lw};
            fvw_upsample_row(x->dsp, &im, 2, &x->xt[2], y, x->w, fvw_slot(x, tid, 4), lup); /* LOW = 2^2 */
        }
        if (enh)
            fvw_enhance_row(x, tid, y, sharp, trow, enh);
        const int64_t tb = fv_time_ns();
        fvw_combine_row(x, y, sharp, coc, far, nfull, lup, trow, enh);
        const int64_t tc = fv_time_ns();
        filter_ns += (double)(tb - ta);
        combine_ns += (double)(tc - tb);
    }
    x->band_ms[2 * band] = (float)(filter_ns * 1e-6);
    x->band_ms[2 * band + 1] = (float)(combine_ns * 1e-6);
}

