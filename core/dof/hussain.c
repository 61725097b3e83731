/* fovea: Hussain, Solari, Chessa, "Simulated foveated depth-of-field blur for virtual reality
 * systems", as a DoF model (fv_dof_hussain).
 *
 * What the paper says:
 *  - DoF: a Gaussian with sigma_d = K |1/d0 - 1/d1| (eq. (1)), d0 the depth under fixation, d1
 *    the pixel's; K folds aperture, posterior nodal distance and the CoC-to-sigma constant.
 *  - Blur is a two-pass (vertical, then horizontal) 1D Gaussian of 15 taps, sigma per pixel.
 *  - Foveation: three regions around the fixation point; the centre is output unprocessed, the
 *    near and mid periphery get sigma_f = 1.7 and 3.5 px. Between regions the outputs I_i of the
 *    regions' filters are blended by a linear ramp of the distance R to the fixation point
 *    (eq. (2)): B = (R - R_i) / (R_{i-1} - R_i) inside the transitional ring.
 *  - The two effects are combined by computing both sigmas and using the minimum.
 *
 * What we chose where it is silent or self-contradictory:
 *  - K = fv_coc_hussain_default (thin-lens disc of the pupil, sigma = diameter / 4), times the
 *    preset's blur_scale.
 *  - Regions: fovea R <= r0_px (sigma_f 0: the input, bit for bit), near periphery up to r1_px
 *    (1.7 px), mid periphery beyond (3.5 px). Each blend ring starts at the inner region's outer
 *    radius and is half the width of the near periphery, (r1 - r0) / 2 (the paper says only that
 *    the radii depend on the HMD and eccentricity); r1 <= r0 gives hard region edges.
 *  - Eq. (3) as printed, O = B I_i + (1 - B) I_{i-1} with i the inner region, would jump at both
 *    ring edges (B = 0 at the inner edge selects the outer image). We use the continuous reading
 *    the text describes: O = B I_outer + (1 - B) I_inner.
 *  - The min rule taken literally: the fovea (sigma_f 0) shows no depth of field at all and the
 *    periphery's DoF is capped at 3.5 px; in-focus regions stay sharp in the periphery too.
 *    I_i is the two-pass Gaussian with sigma min(sigma_d, sigma_f_i) at every pixel; a pixel's
 *    sigma is the one at the pixel (gather), in both passes.
 *  - Near-field spread (not in the paper; a gather by the pixel's own sigma would keep a blurred
 *    near object's silhouette sharp): a nearer-than-focus sigma is dilated onto its
 *    neighbourhood, as far as its kernel reaches (2 sigma, at most the 7 taps), by a separable
 *    max filter; sigma_d = max(own, dilated near sigma). Far sigma is not dilated, so a far blur
 *    never reaches into an in-focus nearer object (whose sigma is 0).
 *  - Kernel weights come from a table of sigma in steps of 1/256 px (nearest), normalised over
 *    the 15 taps (the Gaussian truncated at +-7, i.e. +-2 sigma at 3.5 px).
 *  - Stages: coc (sigma and the near dilation), filter (both passes, both foveation images),
 *    combine (eq. (2)-(3) region blend). */
#include <math.h>
#include <string.h>

#include "dof/dof.h"
#include "base/clock.h"
#include "dof/model_util.h"

#define HU_HALF 7                                 /* 15 taps */
#define HU_SIGMA_NEAR_PX 1.7f                     /* near periphery, r0..r1 */
#define HU_SIGMA_MID_PX 3.5f                      /* mid periphery, beyond r1 */
#define HU_LUT_PER_PX 256                         /* sigma table resolution */
#define HU_LUT_N (HU_LUT_PER_PX * 7 / 2 + 1)      /* sigma 0 .. 3.5 px */

typedef struct hu_job {
    const fv_dof_view *v;
    const fv_pyr_level *L;
    fv_dof_work *wk;
    float *out;
    ptrdiff_t os;
    int w, h;
    fv_coc_hussain K;
    const float (*lut)[HU_HALF + 1];
    float band_px;
    int bx0, bx1, by0, by1; /* where the near-periphery image is needed (inclusive); bx0 > bx1: nowhere */
} hu_job;

static inline int hu_index(float sigma_px) { return (int)(sigma_px * (float)HU_LUT_PER_PX + 0.5f); }

/* sigma_d; near sigma (0 elsewhere) */
static void hu_coc_row(void *ctx, int y, int tid)
{
    (void)tid;
    const hu_job *j = ctx;
    const ptrdiff_t st = j->wk->stride;
    float *sig = j->wk->p1[0] + y * st, *near = j->wk->p1[1] + y * st;
    for (int x = 0; x < j->w; x++) {
        const float s = fv_coc_hussain_sigma_px(&j->K, j->v->focus_m, fv_dm_px(j->L, x, y)[3]) * j->v->blur_scale;
        sig[x] = fabsf(s);
        near[x] = s < 0.0f ? -s : 0.0f;
    }
}

/* The largest near sigma whose kernel (reach 2 sigma, at most HU_HALF) covers the pixel. */
static inline float hu_reach_max(float m, float s, int off)
{
    return (float)off <= 2.0f * s && s > m ? s : m;
}

static void hu_dilate_h_row(void *ctx, int y, int tid)
{
    (void)tid;
    const hu_job *j = ctx;
    const ptrdiff_t st = j->wk->stride;
    const float *near = j->wk->p1[1] + y * st;
    float *nh = j->wk->p1[2] + y * st;
    for (int x = 0; x < j->w; x++) {
        float m = near[x];
        for (int k = 1; k <= HU_HALF; k++) {
            m = hu_reach_max(m, near[fv_clampi(x - k, 0, j->w - 1)], k);
            m = hu_reach_max(m, near[fv_clampi(x + k, 0, j->w - 1)], k);
        }
        nh[x] = m;
    }
}

static void hu_dilate_v_row(void *ctx, int y, int tid)
{
    (void)tid;
    const hu_job *j = ctx;
    const ptrdiff_t st = j->wk->stride;
    const float *nh = j->wk->p1[2], *sig = j->wk->p1[0] + y * st;
    float *eff = j->wk->p1[3] + y * st;
    for (int x = 0; x < j->w; x++) {
        float m = nh[y * st + x];
        for (int k = 1; k <= HU_HALF; k++) {
            m = hu_reach_max(m, nh[fv_clampi(y - k, 0, j->h - 1) * st + x], k);
            m = hu_reach_max(m, nh[fv_clampi(y + k, 0, j->h - 1) * st + x], k);
        }
        eff[x] = sig[x] > m ? sig[x] : m;
    }
}

/* Pass 1 (vertical) of image `img` (0: near periphery, 1: mid periphery) over columns x0..x1. */
static void hu_pass1(const hu_job *j, int y, int img, int x0, int x1)
{
    const ptrdiff_t st = j->wk->stride;
    const float sf = img ? HU_SIGMA_MID_PX : HU_SIGMA_NEAR_PX;
    const float *eff = j->wk->p1[3] + y * st;
    float *dst = j->wk->p4[img] + 4 * y * st;
    for (int x = x0; x <= x1; x++) {
        const int i = hu_index(eff[x] < sf ? eff[x] : sf);
        const float *c = fv_dm_px(j->L, x, y);
        if (i == 0) {
            memcpy(dst + 4 * x, c, 3 * sizeof(float));
            continue;
        }
        const float *g = j->lut[i];
        float a[3] = {g[0] * c[0], g[0] * c[1], g[0] * c[2]};
        for (int k = 1; k <= HU_HALF; k++) {
            const float *p = fv_dm_px(j->L, x, fv_clampi(y - k, 0, j->h - 1));
            const float *q = fv_dm_px(j->L, x, fv_clampi(y + k, 0, j->h - 1));
            for (int ch = 0; ch < 3; ch++)
                a[ch] += g[k] * (p[ch] + q[ch]);
        }
        memcpy(dst + 4 * x, a, sizeof a);
    }
}

static void hu_pass1_row(void *ctx, int y, int tid)
{
    (void)tid;
    const hu_job *j = ctx;
    if (y >= j->by0 && y <= j->by1) /* pass 2 reads up to HU_HALF columns beyond the box */
        hu_pass1(j, y, 0, fv_clampi(j->bx0 - HU_HALF, 0, j->w - 1), fv_clampi(j->bx1 + HU_HALF, 0, j->w - 1));
    hu_pass1(j, y, 1, 0, j->w - 1);
}

/* Pass 2 (horizontal): p4[img] -> p4[2 + img]. */
static void hu_pass2(const hu_job *j, int y, int img, int x0, int x1)
{
    const ptrdiff_t st = j->wk->stride;
    const float sf = img ? HU_SIGMA_MID_PX : HU_SIGMA_NEAR_PX;
    const float *eff = j->wk->p1[3] + y * st;
    const float *src = j->wk->p4[img] + 4 * y * st;
    float *dst = j->wk->p4[2 + img] + 4 * y * st;
    for (int x = x0; x <= x1; x++) {
        const int i = hu_index(eff[x] < sf ? eff[x] : sf);
        if (i == 0) {
            memcpy(dst + 4 * x, src + 4 * x, 3 * sizeof(float));
            continue;
        }
        const float *g = j->lut[i];
        float a[3] = {g[0] * src[4 * x], g[0] * src[4 * x + 1], g[0] * src[4 * x + 2]};
        for (int k = 1; k <= HU_HALF; k++) {
            const float *p = src + 4 * fv_clampi(x - k, 0, j->w - 1);
            const float *q = src + 4 * fv_clampi(x + k, 0, j->w - 1);
            for (int ch = 0; ch < 3; ch++)
                a[ch] += g[k] * (p[ch] + q[ch]);
        }
        memcpy(dst + 4 * x, a, sizeof a);
    }
}

static void hu_pass2_row(void *ctx, int y, int tid)
{
    (void)tid;
    const hu_job *j = ctx;
    if (y >= j->by0 && y <= j->by1)
        hu_pass2(j, y, 0, j->bx0, j->bx1);
    hu_pass2(j, y, 1, 0, j->w - 1);
}

/* Eq. (2)-(3): fovea (input), ring, near periphery (I_2), ring, mid periphery (I_1). */
static void hu_combine_row(void *ctx, int y, int tid)
{
    (void)tid;
    const hu_job *j = ctx;
    const ptrdiff_t st = j->wk->stride;
    const float r0 = j->v->r0_px, r1 = j->v->r1_px, band = j->band_px;
    const float *i2 = j->wk->p4[2] + 4 * y * st, *i1 = j->wk->p4[3] + 4 * y * st;
    float *o = j->out + 4 * y * j->os;
    const float dy = (float)y + 0.5f - j->v->gaze_y;
    for (int x = 0; x < j->w; x++) {
        const float *c = fv_dm_px(j->L, x, y);
        const float dx = (float)x + 0.5f - j->v->gaze_x, R = sqrtf(dx * dx + dy * dy);
        const float *inner, *outer;
        float B;
        if (R <= r0) {
            inner = outer = c, B = 0.0f;
        } else if (R < r0 + band) {
            inner = c, outer = i2 + 4 * x, B = (R - r0) / band;
        } else if (R <= r1) {
            inner = outer = i2 + 4 * x, B = 0.0f;
        } else if (R < r1 + band) {
            inner = i2 + 4 * x, outer = i1 + 4 * x, B = (R - r1) / band;
        } else {
            inner = outer = i1 + 4 * x, B = 0.0f;
        }
        if (inner == outer)
            memcpy(o + 4 * x, inner, 3 * sizeof(float));
        else
            for (int ch = 0; ch < 3; ch++)
                o[4 * x + ch] = B * outer[ch] + (1.0f - B) * inner[ch];
        o[4 * x + 3] = c[3];
    }
}

void fv_dof_hussain(const fv_dof_view *v, fv_dof_work *wk, float *out, ptrdiff_t out_stride, fv_pool *pool,
                    const fv_dof_dsp *dsp, fv_dof_times *t)
{
    (void)dsp;
    float lut[HU_LUT_N][HU_HALF + 1];
    hu_job j = {.v = v, .L = &v->pyr->lv[0], .wk = wk, .out = out, .os = out_stride, .lut = (const float (*)[HU_HALF + 1])lut};
    j.w = j.L->w, j.h = j.L->h;
    fv_coc_hussain_default(&j.K, v->prm->pupil_mm, v->focal_px);

    int64_t t0 = fv_dof_stage_begin(v, FV_STAGE_COC);
    fv_pool_run(pool, j.h, hu_coc_row, &j);
    fv_pool_run(pool, j.h, hu_dilate_h_row, &j);
    fv_pool_run(pool, j.h, hu_dilate_v_row, &j);
    t->coc_ms = fv_dof_ms(t0, fv_dof_stage_end(v, FV_STAGE_COC, t0));

    t0 = fv_dof_stage_begin(v, FV_STAGE_DOF_FILTER);
    /* normalised truncated Gaussians; row 0 (sigma 0) is never read (copies instead) */
    for (int i = 0; i < HU_LUT_N; i++) {
        const double s = (double)i / HU_LUT_PER_PX;
        double g[HU_HALF + 1], sum = 1.0;
        g[0] = 1.0;
        for (int k = 1; k <= HU_HALF; k++) {
            g[k] = i ? exp(-(double)(k * k) / (2.0 * s * s)) : 0.0;
            sum += 2.0 * g[k];
        }
        for (int k = 0; k <= HU_HALF; k++)
            lut[i][k] = (float)(g[k] / sum);
    }
    j.band_px = v->r1_px > v->r0_px ? 0.5f * (v->r1_px - v->r0_px) : 0.0f;
    /* the near-periphery image is read where r0 < R < r1 + band */
    const float rb = (v->r1_px > v->r0_px ? v->r1_px : v->r0_px) + j.band_px;
    j.bx0 = (int)fmaxf(floorf(v->gaze_x - rb) - 1.0f, 0.0f);
    j.bx1 = (int)fminf(ceilf(v->gaze_x + rb) + 1.0f, (float)(j.w - 1));
    j.by0 = (int)fmaxf(floorf(v->gaze_y - rb) - 1.0f, 0.0f);
    j.by1 = (int)fminf(ceilf(v->gaze_y + rb) + 1.0f, (float)(j.h - 1));
    fv_pool_run(pool, j.h, hu_pass1_row, &j);
    fv_pool_run(pool, j.h, hu_pass2_row, &j);
    t->filter_ms = fv_dof_ms(t0, fv_dof_stage_end(v, FV_STAGE_DOF_FILTER, t0));

    t0 = fv_dof_stage_begin(v, FV_STAGE_COMBINE);
    fv_pool_run(pool, j.h, hu_combine_row, &j);
    t->combine_ms = fv_dof_ms(t0, fv_dof_stage_end(v, FV_STAGE_COMBINE, t0));
}
