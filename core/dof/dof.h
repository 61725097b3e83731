/* fovea: gaze-contingent depth of field after reconstruction (issue 4; Weier et al. 2018 sec. 3.2
 * and the other seeds' models as alternatives). One eye, one frame:
 *   focus depth (core/dof/focus.h) -> CoC per pixel -> the model's filter -> combine -> out.
 *
 * Every model reads the reconstruction pyramid (level 0 = the sharp image, r, g, b, depth_m;
 * coarser levels = its weighted box pyramid) and writes linear RGB (4 floats a pixel, the 4th
 * holds the pixel's depth_m, copied) into `out`. It never changes the pyramid: next frame's
 * reprojection reads the unblurred image. Every output pixel depends only on the inputs and its
 * coordinates (work split by rows/tiles through the pool), so the image is identical for any
 * thread count. */
#ifndef FOVEA_DOF_DOF_H
#define FOVEA_DOF_DOF_H

#include <stddef.h>
#include <stdint.h>

#include "dof_dsp.h"
#include "../pool.h"
#include "../prof.h"
#include "../pullpush.h"
#include "../stage.h"
#include "coc.h"
#include "focus.h"

typedef enum {
    FV_DOF_MODEL_WEIER,   /* the layered filter (default) */
    FV_DOF_MODEL_HUSSAIN, /* 15-tap separable Gaussian, three foveation regions */
    FV_DOF_MODEL_MANTIUK, /* 15-sample Poisson-disc gather, downsampled near CoC */
    FV_DOF_MODEL_KONRAD,  /* Zhou 2007 adaptive CoC gather, non-separable */
    FV_DOF_MODEL_LIU,     /* disc bokeh, optional longitudinal chromatic aberration */
    FV_DOF_MODEL_COUNT
} fv_dof_model;
int fv_dof_model_parse(const char *name, fv_dof_model *out); /* 0, or -1 for an unknown name */

typedef struct fv_dof_params {
    fv_dof_preset preset;  /* none = no DoF stage at all */
    fv_dof_model model;
    float pupil_mm;        /* k / tau_e / a: 4.49 (the preset's pupil) */
    float tolerance_m;     /* Weier's t: 0.2 m */
    float contrast_gain;   /* Patney 2016 peripheral contrast enhancement, 0 = off (the default) */
    int chroma;            /* liu: longitudinal chromatic aberration (Liu sec. 3.3.2), default 0 */
    int full_res_periphery; /* weier: 1 = the periphery's pyramid blur at full resolution (the path
                             * the half-resolution one replaced; tests compare them), default 0 */
    int chain_periphery;   /* weier: 1 = beyond the transition disc the chain of kernels (up-sampling,
                            * level blend, combine) that dof_periph_row replaced; tests compare them */
    int hblur_pass;        /* weier: 1 = the periphery's half-resolution blur as a pass over the whole
                            * image (the path the per-band rows of the fused pass replaced) */
    int band_passes;       /* weier: 1 = the CoC pass over the whole image before the fused pass (the
                            * order the band pipeline replaced: level 0 read twice); tests compare */
    fv_focus_params focus; /* focus estimation; focus.fixed_m > 0 fixes it */
} fv_dof_params;
void fv_dof_params_default(fv_dof_params *p);

/* What a model's filter gets for one eye and one frame. */
typedef struct fv_dof_view {
    const fv_pyramid *pyr;  /* the reconstruction (read only) */
    float focus_m;          /* the accommodated focus distance */
    float focal_px;         /* pixels per unit tan of the pinhole eye image */
    float e_px_per_mm;      /* E after the preset's scale: retinal mm -> pixels */
    float blur_scale;       /* the preset's e_scale (1 weak, 2 medium, 4 strong): scales every model */
    float gaze_x, gaze_y;   /* point of regard in pixels */
    float r0_px, r1_px;     /* fovea and end of the transition region (sampling radii), pixels */
    const fv_dof_params *prm;
    /* contrast enhancement (weier): the blur footprint in pixels (1 / sqrt(sampling density))
     * at eccentricity i * enh_step pixels, i < enh_n; NULL for none (full sampling) */
    const float *enh_fp;
    int enh_n;
    float enh_step;
    struct fv_prof *prof;   /* trace recorder for the stage spans (core/prof.h), NULL = off */
    /* The display format written row by row while each output row is hot (the output stage
     * fused into the model's last pass): the converter (core/output_convert.h) and the 8-bit RGB
     * image (rgb8_stride bytes a row). conv NULL: the pipeline converts afterwards. A model
     * that fuses it reports fv_dof_times.output_ms; one that does not leaves it NAN. */
    const struct fv_output_conv *conv;
    uint8_t *rgb8;
    ptrdiff_t rgb8_stride;
    int prof_arg;           /* the spans' argument (the eye) */
} fv_dof_view;

/* A model's stage boundaries (coc, dof_filter, combine): the time, and the stage's span and
 * counter hook when the view has a recorder. */
static inline int64_t fv_dof_stage_begin(const fv_dof_view *v, fv_stage s) { return fv_prof_stage_begin(v->prof, s); }
static inline int64_t fv_dof_stage_end(const fv_dof_view *v, fv_stage s, int64_t t0_ns)
{
    return fv_prof_stage_end(v->prof, s, t0_ns, v->prof_arg);
}
static inline double fv_dof_ms(int64_t t0_ns, int64_t t1_ns) { return (double)(t1_ns - t0_ns) * 1e-6; }

/* Scratch a model may use, allocated once for the eye size (dof.c): FV_DOF_PLANES4 planes of
 * 4 floats a pixel and FV_DOF_PLANES1 planes of 1 float a pixel, all w x h with rows `stride`
 * pixels apart (the pyramid level 0's stride). Contents are undefined on entry. */
#define FV_DOF_PLANES4 4
#define FV_DOF_PLANES1 4
struct fv_dof_gauss_tab;
typedef struct fv_dof_work {
    int w, h;
    ptrdiff_t stride;
    float *p4[FV_DOF_PLANES4];
    float *p1[FV_DOF_PLANES1];
    struct fv_dof_gauss_tab *gauss; /* the layered filter's Gaussian weights (constant) */
    float *aux, *rows;              /* the layered filter's own scratch, grown on first use */
    size_t aux_len, rows_len;
} fv_dof_work;
int fv_dof_work_init(fv_dof_work *wk, int w, int h, ptrdiff_t stride); /* 0, or -1: no memory */
void fv_dof_work_free(fv_dof_work *wk);

/* Stage times of one run, ms (coc, filter, combine; NAN for a stage the model has not). */
typedef struct fv_dof_times {
    double coc_ms, filter_ms, combine_ms;
    double output_ms; /* the fused output stage (view conv set); NAN: not done here */
} fv_dof_times;

/* A model's whole DoF: out (4 floats a pixel, rows out_stride pixels) gets the blurred image.
 * The layered model (weier) takes out NULL with v->conv set: each finished row then goes only to
 * the display format (no float image in memory). */
typedef void (*fv_dof_model_fn)(const fv_dof_view *v, fv_dof_work *wk, float *out, ptrdiff_t out_stride,
                                fv_pool *pool, const fv_dof_dsp *dsp, fv_dof_times *t);
void fv_dof_weier(const fv_dof_view *v, fv_dof_work *wk, float *out, ptrdiff_t out_stride, fv_pool *pool,
                  const fv_dof_dsp *dsp, fv_dof_times *t);
void fv_dof_hussain(const fv_dof_view *v, fv_dof_work *wk, float *out, ptrdiff_t out_stride, fv_pool *pool,
                    const fv_dof_dsp *dsp, fv_dof_times *t);
void fv_dof_mantiuk(const fv_dof_view *v, fv_dof_work *wk, float *out, ptrdiff_t out_stride, fv_pool *pool,
                    const fv_dof_dsp *dsp, fv_dof_times *t);
void fv_dof_konrad(const fv_dof_view *v, fv_dof_work *wk, float *out, ptrdiff_t out_stride, fv_pool *pool,
                   const fv_dof_dsp *dsp, fv_dof_times *t);
void fv_dof_liu(const fv_dof_view *v, fv_dof_work *wk, float *out, ptrdiff_t out_stride, fv_pool *pool,
                const fv_dof_dsp *dsp, fv_dof_times *t);
typedef struct fv_dof_model_info {
    const char *name;   /* command line and JSON: "weier", "hussain", ... */
    fv_dof_model_fn run;
} fv_dof_model_info;
extern const fv_dof_model_info fv_dof_models[FV_DOF_MODEL_COUNT];

/* The signed CoC diameter in pixels of the eye image that the reference renderer
 * (core/reference.h, same pupil) produces at view depth depth_m: pupil_m |1/g - 1/focus| focal_px,
 * times blur_scale. Weier's eq. (3) with t = 0 gives this; models that need a physical CoC use
 * their own formula from coc.h. */
float fv_dof_thin_lens_px(const fv_dof_view *v, float depth_m);

#endif
