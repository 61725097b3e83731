/* fovea: internals of the layered DoF filter (core/dof/weier.c) shared with its hand-vectorised
 * kernels (core/x86/dof_*.c, core/arm/dof_neon.c). */
#ifndef FOVEA_DOF_WEIER_IMPL_H
#define FOVEA_DOF_WEIER_IMPL_H

#include <stddef.h>
#include <stdint.h>

#include "../pullpush.h"

#define FV_DOF_MIN_DEPTH_M 0.05f /* = FV_COC_MIN_DEPTH_M (core/dof/coc.h) */

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

/* One row span of the combine (dsp dof_combine_row). */
typedef struct fv_dof_combine_args {
    const fv_pyramid *pyr;
    int y;
    const float *sharp;  /* level 0 row (r, g, b, depth_m) */
    const float *coc;    /* signed CoC row, px */
    const float *far;    /* far_v row (premultiplied, weight in .w), valid in [far_x0, far_x1); NULL: none */
    int far_x0, far_x1;
    const float *near;   /* near_v row (premultiplied, coverage in .w), read only if has_near */
    int has_near;
    float gx, gy;        /* point of regard, px */
    float r0, inv_tr;    /* region blend t = clamp((ecc - r0) * inv_tr, 0, 1) */
    float gain;          /* contrast enhancement */
    const float *enh;    /* the enhancement's blurred row (valid where t > 0); NULL = none */
} fv_dof_combine_args;

/* Scalar pieces every ISA's combine uses in the same order. */
void fv_dof_footprint(float c, int max_level, int *level, float *offset);
void fv_dof_tap_c(const fv_pyr_level *L, int level, float fx, float fy, float acc[4]);

#endif
