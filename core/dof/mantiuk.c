/* fovea: Mantiuk, Bazyluk, Tomaszewska 2011, "Gaze-dependent depth-of-field effect rendering in
 * virtual environments", as a DoF model (fv_dof_mantiuk).
 *
 * What the paper says:
 *  - CoC from a camera's thin lens, eq. (1): CoC = a |f / (d0 - f)| |1 - d0 / dp| (d0 the depth
 *    at the gaze point, dp the pixel's).
 *  - Reverse-mapped z-buffer DoF (Riguer et al. 2003, Potmesil and Chakravarty): a filter of 15
 *    Poisson-disc samples whose size is the CoC of the centre pixel, the samples averaged.
 *  - Depth discontinuities (Hammon 2007): CoC kept in a "near" and a "far" texture; the near one is
 *    downsampled to 1/8 in each dimension to get a blurred CoC_b, and the blur radius is
 *    CoC = 2 max(CoC_o, CoC_b) - CoC_o (eq. (2)), so a blurred near object's blur spreads past its
 *    silhouette (with the paper's acknowledged drawback: background near it is blurred too).
 *
 * What we chose where it is silent:
 *  - Units: eq. (1) with a = the pupil (prm->pupil_mm) and f = 22.3 mm gives mm on the sensor
 *    (retina); pixels = mm * view->e_px_per_mm (E of the eye image, preset scale included), the
 *    same conversion as the Weier and Liu models, so a = 4.49 mm is the physiological blur at
 *    weak. The CoC is a diameter: the Poisson disc (unit radius) is scaled by CoC / 2.
 *  - The 15 samples: the centre and 14 points of a Poisson disc (best-candidate, minimum spacing
 *    0.476 of the radius, fixed table below), read bilinearly with clamped borders, plain mean.
 *  - Downsampling: the mean of the near CoC over each 8x8 block (partial blocks at the edges over
 *    their pixels), upsampled bilinearly (block centres at 8 i + 3.5) to CoC_b.
 *  - Near and far combined: radius from max(CoC_far, eq. (2) on the near CoC). An in-focus pixel
 *    with no near blur around it has CoC 0 and is copied.
 *  - No depth test on the samples (the paper averages): a far blurred pixel next to a sharp object
 *    takes some of its colour (intensity leakage onto the background, which the paper lists); the
 *    sharp object itself stays sharp (its CoC is 0).
 *  - Stages: coc (eq. (1), the downsampled near CoC, eq. (2)), filter; no combine (NAN). */
#include <math.h>
#include <string.h>

#include "dof/dof.h"
#include "base/clock.h"
#include "dof/model_util.h"

#define MA_TAPS 15
#define MA_DOWN 8

static const float ma_disc[MA_TAPS][2] = {
    {0.0000f, 0.0000f},   {-0.7346f, 0.6780f}, {0.4005f, -0.9154f}, {0.2344f, 0.9703f},  {-0.7717f, -0.6128f},
    {0.9932f, 0.0834f},   {-0.9964f, 0.0490f}, {-0.1863f, -0.7528f}, {0.8322f, -0.4813f}, {0.7044f, 0.6219f},
    {-0.1648f, 0.5660f},  {-0.5087f, 0.1896f}, {0.3233f, -0.4020f},  {0.4386f, 0.2238f},  {-0.3756f, -0.2920f},
};

typedef struct ma_job {
    const fv_dof_view *v;
    const fv_pyr_level *L;
    fv_dof_work *wk;
    float *out;
    ptrdiff_t os;
    int w, h, bw, bh; /* image, downsampled near CoC */
    fv_coc_mantiuk m;
} ma_job;

/* signed CoC diameter, pixels -> p1[0] */
static void ma_coc_row(void *ctx, int y, int tid)
{
    (void)tid;
    const ma_job *j = ctx;
    float *c = j->wk->p1[0] + y * j->wk->stride;
    for (int x = 0; x < j->w; x++)
        c[x] = fv_coc_mantiuk_size(&j->m, j->v->focus_m, fv_dm_px(j->L, x, y)[3]) * j->v->e_px_per_mm;
}

/* 8x8 block means of the near CoC -> p1[1] (bw x bh, rows bw apart) */
static void ma_down_row(void *ctx, int by, int tid)
{
    (void)tid;
    const ma_job *j = ctx;
    const ptrdiff_t st = j->wk->stride;
    const int y0 = by * MA_DOWN, y1 = y0 + MA_DOWN < j->h ? y0 + MA_DOWN : j->h;
    for (int bx = 0; bx < j->bw; bx++) {
        const int x0 = bx * MA_DOWN, x1 = x0 + MA_DOWN < j->w ? x0 + MA_DOWN : j->w;
        float s = 0.0f;
        for (int y = y0; y < y1; y++)
            for (int x = x0; x < x1; x++) {
                const float c = j->wk->p1[0][y * st + x];
                s += c < 0.0f ? -c : 0.0f;
            }
        j->wk->p1[1][by * j->bw + bx] = s / (float)((y1 - y0) * (x1 - x0));
    }
}

/* eq. (2) -> p1[2]: the diameter the filter uses */
static void ma_final_row(void *ctx, int y, int tid)
{
    (void)tid;
    const ma_job *j = ctx;
    const ptrdiff_t st = j->wk->stride;
    const float *c = j->wk->p1[0] + y * st, *b = j->wk->p1[1];
    float *d = j->wk->p1[2] + y * st;
    const float fy = fminf(fmaxf(((float)y + 0.5f) / MA_DOWN - 0.5f, 0.0f), (float)(j->bh - 1));
    const int y0 = (int)fy, y1 = y0 + 1 < j->bh ? y0 + 1 : y0;
    const float ty = fy - (float)y0;
    for (int x = 0; x < j->w; x++) {
        const float fx = fminf(fmaxf(((float)x + 0.5f) / MA_DOWN - 0.5f, 0.0f), (float)(j->bw - 1));
        const int x0 = (int)fx, x1 = x0 + 1 < j->bw ? x0 + 1 : x0;
        const float tx = fx - (float)x0;
        const float top = b[y0 * j->bw + x0] + tx * (b[y0 * j->bw + x1] - b[y0 * j->bw + x0]);
        const float bot = b[y1 * j->bw + x0] + tx * (b[y1 * j->bw + x1] - b[y1 * j->bw + x0]);
        const float nb = top + ty * (bot - top);
        const float no = c[x] < 0.0f ? -c[x] : 0.0f, fa = c[x] > 0.0f ? c[x] : 0.0f;
        const float n = 2.0f * (no > nb ? no : nb) - no;
        d[x] = fa > n ? fa : n;
    }
}

/* bilinear rgb at (fx, fy), borders clamped */
static inline void ma_sample(const ma_job *j, float fx, float fy, float rgb[3])
{
    fx = fminf(fmaxf(fx, 0.0f), (float)(j->w - 1));
    fy = fminf(fmaxf(fy, 0.0f), (float)(j->h - 1));
    const int x0 = (int)fx, y0 = (int)fy;
    const int x1 = x0 + 1 < j->w ? x0 + 1 : x0, y1 = y0 + 1 < j->h ? y0 + 1 : y0;
    const float tx = fx - (float)x0, ty = fy - (float)y0;
    const float *a = fv_dm_px(j->L, x0, y0), *b = fv_dm_px(j->L, x1, y0);
    const float *c = fv_dm_px(j->L, x0, y1), *d = fv_dm_px(j->L, x1, y1);
    for (int ch = 0; ch < 3; ch++) {
        const float top = a[ch] + tx * (b[ch] - a[ch]), bot = c[ch] + tx * (d[ch] - c[ch]);
        rgb[ch] = top + ty * (bot - top);
    }
}

static void ma_filter_row(void *ctx, int y, int tid)
{
    (void)tid;
    const ma_job *j = ctx;
    const float *d = j->wk->p1[2] + y * j->wk->stride;
    float *o = j->out + 4 * y * j->os;
    for (int x = 0; x < j->w; x++) {
        const float *c = fv_dm_px(j->L, x, y);
        o[4 * x + 3] = c[3];
        if (!(d[x] > 0.0f)) {
            memcpy(o + 4 * x, c, 3 * sizeof(float));
            continue;
        }
        const float r = 0.5f * d[x];
        float a[3] = {0.0f, 0.0f, 0.0f};
        for (int k = 0; k < MA_TAPS; k++) {
            float s[3];
            ma_sample(j, (float)x + r * ma_disc[k][0], (float)y + r * ma_disc[k][1], s);
            for (int ch = 0; ch < 3; ch++)
                a[ch] += s[ch];
        }
        for (int ch = 0; ch < 3; ch++)
            o[4 * x + ch] = a[ch] * (1.0f / MA_TAPS);
    }
}

void fv_dof_mantiuk(const fv_dof_view *v, fv_dof_work *wk, float *out, ptrdiff_t out_stride, fv_pool *pool,
                    const fv_dof_dsp *dsp, fv_dof_times *t)
{
    (void)dsp;
    ma_job j = {.v = v, .L = &v->pyr->lv[0], .wk = wk, .out = out, .os = out_stride};
    j.w = j.L->w, j.h = j.L->h;
    j.bw = (j.w + MA_DOWN - 1) / MA_DOWN, j.bh = (j.h + MA_DOWN - 1) / MA_DOWN;
    fv_coc_mantiuk_default(&j.m);
    j.m.aperture = v->prm->pupil_mm;

    int64_t t0 = fv_dof_stage_begin(v, FV_STAGE_COC);
    fv_pool_run(pool, j.h, ma_coc_row, &j);
    fv_pool_run(pool, j.bh, ma_down_row, &j);
    fv_pool_run(pool, j.h, ma_final_row, &j);
    t->coc_ms = fv_dof_ms(t0, fv_dof_stage_end(v, FV_STAGE_COC, t0));

    t0 = fv_dof_stage_begin(v, FV_STAGE_DOF_FILTER);
    fv_pool_run(pool, j.h, ma_filter_row, &j);
    t->filter_ms = fv_dof_ms(t0, fv_dof_stage_end(v, FV_STAGE_DOF_FILTER, t0));
    t->combine_ms = NAN;
}
