/* fovea: the layered filter's blur passes (stage "dof_filter"): the horizontal pass of the far
 * and near layers, the quarter-resolution near layer, the periphery's pyramid blur and the
 * fused vertical pass, which hands each finished row to the combine (combine.c). */
#include "dof/weier_passes.h"
#include "output_convert.h"

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

/* a + t (b - a) over n floats (restrict-qualified so the compiler vectorises it) */
static void vlerp(float *restrict d, const float *restrict a, const float *restrict b, float t, int n)
{
    for (int i = 0; i < n; i++)
        d[i] = a[i] + t * (b[i] - a[i]);
}

/* Image `src` (2^L destination pixels a texel) bilinearly up-sampled to destination row y,
 * columns [xa, xb) (dst indexed from 0). Separable: the two source rows are blended once into
 * tmp over the texels those columns read, then each pixel reads two texels. */
void fvw_upsample_row(const fv_dof_dsp *dsp, const img4 *src, int L, const xtaps *xt, int y, int xa, int xb,
                      float *restrict tmp, float *restrict dst)
{
    if (xa >= xb)
        return;
    const float sc = 1.0f / (float)(1 << L);
    const float v = ((float)y + 0.5f) * sc - 0.5f, fv = floorf(v), ay = v - fv;
    const float *ra = src->px + 4 * (ptrdiff_t)fv_clampi((int)fv, 0, src->h - 1) * src->stride;
    const float *rb = src->px + 4 * (ptrdiff_t)fv_clampi((int)fv + 1, 0, src->h - 1) * src->stride;
    const int t0 = xt->i0[xa], t1 = xt->i1[xb - 1] + 1; /* the taps grow with x */
    vlerp(tmp + 4 * t0, ra + 4 * t0, rb + 4 * t0, ay, 4 * (t1 - t0));
    dsp->dof_upsample_row(dst + 4 * xa, tmp, L, src->w, xa, xb - xa);
}

/* One tap row of the scatter-as-gather box down the columns (the horizontal one is the kernel
 * dof_nearbox_row): out[i] += wgt[i] src[i] for the n columns whose radius r[i] >= aj (the tap's
 * |offset|). Row by row in the reference's order of taps; a tap that does not reach adds +0
 * (0 times a finite value) to a sum that started at +0, which leaves its bits as skipping it
 * did, so the loop has no branch and the compiler can vectorise it. */
static void near_box_tap(float *restrict out, const float *restrict src, const float *restrict r,
                         const float *restrict wgt, float aj, int n)
{
    for (int i = 0; i < n; i++) {
        const float m = r[i] < aj ? 0.0f : wgt[i];
        for (int c = 0; c < 4; c++)
            out[4 * i + c] += m * src[4 * i + c];
    }
}

/* The near sources of columns [lo, hi): radius r = min(floor(-c / 2), FV_DOF_RMAX) for c < 0,
 * else -1; box weight 1 / (2 max(r, 0) + 1); colour with coverage 1. floor is the truncation of
 * the clamped, non-negative half CoC, so the loop vectorises (SSE2 conversions). */
static void near_sources(float *restrict s4, float *restrict sr, float *restrict sw, const float *restrict rgbd,
                         const float *restrict coc, int lo, int hi)
{
    for (int i = lo; i < hi; i++) {
        const float c = coc[i], h = -c * 0.5f;
        const float hc = h < (float)FV_DOF_RMAX ? (h > 0.0f ? h : 0.0f) : (float)FV_DOF_RMAX;
        const float r = c < 0.0f ? (float)(int)hc : -1.0f;
        sr[i] = r;
        sw[i] = 1.0f / (2.0f * (r > 0.0f ? r : 0.0f) + 1.0f);
    }
    for (int i = lo; i < hi; i++) {
        s4[4 * i + 0] = rgbd[4 * i + 0];
        s4[4 * i + 1] = rgbd[4 * i + 1];
        s4[4 * i + 2] = rgbd[4 * i + 2];
        s4[4 * i + 3] = 1.0f;
    }
}

/* Horizontal pass of one band: far_h (p4[1]) and near_h (p4[3], radius p1[2], weight p1[1]) in
 * the centre rectangle, and the band's quarter-resolution rows. */
void fvw_hpass_band(void *ctx, int band, int tid)
{
    fvw_ctx *x = ctx;
    const fv_pyr_level *l0 = &x->v->pyr->lv[0];
    const ptrdiff_t st = x->wk->stride;
    const int y0 = band * TILE, y1 = fv_mini(y0 + TILE, x->h);
    uint8_t sig[TILE * 8];
    for (int y = y0 > x->cy0 ? y0 : x->cy0; y < y1 && y < x->cy1; y++) {
        const float *rgbd = l0->rgbd + 4 * (ptrdiff_t)y * l0->stride;
        const float *coc = x->wk->p1[0] + y * st;
        float *fh = x->wk->p4[1] + 4 * y * st;
        /* the far Gaussian is read only by pixels inside the transition disc (t < 1), from rows
         * up to FV_DOF_RMAX away: this row is needed over the widest disc span within that
         * reach, the one nearest the gaze's row */
        int fa, fb;
        fvw_disc_span(x, fv_clampf(x->v->gaze_y, (float)y + 0.5f - FV_DOF_RMAX, (float)y + 0.5f + FV_DOF_RMAX), &fa, &fb);
        fa = fa > x->cx0 ? fa : x->cx0, fb = fb < x->cx1 ? fb : x->cx1;
        for (int xs = fa; xs < fb; xs += TILE * 8) {
            const int n = fv_mini(fb - xs, TILE * 8);
            for (int i = 0; i < n; i++) {
                const float c = coc[xs + i];
                sig[i] = fvw_sig_index(c > 0.0f ? c * 0.25f : x->t_fsig[band * x->tw + (xs + i) / TILE]);
            }
            x->dsp->dof_hgauss_row(fh, rgbd, coc, x->w, xs, n, sig, x->tab);
        }
        /* near sources of the row: premultiplied colour, radius (-1: not near), box weight, in
         * the thread's row buffers (only this row reads them); the horizontal result's radius and
         * weight go straight to p1[1] / p1[2] for the vertical pass */
        float *s4 = fvw_slot(x, tid, 0), *sr = fvw_slot(x, tid, 1), *sw = sr + x->w;
        float *nh = x->wk->p4[3] + 4 * y * st, *nr = x->wk->p1[1] + y * st, *nw = x->wk->p1[2] + y * st;
        int prepped = 0;
        for (int tx = x->cx0 / TILE; tx * TILE < x->cx1; tx++) {
            const int reach = (int)x->t_near[band * x->tw + tx];
            if (reach <= 0)
                continue;
            if (!prepped) {
                const int lo = x->cx0 - FV_DOF_RMAX > 0 ? x->cx0 - FV_DOF_RMAX : 0;
                const int hi = fv_mini(x->cx1 + FV_DOF_RMAX, x->w);
                near_sources(s4, sr, sw, rgbd, coc, lo, hi);
                prepped = 1;
            }
            const int i0 = tx * TILE > x->cx0 ? tx * TILE : x->cx0, i1 = fv_mini((tx + 1) * TILE, x->cx1);
            x->dsp->dof_nearbox_row(nh, nr, nw, s4, sr, sw, x->w, i0, i1 - i0, reach);
        }
    }
    /* the quarter-resolution rows of this band (the band pipeline made them after its CoC work) */
    if (x->l_reach >= 0 && !x->pipe)
        for (int by = y0 / LOW; by < (y1 + LOW - 1) / LOW; by++) {
            const ptrdiff_t o = (ptrdiff_t)by * x->lw;
            x->dsp->dof_nearbox_row(x->l_h + 4 * o, x->l_hr + o, x->l_hw + o, x->l_src + 4 * o, x->l_r + o, x->l_w + o,
                                    x->lw, 0, x->lw, x->l_reach);
        }
}

/* The band pipeline's quarter-resolution horizontal rows of a band, right after its CoC work:
 * each block row to its own largest radius (at least 0) instead of the frame's, which the
 * pipeline does not know yet. The same bits: dof_nearbox_row adds only the taps within a
 * source's radius, and no source of the row has a larger one; a row without near blocks gets
 * what the frame's reach gives it (+0 sums, radius +0, weight 1). Also records that radius for
 * the vertical pass (l_rowr). */
void fvw_lhpass_band(fvw_ctx *x, int band)
{
    const int y0 = band * TILE, y1 = fv_mini(y0 + TILE, x->h);
    for (int by = y0 / LOW; by < (y1 + LOW - 1) / LOW; by++) {
        const ptrdiff_t o = (ptrdiff_t)by * x->lw;
        float rmax = 0.0f;
        for (int i = 0; i < x->lw; i++)
            rmax = x->l_r[o + i] > rmax ? x->l_r[o + i] : rmax;
        const int reach = (int)rmax;
        x->l_rowr[by] = reach;
        x->dsp->dof_nearbox_row(x->l_h + 4 * o, x->l_hr + o, x->l_hw + o, x->l_src + 4 * o, x->l_r + o, x->l_w + o,
                                x->lw, 0, x->lw, reach);
    }
}

/* The quarter-resolution vertical pass (rows of blocks, a band of them per task). */
void fvw_lvpass_band(void *ctx, int band, int tid)
{
    (void)tid;
    fvw_ctx *x = ctx;
    for (int by = band * (TILE / LOW); by < fv_mini((band + 1) * (TILE / LOW), x->lh); by++) {
        int lo = x->lw, hi = 0;
        float *o = x->l_v + 4 * (ptrdiff_t)by * x->lw;
        memset(o, 0, (size_t)x->lw * 4 * sizeof(float));
        /* the band pipeline: the largest radius of the block rows within LREACH_MAX (the frame's
         * is not known yet; taps beyond a row's radius add +0: the same bits) */
        int reach = x->l_reach;
        if (x->pipe) {
            reach = 0;
            for (int r = fv_maxi(by - LREACH_MAX, 0); r <= fv_mini(by + LREACH_MAX, x->lh - 1); r++)
                reach = x->l_rowr[r] > reach && x->l_rowr[r] >= (by > r ? by - r : r - by) ? x->l_rowr[r] : reach;
        }
        const int jlo = by - reach > 0 ? -reach : -by, jhi = by + reach < x->lh ? reach : x->lh - 1 - by;
        for (int j = jlo; j <= jhi; j++) {
            const ptrdiff_t q = (ptrdiff_t)(by + j) * x->lw;
            near_box_tap(o, x->l_h + 4 * q, x->l_hr + q, x->l_hw + q, (float)(j < 0 ? -j : j), x->lw);
        }
        for (int i = 0; i < x->lw; i++)
            if (o[4 * i] != 0.0f || o[4 * i + 1] != 0.0f || o[4 * i + 2] != 0.0f || o[4 * i + 3] != 0.0f)
                lo = lo < i ? lo : i, hi = i + 1;
        x->l_span[2 * by] = lo < hi ? lo : 0;
        x->l_span[2 * by + 1] = lo < hi ? hi : 0;
    }
}

/* Row y of the quarter-resolution near layer up-sampled into lup (slot 14, all 0 at the band's
 * start): only over the columns whose texels are not all 0 (most of the image has no near
 * field), the rest of the row kept at 0 from the last row's dirty span [*da, *db). The same
 * values as up-sampling the whole row (0 + a (0 - 0) is 0). */
static void near_upsample_row(const fvw_ctx *x, int tid, int y, float *restrict lup, int *da, int *db, int na, int nb)
{
    const float v = ((float)y + 0.5f) * (1.0f / LOW) - 0.5f, fv = floorf(v);
    const int r0 = fv_clampi((int)fv, 0, x->lh - 1), r1 = fv_clampi((int)fv + 1, 0, x->lh - 1);
    const int lo = fv_mini(x->l_span[2 * r0] < x->l_span[2 * r0 + 1] ? x->l_span[2 * r0] : x->lw,
                           x->l_span[2 * r1] < x->l_span[2 * r1 + 1] ? x->l_span[2 * r1] : x->lw);
    const int hi = x->l_span[2 * r0 + 1] > x->l_span[2 * r1 + 1] ? x->l_span[2 * r0 + 1] : x->l_span[2 * r1 + 1];
    int xa = x->w, xb = x->w;
    if (lo < hi) { /* pixel x reads texels floor((x + 0.5) / 4 - 0.5) and the next: a pixel to spare */
        xa = fv_clampi(LOW * lo - LOW, 0, x->w);
        xb = fv_clampi(LOW * hi + LOW, 0, x->w);
    }
    /* and only where it is read: [na, nb) (beyond it the row keeps its 0s or stale values) */
    xa = xa > na ? xa : na, xb = xb < nb ? xb : nb;
    if (xa >= xb)
        xa = xb = x->w;
    /* zero what the last row left outside [xa, xb) */
    if (*da < *db) {
        const int za = *da, zb = fv_mini(*db, xa);
        if (za < zb)
            memset(lup + 4 * za, 0, (size_t)(zb - za) * 4 * sizeof(float));
        const int wa = *da > xb ? *da : xb, wb = *db;
        if (wa < wb)
            memset(lup + 4 * wa, 0, (size_t)(wb - wa) * 4 * sizeof(float));
    }
    const img4 im = {x->l_v, x->lw, x->lh, x->lw};
    fvw_upsample_row(x->dsp, &im, 2, &x->xt[2], y, xa, xb, fvw_slot(x, tid, 4), lup); /* LOW = 2^2 */
    *da = xa, *db = xb;
}

/* The deepest pyramid level the pixels of [xa, xb) with t > 0 read: lambda grows with |c|, so
 * it is the largest |c|'s. */
static int levels_needed(const float *lambda, const float *coc, const float *trow, int xa, int xb)
{
    float amax = 0.0f;
    for (int i = xa; i < xb; i++) {
        const float a = fabsf(coc[i]);
        amax = trow[i] > 0.0f && a > amax ? a : amax;
    }
    if (!(amax > 0.0f))
        return 0;
    const float l = lambda[fv_mini((int)(amax * LAMBDA_STEPS), (LAMBDA_N - 1))];
    return (int)l + (l > (float)(int)l);
}

/* The periphery's blur of every out-of-focus pixel of row y, columns [xa, xb), with t > 0, by its
 * own |c|: the two nearest up-sampled pyramid levels, interpolated (level 0 is the sharp row).
 * Far pixels blend it into the centre's Gaussian by t; near pixels' own blur is this alone (the
 * combine fades it in by t), the quarter-resolution near layer only spreading them over their
 * surroundings. Used in the transition region; beyond it fvw_hblur_band's half-resolution
 * result stands in for levels >= 1. */
static void blur_periphery(const fvw_ctx *x, int tid, int y, const float *coc, const float *trow, const float *sharp,
                           float *restrict blur, int xa, int xb)
{
    if (xa >= xb)
        return;
    const fv_pyramid *pyr = x->v->pyr;
    const int need = fv_mini(levels_needed(x->lambda, coc, trow, xa, xb), x->up_levels);
    float *up[MAX_UP_LEVEL + 1];
    up[0] = (float *)sharp;
    float *tmp = fvw_slot(x, tid, 2);
    for (int L = 1; L <= need; L++) {
        const fv_pyr_level *lv = &pyr->lv[L];
        const img4 im = {lv->rgbd, lv->w, lv->h, lv->stride};
        up[L] = fvw_slot(x, tid, 2 + L);
        fvw_upsample_row(x->dsp, &im, L, &x->xt[L], y, xa, xb, tmp, up[L]);
    }
    const fv_dof_pyrblur_args pa = {.coc = coc, .t = trow, .up = (const float *const *)up, .need = need,
                                    .lambda = x->lambda, .lambda_steps = LAMBDA_STEPS, .lambda_max = (LAMBDA_N - 1)};
    x->dsp->dof_pyrblur_row(blur, &pa, xa, xb - xa);
}

/* Beyond the transition disc the sampler shoots about one ray per five pixels and the blur
 * comes from the depth-blind pyramid anyway, so the levels >= 1 part of it is computed once on
 * the level 1 grid (this pass: half-resolution |c|, the 2x2 mean; levels 2.. up-sampled to that
 * grid and interpolated like blur_periphery, level 1 standing for the sharp row) and each
 * full-resolution row reads it up-sampled as its "level 1" (periphery_row): a pixel whose level
 * is below 1 still mixes in its own sharp colour at full resolution, so small CoCs stay exact.
 * Half row vy of that blur into blur (hw texels; those feeding no pixel outside the disc are
 * left as they were). ones: hw floats of 1 (the pyramid kernel's t). A function of vy and the
 * frame alone, so the global pass and the fused pass's band rows give the same bits. */
static void hblur_row(const fvw_ctx *x, int tid, int vy, const float *ones, float *restrict blur)
{
    const fv_dof_view *v = x->v;
    const fv_pyr_level *l1 = &v->pyr->lv[1];
    float *tmp = fvw_slot(x, tid, 2);
    /* a texel's centre is within 2 px per axis of every pixel it feeds, pixels outside the disc
     * are farther than r1 from the gaze: texels nearer than r1 - 3 feed none */
    const float rin = v->r1_px - 3.0f;
    int u0 = x->hw, u1 = x->hw; /* the skipped texels [u0, u1) */
    const float dy = 2.0f * (float)vy + 1.0f - v->gaze_y;
    if (rin > 0.0f && dy * dy < rin * rin) {
        const float half = sqrtf(rin * rin - dy * dy);
        u0 = fv_clampi((int)ceilf((v->gaze_x - half - 1.0f) * 0.5f) + 1, 0, x->hw);
        u1 = fv_clampi((int)floorf((v->gaze_x + half - 1.0f) * 0.5f), 0, x->hw);
        if (u1 <= u0)
            u0 = u1 = x->hw;
    }
    const float *ch = x->hcoc + (ptrdiff_t)vy * x->hw; /* the 2x2-mean |c| (the CoC pass) */
    const float *sharp = l1->rgbd + 4 * (ptrdiff_t)vy * l1->stride;
    const int seg[2][2] = {{0, u0}, {u1, x->hw}};
    for (int k = 0; k < 2; k++) {
        const int a = seg[k][0], b = seg[k][1];
        if (a >= b)
            continue;
        float amax = 0.0f;
        for (int u = a; u < b; u++)
            amax = ch[u] > amax ? ch[u] : amax;
        memcpy(blur + 4 * a, sharp + 4 * a, (size_t)(b - a) * 4 * sizeof(float));
        int need = 0; /* levels_needed's: the deepest level the largest |c| reads */
        if (amax > 0.0f) {
            const float l = x->lambda_h[fv_mini((int)(amax * LAMBDA_STEPS), (LAMBDA_N - 1))];
            need = fv_mini((int)l + (l > (float)(int)l), x->up_levels - 1);
        }
        float *up[MAX_UP_LEVEL];
        up[0] = (float *)sharp;
        for (int L = 1; L <= need; L++) {
            const fv_pyr_level *lv = &v->pyr->lv[L + 1];
            const img4 im = {lv->rgbd, lv->w, lv->h, lv->stride};
            up[L] = fvw_slot(x, tid, 2 + L);
            fvw_upsample_row(x->dsp, &im, L, &x->xh[L], vy, a, b, tmp, up[L]);
        }
        const fv_dof_pyrblur_args pa = {.coc = ch, .t = ones, .up = (const float *const *)up, .need = need,
                                        .lambda = x->lambda_h, .lambda_steps = LAMBDA_STEPS,
                                        .lambda_max = (LAMBDA_N - 1)};
        x->dsp->dof_pyrblur_row(blur, &pa, a, b - a);
    }
}

/* The whole half-resolution image (x->hblur), half rows of one band (TILE / 2): for the chain of
 * kernels (contrast enhancement, prm.chain_periphery) and prm.hblur_pass; the fused path makes
 * each band's rows itself (fvw_vcombine_band). */
void fvw_hblur_band(void *ctx, int band, int tid)
{
    fvw_ctx *x = ctx;
    if (!x->half_on || x->hblur_fused)
        return;
    float *ones = fvw_slot(x, tid, 8);
    for (int i = 0; i < x->hw; i++)
        ones[i] = 1.0f;
    for (int vy = band * (TILE / 2); vy < fv_mini((band + 1) * (TILE / 2), x->hh); vy++)
        hblur_row(x, tid, vy, ones, x->hblur + 4 * (ptrdiff_t)vy * x->hw);
}

/* Columns [xa, xb) of row y beyond the transition disc: the half-resolution blur up-sampled is
 * the row's level 1 for the pyramid blur kernel (levels 0 and 1 only). */
static void periphery_row(const fvw_ctx *x, int tid, int y, const float *coc, const float *trow, const float *sharp,
                          float *restrict blur, int xa, int xb)
{
    if (xa >= xb)
        return;
    const img4 im = {x->hblur, x->hw, x->hh, x->hw};
    float *up[2] = {(float *)sharp, fvw_slot(x, tid, 9)};
    fvw_upsample_row(x->dsp, &im, 1, &x->xt[1], y, xa, xb, fvw_slot(x, tid, 2), up[1]);
    const fv_dof_pyrblur_args pa = {.coc = coc, .t = trow, .up = (const float *const *)up, .need = 1,
                                    .lambda = x->lambda, .lambda_steps = LAMBDA_STEPS, .lambda_max = (LAMBDA_N - 1)};
    x->dsp->dof_pyrblur_row(blur, &pa, xa, xb - xa);
}

/* Row y of the half-resolution blur up-sampled vertically (fixed taps 0.25 / 0.75) into h over the
 * texels that the pixels [0, a) and [b, w) read (dof_periph_row: x / 2 and its neighbours), with
 * h[-1] = h[0] and h[hw] = h[hw - 1] (the borders clamp). hb holds the half rows from vbase on. */
static void half_row(const fvw_ctx *x, int y, const float *hb, int vbase, float *restrict h, int a0, int a, int b)
{
    const float v = ((float)y + 0.5f) * 0.5f - 0.5f, fv = floorf(v), ay = v - fv;
    const float *ra = hb + 4 * (ptrdiff_t)(fv_clampi((int)fv, 0, x->hh - 1) - vbase) * x->hw;
    const float *rb = hb + 4 * (ptrdiff_t)(fv_clampi((int)fv + 1, 0, x->hh - 1) - vbase) * x->hw;
    const int seg[2][2] = {{a0, a}, {b, x->w}};
    for (int k = 0; k < 2; k++) {
        if (seg[k][0] >= seg[k][1])
            continue;
        const int ka = fv_maxi((seg[k][0] >> 1) - 1, 0), kb = fv_mini(((seg[k][1] - 1) >> 1) + 2, x->hw);
        vlerp(h + 4 * ka, ra + 4 * ka, rb + 4 * ka, ay, 4 * (kb - ka));
        if (ka == 0)
            memcpy(h - 4, h, 4 * sizeof(float));
        if (kb == x->hw)
            memcpy(h + 4 * x->hw, h + 4 * (x->hw - 1), 4 * sizeof(float));
    }
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
     * 8 t; the half-resolution blur up-sampled (9), then the enhancement's CoC-like width (9),
     * result (10), temporary (11), ones (12); the output row without a float image (13); the
     * quarter-resolution near layer up-sampled (14) */
    float *far = fvw_slot(x, tid, 0), *near = fvw_slot(x, tid, 1), *trow = fvw_slot(x, tid, 8);
    float *enh = x->enh_on ? fvw_slot(x, tid, 10) : NULL;
    /* beyond the disc (t = 1) one kernel (dof_periph_row) blurs and combines from the half-
     * resolution blur's row (slot 9, a texel of clamped border each side); with contrast
     * enhancement the chain of kernels */
    const int fused = x->half_on && !enh && !v->prm->chain_periphery;
    float *hrow = fvw_slot(x, tid, 9) + 4;
    uint8_t sig[TILE * 8];
    double filter_ns = 0.0, combine_ns = 0.0, output_ns = 0.0, coc_ns = 0.0;
    /* t is 1 outside the disc of radius r1: the row holds 1 except across the disc's span, which
     * each row writes and puts back */
    for (int i = 0; i < x->w; i++)
        trow[i] = 1.0f;
    /* the half-resolution blur's rows this band reads (a half row of halo each side), made here
     * while level 1's rows are hot instead of by a pass writing the whole image to memory and
     * this one reading it back; the halo rows are also the neighbour bands' (~25 % more of that
     * work for 2 x 7.4 MB less traffic); slot 8 (trow) is all 1 here: the kernel's t */
    const float *hb = x->hblur;
    int vbase = 0;
    if (fused && x->hblur_fused) {
        const int64_t th0 = fv_time_ns();
        const int va = fv_clampi((int)floorf(((float)y0 + 0.5f) * 0.5f - 0.5f), 0, x->hh - 1);
        const int vb = fv_clampi((int)floorf(((float)y1 - 0.5f) * 0.5f - 0.5f) + 1, 0, x->hh - 1);
        float *band_rows = fvw_hband(x, tid);
        for (int vy = va; vy <= vb; vy++)
            hblur_row(x, tid, vy, trow, band_rows + 4 * (ptrdiff_t)(vy - va) * x->hw);
        hb = band_rows, vbase = va;
        filter_ns += (double)(fv_time_ns() - th0);
    }
    int lup_da = 0, lup_db = 0; /* the up-sampled near row's span that is not 0 */
    /* the band pipeline runs the bands outside the centre rectangle before the frame's l_reach is
     * known: it up-samples every row and passes the combine NULL where the row is all 0 (below) */
    const int lup_on = x->pipe || x->l_reach >= 0;
    if (lup_on)
        memset(fvw_slot(x, tid, 14), 0, (size_t)x->w * 4 * sizeof(float));
    for (int y = y0; y < y1; y++) {
        int64_t ta = fv_time_ns();
        const float fy = (float)y + 0.5f;
        const float *sharp = l0->rgbd + 4 * (ptrdiff_t)y * l0->stride;
        const float *coc = x->wk->p1[0] + y * st;
        if (!fvw_coc_kept(x, y)) { /* the CoC pass did not keep this row: the same kernel on the same row */
            float *c = fvw_slot(x, tid, 15);
            x->dsp->dof_coc_row(c, sharp, x->w, x->K, x->dn, x->df);
            coc = c;
            const int64_t tk = fv_time_ns();
            coc_ns += (double)(tk - ta);
            ta = tk;
        }
        int tx0, tx1;
        fvw_disc_span(x, fy, &tx0, &tx1);
        for (int i = tx0; i < tx1; i++)
            trow[i] = fvw_t_of(x, (float)i + 0.5f, fy);
        /* far: the centre's Gaussian (normalised), then the periphery's pyramid blended in. Only
         * pixels with t < 1 (inside the disc's span) read the Gaussian: the periphery's blur
         * replaces it wherever t is 1, and the combine reads no far colour where c is 0 */
        const int centre_row = y >= x->cy0 && y < x->cy1;
        if (centre_row) {
            const int ga = tx0 > x->cx0 ? tx0 : x->cx0, gb = tx1 < x->cx1 ? tx1 : x->cx1;
            for (int xs = ga; xs < gb; xs += TILE * 8) {
                const int n = fv_mini(gb - xs, TILE * 8);
                for (int i = 0; i < n; i++)
                    sig[i] = fvw_sig_index(coc[xs + i] > 0.0f ? coc[xs + i] * 0.25f : 0.0f);
                x->dsp->dof_vgauss_row(far, x->wk->p4[1], st, y, x->cy0, x->cy1, xs, n, sig, x->tab);
            }
            for (int i = ga; i < gb; i++)
                if (coc[i] > 0.0f && trow[i] < 1.0f && far[4 * i + 3] > 0.0f)
                    for (int k = 0; k < 3; k++)
                        far[4 * i + k] /= far[4 * i + 3];
        }
        if (fused) /* beyond the disc the combine's kernel reads the half-resolution blur itself */
            half_row(x, y, hb, vbase, hrow, 0, tx0, tx1);
        else if (x->half_on) {
            periphery_row(x, tid, y, coc, trow, sharp, far, 0, tx0);
            periphery_row(x, tid, y, coc, trow, sharp, far, tx1, x->w);
            blur_periphery(x, tid, y, coc, trow, sharp, far, tx0, tx1);
        } else
            blur_periphery(x, tid, y, coc, trow, sharp, far, 0, x->w);
        if (fused)
            blur_periphery(x, tid, y, coc, trow, sharp, far, tx0, tx1);
        /* near: full resolution in the centre rectangle (pixels with t < 1); the quarter-
         * resolution layer up-sampled is blended in by t in the combine */
        float *nfull = NULL;
        if (centre_row) {
            nfull = near;
            /* the near loop writes only pixels with t < 1 (the disc's span), which is all the
             * fused path's combine reads */
            if (fused)
                memset(near + 4 * tx0, 0, (size_t)(tx1 - tx0) * 4 * sizeof(float));
            else
                memset(near, 0, (size_t)x->w * 4 * sizeof(float));
            /* the vertical scatter-as-gather box over the tile's columns, a tap row at a time
             * (near_box_tap: in the reference's order of taps, +0 where a tap does not reach; a
             * horizontal result with no sample, w = 0, is all +0 and adds nothing), only over
             * pixels with t < 1, i.e. within the disc's span; rows of the column outside the
             * rectangle or in tiles no near sample reaches hold no near_h: stay within
             * [cy0, cy1) and skip those tiles */
            for (int tx = x->cx0 / TILE; tx * TILE < x->cx1; tx++) {
                const int reach = (int)x->t_near[(y / TILE) * x->tw + tx];
                const int ia = fv_maxi(fv_maxi(tx * TILE, x->cx0), tx0), ib = fv_mini(fv_mini((tx + 1) * TILE, x->cx1), tx1);
                if (reach <= 0 || ia >= ib)
                    continue;
                const int jlo = y - reach > x->cy0 ? -reach : x->cy0 - y;
                const int jhi = y + reach < x->cy1 ? reach : x->cy1 - 1 - y;
                for (int j = jlo; j <= jhi; j++) {
                    const int s = y + j;
                    if (!(x->t_near[(s / TILE) * x->tw + tx] > 0.0f))
                        continue;
                    near_box_tap(near + 4 * ia, x->wk->p4[3] + 4 * (s * st + ia), x->wk->p1[1] + s * st + ia,
                                 x->wk->p1[2] + s * st + ia, (float)(j < 0 ? -j : j), ib - ia);
                }
                for (int i = ia; i < ib; i++)
                    if (!(trow[i] < 1.0f))
                        memset(near + 4 * i, 0, 4 * sizeof(float));
            }
        }
        float *lup = NULL;
        if (lup_on) {
            lup = fvw_slot(x, tid, 14);
            /* read only by pixels that are not near (c >= 0: the blocks l_nn spans) and, by the
             * chain's combine, across the disc */
            int na = 0, nb = x->w;
            if (fused) {
                const int32_t *nn = x->l_nn + 2 * (y / LOW);
                na = nn[0] < nn[1] ? LOW * nn[0] : x->w, nb = nn[0] < nn[1] ? fv_mini(LOW * nn[1], x->w) : 0;
                if (tx0 < tx1)
                    na = na < tx0 ? na : tx0, nb = nb > tx1 ? nb : tx1;
            }
            near_upsample_row(x, tid, y, lup, &lup_da, &lup_db, na, nb);
            /* the same bits as the passes one after another: outside the centre rectangle only
             * dof_periph_row reads lup (the disc is inside it), for which a row of 0s is NULL. In
             * it the combine gets the row of 0s where those passes gave NULL (no near block in the
             * frame): then the full-resolution near layer is +0 too (no tile has a near radius),
             * and n + t (s 0 - n) of n = +0 is +0: the same bits */
            if (x->pipe && !centre_row && lup_da >= lup_db)
                lup = NULL;
        }
        if (enh)
            fvw_enhance_row(x, tid, y, sharp, trow, enh);
        const int64_t tb = fv_time_ns();
        /* without a float image the row lives in slot 13 only, converted while in cache */
        float *orow = x->out ? x->out + 4 * (ptrdiff_t)y * x->out_stride : fvw_slot(x, tid, 13);
        if (fused) {
            fvw_combine_row(x, orow, sharp, coc, far, nfull, lup, trow, enh, tx0, tx1);
            x->dsp->dof_periph_row(orow, sharp, coc, hrow, lup, 0, tx0);
            x->dsp->dof_periph_row(orow, sharp, coc, hrow, lup, tx1, x->w - tx1);
        } else
            fvw_combine_row(x, orow, sharp, coc, far, nfull, lup, trow, enh, 0, x->w);
        const int64_t tc = fv_time_ns();
        if (v->conv) /* the output stage on the row just written, while it is in cache */
            fv_output_convert(v->conv, orow, x->out_stride, x->w, 1, NULL, NULL, v->rgb8 + (ptrdiff_t)y * v->rgb8_stride,
                              v->rgb8_stride);
        const int64_t td = v->conv ? fv_time_ns() : tc;
        for (int i = tx0; i < tx1; i++)
            trow[i] = 1.0f;
        filter_ns += (double)(tb - ta);
        combine_ns += (double)(tc - tb);
        output_ns += (double)(td - tc);
    }
    x->band_ms[BAND_MS * band] = (float)(filter_ns * 1e-6);
    x->band_ms[BAND_MS * band + 1] = (float)(combine_ns * 1e-6);
    x->band_ms[BAND_MS * band + 2] = (float)(output_ns * 1e-6);
    x->band_ms[BAND_MS * band + 3] = (float)(coc_ns * 1e-6);
}

