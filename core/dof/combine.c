/* fovea: the layered filter's combine stage (Weier sec. 3.2): one output row from the sharp
 * row and the layers, with Patney et al. 2016's peripheral contrast enhancement. */
#include "dof/weier_passes.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "base/util.h"

/* Patney et al. 2016's contrast enhancement needs a blur of the sharp row whose width follows
 * the sampling footprint: row y's blur into enh (the periphery's own-blur kernel, read from the
 * pyramid like the far layer's periphery). */
void fvw_enhance_row(const fvw_ctx *x, int tid, int y, const float *sharp, const float *trow, float *restrict enh)
{
    const fv_dof_view *v = x->v;
    const float dyr = (float)y + 0.5f - v->gaze_y;
    /* the periphery's own-blur kernel with a "CoC" of 2 fp (sigma fp / 2) */
    float *ecoc = fvw_slot(x, tid, 9), *ones = fvw_slot(x, tid, 12), *up[ENH_LEVELS + 1];
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
        up[L] = fvw_slot(x, tid, 4 + L);
        fvw_upsample_row(x->dsp, &im, L, &x->xt[L], y, 0, x->w, fvw_slot(x, tid, 11), up[L]);
    }
    const fv_dof_pyrblur_args ea = {.coc = ecoc, .t = ones, .up = (const float *const *)up, .need = need,
                                    .lambda = x->lambda, .lambda_steps = LAMBDA_STEPS,
                                    .lambda_max = (LAMBDA_N - 1)};
    x->dsp->dof_pyrblur_row(enh, &ea, 0, x->w);
}

/* Columns [xa, xb) of an output row into dst: the sharp row blended with the far layer by the CoC, the near layers by
 * their coverage (the full-resolution one in the centre, the quarter-resolution one faded in by
 * t), and the enhancement (enh, NULL = off); the dsp kernel dof_combine_row has the formula. */
void fvw_combine_row(const fvw_ctx *x, float *restrict dst, const float *sharp, const float *coc, const float *far, const float *near,
                     const float *lnear, const float *trow, const float *enh, int xa, int xb)
{
    const fv_dof_view *v = x->v;
    fv_dof_combine_args a = {.sharp = sharp, .coc = coc, .far = far, .near = near, .lnear = lnear, .t = trow,
                             .enh = enh, .gain = v->prm->contrast_gain};
    if (xa < xb)
        x->dsp->dof_combine_row(dst, &a, xa, xb - xa);
}
