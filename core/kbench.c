#include "kbench.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

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
static void pull_run(void *st, const fv_dsp *d, int row0, int rows)
{
    pull_st *t = st;
    for (int k = 0; k < rows; k++) {
        const int r = (row0 + k) % (H / 2);
        const size_t a = (size_t)(2 * r) * W, b = a + W;
        d->pull_row(t->drgbd + (size_t)r * (W / 2) * 4, t->dwgt + (size_t)r * (W / 2), t->rgbd + 4 * a, t->wgt + a,
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
static void push_run(void *st, const fv_dsp *d, int row0, int rows)
{
    push_st *t = st;
    for (int k = 0; k < rows; k++) {
        const int y = (row0 + k) % H, Y = y >> 1, Yf = y & 1 ? Y + 1 : Y - 1;
        d->push_row(t->rgbd + (size_t)y * W * 4, t->wgt + (size_t)y * W, t->coarse + ((size_t)(Y + 1) * CW + 1) * 4,
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
    fv_dsp c;
    fv_dsp_init(&c, FV_ISA_C);
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
static void taa_reset(void *st)
{
    taa_st *t = st;
    const size_t n = (size_t)t->cur.lv[0].stride * H;
    memcpy(t->cur.lv[0].rgbd, t->rgbd0, 4 * n * sizeof(float));
    memcpy(t->cur.lv[0].wgt, t->wgt0, n * sizeof(float));
}
#define TX ((W + FV_TILE - 1) / FV_TILE)
#define TY ((H + FV_TILE - 1) / FV_TILE)
static void taa_run(void *st, const fv_dsp *d, int row0, int rows)
{
    taa_st *t = st;
    for (int k = 0; k < rows; k++) {
        const int i = (row0 + k) % (TX * TY), x0 = i % TX * FV_TILE, y0 = i / TX * FV_TILE;
        const int tw = W - x0 < FV_TILE ? W - x0 : FV_TILE, th = H - y0 < FV_TILE ? H - y0 : FV_TILE;
        fv_taa_tile_run(&t->f, &t->prm, &t->smp, W / 2, H / 2, &t->cur.lv[0], d, x0, y0, tw, th);
    }
}

/* ---- depth of field ---- */
typedef struct {
    float *rgbd, *coc, *a4, *b4, *c4, *out, *t;
    uint8_t *sig;
    fv_dof_gauss_tab *tab;
    int32_t *i0, *i1; /* up-sampling by 2: taps into a 640-pixel coarse row */
    float *ax, *lambda;
} dof_st;
#define LSTEPS 8 /* the level table's steps per pixel of CoC (core/dof/weier.c) */
static void dof_free(void *st)
{
    dof_st *t = st;
    free(t->rgbd), free(t->coc), free(t->a4), free(t->b4), free(t->c4), free(t->out), free(t->t), free(t->sig);
    free(t->tab), free(t->i0), free(t->i1), free(t->ax), free(t->lambda), free(t);
}
static void *dof_setup(void)
{
    dof_st *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    const size_t n = (size_t)W * H;
    t->rgbd = fplane(4 * n), t->coc = fplane(n), t->a4 = fplane(4 * n), t->b4 = fplane(4 * n);
    t->c4 = fplane(4 * n), t->out = fplane(4 * n), t->t = fplane(n), t->sig = malloc(n);
    t->tab = malloc(sizeof *t->tab);
    t->i0 = malloc(W * sizeof *t->i0), t->i1 = malloc(W * sizeof *t->i1), t->ax = fplane(W);
    t->lambda = fplane(64 * LSTEPS + 1);
    if (!t->rgbd || !t->coc || !t->a4 || !t->b4 || !t->c4 || !t->out || !t->t || !t->sig || !t->tab || !t->i0 ||
        !t->i1 || !t->ax || !t->lambda)
        return dof_free(t), NULL;
    for (int x = 0; x < W; x++) { /* pixel centres: x = 2 X + 0.5 +- 0.25 */
        const int X = x / 2;
        t->i0[x] = x & 1 ? X : (X > 0 ? X - 1 : 0);
        t->i1[x] = x & 1 ? (X + 1 < W / 2 ? X + 1 : X) : X;
        t->ax[x] = x & 1 ? 0.25f : (X > 0 ? 0.75f : 0.0f);
    }
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
    return t;
}
static void coc_run(void *st, const fv_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H);
        d->dof_coc_row(t->coc + y * W, t->rgbd + 4 * y * W, W, 2.4f, 1.8f, 2.2f);
    }
}
static void hgauss_run(void *st, const fv_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H);
        d->dof_hgauss_row(t->out + 4 * y * W, t->rgbd + 4 * y * W, t->coc + y * W, W, 0, W, t->sig + y * W, t->tab);
    }
}
static void vgauss_run(void *st, const fv_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const int y = (row0 + k) % H;
        d->dof_vgauss_row(t->out + 4 * (size_t)y * W, t->a4, W, y, 0, H, 0, W, t->sig + (size_t)y * W, t->tab);
    }
}
static void upsample_run(void *st, const fv_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H);
        d->dof_upsample_row(t->out + 4 * y * W, t->a4 + 4 * (y / 2) * W, t->i0, t->i1, t->ax, W);
    }
}
static void pyrblur_run(void *st, const fv_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H);
        const float *up[5] = {t->rgbd + 4 * y * W, t->a4 + 4 * y * W, t->b4 + 4 * y * W, t->c4 + 4 * y * W,
                              t->a4 + 4 * ((y + 1) % H) * W};
        const fv_dof_pyrblur_args a = {.coc = t->coc + y * W, .t = t->t + y * W, .up = up, .need = 4,
                                       .lambda = t->lambda, .lambda_steps = LSTEPS, .lambda_max = 64 * LSTEPS};
        d->dof_pyrblur_row(t->out + 4 * y * W, &a, 0, W);
    }
}
static void combine_run(void *st, const fv_dsp *d, int row0, int rows)
{
    dof_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % H);
        const fv_dof_combine_args a = {.sharp = t->rgbd + 4 * y * W, .coc = t->coc + y * W, .far = t->a4 + 4 * y * W,
                                       .near = t->b4 + 4 * y * W, .lnear = t->c4 + 4 * y * W, .t = t->t + y * W,
                                       .enh = t->a4 + 4 * y * W, .gain = 0.5f};
        d->dof_combine_row(t->out + 4 * y * W, &a, 0, W);
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
static void down2_run(void *st, const fv_dsp *d, int row0, int rows)
{
    et_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % (EH / 2));
        d->et_down2_row(t->half + y * (EW / 2), t->img + 2 * y * EW, t->img + (2 * y + 1) * EW, EW / 2);
    }
}
static void integral_run(void *st, const fv_dsp *d, int row0, int rows)
{
    et_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % EH);
        d->et_integral_row(t->ii + (y + 1) * (EW + 1) + 1, t->ii + y * (EW + 1) + 1, t->img + y * EW, EW);
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
static void box_run(void *st, const fv_dsp *d, int row0, int rows)
{
    et_st *t = st;
    const int iw = EW + 1, n = EW - 2 * ET_KO, na = (2 * ET_K + 1) * (2 * ET_K + 1);
    const float inv_a = 1.0f / (float)na, inv_r = 1.0f / (float)((2 * ET_KO + 1) * (2 * ET_KO + 1) - na);
    float m = 0;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % (EH - 2 * ET_KO));
        const uint32_t *ot = t->ii + y * iw, *it = ot + (ET_KO - ET_K) * (iw + 1);
        m += d->et_box_score_row(t->score, it, it + (2 * ET_K + 1) * iw, 2 * ET_K + 1, ot, ot + (2 * ET_KO + 1) * iw,
                                 2 * ET_KO + 1, n, inv_a, inv_r, 30.0f);
    }
    et_fsink = m;
}
static void box3_run(void *st, const fv_dsp *d, int row0, int rows)
{
    et_st *t = st;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % (EH - 2)) + 1;
        d->et_box3_row(t->bin + y * EW, t->img + (y - 1) * EW, t->img + y * EW, t->img + (y + 1) * EW, EW);
    }
}
static volatile int et_sink;
static void thresh_run(void *st, const fv_dsp *d, int row0, int rows)
{
    et_st *t = st;
    int c = 0;
    for (int k = 0; k < rows; k++) {
        const size_t y = (size_t)((row0 + k) % EH);
        c += d->et_thresh_row(t->bin + y * EW, t->img + y * EW, EW, 60);
    }
    et_sink = c;
}

#define F(x) offsetof(fv_dsp, x)
const fv_kbench_kernel fv_kbench_kernels[] = {
    {"pull_row", "1280x1440 -> 640x720, 720 rows", {F(pull_row), 0}, H / 2, pull_setup, NULL, pull_run, pull_free},
    {"push_row", "1280x1440, 1440 rows", {F(push_row), 0}, H, push_setup, NULL, push_run, push_free},
    {"taa_blend+taa_fill", "1280x1440, 7200 16x16 tiles, still head", {F(taa_blend), F(taa_fill)}, TX * TY, taa_setup,
     taa_reset, taa_run, taa_free},
    {"dof_coc_row", "1280x1440, 1440 rows", {F(dof_coc_row), 0}, H, dof_setup, NULL, coc_run, dof_free},
    {"dof_hgauss_row", "1280x1440, 1440 rows, sigma 1-4 px", {F(dof_hgauss_row), 0}, H, dof_setup, NULL, hgauss_run,
     dof_free},
    {"dof_vgauss_row", "1280x1440, 1440 rows, sigma 1-4 px", {F(dof_vgauss_row), 0}, H, dof_setup, NULL, vgauss_run,
     dof_free},
    {"dof_upsample_row", "1280x1440, 1440 rows, by 2 from 640", {F(dof_upsample_row), 0}, H, dof_setup, NULL,
     upsample_run, dof_free},
    {"dof_pyrblur_row", "1280x1440, 1440 rows, 5 levels", {F(dof_pyrblur_row), 0}, H, dof_setup, NULL, pyrblur_run,
     dof_free},
    {"dof_combine_row", "1280x1440, 1440 rows, all layers", {F(dof_combine_row), 0}, H, dof_setup, NULL, combine_run,
     dof_free},
    {"et_down2_row", "640x480 -> 320x240, 240 rows", {F(et_down2_row), 0}, EH / 2, et_setup, NULL, down2_run, et_free},
    {"et_integral_row", "640x480, 480 rows", {F(et_integral_row), 0}, EH, et_setup, NULL, integral_run, et_free},
    {"et_thresh_row", "640x480, 480 rows", {F(et_thresh_row), 0}, EH, et_setup, NULL, thresh_run, et_free},
    {"et_box_score_row", "640x480 integral, k 8 ring 12, 456 rows", {F(et_box_score_row), 0}, EH - 2 * ET_KO,
     box_setup, NULL, box_run, et_free},
    {"et_box3_row", "640x480, 478 rows", {F(et_box3_row), 0}, EH - 2, et_setup, NULL, box3_run, et_free},
};
const int fv_kbench_count = (int)(sizeof fv_kbench_kernels / sizeof fv_kbench_kernels[0]);

int fv_kbench_differs(const fv_kbench_kernel *k, const fv_dsp *d, const fv_dsp *ref)
{
    for (int i = 0; i < FV_KBENCH_MAX_FIELDS; i++) {
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

const fv_kbench_kernel *fv_kbench_find(const char *name)
{
    for (int i = 0; i < fv_kbench_count; i++)
        if (!strcmp(fv_kbench_kernels[i].name, name))
            return &fv_kbench_kernels[i];
    return NULL;
}
