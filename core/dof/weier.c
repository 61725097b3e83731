/* fovea: Weier et al. 2018's layered depth-of-field filter (sec. 3.2, after Bukowski et al. 2013
 * and Mulder and van Liere 2000), one eye, full resolution.
 *
 * CoC (stage "coc"): the signed tracking-aware thin-lens CoC of eq. (3) per pixel, in pixels:
 *   c = K (1/d - 1/g), K = k E d_i = pupil_m * focal_px * preset scale, d = the nearer bound of
 *   [d_o - t, d_o + t] (exactly 0 inside), which is eq. (3) simplified (docs/dof.md). Per 16x16
 *   tile the largest near radius and far sigma, dilated so a tile knows what can reach it.
 *
 * Filter (stage "dof_filter"), two separable passes, three layers:
 *   far  (c > 0): in the centre and transition region (eccentricity < r1 + kernel) a Gaussian of
 *        sigma = c / 4 (the disc of diameter c has that standard deviation per axis) gathering
 *        ONLY far-field samples, so in-focus foreground never bleeds into the far layer. Pixels
 *        in focus carry the tile's largest far sigma in the horizontal pass so that far pixels
 *        above and below them gather across. In the periphery the far layer is read from the
 *        reconstruction pyramid at the level the CoC selects, with five quincunx taps (the
 *        reprojection's scheme), in the combine pass that writes the pixel anyway.
 *   near (c < 0): scatter-as-gather box blur: a near sample of radius r = floor(|c| / 2) covers
 *        2r + 1 pixels with weight 1 / (2r + 1) each, so it spreads over whatever lies around it
 *        (the focused background included) and the sum of weights is the layer's coverage
 *        (Bukowski's alpha). The vertical pass spreads each horizontal result over its rows the
 *        same way. Only tiles a near sample can reach run it.
 *   focused: the sharp image itself.
 *   The vertical pass blends the two kinds of far blur across the transition region (linear in
 *   eccentricity from r0 to r1), Weier's single-pass blend.
 *
 * Combine (stage "combine"): sharp -> far layer by min(1, c) (a CoC of one pixel is fully
 * blurred), near layer alpha-blended with its coverage, then Patney et al. 2016's contrast
 * enhancement in the transition and periphery: out + gain t (out - blur), blur read from the
 * pyramid (quincunx) at the footprint of the sampling density there (1/sqrt(p) pixels).
 *
 * Determinism: every pass splits the image into bands of rows; each pixel depends only on the
 * inputs and its coordinates. */
#include "dof/dof.h"

#include <math.h>
#include <string.h>

#include "dof/weier_impl.h"
#include "pipeline.h"

#define TILE 16

static inline float clampf(float v, float lo, float hi) { return v < lo ? lo : v > hi ? hi : v; }
static inline int clampi(int v, int lo, int hi) { return v < lo ? lo : v > hi ? hi : v; }

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

/* ---- the per-pixel pieces shared by every ISA (scalar) ---- */

/* Bilinear tap of pyramid level L at level-0 pixel coordinates (fx, fy) (pixel centres at +0.5),
 * clamped at the edges, added to acc. */
void fv_dof_tap_c(const fv_pyr_level *L, int level, float fx, float fy, float acc[4])
{
    const float sc = 1.0f / (float)(1 << level);
    const float u = fx * sc - 0.5f, v = fy * sc - 0.5f;
    const float fu = floorf(u), fv = floorf(v);
    const float ax = u - fu, ay = v - fv;
    const int x0 = clampi((int)fu, 0, L->w - 1), x1 = clampi((int)fu + 1, 0, L->w - 1);
    const int y0 = clampi((int)fv, 0, L->h - 1), y1 = clampi((int)fv + 1, 0, L->h - 1);
    const float *r0 = L->rgbd + 4 * (ptrdiff_t)y0 * L->stride, *r1 = L->rgbd + 4 * (ptrdiff_t)y1 * L->stride;
    const float b00 = (1.0f - ax) * (1.0f - ay), b10 = ax * (1.0f - ay), b01 = (1.0f - ax) * ay, b11 = ax * ay;
    for (int c = 0; c < 4; c++)
        acc[c] += (b00 * r0[4 * x0 + c] + b10 * r0[4 * x1 + c]) + (b01 * r1[4 * x0 + c] + b11 * r1[4 * x1 + c]);
}

/* The pyramid level and quincunx offset that give a blur of standard deviation c / 4 (a disc of
 * diameter c): level L's box plus bilinear tent has a variance of about 4^L / 4 per axis (level
 * 0 at pixel centres: none); the four corner taps at +-o add 4/5 o^2. */
void fv_dof_footprint(float c, int max_level, int *level, float *offset)
{
    int L = 0;
    float half = c * 0.5f;
    while (L < max_level && half >= 2.0f)
        half *= 0.5f, L++;
    const float base = L ? 0.25f * (float)(1 << L) * (float)(1 << L) : 0.0f;
    const float rest = c * c * (1.0f / 16.0f) - base;
    *level = L;
    *offset = rest > 0.0f ? sqrtf(1.25f * rest) : 0.0f;
}

/* ---- passes ---- */

typedef struct {
    const fv_dof_view *v;
    fv_dof_work *wk;
    const fv_dsp *dsp;
    const fv_dof_gauss_tab *tab;
    float *out;
    ptrdiff_t out_stride;
    int w, h, tw, th;
    float K;            /* CoC scale: pupil_m * focal_px * blur_scale */
    float inv_dn, inv_df, dn, df;
    float *t_near;      /* per tile: the largest near radius that can reach it (dilated) */
    float *t_fsig;      /* per tile: the largest far sigma (dilated) */
    float *t_fsig_own;  /* per tile: its own largest far sigma */
    float *t_near_own;
    int centre_y0, centre_y1; /* rows where the Gaussian far layer is needed (+- kernel) */
    int centre_x0, centre_x1;
    int enh_level;      /* contrast enhancement: the pyramid level of the peripheral blur, 0 = off */
} wctx;

static void coc_band(void *ctx, int band, int tid)
{
    (void)tid;
    wctx *x = ctx;
    const fv_pyr_level *l0 = &x->v->pyr->lv[0];
    const int y0 = band * TILE, y1 = y0 + TILE < x->h ? y0 + TILE : x->h;
    for (int y = y0; y < y1; y++)
        x->dsp->dof_coc_row(x->wk->p1[0] + (ptrdiff_t)y * x->wk->stride, l0->rgbd + 4 * (ptrdiff_t)y * l0->stride,
                            x->w, x->K, x->dn, x->df);
    for (int tx = 0; tx < x->tw; tx++) {
        float nr = 0.0f, fc = 0.0f;
        for (int y = y0; y < y1; y++) {
            const float *c = x->wk->p1[0] + (ptrdiff_t)y * x->wk->stride;
            for (int i = tx * TILE; i < (tx + 1) * TILE && i < x->w; i++) {
                nr = -c[i] > nr ? -c[i] : nr;
                fc = c[i] > fc ? c[i] : fc;
            }
        }
        x->t_near_own[band * x->tw + tx] = floorf(nr * 0.5f);
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
}

/* Horizontal pass of one band: far_h (p4[1]) in the centre rectangle, near_h (p4[3], radius
 * p1[2]) in tiles a near sample reaches. */
static void hpass_band(void *ctx, int band, int tid)
{
    (void)tid;
    wctx *x = ctx;
    const fv_pyr_level *l0 = &x->v->pyr->lv[0];
    const ptrdiff_t st = x->wk->stride;
    const int y0 = band * TILE, y1 = y0 + TILE < x->h ? y0 + TILE : x->h;
    uint8_t sig[TILE * 8];
    for (int y = y0; y < y1; y++) {
        const float *rgbd = l0->rgbd + 4 * (ptrdiff_t)y * l0->stride;
        const float *coc = x->wk->p1[0] + y * st;
        if (y >= x->centre_y0 && y < x->centre_y1) {
            float *fh = x->wk->p4[1] + 4 * y * st;
            for (int xs = x->centre_x0; xs < x->centre_x1; xs += TILE * 8) {
                const int n = x->centre_x1 - xs < TILE * 8 ? x->centre_x1 - xs : TILE * 8;
                for (int i = 0; i < n; i++) {
                    const float c = coc[xs + i];
                    sig[i] = sig_index(c > 0.0f ? c * 0.25f : x->t_fsig[band * x->tw + (xs + i) / TILE]);
                }
                x->dsp->dof_hgauss_row(fh, rgbd, coc, x->w, xs, n, sig, x->tab);
            }
        }
        float *nh = x->wk->p4[3] + 4 * y * st, *nr = x->wk->p1[2] + y * st, *nw = x->wk->p1[1] + y * st;
        /* each near sample's radius and box weight once per row (far_v's row is free until the
         * vertical pass): radius -1 marks a sample that is not near */
        float *sr = x->wk->p4[0] + 4 * y * st, *sw = sr + st;
        int row_prepped = 0;
        for (int tx = 0; tx < x->tw; tx++) {
            const float reach = x->t_near[band * x->tw + tx];
            if (!(reach > 0.0f))
                continue;
            if (!row_prepped) {
                for (int i = 0; i < x->w; i++) {
                    const float r = coc[i] < 0.0f ? floorf(-coc[i] * 0.5f) : -1.0f;
                    sr[i] = r;
                    sw[i] = 1.0f / (2.0f * (r > 0.0f ? r : 0.0f) + 1.0f);
                }
                row_prepped = 1;
            }
            const int R = (int)reach;
            for (int i = tx * TILE; i < (tx + 1) * TILE && i < x->w; i++) {
                float acc[4] = {0, 0, 0, 0}, rmax = 0.0f;
                const int jlo = i - R > 0 ? -R : -i, jhi = i + R < x->w ? R : x->w - 1 - i;
                for (int j = jlo; j <= jhi; j++) {
                    const int s = i + j;
                    const float r = sr[s];
                    if (r < (float)(j < 0 ? -j : j)) /* not near (-1), or does not reach */
                        continue;
                    const float wgt = sw[s];
                    for (int c = 0; c < 3; c++)
                        acc[c] += wgt * rgbd[4 * s + c];
                    acc[3] += wgt;
                    rmax = r > rmax ? r : rmax;
                }
                memcpy(nh + 4 * i, acc, sizeof acc);
                nr[i] = rmax;
                nw[i] = 1.0f / (2.0f * rmax + 1.0f);
            }
        }
    }
}

/* Vertical pass of one band: far_v (p4[0], premultiplied, weight in .w) in the centre rectangle,
 * near_v (p4[2], premultiplied colour, coverage in .w) in near tiles. */
static void vpass_band(void *ctx, int band, int tid)
{
    (void)tid;
    wctx *x = ctx;
    const ptrdiff_t st = x->wk->stride;
    const int y0 = band * TILE, y1 = y0 + TILE < x->h ? y0 + TILE : x->h;
    uint8_t sig[TILE * 8];
    for (int y = y0; y < y1; y++) {
        const float *coc = x->wk->p1[0] + y * st;
        if (y >= x->centre_y0 && y < x->centre_y1) {
            float *fv = x->wk->p4[0] + 4 * y * st;
            for (int xs = x->centre_x0; xs < x->centre_x1; xs += TILE * 8) {
                const int n = x->centre_x1 - xs < TILE * 8 ? x->centre_x1 - xs : TILE * 8;
                for (int i = 0; i < n; i++)
                    sig[i] = sig_index(coc[xs + i] > 0.0f ? coc[xs + i] * 0.25f : 0.0f);
                /* rows outside the centre rectangle hold no far_h: clamp the taps into it */
                x->dsp->dof_vgauss_row(fv, x->wk->p4[1], st, y, x->centre_y0, x->centre_y1, xs, n, sig, x->tab);
            }
        }
        float *nv = x->wk->p4[2] + 4 * y * st;
        for (int tx = 0; tx < x->tw; tx++) {
            const float reach = x->t_near[band * x->tw + tx];
            if (!(reach > 0.0f))
                continue;
            const int R = (int)reach;
            for (int i = tx * TILE; i < (tx + 1) * TILE && i < x->w; i++) {
                float acc[4] = {0, 0, 0, 0};
                for (int j = -R; j <= R; j++) {
                    const int s = y + j;
                    if (s < 0 || s >= x->h)
                        continue;
                    /* a row of a tile no near sample reaches holds no near_h */
                    if (!(x->t_near[(s / TILE) * x->tw + tx] > 0.0f))
                        continue;
                    const float *nh = x->wk->p4[3] + 4 * (s * st + i);
                    const float r = x->wk->p1[2][s * st + i];
                    if (!(nh[3] > 0.0f) || r < (float)(j < 0 ? -j : j))
                        continue;
                    const float wgt = x->wk->p1[1][s * st + i];
                    for (int c = 0; c < 4; c++)
                        acc[c] += wgt * nh[c];
                }
                memcpy(nv + 4 * i, acc, sizeof acc);
            }
        }
    }
}

/* Level L bilinearly up-sampled to row y of level 0 (pixel centres), the same taps as
 * fv_dof_tap_c, done separably: the level's two rows are blended once, then each pixel reads two
 * texels. tmp holds the level's row (4 floats a texel). */
static void upsample_row(const fv_pyr_level *L, int level, int y, int w, float *restrict tmp, float *restrict dst)
{
    const float sc = 1.0f / (float)(1 << level);
    const float v = ((float)y + 0.5f) * sc - 0.5f, fv = floorf(v), ay = v - fv;
    const float *ra = L->rgbd + 4 * (ptrdiff_t)clampi((int)fv, 0, L->h - 1) * L->stride;
    const float *rb = L->rgbd + 4 * (ptrdiff_t)clampi((int)fv + 1, 0, L->h - 1) * L->stride;
    for (int i = 0; i < 4 * L->w; i++)
        tmp[i] = ra[i] + ay * (rb[i] - ra[i]);
    for (int x = 0; x < w; x++) {
        const float u = ((float)x + 0.5f) * sc - 0.5f, fu = floorf(u), ax = u - fu;
        const int i0 = clampi((int)fu, 0, L->w - 1), i1 = clampi((int)fu + 1, 0, L->w - 1);
        for (int c = 0; c < 4; c++)
            dst[4 * x + c] = tmp[4 * i0 + c] + ax * (tmp[4 * i1 + c] - tmp[4 * i0 + c]);
    }
}

static void combine_band(void *ctx, int band, int tid)
{
    (void)tid;
    wctx *x = ctx;
    const fv_dof_view *v = x->v;
    const fv_pyr_level *l0 = &v->pyr->lv[0];
    const ptrdiff_t st = x->wk->stride;
    const int y0 = band * TILE, y1 = y0 + TILE < x->h ? y0 + TILE : x->h;
    fv_dof_combine_args a = {
        .pyr = v->pyr,
        .gx = v->gaze_x,
        .gy = v->gaze_y,
        .r0 = v->r0_px,
        .inv_tr = v->r1_px > v->r0_px ? 1.0f / (v->r1_px - v->r0_px) : 1e30f,
        .gain = v->prm->contrast_gain,
    };
    float *enh = x->wk->p4[1] + 4 * y0 * st; /* far_h is consumed: the band's enhancement rows */
    for (int y = y0; y < y1; y++) {
        a.y = y;
        a.enh = NULL;
        if (x->enh_level > 0) {
            float *e = enh + 4 * (y - y0) * st;
            upsample_row(&v->pyr->lv[x->enh_level], x->enh_level, y, x->w, x->wk->p4[3] + 4 * y0 * st, e);
            a.enh = e;
        }
        a.sharp = l0->rgbd + 4 * (ptrdiff_t)y * l0->stride;
        a.coc = x->wk->p1[0] + y * st;
        a.far = y >= x->centre_y0 && y < x->centre_y1 ? x->wk->p4[0] + 4 * y * st : NULL;
        a.far_x0 = x->centre_x0, a.far_x1 = x->centre_x1;
        a.near = x->wk->p4[2] + 4 * y * st;
        float *o = x->out + 4 * (ptrdiff_t)y * x->out_stride;
        for (int tx = 0; tx < x->tw; tx++) {
            const int xs = tx * TILE, n = xs + TILE < x->w ? TILE : x->w - xs;
            a.has_near = x->t_near[band * x->tw + tx] > 0.0f;
            x->dsp->dof_combine_row(o, &a, xs, n);
        }
    }
}

void fv_dof_weier(const fv_dof_view *v, fv_dof_work *wk, float *out, ptrdiff_t out_stride, fv_pool *pool,
                  const fv_dsp *dsp, fv_dof_times *t)
{
    wctx x = {.v = v, .wk = wk, .dsp = dsp, .out = out, .out_stride = out_stride};
    x.tab = wk->gauss;
    x.w = v->pyr->lv[0].w, x.h = v->pyr->lv[0].h;
    x.tw = (x.w + TILE - 1) / TILE, x.th = (x.h + TILE - 1) / TILE;
    x.K = v->prm->pupil_mm * 1e-3f * v->focal_px * v->blur_scale;
    x.dn = v->focus_m - v->prm->tolerance_m, x.df = v->focus_m + v->prm->tolerance_m;
    x.dn = x.dn > FV_COC_MIN_DEPTH_M ? x.dn : FV_COC_MIN_DEPTH_M;
    const int nt = x.tw * x.th;
    x.t_near = wk->p1[3], x.t_fsig = x.t_near + nt, x.t_near_own = x.t_fsig + nt, x.t_fsig_own = x.t_near_own + nt;
    /* the centre rectangle: the transition disc plus the Gaussian's reach */
    const float reach = v->r1_px + 2.0f * FV_DOF_RMAX;
    x.centre_x0 = clampi((int)floorf(v->gaze_x - reach), 0, x.w), x.centre_x1 = clampi((int)ceilf(v->gaze_x + reach), 0, x.w);
    x.centre_y0 = clampi((int)floorf(v->gaze_y - reach), 0, x.h), x.centre_y1 = clampi((int)ceilf(v->gaze_y + reach), 0, x.h);

    /* Patney's kernel follows the sampling footprint 1/sqrt(p): the level whose texel covers the
     * periphery's footprint; its strength ramps with the transition weight t */
    if (v->prm->contrast_gain > 0.0f && v->enh_fp && v->enh_n > 0) {
        float fp = 1.0f;
        for (int i = 0; i < v->enh_n; i++)
            fp = v->enh_fp[i] > fp ? v->enh_fp[i] : fp;
        int L = (int)floorf(log2f(fp) + 0.5f);
        x.enh_level = clampi(L, 0, v->pyr->levels - 1);
    }
    const int64_t t0 = fv_time_ns();
    fv_pool_run(pool, x.th, coc_band, &x);
    dilate_tiles(&x);
    const int64_t t1 = fv_time_ns();
    fv_pool_run(pool, x.th, hpass_band, &x);
    fv_pool_run(pool, x.th, vpass_band, &x);
    const int64_t t2 = fv_time_ns();
    fv_pool_run(pool, x.th, combine_band, &x);
    const int64_t t3 = fv_time_ns();
    if (t) {
        t->coc_ms = (double)(t1 - t0) * 1e-6;
        t->filter_ms = (double)(t2 - t1) * 1e-6;
        t->combine_ms = (double)(t3 - t2) * 1e-6;
    }
}
