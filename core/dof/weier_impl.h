/* fovea: internals of the layered DoF filter (core/dof/weier.c) shared with its hand-vectorised
 * kernels (core/x86/dof_*.c, core/arm/dof_neon.c). */
#ifndef FOVEA_DOF_WEIER_IMPL_H
#define FOVEA_DOF_WEIER_IMPL_H

#include <stddef.h>
#include <stdint.h>

#include "../pullpush.h"
#include "coc.h" /* FV_COC_MIN_DEPTH_M */

/* Gaussian weights for sigma = s / FV_DOF_SIG_STEPS px, s < FV_DOF_NSIG; w[s][j] for |offset| j
 * (0 beyond rad[s] = ceil(3 sigma)), inv[s] = 1 / (the full kernel's sum). */
#define FV_DOF_SIG_STEPS 4
#define FV_DOF_RMAX 24
#define FV_DOF_NSIG (FV_DOF_RMAX / 3 * FV_DOF_SIG_STEPS + 1)
typedef struct fv_dof_gauss_tab {
    int rad[FV_DOF_NSIG];
    float w[FV_DOF_NSIG][FV_DOF_RMAX + 1];
    float inv[FV_DOF_NSIG];
} fv_dof_gauss_tab;
void fv_dof_gauss_tab_init(fv_dof_gauss_tab *t);

/* One row of the combine (dsp dof_combine_row): the layers the filter made for that row. */
typedef struct fv_dof_combine_args {
    const float *sharp; /* level 0 row (r, g, b, depth_m) */
    const float *coc;   /* signed CoC row, px */
    const float *far;   /* the pixel's own blur (r, g, b, -): read where coc > 0, and where coc < 0
                         * and t > 0 (a near pixel's periphery blur) */
    const float *near;  /* full-resolution near layer: premultiplied colour, coverage in .w; NULL = 0 */
    const float *lnear; /* the quarter-resolution near layer up-sampled (same form); NULL = 0 */
    const float *t;     /* transition weight per pixel: 0 in the fovea .. 1 in the periphery */
    const float *enh;   /* contrast enhancement's blurred row; NULL = off */
    float gain;         /* contrast enhancement gain (used with enh) */
} fv_dof_combine_args;

/* One row of the periphery's own-pixel blur (dsp dof_pyrblur_row). */
typedef struct fv_dof_pyrblur_args {
    const float *coc;          /* signed CoC row, px */
    const float *t;            /* transition weight row */
    const float *const *up;    /* up[L], L = 0..need: pyramid level L up-sampled to the row (up[0] sharp) */
    int need;                  /* the deepest level read */
    const float *lambda;       /* |c| * lambda_steps (clamped to lambda_max) -> continuous level */
    int lambda_steps, lambda_max;
} fv_dof_pyrblur_args;

#endif
