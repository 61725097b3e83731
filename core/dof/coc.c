#include "coc.h"

#include <math.h>
#include <string.h>

/* Lengths in mm, in double: the image distances differ from d_i in the 3rd or 4th digit. */
static inline double depth_mm(float depth_m)
{
    return 1000.0 * (double)(depth_m > FV_COC_MIN_DEPTH_M ? depth_m : FV_COC_MIN_DEPTH_M);
}

/* Image distance of an object at G for focal length F, G > F. Written F / (1 - F/G) rather
 * than F G / (G - F) so that G = infinity (a miss) gives F instead of inf/inf. */
static inline double image_dist(double F, double G) { return F / (1.0 - F / G); }

void fv_coc_weier_default(fv_coc_weier *p, float focal_px)
{
    p->image_dist_mm = FV_EYE_IMAGE_DIST_MM;
    p->pupil_mm = FV_EYE_PUPIL_MM;
    p->tolerance_m = FV_EYE_DEPTH_TOL_M;
    p->retina_px_per_mm = fv_retina_px_per_mm(focal_px, FV_EYE_IMAGE_DIST_MM);
}

float fv_coc_weier_mm(const fv_coc_weier *p, float focus_m, float depth_m)
{
    /* the range test in the caller's float precision, so d_o +- t given in float is inside */
    const float dn_m = focus_m - p->tolerance_m, df_m = focus_m + p->tolerance_m;
    const float gm = depth_m > FV_COC_MIN_DEPTH_M ? depth_m : FV_COC_MIN_DEPTH_M;
    double d; /* the bound of [d_n, d_f] the eye focuses at for this point, mm */
    if (gm < dn_m)
        d = 1000.0 * (double)dn_m;
    else if (gm > df_m)
        d = 1000.0 * (double)df_m;
    else
        return 0.0f;
    const double di = p->image_dist_mm, g = depth_mm(depth_m);
    const double f = 1.0 / (1.0 / d + 1.0 / di); /* f_n or f_f */
    const double vd = image_dist(f, g), vf = image_dist(f, d);
    /* near: the image lies behind the retina (vd > vf): negative */
    return (float)((vf - vd) * p->pupil_mm / vd);
}

float fv_coc_weier_px(const fv_coc_weier *p, float focus_m, float depth_m)
{
    return fv_coc_weier_mm(p, focus_m, depth_m) * p->retina_px_per_mm;
}

const fv_dof_preset_desc fv_dof_presets[FV_DOF_PRESET_COUNT] = {
    {"none", FV_EYE_PUPIL_MM, 0.0f},
    {"weak", FV_EYE_PUPIL_MM, 1.0f},
    {"medium", FV_EYE_PUPIL_MM, 2.0f},
    {"strong", FV_EYE_PUPIL_MM, 4.0f},
};

int fv_dof_preset_parse(const char *name, fv_dof_preset *out)
{
    for (int i = 0; i < FV_DOF_PRESET_COUNT; i++)
        if (!strcmp(name, fv_dof_presets[i].name)) {
            *out = (fv_dof_preset)i;
            return 0;
        }
    return -1;
}

void fv_coc_weier_apply_preset(fv_coc_weier *p, fv_dof_preset preset)
{
    p->pupil_mm = fv_dof_presets[preset].pupil_mm;
    p->retina_px_per_mm *= fv_dof_presets[preset].e_scale;
}

void fv_coc_liu_default(fv_coc_liu *p)
{
    p->focal_mm = FV_EYE_FOCAL_MM;
    p->pupil_mm = FV_EYE_PUPIL_MM;
}

float fv_coc_liu_mm(const fv_coc_liu *p, float focus_m, float depth_m)
{
    const double fe = p->focal_mm, F = depth_mm(focus_m), D = depth_mm(depth_m);
    const double v = fe * F * D / (F * D + fe * D - fe * F);
    const double c = fabs(v - fe) * p->pupil_mm / v;
    return (float)(D < F ? -c : c);
}

void fv_coc_mantiuk_default(fv_coc_mantiuk *p)
{
    p->aperture = FV_EYE_PUPIL_MM;
    p->focal_mm = FV_EYE_FOCAL_MM;
}

float fv_coc_mantiuk_size(const fv_coc_mantiuk *p, float focus_m, float depth_m)
{
    const double f = p->focal_mm, d0 = depth_mm(focus_m), dp = depth_mm(depth_m);
    const double c = p->aperture * fabs(f / (d0 - f)) * fabs(1.0 - d0 / dp);
    return (float)(dp < d0 ? -c : c);
}

void fv_coc_hussain_default(fv_coc_hussain *p, float pupil_mm, float focal_px)
{
    p->k_px_m = 0.001f * pupil_mm * focal_px / 4.0f;
}

float fv_coc_hussain_sigma_px(const fv_coc_hussain *p, float focus_m, float depth_m)
{
    const double d0 = focus_m > FV_COC_MIN_DEPTH_M ? focus_m : FV_COC_MIN_DEPTH_M;
    const double d1 = depth_m > FV_COC_MIN_DEPTH_M ? depth_m : FV_COC_MIN_DEPTH_M;
    const double s = p->k_px_m * fabs(1.0 / d0 - 1.0 / d1);
    return (float)(d1 < d0 ? -s : s);
}
