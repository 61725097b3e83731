#include "dof/focus.h"

#include <math.h>
#include <string.h>

#define BIN_DPT 0.05f /* dioptres per histogram bin */

void fv_focus_params_default(fv_focus_params *p)
{
    p->error_deg = 1.0f;
    p->min_share = 0.1f;
    p->memory_ms = 100.0f;
    p->tau_ms = 370.0f;
    p->fixed_m = 0.0f;
    p->min_m = 0.1f;
    p->max_m = 1000.0f;
}

void fv_focus_init(fv_focus *f, const fv_focus_params *p)
{
    memset(f, 0, sizeof *f);
    f->prm = *p;
}

/* Weier Fig. 4: the point of regard, and 8 directions at half and full radius. */
static void add_samples(fv_focus *f, fv_depth_fn depth, void *ctx, float gx, float gy, float r)
{
    static const float dir[8][2] = {{1, 0},       {0.70710678f, 0.70710678f},   {0, 1},  {-0.70710678f, 0.70710678f},
                                    {-1, 0},      {-0.70710678f, -0.70710678f}, {0, -1}, {0.70710678f, -0.70710678f}};
    f->samples_used = 0;
    for (int k = 0; k < 17; k++) {
        const float s = k == 0 ? 0.0f : k <= 8 ? 0.5f : 1.0f; /* ring radius in units of r */
        const float dx = k ? dir[(k - 1) & 7][0] * s * r : 0.0f, dy = k ? dir[(k - 1) & 7][1] * s * r : 0.0f;
        const float d = depth(ctx, gx + dx, gy + dy);
        if (!(d > 0.0f))
            continue;
        const float dm = d < f->prm.min_m ? f->prm.min_m : d > f->prm.max_m ? f->prm.max_m : d;
        int bin = (int)(1.0f / dm / BIN_DPT);
        bin = bin < FV_FOCUS_BINS - 1 ? bin : FV_FOCUS_BINS - 1;
        const float w = expf(-0.5f * s * s); /* Gaussian of the distance, sigma = r */
        f->hist[bin] += w;
        f->hist_d[bin] += w / dm;
        f->samples_used++;
    }
}

/* The nearest cluster of adjacent occupied bins with at least min_share of the evidence. */
static int pick_target(const fv_focus *f, float *target_dpt)
{
    float total = 0.0f;
    for (int b = 0; b < FV_FOCUS_BINS; b++)
        total += f->hist[b];
    if (!(total > 1e-6f))
        return 0;
    const float floor_w = 1e-3f * total; /* bins that have faded away do not join clusters */
    for (int b = FV_FOCUS_BINS - 1; b >= 0;) { /* from the nearest (most dioptres) down */
        if (!(f->hist[b] > floor_w)) {
            b--;
            continue;
        }
        float w = 0.0f, wd = 0.0f;
        int e = b;
        for (; e >= 0 && f->hist[e] > floor_w; e--) {
            w += f->hist[e];
            wd += f->hist_d[e];
        }
        if (w >= f->prm.min_share * total) {
            *target_dpt = wd / w;
            return 1;
        }
        b = e;
    }
    return 0;
}

float fv_focus_update(fv_focus *f, fv_depth_fn depth, void *ctx, float gx, float gy, float ppd, float dt_ms)
{
    if (f->prm.fixed_m > 0.0f) {
        f->valid = 1;
        f->focus_dpt = f->target_dpt = 1.0f / f->prm.fixed_m;
        return f->prm.fixed_m;
    }
    const float fade = f->prm.memory_ms > 0.0f ? exp2f(-dt_ms / f->prm.memory_ms) : 0.0f;
    for (int b = 0; b < FV_FOCUS_BINS; b++) {
        f->hist[b] *= fade;
        f->hist_d[b] *= fade;
    }
    add_samples(f, depth, ctx, gx, gy, f->prm.error_deg * ppd);
    float t;
    if (pick_target(f, &t)) {
        f->target_dpt = t;
        if (!f->valid || !(f->prm.tau_ms > 0.0f)) {
            f->focus_dpt = t;
            f->valid = 1;
        } else {
            f->focus_dpt += (1.0f - expf(-dt_ms / f->prm.tau_ms)) * (t - f->focus_dpt);
        }
    }
    if (!f->valid)
        return NAN;
    const float m = 1.0f / (f->focus_dpt > 1e-6f ? f->focus_dpt : 1e-6f);
    return m < f->prm.min_m ? f->prm.min_m : m > f->prm.max_m ? f->prm.max_m : m;
}
