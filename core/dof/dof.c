#include "dof/dof.h"
#include "dof/weier_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>


int fv_dof_model_parse(const char *name, fv_dof_model *out)
{
    for (int i = 0; i < FV_DOF_MODEL_COUNT; i++)
        if (!strcmp(name, fv_dof_models[i].name)) {
            *out = (fv_dof_model)i;
            return 0;
        }
    return -1;
}

void fv_dof_params_default(fv_dof_params *p)
{
    memset(p, 0, sizeof *p);
    p->preset = FV_DOF_NONE;
    p->model = FV_DOF_MODEL_WEIER;
    p->pupil_mm = FV_EYE_PUPIL_MM;
    p->tolerance_m = FV_EYE_DEPTH_TOL_M;
    p->contrast_gain = 0.0f; /* off: it costs 2.5 dB against full sampling (docs/dof.md) */
    p->chroma = 0;
    fv_focus_params_default(&p->focus);
}

int fv_dof_work_init(fv_dof_work *wk, int w, int h, ptrdiff_t stride)
{
    memset(wk, 0, sizeof *wk);
    wk->w = w, wk->h = h, wk->stride = stride;
    const size_t n = (size_t)stride * (size_t)h;
    for (int i = 0; i < FV_DOF_PLANES4; i++)
        if (!(wk->p4[i] = aligned_alloc(64, (n * 4 * sizeof(float) + 63) & ~(size_t)63)))
            goto bad;
    for (int i = 0; i < FV_DOF_PLANES1; i++)
        if (!(wk->p1[i] = aligned_alloc(64, (n * sizeof(float) + 63) & ~(size_t)63)))
            goto bad;
    if (!(wk->gauss = malloc(sizeof *wk->gauss)))
        goto bad;
    fv_dof_gauss_tab_init(wk->gauss);
    return 0;
bad:
    fv_dof_work_free(wk);
    return -1;
}

void fv_dof_work_free(fv_dof_work *wk)
{
    for (int i = 0; i < FV_DOF_PLANES4; i++)
        free(wk->p4[i]);
    for (int i = 0; i < FV_DOF_PLANES1; i++)
        free(wk->p1[i]);
    free(wk->gauss);
    free(wk->aux);
    free(wk->rows);
    memset(wk, 0, sizeof *wk);
}

float fv_dof_thin_lens_px(const fv_dof_view *v, float depth_m)
{
    const float g = depth_m > FV_COC_MIN_DEPTH_M ? depth_m : FV_COC_MIN_DEPTH_M;
    /* positive far of the focus, negative near; a miss (huge depth) gives the 1/focus limit */
    return v->prm->pupil_mm * 1e-3f * (1.0f / v->focus_m - 1.0f / g) * v->focal_px * v->blur_scale;
}

/* The one table of models: a new model is an enum entry (dof.h), its file and a row here. */
const fv_dof_model_info fv_dof_models[FV_DOF_MODEL_COUNT] = {
    [FV_DOF_MODEL_WEIER] = {"weier", fv_dof_weier},       [FV_DOF_MODEL_HUSSAIN] = {"hussain", fv_dof_hussain},
    [FV_DOF_MODEL_MANTIUK] = {"mantiuk", fv_dof_mantiuk}, [FV_DOF_MODEL_KONRAD] = {"konrad", fv_dof_konrad},
    [FV_DOF_MODEL_LIU] = {"liu", fv_dof_liu},
};
