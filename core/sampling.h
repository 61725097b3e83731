/* fovea: acuity-driven sampling pattern (Weier et al. 2018, section 3.1).
 * Two precomputed bit tables: S_in, centred on the point of regard and moved with it (probability
 * 1 inside r0, importance-sampled with eq. (1)-(2) from a Halton sequence in r0..r1), and S_out,
 * a static uniform pattern of probability p_min for the periphery (static so it does not flicker).
 * Eccentricity is measured in pixels from the point of regard divided by the pixels per degree at
 * the optical axis, as the table is a fixed pixel pattern that moves with the gaze. */
#ifndef FOVEA_SAMPLING_H
#define FOVEA_SAMPLING_H

#include <stdint.h>

typedef struct fv_sampling_params {
    float r0_deg;  /* fully sampled fovea radius, default 10 */
    float r1_deg;  /* end of the transition region, default 20 */
    float p_min;   /* peripheral sampling probability, default 0.2 */
    int full;      /* 1: sample every pixel */
    /* 1: the pattern changes every frame through fv_sampler.phases phases (temporal
     * reprojection accumulates them: static content converges to every pixel sampled);
     * 0: one static pattern, as in Weier et al. (nothing new to accumulate). */
    int rotate;
} fv_sampling_params;

typedef struct fv_sampler {
    fv_sampling_params prm;
    int width, height;
    float ppd;              /* pixels per degree at the optical axis */
    float r0_px, r1_px;
    int rin;                /* S_in covers offsets -rin..rin in x and y */
    int in_stride;          /* 64-bit words per S_in row */
    uint64_t *s_in;         /* phases x (2*rin+1) rows */
    int out_stride;         /* 64-bit words per S_out row */
    uint64_t *s_out;        /* phases x height rows */
    long transition_points; /* Halton points thrown into the transition ring (per phase) */
    /* Pattern phases K: 1 when static; with rotate, ceil(1/p_min) capped at FV_SAMPLER_MAX_PHASES.
     * S_out phase k is the lattice shifted by k/K (so K >= 1/p_min phases cover every pixel),
     * S_in phase k takes the k-th block of transition_points Halton points. */
    int phases;
} fv_sampler;

#define FV_SAMPLER_MAX_PHASES 16

void fv_sampling_params_default(fv_sampling_params *p);
/* focal_px: pixels per unit tangent at the optical axis (fv_camera.focal_px). 0 on success,
 * -1 on parameters out of range (0 < r0 <= r1 <= 90, 0 < p_min <= 1) or no memory. */
int fv_sampler_init(fv_sampler *s, int width, int height, float focal_px, const fv_sampling_params *p);
void fv_sampler_free(fv_sampler *s);

/* Eq. (1): radius (degrees) of the transition sample for a uniform variate u in [0,1]. */
float fv_sampling_radius(const fv_sampling_params *p, float u);
/* Expected areal sample density (samples per pixel, before collisions) of the S_in transition
 * points at eccentricity r_deg in [r0, r1]; equals p_min at r1 by the choice of point count. */
float fv_sampling_transition_density(const fv_sampling_params *p, float r_deg);

/* Sampling bits of the n <= 64 pixels x0..x0+n-1 of row y (bit i = pixel x0+i) for the point of
 * regard at pixel (gx, gy) (integer pixel the pattern is centred on), in pattern phase
 * `phase` (taken modulo s->phases; 0 for a static pattern). */
uint64_t fv_sampler_row(const fv_sampler *s, int x0, int y, int n, int gx, int gy, int phase);

/* S_out's lattice value at pixel (x, y) in pattern phase `phase`, frac(a1 x + a2 y + k / K) in
 * [0, 1): the pixel is in S_out when it is below p_min. S_out's pixels whose value is below
 * p_min * q form the same even dither at density p_min * q (DoF-driven sampling thins by it). */
double fv_sampler_lattice(const fv_sampler *s, int x, int y, int phase);
/* The same with the phase's offset k / K given (x, y >= 0): R2's a1 = 1/g, a2 = 1/g^2, g^3 = g + 1. */
static inline double fv_sampler_lattice_at(int x, int y, double k_over_k)
{
    const double v = 0.7548776662466927 * x + 0.5698402909980532 * y + k_over_k;
    return v - (double)(long long)v; /* v >= 0: truncation is floor */
}

/* The acuity model's sampling probability per frame at pixel offset (dx, dy) from the point of
 * regard: 1 inside r0, eq. (1)'s density lambda(r) (clamped to [p_min, 1]) in r0..r1, p_min
 * outside; 1 everywhere with full. */
float fv_sampler_probability(const fv_sampler *s, float dx_px, float dy_px);

#endif
