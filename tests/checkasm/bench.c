/* fovea checkasm --bench: the kernel table (bench.h) and its timing loop. */
#define _DEFAULT_SOURCE /* getloadavg */
#include "bench.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "cli.h"
#include "output.h"
#include "timewarp.h"

#include "camera.h"
#include "dof/weier_impl.h"
#include "pullpush.h"
#include "raycast.h"
#include "reproject.h"
#include "sampling.h"

#define W 1280 /* the default eye: 1280x1440 */
#define H 1440
#define EW 640 /* an eye camera image */
#define EH 480

/* deterministic inputs */
static uint32_t rnd(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}
static float frand(uint32_t *s, float lo, float hi) { return lo + (hi - lo) * (float)rnd(s) * (1.0f / 16777216.0f); }
/* a weight: half holes, a third samples, the rest partial */
static float wrand(uint32_t *s)
{
    const float u = frand(s, 0.0f, 1.0f);
    return u < 0.5f ? 0.0f : u < 0.83f ? 1.0f : frand(s, 0.05f, 0.95f);
}
static float *fplane(size_t n) { return malloc(n * sizeof(float)); }
static void fill_rgbd(float *p, size_t px, uint32_t *s, float dlo, float dhi)
{
    for (size_t i = 0; i < px; i++) {
        p[4 * i] = frand(s, 0.0f, 1.0f);
        p[4 * i + 1] = frand(s, 0.0f, 1.0f);
        p[4 * i + 2] = frand(s, 0.0f, 1.0f);
        p[4 * i + 3] = frand(s, dlo, dhi);
    }
}

/* ---- pull-push ---- */
typedef struct {
    float *rgbd, *wgt, *drgbd, *dwgt;
} pull_st;
static void *pull_setup(void)
{
    pull_st *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    t->rgbd = fplane((size_t)W * H * 4), t->wgt = fplane((size_t)W * H);
    t->drgbd = fplane((size_t)W / 2 * H / 2 * 4), t->dwgt = fplane((size_t)W / 2 * H / 2);
    if (!t->rgbd || !t->wgt || !t->drgbd || !t->dwgt)
        return free(t->rgbd), free(t->wgt), free(t->drgbd), free(t->dwgt), free(t), NULL;
    uint32_t s = 1;
    fill_rgbd(t->rgbd, (size_t)W * H, &s, 0.5f, 20.0f);
    for (size_t i = 0; i < (size_t)W * H; i++)
        t->wgt[i] = wrand(&s);
    return t;
}
static void pull_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    pull_st *t = st;
    for (int k = 0; k < rows; k++) {
        const int r = (row0 + k) % (H / 2);
        const size_t a = (size_t)(2 * r) * W, b = a + W;
        d->pp.pull_row(t->drgbd + (size_t)r * (W / 2) * 4, t->dwgt + (size_t)r * (W / 2), t->rgbd + 4 * a, t->wgt + a,
                    t->rgbd + 4 * b, t->wgt + b, W / 2);
    }
}
static void pull_free(void *st)
{
    pull_st *t = st;
    free(t->rgbd), free(t->wgt), free(t->drgbd), free(t->dwgt), free(t);
}

typedef struct {
    float *rgbd, *wgt, *coarse; /* coarse: (W/2 + 2) x (H/2 + 2) with a 1-pixel border */
} push_st;
#define CW (W / 2 + 2)
static void *push_setup(void)
{
    push_st *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    t->rgbd = fplane((size_t)W * H * 4), t->wgt = fplane((size_t)W * H);
    t->coarse = fplane((size_t)CW * (H / 2 + 2) * 4);
    if (!t->rgbd || !t->wgt || !t->coarse)
        return free(t->rgbd), free(t->wgt), free(t->coarse), free(t), NULL;
    uint32_t s = 2;
    fill_rgbd(t->rgbd, (size_t)W * H, &s, 0.5f, 20.0f);
    for (size_t i = 0; i < (size_t)W * H; i++)
        t->wgt[i] = wrand(&s);
    fill_rgbd(t->coarse, (size_t)CW * (H / 2 + 2), &s, 0.5f, 20.0f);
    return t;
}
static void push_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    push_st *t = st;
    for (int k = 0; k < rows; k++) {
        const int y = (row0 + k) % H, Y = y >> 1, Yf = y & 1 ? Y + 1 : Y - 1;
        d->pp.push_row(t->rgbd + (size_t)y * W * 4, t->wgt + (size_t)y * W, t->coarse + ((size_t)(Y + 1) * CW + 1) * 4,
                    t->coarse + ((size_t)(Yf + 1) * CW + 1) * 4, W);
    }
}
static void push_free(void *st)
{
    push_st *t = st;
    free(t->rgbd), free(t->wgt), free(t->coarse), free(t);
}

/* ---- temporal reprojection: whole 16x16 tiles through fv_taa_tile_run, a still head ---- */
typedef struct {
    fv_camera cam;
    fv_pyramid hist, cur;
    float *rgbd0, *wgt0; /* the current level 0 before reprojection */
    fv_sampler smp;
    fv_taa_params prm;
    fv_taa_frame f;
    fv_camera prev; /* taa_turn: the previous frame's camera, 1/3 deg of yaw away */
} taa_st;
static void taa_free(void *st)
{
    taa_st *t = st;
    fv_pyramid_free(&t->hist), fv_pyramid_free(&t->cur), fv_sampler_free(&t->smp);
    free(t->rgbd0), free(t->wgt0), free(t);
}
static void *taa_setup(void)
{
    taa_st *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    fv_camera_desc cd;
    fv_camera_desc_default(&cd);
    cd.width = W, cd.height = H;
    static const fv_pose origin = {{0, 0, 0}, {0, 0, 0, 1}};
    fv_sampling_params sp;
    fv_sampling_params_default(&sp);
    sp.rotate = 1;
    fv_taa_params_default(&t->prm);
    if (fv_camera_setup(&t->cam, &cd, &origin) || fv_pyramid_init(&t->hist, W, H) || fv_pyramid_init(&t->cur, W, H) ||
        fv_sampler_init(&t->smp, W, H, t->cam.focal_px, &sp))
        return taa_free(t), NULL;
    const fv_pyr_level *h0 = &t->hist.lv[0], *c0 = &t->cur.lv[0];
    const size_t n = (size_t)c0->stride * H;
    if (!(t->rgbd0 = fplane(4 * n)) || !(t->wgt0 = fplane(n)))
        return taa_free(t), NULL;
    uint32_t s = 3;
    /* history: a converged image of a wall 5 m away; current: the sampled pixels of the pattern */
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float *p = h0->rgbd + 4 * ((size_t)y * h0->stride + x);
            fill_rgbd(p, 1, &s, 5.0f, 5.0f);
            h0->wgt[(size_t)y * h0->stride + x] = 1.0f;
        }
    fv_pullpush_dsp c;
    fv_pullpush_dsp_init(&c, FV_ISA_C);
    fv_pullpush(&t->hist, &c, NULL);
    for (int y = 0; y < H; y++) {
        for (int x0 = 0; x0 < W; x0 += 32) {
            const uint32_t bits = (uint32_t)fv_sampler_row(&t->smp, x0, y, 32, W / 2, H / 2, 0);
            for (int x = x0; x < x0 + 32; x++) {
                const size_t o = (size_t)y * c0->stride + x;
                fill_rgbd(t->rgbd0 + 4 * o, 1, &s, 4.9f, 5.1f);
                t->wgt0[o] = (bits >> (x - x0)) & 1u ? 1.0f : 0.0f;
            }
        }
    }
    fv_taa_frame_setup(&t->f, &t->cam, &t->cam, &t->hist, t->prm.depth_tol);
    return t;
}
/* The same inputs with the head turning 30 deg/s (1/3 deg of yaw a 90 Hz frame): the production
 * path of a moving head (projection, the fill's check, flows of ~4-8 px), the wall's depth within
 * the tolerance so the taps and the fill really take the history. */
static void *taa_turn_setup(void)
{
    taa_st *t = taa_setup();
    if (!t)
        return NULL;
    fv_camera_desc cd;
    fv_camera_desc_default(&cd);
    cd.width = W, cd.height = H;
    const float a = 0.5f * (1.0f / 3.0f) * 3.14159265f / 180.0f;
    const fv_pose p1 = {{0, 0, 0}, {0, sinf(a), 0, cosf(a)}};
    if (fv_camera_setup(&t->prev, &cd, &p1))
        return taa_free(t), NULL;
    fv_taa_frame_setup(&t->f, &t->cam, &t->prev, &t->hist, t->prm.depth_tol);
    return t;
}
static void taa_reset(void *st)
{
    taa_st *t = st;
    const size_t n = (size_t)t->cur.lv[0].stride * H;
    memcpy(t->cur.lv[0].rgbd, t->rgbd0, 4 * n * sizeof(float));
    memcpy(t->cur.lv[0].wgt, t->wgt0, n * sizeof(float));
}
#define TX ((W + FV_TILE - 1) / FV_TILE)
#define TY ((H + FV_TILE - 1) / FV_TILE)
static void taa_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    taa_st *t = st;
    for (int k = 0; k < rows; k++) {
        const int i = (row0 + k) % (TX * TY), x0 = i % TX * FV_TILE, y0 = i / TX * FV_TILE;
        const int tw = W - x0 < FV_TILE ? W - x0 : FV_TILE, th = H - y0 < FV_TILE ? H - y0 : FV_TILE;
        fv_taa_tile_run(&t->f, &t->prm, &t->smp, W / 2, H / 2, &t->cur.lv[0], &d->taa, x0, y0, tw, th);
    }
}

/* ---- the fovea's anti-aliasing: the 12x12 AA tiles around the gaze, head turning or still ---- */
#define AA_T 12 /* tiles a side: 144, about the fovea's ~140 at 1280x1440 */
typedef struct {
    fv_camera cur, prev;
    fv_pyramid hist, l;
    float *rgbd0; /* the current level 0 before the AA */
    uint8_t *n_prev, *n_cur;
    fv_taa_frame f, still;
    fv_taa_aa_frame a;
} aa_st;
static void aa_free(void *st)
{
    aa_st *t = st;
    fv_pyramid_free(&t->hist), fv_pyramid_free(&t->l);
    free(t->rgbd0), free(t->n_prev), free(t->n_cur), free(t);
}
static void *aa_setup(void)
{
    aa_st *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    fv_camera_desc cd;
    fv_camera_desc_default(&cd);
    cd.width = W, cd.height = H;
    /* 30 deg/s of yaw at 90 Hz: 1/3 deg a frame */
    const float a = 0.5f * (1.0f / 3.0f) * 3.14159265f / 180.0f;
    const fv_pose p0 = {{0, 0, 0}, {0, 0, 0, 1}}, p1 = {{0, 0, 0}, {0, sinf(a), 0, cosf(a)}};
    if (fv_camera_setup(&t->cur, &cd, &p0) || fv_camera_setup(&t->prev, &cd, &p1) || fv_pyramid_init(&t->hist, W, H) ||
        fv_pyramid_init(&t->l, W, H))
        return aa_free(t), NULL;
    const fv_pyr_level *h0 = &t->hist.lv[0], *c0 = &t->l.lv[0];
    const size_t n = (size_t)c0->stride * H;
    if (!(t->rgbd0 = fplane(4 * n)) || !(t->n_prev = malloc((size_t)W * H)) || !(t->n_cur = malloc((size_t)W * H)))
        return aa_free(t), NULL;
    uint32_t s = 5;
    /* history: a converged wall 5 m away; current: its jittered samples, every pixel */
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            fill_rgbd(h0->rgbd + 4 * ((size_t)y * h0->stride + x), 1, &s, 5.0f, 5.0f);
            h0->wgt[(size_t)y * h0->stride + x] = 1.0f;
            fill_rgbd(t->rgbd0 + 4 * ((size_t)y * c0->stride + x), 1, &s, 4.99f, 5.01f);
            c0->wgt[(size_t)y * c0->stride + x] = 1.0f;
            t->n_prev[(size_t)y * W + x] = (uint8_t)(1 + rnd(&s) % FV_TAA_AA_MAX_N);
        }
    fv_taa_frame_setup(&t->f, &t->cur, &t->prev, &t->hist, 0.03f);
    fv_taa_frame_setup(&t->still, &t->cur, &t->cur, &t->hist, 0.03f);
    t->a.n_prev = t->n_prev, t->a.n_cur = t->n_cur, t->a.stride = W, t->a.ox = 0.3125f, t->a.oy = 0.6875f;
    memcpy(t->l.lv[0].rgbd, t->rgbd0, 4 * n * sizeof(float));
    return t;
}
static void aa_reset(void *st)
{
    aa_st *t = st;
    const size_t n = (size_t)t->l.lv[0].stride * H;
    memcpy(t->l.lv[0].rgbd, t->rgbd0, 4 * n * sizeof(float));
}
static void aa_tiles(aa_st *t, const fv_taa_frame *f, const checkasm_dsp *d, int row0, int rows)
{
    for (int k = 0; k < rows; k++) {
        const int i = (row0 + k) % (AA_T * AA_T);
        const int x0 = (W / 2 / FV_TILE - AA_T / 2 + i % AA_T) * FV_TILE, y0 = (H / 2 / FV_TILE - AA_T / 2 + i / AA_T) * FV_TILE;
        d->taa.taa_aa(f, &t->a, &t->l.lv[0], x0, y0, FV_TILE, FV_TILE);
    }
}
static void aa_turn_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    aa_st *t = st;
    aa_tiles(t, &t->f, d, row0, rows);
}
static void aa_still_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    aa_st *t = st;
    aa_tiles(t, &t->still, d, row0, rows);
}

/* ---- depth of field ---- */
typedef struct {
    float *rgbd, *coc, *a4, *b4, *c4, *out, *t;
    float *cocs, *ts; /* pyrblur: a smooth CoC and the transition ramp of t, as the pipeline's */
    float *tsd, *hcs; /* pyrblur_spans: t of the disc (r0 106, r1 212 px), the half grid's |c| */
    uint8_t *sig;
    uint8_t *sigr; /* vgauss: sigmas in runs */
    fv_dof_gauss_tab *tab;
    float *lambda;
} dof_st;
#define LSTEPS 8 /* the level table's steps per pixel of CoC (core/dof/weier.c) */
#define SPAN 128 /* the Gaussians' span per call in core/dof/weier.c (TILE * 8) */
static void dof_free(void *st)
{
    dof_st *t = st;
    free(t->rgbd), free(t->coc), free(t->a4), free(t->b4), free(t->c4), free(t->out), free(t->t), free(t->sig), free(t->sigr);
    free(t->cocs), free(t->ts), free(t->tsd), free(t->hcs), free(t->tab), free(t->lambda), free(t);
}
static void *dof_setup(void)
{
    dof_st *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    const size_t n = (size_t)W * H;
    t->rgbd = fplane(4 * n), t->coc = fplane(n), t->a4 = fplane(4 * n), t->b4 = fplane(4 * n);
    t->c4 = fplane(4 * n), t->out = fplane(4 * n), t->t = fplane(n), t->sig = malloc(n), t->sigr = malloc(n);
    t->tab = malloc(sizeof *t->tab);
    t->cocs = fplane(n), t->ts = fplane(n), t->tsd = fplane(n), t->hcs = fplane(n / 4);
    t->lambda = fplane(64 * LSTEPS + 1);
    if (!t->rgbd || !t->coc || !t->a4 || !t->b4 || !t->c4 || !t->out || !t->t || !t->sig || !t->sigr || !t->tab || !t->lambda || !t->cocs || !t->ts || !t->tsd || !t->hcs)
        return dof_free(t), NULL;
    for (int i = 0; i <= 64 * LSTEPS; i++) /* about log2 of the CoC */
        t->lambda[i] = i < LSTEPS ? 0.0f : fminf(5.0f, log2f((float)i / LSTEPS));
    fv_dof_gauss_tab_init(t->tab);
    uint32_t s = 4;
    fill_rgbd(t->rgbd, n, &s, 0.3f, 20.0f);
    fill_rgbd(t->a4, n, &s, 0.0f, 1.0f);
    fill_rgbd(t->b4, n, &s, 0.0f, 1.0f); /* near layers: coverage in .w */
    fill_rgbd(t->c4, n, &s, 0.0f, 1.0f);
    for (size_t i = 0; i < n; i++) {
        t->coc[i] = frand(&s, -6.0f, 6.0f);
        t->t[i] = frand(&s, -0.5f, 1.0f) < 0.0f ? 0.0f : frand(&s, 0.0f, 1.0f);
        t->sig[i] = (uint8_t)(4 + rnd(&s) % 13); /* sigma 1 .. 4 px */
    }
    /* the vertical Gaussian's sigmas as core/dof/weier_filter.c makes them, from a far CoC that
     * varies slowly along a row (one step of 1/4 px sigma is 1 px of CoC): runs of 8 .. 71 pixels
     * of one sigma 1 .. 4 px (a sigma per pixel made every 4-pixel block run to its largest
     * radius, which the pipeline does only at the edges of runs) */
    for (size_t i = 0; i < n;) {
        const size_t len = 8 + rnd(&s) % 64;
        const uint8_t v = (uint8_t)(4 + rnd(&s) % 13);
        for (size_t k = 0; k < len && i < n; k++, i++)
            t->sigr[i] = v;
    }
    /* pyrblur as core/dof/weier_filter.c calls it: the CoC of a rendered image varies slowly
     * (here +-6 px over tens of pixels), t is 0 in the fovea, a ramp over the transition ring
     * (radius 170 .. 350 px around the image centre), 1 beyond */
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const size_t i = (size_t)y * W + (size_t)x;
            t->cocs[i] = 6.0f * sinf((float)x * 0.043f + (float)y * 0.027f) * cosf((float)x * 0.011f - (float)y * 0.019f);
            const float dx = (float)x + 0.5f - 0.5f * W, dy = (float)y + 0.5f - 0.5f * H;
            t->ts[i] = fminf(fmaxf((sqrtf(dx * dx + dy * dy) - 170.0f) / 180.0f, 0.0f), 1.0f);
            t->tsd[i] = fminf(fmaxf((sqrtf(dx * dx + dy * dy) - 106.0f) / 106.0f, 0.0f), 1.0f);
        }
    for (int v = 0; v < H / 2; v++) /* the 2x2 mean |c| changes twice as fast a texel */
        for (int u = 0; u < W / 2; u++)
            t->hcs[(size_t)v * (W / 2) + (size_t)u] = fabsf(t->cocs[(size_t)(2 * v) * W + (size_t)(2 * u)]);
    return t;
}
static void coc_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H);
        d->dof.dof_coc_row(t->coc + y * W, t->rgbd + 4 * y * W, W, 2.4f, 1.8f, 2.2f);
    }
}
static void nearblk_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) { /* 4 rows into one block row's sums, as core/dof/weier_coc.c */
        const size_t y = (size_t)((row0 + k) % H);
        d->dof.dof_nearblk_row(t->out + 4 * (y / 4) * (W / 4), t->t + (y / 4) * (W / 2), t->coc + y * W,
                               t->rgbd + 4 * y * W, W);
    }
}
static void hcoc_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) { /* one level-1 row from two CoC rows, as core/dof/weier_coc.c */
        /* rows in cache, as there (the CoC pass has just written them): a whole plane would time
         * the memory */
        const size_t v = (size_t)((row0 + k) % 4);
        d->dof.dof_hcoc_row(t->t + v * (W / 2), t->coc + 2 * v * W, t->coc + (2 * v + 1) * W, W / 2);
    }
}
static void nearfin_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) { /* a block row (320 blocks): near sums in a4, min / max c in coc */
        const size_t v = (size_t)((row0 + k) % (H / 4));
        d->dof.dof_nearfin_row(t->t + v * W, t->t + v * W + W / 4, t->t + v * W + W / 2, t->a4 + 4 * v * (W / 4),
                               t->coc + v * (W / 2), W / 4, 1.0f); /* 1: the sums stay as they are, rep after rep */
    }
}
static void nearbox_reset(void *st) /* radii (t) and box weights (c4) from the CoC, as core/dof/weier_filter.c */
{
    dof_st *t = st;
    for (size_t i = 0; i < (size_t)W * H; i++) {
        const float r = t->coc[i] < 0.0f ? floorf(-t->coc[i] * 0.5f) : -1.0f;
        t->t[i] = r;
        t->c4[i] = 1.0f / (2.0f * (r > 0.0f ? r : 0.0f) + 1.0f);
    }
}
static void nearbox_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H);
        d->dof.dof_nearbox_row(t->out + 4 * y * W, t->b4 + y * W, t->b4 + (size_t)W * H + y * W, t->rgbd + 4 * y * W,
                               t->t + y * W, t->c4 + y * W, W, 0, W, 3);
    }
}
static void hgauss_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H);
        for (int xs = 0; xs < W; xs += SPAN) /* as core/dof/weier.c calls it */
            d->dof.dof_hgauss_row(t->out + 4 * y * W, t->rgbd + 4 * y * W, t->coc + y * W, W, xs, SPAN,
                                  t->sig + y * W + xs, t->tab);
    }
}
static void vgauss_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const int y = (row0 + k) % H;
        for (int xs = 0; xs < W; xs += SPAN)
            d->dof.dof_vgauss_row(t->out + 4 * (size_t)y * W, t->a4, W, y, 0, H, xs, SPAN, t->sigr + (size_t)y * W + xs,
                                  t->tab);
    }
}
static void upsample_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H);
        /* rows in cache, as core/dof/weier_filter.c runs it (per-thread row buffers): a whole
         * 1280x1440 plane out would time the memory, not the kernel (1.05x for any version) */
        d->dof.dof_upsample_row(t->out + 4 * (y % 4) * W, t->a4 + 4 * (y % 4) * W, 1, W / 2, 0, W);
    }
}
static void upsample_spans_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const int y = (row0 + k) % H, L = y % 8 == 7 ? 3 : 1 + (y & 1);
        const size_t v = (size_t)(y % 4);
        /* as core/dof/weier_filter.c calls it (range, DoF medium / FlightHelmet strong: by 2 and
         * by 4 about 1:1 in pixels, some by 8; ~430-px spans at any start) */
        const int x0 = (y * 97) % (W - 448);
        d->dof.dof_upsample_row(t->out + 4 * v * W, t->a4 + 4 * v * W, L, (W + (1 << L) - 1) >> L, x0, 448);
    }
}
static void pyrblur_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H), v = y % 4;
        /* the up-sampled levels and the blur row in cache, as core/dof/weier_filter.c's per-thread
         * rows (whole planes timed the memory: 5 planes in, one read and written) */
        const float *up[5] = {t->rgbd + 4 * v * W, t->a4 + 4 * v * W, t->b4 + 4 * v * W, t->c4 + 4 * v * W,
                              t->a4 + 4 * ((v + 1) % 4) * W};
        const fv_dof_pyrblur_args a = {.coc = t->cocs + y * W, .t = t->ts + y * W, .up = up, .need = 4,
                                       .lambda = t->lambda, .lambda_steps = LSTEPS, .lambda_max = 64 * LSTEPS};
        d->dof.dof_pyrblur_row(t->out + 4 * v * W, &a, 0, W);
    }
}
/* pyrblur as the pipeline calls it (core/dof/weier_filter.c; calls counted over 2 frames of
 * range / DoF medium and FlightHelmet / strong, 2026-11-28): the transition disc's span of each
 * full-resolution row (~340 px, ring t, need 1 on range, 3 on FlightHelmet) and the half-
 * resolution periphery's rows (hblur_row: 390-640 texels, t = 1, the 2x2-mean |c| >= 0, need 0
 * on 60 % of range's texels, else 1-3), about 1:2 in pixels. A cycle of 6 rows: disc need 1, half
 * need 0, half need 1, disc need 3, half need 2, half need 0. Rows in cache, as there. */
static void pyrblur_spans_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    static const int need_of[6] = {1, 0, 1, 3, 2, 0};
    for (int k = 0; k < rows; k++) {
        const int y = (row0 + k) % H, ph = y % 6;
        const size_t v = (size_t)(y % 4);
        const float *up[5] = {t->rgbd + 4 * v * W, t->a4 + 4 * v * W, t->b4 + 4 * v * W, t->c4 + 4 * v * W,
                              t->a4 + 4 * ((v + 1) % 4) * W};
        if (ph == 0 || ph == 3) { /* a row of the disc (radius 212 around the centre): its span */
            const int yr = H / 2 - 211 + (y * 7) % 422;
            const float dy = (float)yr + 0.5f - 0.5f * H, half = sqrtf(fmaxf(212.0f * 212.0f - dy * dy, 0.0f));
            const int xa = (int)floorf(0.5f * W - half) - 1, xb = (int)ceilf(0.5f * W + half) + 1;
            const fv_dof_pyrblur_args a = {.coc = t->cocs + (size_t)yr * W, .t = t->tsd + (size_t)yr * W, .up = up,
                                           .need = need_of[ph], .lambda = t->lambda, .lambda_steps = LSTEPS,
                                           .lambda_max = 64 * LSTEPS};
            d->dof.dof_pyrblur_row(t->out + 4 * v * W, &a, xa, xb - xa);
        } else { /* a half row: t = 1 (row 0 of the ring's t) */
            const fv_dof_pyrblur_args a = {.coc = t->hcs + (size_t)(y / 2) * (W / 2), .t = t->ts, .up = up,
                                           .need = need_of[ph], .lambda = t->lambda, .lambda_steps = LSTEPS,
                                           .lambda_max = 64 * LSTEPS};
            d->dof.dof_pyrblur_row(t->out + 4 * v * W, &a, 0, W / 2);
        }
    }
}
/* the periphery beyond the disc: half-resolution blur row (with its clamped texel before it), near
 * layer, combine (coc +-6 px: both signs, every weight) */
static void periph_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H);
        d->dof.dof_periph_row(t->out + 4 * y * W, t->rgbd + 4 * y * W, t->coc + y * W, t->a4 + 4 * y * W + 4,
                              t->c4 + 4 * y * W, 0, W);
    }
}

static void combine_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H);
        const fv_dof_combine_args a = {.sharp = t->rgbd + 4 * y * W, .coc = t->coc + y * W, .far = t->a4 + 4 * y * W,
                                       .near = t->b4 + 4 * y * W, .lnear = t->c4 + 4 * y * W, .t = t->t + y * W,
                                       .enh = t->a4 + 4 * y * W, .gain = 0.5f};
        d->dof.dof_combine_row(t->out + 4 * y * W, &a, 0, W);
    }
}

/* ---- eye tracker (a 640x480 eye camera image) ---- */
typedef struct {
    uint8_t *img, *half, *bin;
    uint32_t *ii;
    float *score;
} et_st;
static void et_free(void *st)
{
    et_st *t = st;
    free(t->img), free(t->half), free(t->bin), free(t->ii), free(t->score), free(t);
}
static void *et_setup(void)
{
    et_st *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    t->img = malloc((size_t)EW * EH), t->half = malloc((size_t)EW * EH / 4), t->bin = malloc((size_t)EW * EH);
    t->ii = malloc(((size_t)EW + 1) * (EH + 1) * sizeof *t->ii);
    if (!t->img || !t->half || !t->bin || !t->ii)
        return et_free(t), NULL;
    uint32_t s = 5;
    for (size_t i = 0; i < (size_t)EW * EH; i++)
        t->img[i] = (uint8_t)(rnd(&s) & 255u);
    memset(t->ii, 0, ((size_t)EW + 1) * sizeof *t->ii);
    return t;
}
static void down2_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    et_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % (EH / 2));
        d->et.et_down2_row(t->half + y * (EW / 2), t->img + 2 * y * EW, t->img + (2 * y + 1) * EW, EW / 2);
    }
}
static void integral_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    et_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % EH);
        d->et.et_integral_row(t->ii + (y + 1) * (EW + 1) + 1, t->ii + y * (EW + 1) + 1, t->img + y * EW, EW);
    }
}
/* box search scores: box half-size 8, ring 12 (the tracker's 1.5), every centre whose ring is
 * inside the image */
enum { ET_K = 8, ET_KO = 12 };
static void *box_setup(void)
{
    et_st *t = et_setup();
    if (!t)
        return NULL;
    t->score = malloc((size_t)EW * sizeof *t->score);
    if (!t->score)
        return et_free(t), NULL;
    for (int y = 0; y < EH; y++)
        fv_et_integral_row_c(t->ii + (y + 1) * (EW + 1) + 1, t->ii + y * (EW + 1) + 1, t->img + y * EW, EW);
    return t;
}
static volatile float et_fsink;
static void box_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    et_st *t = st;
    const int iw = EW + 1, n = EW - 2 * ET_KO, na = (2 * ET_K + 1) * (2 * ET_K + 1);
    const float inv_a = 1.0f / (float)na, inv_r = 1.0f / (float)((2 * ET_KO + 1) * (2 * ET_KO + 1) - na);
    float m = 0;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % (EH - 2 * ET_KO));
        const uint32_t *ot = t->ii + y * iw, *it = ot + (ET_KO - ET_K) * (iw + 1);
        m += d->et.et_box_score_row(t->score, it, it + (2 * ET_K + 1) * iw, 2 * ET_K + 1, ot, ot + (2 * ET_KO + 1) * iw,
                                 2 * ET_KO + 1, n, inv_a, inv_r, 30.0f);
    }
    et_fsink = m;
}
static void box3_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    et_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % (EH - 2)) + 1;
        d->et.et_box3_row(t->bin + y * EW, t->img + (y - 1) * EW, t->img + y * EW, t->img + (y + 1) * EW, EW);
    }
}
static volatile int et_sink;
static void thresh_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    et_st *t = st;
    int c = 0;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % EH);
        c += d->et.et_thresh_row(t->bin + y * EW, t->img + y * EW, EW, 60);
    }
    et_sink = c;
}

/* ---- output ---- */
typedef struct {
    float *rgbd;
    uint8_t *rgb, lut[FV_SRGB_LUT + 1 + FV_SRGB_LUT_PAD];
} out_st;
static void *out_setup(void)
{
    out_st *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    t->rgbd = fplane((size_t)W * H * 4), t->rgb = malloc((size_t)W * H * 3);
    if (!t->rgbd || !t->rgb)
        return free(t->rgbd), free(t->rgb), free(t), NULL;
    uint32_t s = 7;
    fill_rgbd(t->rgbd, (size_t)W * H, &s, 0.5f, 20.0f);
    fv_srgb_lut_init(t->lut); /* the AVX2 version computes sRGB: only this table is its contract */
    return t;
}
static void out_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    out_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H);
        /* rows in cache, as the depth of field's last pass hands them over (its row buffer),
         * written to a whole display image */
        d->out.rgb8_row(t->rgb + y * W * 3, t->rgbd + (y % 4) * W * 4, W, t->lut);
    }
}
static void out_free(void *st)
{
    out_st *t = st;
    free(t->rgbd), free(t->rgb), free(t);
}

/* ---- timewarp: one eye's frame warped by a refresh of head turn (30 deg/s, 11.1 ms, plus
 * 2 mm of the eye's swing) over a source with depth edges ---- */
typedef struct {
    uint8_t *rgb, *dst;
    uint16_t *invd;
    fv_tw_map m;
    fv_tw_src s;
} tw_st;
static void *tw_setup(void)
{
    tw_st *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    t->rgb = malloc((size_t)W * H * 3 + FV_TW_RGB_PAD), t->dst = malloc((size_t)W * H * 3);
    t->invd = malloc(((size_t)W * H + FV_TW_INVD_PAD / 2) * sizeof *t->invd);
    if (!t->rgb || !t->dst || !t->invd)
        return free(t->rgb), free(t->dst), free(t->invd), free(t), NULL;
    uint32_t s = 11;
    for (size_t i = 0; i < (size_t)W * H * 3 + FV_TW_RGB_PAD; i++)
        t->rgb[i] = (uint8_t)((s = s * 1664525u + 1013904223u) >> 24);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            t->invd[(size_t)y * W + x] = (uint16_t)(FV_TW_INVD_PER_M / (1.0f + (float)(((x >> 6) + (y >> 6)) & 7)));
    fv_camera_desc cd;
    fv_camera_desc_default(&cd);
    const float a = 30.0f / 90.0f * 3.14159265f / 360.0f;
    fv_pose p0 = {{0, 0, 0}, {0, 0, 0, 1}}, p1 = {{0.002f, 0, 0}, {0, sinf(a), 0, cosf(a)}};
    fv_camera c0, c1;
    fv_camera_setup(&c0, &cd, &p0);
    fv_camera_setup(&c1, &cd, &p1);
    fv_tw_setup(&t->m, &c1, &c0, 0.05f);
    t->s = (fv_tw_src){t->rgb, (ptrdiff_t)W * 3, t->invd, W, W, H};
    return t;
}
static int tw_sink;
static void tw_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    tw_st *t = st;
    int h = 0;
    for (int k = 0; k < rows; k++) {
        const int y = (row0 + k) % H;
        h += d->tw.tw_row(t->dst + (size_t)y * W * 3, 0, y, W, &t->m, &t->s);
    }
    tw_sink = h;
}
static void tw_free(void *st)
{
    tw_st *t = st;
    free(t->rgb), free(t->dst), free(t->invd), free(t);
}

/* tw_runs: the block warp's translated rows as a one-refresh turn gives them (timewarp.c's
 * runners): 40 runs of 32 px a row, each translated by a few px at its own phase, stepping a
 * source row a display row with a slow vertical drift (the kept passes reused most rows) */
static void runs_setup(const tw_st *t, fv_tw_run *r, int y)
{
    for (int i = 0; i < W / 32; i++) {
        const int64_t one = (int64_t)1 << 22;
        r[i].qu = (int64_t)(2 * one + i * one / 37) + (FV_TW_RUN_BIAS << 22) + 32768;
        r[i].qv = (int64_t)(-one - i * one / 53) + (FV_TW_RUN_BIAS << 22) + 32768;
        r[i].dqu = 0, r[i].dqv = one / 300 + i * one / 20000;
        r[i].off = (int64_t)y * W * 3 + 3 * 32 * i - FV_TW_RUN_BIAS * ((int64_t)W * 3 + 3);
        r[i].hoff = -1, r[i].hfx = 0, r[i].dst = 96 * i, r[i].n = 96;
    }
    (void)t;
}
static void tw_runs_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    tw_st *t = st;
    fv_tw_run r[W / 32];
    static int16_t hbuf[W * 3];
    int y = 2 + row0 % (H - 12);
    runs_setup(t, r, y);
    for (int k = 0; k < rows; k++, y++) {
        if (y >= H - 10) /* the runs read a few rows below: start again at the top */
            runs_setup(t, r, y = 2);
        d->tw.tw_runs(t->dst + (size_t)y * W * 3, r, W / 32, t->rgb, (ptrdiff_t)W * 3, (ptrdiff_t)H * W * 3, hbuf);
    }
    d->tw.tw_stream(NULL, NULL, 0);
}

/* ---- shading: a full frame's packets of 16 hits, head light (range, FlightHelmet) and two
 * KHR lights (DepthOfFieldExample has KHR lights) ---- */
#define SH_PACKETS (W * H / FV_SHADE_LANES)
#define SH_SET 64 /* distinct packets, cycled */
typedef struct {
    fv_shade_packet p[SH_SET];
    fv_shade_lanes geo[SH_SET];
    fv_light_rec lights[2];
    float rgb[3][FV_SHADE_LANES];
} shade_st;
static void *shade_setup(void)
{
    shade_st *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    uint32_t s = 7;
    for (int i = 0; i < SH_SET; i++)
        for (int q = 0; q < FV_SHADE_LANES; q++) {
            fv_shade_packet *p = &t->p[i];
            fv_shade_lanes *l = &t->geo[i];
            fv_shade_packet_lanes(p, l);
            l->u[q] = frand(&s, 0.0f, 0.5f), l->v[q] = frand(&s, 0.0f, 0.5f), l->t[q] = frand(&s, 0.5f, 20.0f);
            for (int k = 0; k < 9; k++) l->nrm[q][k] = frand(&s, -1.0f, 1.0f);
            for (int k = 0; k < 3; k++)
                l->dir[k][q] = k == 2 ? -1.0f : frand(&s, -1.0f, 1.0f), p->base[k][q] = frand(&s, 0.0f, 1.0f);
            p->metal[q] = q & 1 ? 1.0f : 0.0f, p->a2[q] = frand(&s, 0.0f, 1.0f); /* glTF materials */
            p->spec[q] = 1.0f, p->occl[q] = 1.0f;
        }
    t->lights[0].l = (fv_light){.type = FV_LIGHT_DIRECTIONAL, .color = {1, 1, 1}, .intensity = 3, .dir = {0, -1, 0}};
    t->lights[1].l = (fv_light){.type = FV_LIGHT_POINT, .color = {1, 0.8f, 0.6f}, .intensity = 50, .pos = {2, 5, 1},
                                .range = 30};
    return t;
}
static volatile float shade_sink;
static void shade_run_n(void *st, const checkasm_dsp *d, int row0, int rows, int nlights)
{
    shade_st *t = st;
    const fv_shade_env env = {.lights = t->lights, .nlights = nlights, .exposure = 1.0f, .eye = {0, 1.6f, 3}};
    unsigned m = 0;
    for (int k = 0; k < rows; k++)
        m += d->shade.brdf(&t->p[(row0 + k) % SH_SET], &env, t->rgb);
    shade_sink = t->rgb[0][0] + (float)m;
}
static void shade_head_run(void *st, const checkasm_dsp *d, int row0, int rows) { shade_run_n(st, d, row0, rows, 0); }
static void shade_lights_run(void *st, const checkasm_dsp *d, int row0, int rows) { shade_run_n(st, d, row0, rows, 2); }

/* ---- ray generation: every pixel of a 1280x1440 eye in packets of 16 (8x2 pixels) ---- */
typedef struct {
    uint8_t px[FV_TILE * FV_TILE];
    float d[3][16];
} ray_st;
static void *ray_setup(void)
{
    ray_st *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    for (int i = 0; i < FV_TILE * FV_TILE; i++) /* 4x2 blocks, as core/raycast.c orders a full tile */
        t->px[i] = (uint8_t)(((i >> 5) * 2 + (i >> 2 & 1)) << 4 | ((i >> 3 & 3) * 4 + (i & 3)));
    return t;
}
static volatile float ray_sink;
static void ray_run(void *st, const checkasm_dsp *d, int row0, int rows)
{
    ray_st *t = st;
    const fv_raygen_cam c = {-1.19f, 1.19f, 0.00186f, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, 0.5f, 0.5f};
    for (int k = 0; k < rows; k++) {
        const int p = (row0 + k) % (W * H / 16), tile = p / 16;
        d->ray.camera_rays(&c, t->px + 16 * (p % 16), tile % (W / 16) * 16, tile / (W / 16) * 16, t->d[0], t->d[1],
                           t->d[2], 16);
    }
    ray_sink = t->d[0][0];
}

#define F(x) offsetof(checkasm_dsp, x)
const checkasm_bench_kernel checkasm_bench_kernels[] = {
    {"camera_rays", "1280x1440 rays, 115200 packets of 16", {F(ray.camera_rays), 0}, W * H / 16, ray_setup, NULL,
     ray_run, free},
    {"brdf", "1280x1440 hits, 115200 packets of 16, head light", {F(shade.brdf), 0}, SH_PACKETS, shade_setup,
     NULL, shade_head_run, free},
    {"brdf_lights", "1280x1440 hits, 115200 packets of 16, 2 KHR lights", {F(shade.brdf), 0}, SH_PACKETS,
     shade_setup, NULL, shade_lights_run, free},
    {"pull_row", "1280x1440 -> 640x720, 720 rows", {F(pp.pull_row), 0}, H / 2, pull_setup, NULL, pull_run, pull_free},
    {"push_row", "1280x1440, 1440 rows", {F(pp.push_row), 0}, H, push_setup, NULL, push_run, push_free},
    {"taa_blend+taa_fill", "1280x1440, 7200 16x16 tiles, still head", {F(taa.taa_blend), F(taa.taa_fill)}, TX * TY, taa_setup,
     taa_reset, taa_run, taa_free},
    {"taa_turn", "1280x1440, 7200 16x16 tiles, head turning 30 deg/s", {F(taa.taa_blend), F(taa.taa_fill)}, TX * TY,
     taa_turn_setup, taa_reset, taa_run, taa_free},
    {"taa_aa", "1280x1440, 144 16x16 fovea tiles, head turning 30 deg/s", {F(taa.taa_aa), 0}, AA_T * AA_T, aa_setup,
     aa_reset, aa_turn_run, aa_free},
    {"taa_aa_still", "1280x1440, 144 16x16 fovea tiles, still head", {F(taa.taa_aa), 0}, AA_T * AA_T, aa_setup,
     aa_reset, aa_still_run, aa_free},
    {"dof_coc_row", "1280x1440, 1440 rows", {F(dof.dof_coc_row), 0}, H, dof_setup, NULL, coc_run, dof_free},
    {"dof_nearblk_row", "1280x1440, 1440 rows, 4x4 blocks", {F(dof.dof_nearblk_row), 0}, H, dof_setup, NULL,
     nearblk_run, dof_free},
    {"dof_hcoc_row", "1280-px rows in cache, 720 out", {F(dof.dof_hcoc_row), 0}, H / 2, dof_setup, NULL, hcoc_run,
     dof_free},
    {"dof_nearfin_row", "1280x1440, 360 rows of 4x4 blocks", {F(dof.dof_nearfin_row), 0}, H / 4, dof_setup, NULL,
     nearfin_run, dof_free},
    {"dof_nearbox_row", "1280x1440, 1440 rows, reach 3", {F(dof.dof_nearbox_row), 0}, H, dof_setup, nearbox_reset,
     nearbox_run, dof_free},
    {"dof_hgauss_row", "1280x1440, 10 128-px spans/row, sigma 1-4", {F(dof.dof_hgauss_row), 0}, H, dof_setup, NULL,
     hgauss_run, dof_free},
    {"dof_vgauss_row", "1280x1440, 10 128-px spans/row, sigma 1-4 in runs of 8-71 px", {F(dof.dof_vgauss_row), 0}, H, dof_setup, NULL,
     vgauss_run, dof_free},
    {"dof_upsample_row", "1280-px rows in cache, 1440, by 2 from 640", {F(dof.dof_upsample_row), 0}, H, dof_setup, NULL,
     upsample_run, dof_free},
    {"dof_upsample_spans", "1440 448-px spans in cache, by 2, 4, 8", {F(dof.dof_upsample_row), 0}, H, dof_setup, NULL,
     upsample_spans_run, dof_free},
    {"dof_pyrblur_row", "1440 rows in cache, 5 levels, smooth CoC, ring t", {F(dof.dof_pyrblur_row), 0}, H, dof_setup, NULL, pyrblur_run,
     dof_free},
    {"dof_pyrblur_spans", "1440 calls as the pipeline's: disc spans (r 212), 640-px half rows", {F(dof.dof_pyrblur_row), 0}, H,
     dof_setup, NULL, pyrblur_spans_run, dof_free},
    {"dof_combine_row", "1280x1440, 1440 rows, all layers", {F(dof.dof_combine_row), 0}, H, dof_setup, NULL, combine_run,
     dof_free},
    {"dof_periph_row", "1280x1440, 1440 rows, near layer on", {F(dof.dof_periph_row), 0}, H, dof_setup, NULL, periph_run,
     dof_free},
    {"et_down2_row", "640x480 -> 320x240, 240 rows", {F(et.et_down2_row), 0}, EH / 2, et_setup, NULL, down2_run, et_free},
    {"et_integral_row", "640x480, 480 rows", {F(et.et_integral_row), 0}, EH, et_setup, NULL, integral_run, et_free},
    {"et_thresh_row", "640x480, 480 rows", {F(et.et_thresh_row), 0}, EH, et_setup, NULL, thresh_run, et_free},
    {"et_box_score_row", "640x480 integral, k 8 ring 12, 456 rows", {F(et.et_box_score_row), 0}, EH - 2 * ET_KO,
     box_setup, NULL, box_run, et_free},
    {"et_box3_row", "640x480, 478 rows", {F(et.et_box3_row), 0}, EH - 2, et_setup, NULL, box3_run, et_free},
    {"rgb8_row", "1280-px rows in cache, 1440 out", {F(out.rgb8_row), 0}, H, out_setup, NULL, out_run, out_free},
    {"tw_row", "1280x1440, 1440 rows, 1 refresh of a 30 deg/s turn", {F(tw.tw_row), 0}, H, tw_setup, NULL, tw_run,
     tw_free},
    {"tw_runs", "1280x1440, 1440 rows of 40 translated 32-px runs", {F(tw.tw_runs), 0}, H, tw_setup, NULL, tw_runs_run,
     tw_free},
};
const int checkasm_bench_count = (int)(sizeof checkasm_bench_kernels / sizeof checkasm_bench_kernels[0]);

int checkasm_bench_differs(const checkasm_bench_kernel *k, const checkasm_dsp *d, const checkasm_dsp *ref)
{
    for (int i = 0; i < CHECKASM_BENCH_MAX_FIELDS; i++) {
        if (k->field[i] == 0)
            continue;
        void (*a)(void), (*b)(void);
        memcpy(&a, (const char *)d + k->field[i], sizeof a);
        memcpy(&b, (const char *)ref + k->field[i], sizeof b);
        if (a != b)
            return 1;
    }
    return 0;
}

const checkasm_bench_kernel *checkasm_bench_find(const char *name)
{
    for (int i = 0; i < checkasm_bench_count; i++)
        if (!strcmp(checkasm_bench_kernels[i].name, name))
            return &checkasm_bench_kernels[i];
    return NULL;
}

void checkasm_dsp_init(checkasm_dsp *d, unsigned isa_mask)
{
    d->isa = fv_cpu_best_isa(isa_mask);
    fv_pullpush_dsp_init(&d->pp, isa_mask);
    fv_reproject_dsp_init(&d->taa, isa_mask);
    fv_dof_dsp_init(&d->dof, isa_mask);
    fv_eyetrack_dsp_init(&d->et, isa_mask);
    fv_output_dsp_init(&d->out, isa_mask);
    fv_shade_dsp_init(&d->shade, isa_mask);
    fv_raygen_dsp_init(&d->ray, isa_mask);
    fv_timewarp_dsp_init(&d->tw, isa_mask);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void load_avg(double la[3])
{
    if (getloadavg(la, 3) != 3)
        la[0] = la[1] = la[2] = NAN;
}

/* ---- the timing loop ---- */
typedef struct {
    const char *name, *shape, *isa;
    double ms;      /* median per frame of calls */
    double speedup; /* C reference time / this */
} kres;

int checkasm_bench_run(const char *prog, const char *json_path, int reps, const char *only, long calls,
                       unsigned isa_mask)
{
    if (only && !checkasm_bench_find(only))
        fv_usage_error(prog, "--kernel: '%s' is not a kernel of the table (see --kernels)", only);
    if (only && calls > 0) { /* instruction counting: one kernel, one ISA, `calls` calls after the set-up */
        const checkasm_bench_kernel *k = checkasm_bench_find(only);
        checkasm_dsp d;
        checkasm_dsp_init(&d, isa_mask);
        void *st = k->setup();
        if (!st)
            fv_fail(prog, FV_EXIT_FAIL, "out of memory setting %s up", k->name);
        if (k->reset)
            k->reset(st);
        k->run(st, &d, 0, (int)calls);
        k->free(st);
        /* where the kernels' code is (tools/kernel_icount.py counts the instructions run there) */
        printf("%s: %s %s x %ld calls; code at", prog, k->name, fv_isa_name(d.isa), calls);
        for (int i = 0; i < CHECKASM_BENCH_MAX_FIELDS; i++)
            if (k->field[i]) {
                void (*fn)(void);
                uintptr_t a;
                memcpy(&fn, (const char *)&d + k->field[i], sizeof fn);
                memcpy(&a, &fn, sizeof a);
                printf(" 0x%llx", (unsigned long long)a);
            }
        printf("\n");
        return FV_EXIT_OK;
    }
    static const unsigned masks[] = {FV_ISA_C, FV_ISA_SSE41, FV_ISA_SSE41 | FV_ISA_AVX2, FV_ISA_NEON};
    enum { NM = 4 };
    checkasm_dsp ds[NM];
    int have[NM], nisa = 0;
    for (int m = 0; m < NM; m++) {
        checkasm_dsp_init(&ds[m], masks[m]);
        have[m] = m == 0 || ds[m].isa != FV_ISA_C; /* that ISA runs on this CPU */
        nisa += have[m];
    }
    double la[3];
    load_avg(la);
    printf("%s (kernel bench): %d ISA%s on this CPU, median of %d runs, each ISA timed back to back; "
           "load average %.2f %.2f %.2f\n",
           prog, nisa, nisa == 1 ? "" : "s", reps, la[0], la[1], la[2]);
    printf("%-20s %-42s %-8s %10s %8s\n", "kernel", "one frame of calls", "isa", "ms/frame", "speedup");
    kres *out = calloc((size_t)checkasm_bench_count * NM, sizeof *out);
    double *t = calloc((size_t)reps * NM, sizeof *t);
    if (!out || !t)
        fv_fail(prog, FV_EXIT_FAIL, "out of memory");
    int nout = 0;
    for (int i = 0; i < checkasm_bench_count; i++) {
        const checkasm_bench_kernel *k = &checkasm_bench_kernels[i];
        if (only && strcmp(k->name, only))
            continue;
        /* the ISAs with their own version (not the C one, not the same as a lower ISA's) */
        int use[NM];
        for (int m = 0; m < NM; m++) {
            use[m] = have[m] && (m == 0 || checkasm_bench_differs(k, &ds[m], &ds[0]));
            for (int q = 1; q < m && use[m]; q++)
                if (use[q] && !checkasm_bench_differs(k, &ds[m], &ds[q]))
                    use[m] = 0;
        }
        void *st = k->setup();
        if (!st)
            fv_fail(prog, FV_EXIT_FAIL, "out of memory setting %s up", k->name);
        /* frames per sample: at least ~20 ms of the C reference (the eye tracker's are small) */
        if (k->reset)
            k->reset(st);
        int64_t t0 = fv_time_ns();
        k->run(st, &ds[0], 0, k->calls_per_frame);
        const double once = (double)(fv_time_ns() - t0) * 1e-6;
        const int nf = once >= 20.0 ? 1 : once <= 0.01 ? 2000 : (int)ceil(20.0 / once);
        for (int r = 0; r < reps; r++)
            for (int m = 0; m < NM; m++) {
                if (!use[m])
                    continue;
                double ns = 0.0;
                for (int f = 0; f < nf; f++) {
                    if (k->reset)
                        k->reset(st);
                    t0 = fv_time_ns();
                    k->run(st, &ds[m], 0, k->calls_per_frame);
                    ns += (double)(fv_time_ns() - t0);
                }
                t[r * NM + m] = ns * 1e-6 / nf;
            }
        double med[NM];
        for (int m = 0; m < NM; m++) {
            if (!use[m])
                continue;
            double v[64];
            int n = 0;
            for (int r = 0; r < reps && n < 64; r++)
                v[n++] = t[r * NM + m];
            qsort(v, (size_t)n, sizeof *v, cmp_double);
            med[m] = n & 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
            kres *o = &out[nout++];
            o->name = k->name, o->shape = k->shape, o->isa = fv_isa_name(ds[m].isa);
            o->ms = med[m];
            o->speedup = med[0] / med[m];
            printf("%-20s %-42s %-8s %10.3f %7.2fx\n", k->name, k->shape, o->isa, o->ms, o->speedup);
        }
        k->free(st);
    }
    int status = FV_EXIT_OK;
    if (json_path) {
        char err[512];
        fv_afile a;
        if (fv_afile_open(&a, json_path, err, sizeof err))
            fv_fail(prog, FV_EXIT_FAIL, "%s", err);
        fprintf(a.f, "{\"kernels_bench\": {\"reps\": %d, \"load_avg\": [%.2f, %.2f, %.2f], \"results\": [", reps, la[0],
                la[1], la[2]);
        for (int i = 0; i < nout; i++)
            fprintf(a.f, "%s\n  {\"kernel\": \"%s\", \"shape\": \"%s\", \"isa\": \"%s\", \"ms_per_frame\": %.4f, "
                         "\"speedup\": %.3f}",
                    i ? "," : "", out[i].name, out[i].shape, out[i].isa, out[i].ms, out[i].speedup);
        fprintf(a.f, "]}}\n");
        if (fv_afile_commit(&a, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", prog, err);
            status = FV_EXIT_FAIL;
        }
    }
    free(out);
    free(t);
    return status;
}

int checkasm_bench_main(const char *prog, int argc, char **argv)
{
    const char *json_path = NULL, *only = NULL;
    int reps = 7;
    long calls = 0;
    unsigned isa_mask = ~0u;
    for (int i = 1; i < argc; i += 2) { /* every option takes a value */
        const char *o = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(o, "--json") && v)
            json_path = v;
        else if (!strcmp(o, "--kernel-reps") && v)
            reps = (int)fv_arg_long(prog, o, v, 1, 64);
        else if (!strcmp(o, "--kernel") && v)
            only = v;
        else if (!strcmp(o, "--calls") && v)
            calls = fv_arg_long(prog, o, v, 0, 100000000);
        else if (!strcmp(o, "--isa") && v) {
            if (!strcmp(v, "c")) isa_mask = FV_ISA_C;
            else if (!strcmp(v, "sse41")) isa_mask = FV_ISA_SSE41;
            else if (!strcmp(v, "avx2")) isa_mask = FV_ISA_SSE41 | FV_ISA_AVX2;
            else if (!strcmp(v, "neon")) isa_mask = FV_ISA_NEON;
            else fv_usage_error(prog, "--isa: '%s' is not one of c, sse41, avx2, neon", v);
        } else
            fv_usage_error(prog, "'%s': expected --json FILE, --kernel-reps N, --kernel NAME, --calls N or --isa I", o);
    }
    if (calls > 0 && !only)
        fv_usage_error(prog, "--calls N needs --kernel NAME");
    return checkasm_bench_run(prog, json_path, reps, only, calls, isa_mask);
}
