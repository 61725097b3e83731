/* fovea: acuity-driven sampling pattern (Weier et al. 2018, section 3.1; or Liu et al.'s polar
 * pattern, core/sampling_liu.c, selected by fv_sampling_params.kind).
 * Two precomputed bit tables: S_in, centred on the point of regard and moved with it (probability
 * 1 inside r0, importance-sampled with eq. (1)-(2) from a Halton sequence in r0..r1), and S_out,
 * a static uniform pattern of probability p_min for the periphery (static so it does not flicker).
 * Eccentricity is measured in pixels from the point of regard divided by the pixels per degree at
 * the optical axis, as the table is a fixed pixel pattern that moves with the gaze. */
#ifndef FOVEA_SAMPLING_H
#define FOVEA_SAMPLING_H

#include <stdint.h>

/* Which pattern: the values index fv_sampler_names (the --sampling flag, the bench's "sampler"). */
typedef enum fv_sampler_kind {
    FV_SAMPLER_WEIER = 0, /* S_in / S_out, Weier et al. 2018 */
    FV_SAMPLER_LIU,       /* polar-space acuity sampling, Liu et al. eq. 1-3 (sampling_liu.h) */
    FV_SAMPLER_KIND_COUNT
} fv_sampler_kind;
extern const char *const fv_sampler_names[FV_SAMPLER_KIND_COUNT];
/* "weier" or "liu" -> *kind; 0 on success, -1 for any other name. */
int fv_sampler_kind_parse(const char *name, int *kind);

typedef struct fv_sampling_params {
    float r0_deg;  /* fully sampled fovea radius, default 10 */
    float r1_deg;  /* end of the transition region, default 20 */
    float p_min;   /* peripheral sampling probability, default 0.2 */
    int full;      /* 1: sample every pixel */
    /* 1: the pattern changes every frame through fv_sampler.phases phases (temporal
     * reprojection accumulates them: static content converges to every pixel sampled);
     * 0: one static pattern, as in Weier et al. (nothing new to accumulate). */
    int rotate;
    int kind;      /* fv_sampler_kind, default FV_SAMPLER_WEIER */
    /* Liu only: samples per pixel of the polar grid where eq. 1 is flat (lambda_0 in
     * sampling_liu.h), 1..1e4; 0 (default): chosen so the pattern casts as many rays as Weier's
     * pattern with the same r0, r1, p_min for the gaze at the image centre (equal ray counts;
     * at least 1, a fully sampled fovea). */
    float liu_density;
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
    /* Liu (kind FV_SAMPLER_LIU): s_in holds phases tables of (2 width - 1) x (2 height - 1)
     * bits, offsets -(width-1)..width-1 around the gaze, in_stride words a row; s_out is unused.
     * r0_px, r1_px are still the parameters' (they mark the fovea for DoF and the metrics). */
    double liu_l0;        /* lambda_0 in force (given or matched to Weier's ray count) */
    int liu_nphi;         /* polar grid: samples per ring */
    double liu_drho;      /* polar grid: ring spacing in eq. 2's units (deg^2) */
    double liu_sat_px;    /* every pixel closer than this is sampled (lambda >= 1) */
    long liu_target;      /* Weier's ray count it was matched to (0: liu_density was given) */
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
 * `phase` (taken modulo s->phases; 0 for a static pattern). Liu: a gaze outside the image is
 * clamped to its nearest pixel (the table reaches every pixel from any pixel). */
uint64_t fv_sampler_row(const fv_sampler *s, int x0, int y, int n, int gx, int gy, int phase);
/* fv_sampler_row of rows y0 .. y0+count-1 into rows[0 .. count), n <= 32 (a tile's rows; the
 * same bits, with the per-row work done once where the tile is outside the r1 disc). */
void fv_sampler_rows(const fv_sampler *s, int x0, int y0, int n, int count, int gx, int gy, int phase, uint32_t *rows);

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
 * outside; 1 everywhere with full. Liu: min(1, lambda(eccentricity)) of sampling_liu.h. */
float fv_sampler_probability(const fv_sampler *s, float dx_px, float dy_px);

/* Fovea anti-aliasing: where the ray of frame `frame` goes through a fully sampled pixel, as a
 * position inside the pixel, (*ox, *oy) in [0, 1)^2 ((0.5, 0.5) is the centre, frame 0's).
 * The Halton (2, 3) sequence from index 0 shifted by (1/2, 1/2) mod 1 (a Cranley-Patterson
 * rotation that puts frame 0 at the centre, so a first frame is the pixel-centre image). Chosen
 * over R2 (S_out's lattice) by the star discrepancy of runs of consecutive frames starting
 * anywhere (a pixel joins the fovea at any frame, and its history is such a run): 16 frames
 * 0.12-0.19, 32 frames 0.08-0.12, against R2's 0.23-0.24 and 0.14-0.17 (random points: 0.28
 * at 16); starts 0, 1, 5, 16, 1000, 123457, 4e9 (tests/test_fovea_aa.c checks a bound). */
void fv_sampling_jitter(uint32_t frame, float *ox, float *oy);

#endif
