/* fovea: Liu et al.'s polar-space acuity sampling (liu-hybrid-foveated-dof, section 3.1).
 *
 * Eq. 1 is the number of receptive fields (samples) per ring of eccentricity alpha (degrees):
 * g(alpha) = 2 pi alpha up to alpha_F = 5.79 deg (constant areal density), 14.98 pi alpha /
 * (0.3 alpha + 1)^2 beyond. Eq. 2 is its integral, the polar coordinate rho (samples within
 * alpha); eq. 3 is the paper's polynomial fit of the inverse for rho normalised to [0, 1] (it fits
 * alpha_M = 80 deg to 0.3 deg); here the inverse is exact (bisection on eq. 2).
 *
 * The pattern is a grid in polar space: rings equally spaced in rho (drho apart), n_phi samples
 * per ring, mapped back to pixel offsets around the gaze. Its areal density, in samples per
 * pixel, is lambda(alpha) = lambda_0 g(alpha) / (2 pi alpha) = lambda_0 min(1, 7.49 / (0.3 alpha
 * + 1)^2), lambda_0 = n_phi / (drho ppd^2). Where lambda >= 1 every pixel is sampled (many polar
 * samples fall on one pixel there, the paper's "many polar pixels map to the same screen
 * pixel"). Rotation over frames: phase k shifts the grid by (u_k, v_k) of a polar cell (an R2
 * sequence), i.e. rotates it by v_k / n_phi of a turn and moves the rings out by u_k drho, so
 * reprojection accumulates new pixels from every phase. */
#ifndef FOVEA_SAMPLING_LIU_H
#define FOVEA_SAMPLING_LIU_H

#include "sampling.h"

#define FV_LIU_ALPHA_F 5.79 /* eq. 1: end of the constant-density fovea, degrees */

/* Eq. 1: samples per unit of eccentricity on the ring at alpha_deg (per degree). */
double fv_liu_ring_density(double alpha_deg);
/* g(alpha) / (2 pi alpha): areal density relative to the fovea's, 1 up to alpha_F. */
double fv_liu_relative_density(double alpha_deg);
/* Eq. 2 (pi alpha^2 in the fovea): samples within alpha_deg, the polar coordinate rho. Eq. 2's
 * constant is taken so the two pieces meet at alpha_F (612.03; the paper rounds to 612.3). */
double fv_liu_cdf(double alpha_deg);
/* Inverse of fv_liu_cdf. */
double fv_liu_cdf_inv(double rho);
/* Eq. 3, the paper's fitted inverse, rho normalised to [0, 1]. */
double fv_liu_eq3(double rho_norm);

/* Phase k's offsets of the polar grid, in cells: rings at rho = (i + u) drho, ring i's samples
 * at angles 2 pi (j + v + frac(0.618.. i)) / n_phi. An R2 sequence, so any run of phases spreads
 * evenly over the cell. */
void fv_liu_phase_offset(int k, double *u, double *v);

/* Called by fv_sampler_init / fv_sampler_probability for kind FV_SAMPLER_LIU (sampling.c has
 * filled prm, width, height, ppd, r0_px, r1_px, phases). */
int fv_sampler_liu_init(fv_sampler *s, float focal_px);
float fv_sampler_liu_probability(const fv_sampler *s, float dx_px, float dy_px);

#endif
