/* fovea: focus depth from the point of regard (issue 4 item 1; Weier et al. 2018 Fig. 4).
 *
 * Depth is sampled at the point of regard and on two rings around it (8 directions at half and
 * full radius: 17 samples, Weier's Fig. 4 pattern), the radius matched to the tracker's angular
 * error, each sample weighted by a Gaussian of its distance from the point of regard. Samples are
 * compared in dioptres (1 / depth), the unit the eye's focus works in, and collected in a
 * histogram of dioptres that fades with a half-life of `memory_ms`: the evidence of the last few
 * frames, so one noisy gaze sample off a thin object does not decide alone. Adjacent occupied
 * bins form depth clusters; the target is the NEAREST cluster holding at least `min_share` of
 * the evidence (a foreground object under the tracker's error disc is what the eye is on; the
 * background around a thin object always holds more samples), at its weighted mean. The eye then
 * accommodates towards the target with a first-order filter in dioptres, time constant `tau_ms`
 * (Mantiuk et al. 2011: 370 ms), and `fixed_m` > 0 overrides all of it.
 *
 * Pure: depth comes from a caller-provided accessor, no pipeline or OS calls. */
#ifndef FOVEA_DOF_FOCUS_H
#define FOVEA_DOF_FOCUS_H

typedef struct fv_focus_params {
    float error_deg;    /* tracker's angular error: the sampling radius (default 1.0 deg) */
    float min_share;    /* smallest share of the evidence a cluster needs to be focused (0.1) */
    float memory_ms;    /* half-life of the evidence (default 100 ms) */
    float tau_ms;       /* accommodation time constant (default 370 ms); 0 = instantaneous */
    float fixed_m;      /* > 0: a fixed focus distance in metres, no estimation */
    float min_m, max_m; /* the focus is kept within [min_m, max_m] (default 0.1 m .. 1000 m) */
} fv_focus_params;

void fv_focus_params_default(fv_focus_params *p);

/* View depth in metres at continuous pixel (x, y) of the eye image (NAN or <= 0 for none). */
typedef float (*fv_depth_fn)(void *ctx, float x, float y);

#define FV_FOCUS_BINS 256 /* dioptre histogram: 0 .. 12.8 D (8 cm) in 0.05 D bins */

typedef struct fv_focus {
    fv_focus_params prm;
    int valid;          /* a focus has been set */
    float focus_dpt;    /* the accommodated focus, dioptres */
    float target_dpt;   /* the last frame's target before accommodation */
    int samples_used;   /* valid depth samples in the last frame */
    float hist[FV_FOCUS_BINS]; /* fading evidence (sample weights) per dioptre bin */
    float hist_d[FV_FOCUS_BINS]; /* the same weights times the samples' dioptres (exact means) */
} fv_focus;

void fv_focus_init(fv_focus *f, const fv_focus_params *p);

/* One frame: adds the samples around the point of regard (gx, gy pixels; ppd pixels per degree)
 * to the evidence, picks the target and accommodates towards it over dt_ms (the first frame
 * jumps there). Returns the focus distance in metres; with no depth under the gaze so far, NAN. */
float fv_focus_update(fv_focus *f, fv_depth_fn depth, void *ctx, float gx, float gy, float ppd, float dt_ms);

#endif
