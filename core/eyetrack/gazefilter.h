/* fovea eye tracker: gaze filter between the calibrated tracker and the renderer.
 *  - outlier rejection: a sample implying an angular velocity above outlier_deg_s is dropped,
 *    unless the next confirm_samples samples agree with it (then the eye really went there);
 *  - classification by angular velocity: saccade above saccade_deg_s, fixation below; the
 *    velocity is taken over at least velocity_window_ms (tracker jitter between consecutive
 *    frames would otherwise look like a saccade at 120 Hz);
 *  - smoothing during fixations with a 1-euro filter (Casiez et al. 2012); saccades pass
 *    through unsmoothed (lag there costs more than jitter);
 *  - blinks / lost frames: hold the last good gaze for up to hold_ms with a confidence that
 *    falls linearly to 0, then report LOST (gaze still held).
 * The output confidence is what the renderer uses to widen the fovea: fv_fovea_radius_scale. */
#ifndef FOVEA_EYETRACK_GAZEFILTER_H
#define FOVEA_EYETRACK_GAZEFILTER_H

enum { FV_GAZE_NONE = 0, FV_GAZE_FIXATION, FV_GAZE_SACCADE, FV_GAZE_HOLD, FV_GAZE_LOST };

typedef struct fv_gaze_filter_params {
    float saccade_deg_s;  /* 50 */
    float outlier_deg_s;  /* 1000: above any saccade's peak velocity */
    int confirm_samples;  /* 2 */
    float min_cutoff_hz;  /* 1-euro: 1.0 */
    float beta;           /* 1-euro: 0.02 (per deg/s) */
    float d_cutoff_hz;    /* 1-euro: 1.0 */
    float hold_ms;        /* 300 */
    float velocity_window_ms; /* 30 */
} fv_gaze_filter_params;

typedef struct fv_gaze_out {
    float yaw_deg, pitch_deg; /* filtered gaze */
    float confidence;         /* 0..1 */
    float velocity_deg_s;     /* of the raw samples */
    int state;                /* FV_GAZE_* */
} fv_gaze_out;

typedef struct fv_gaze_filter {
    fv_gaze_filter_params p;
    int have;                       /* a good sample has been seen */
    double last_t_ms, last_good_ms; /* time of the last sample / last good sample */
    float raw_x, raw_y;             /* last accepted raw sample */
    float fx, fy, dfx, dfy;         /* 1-euro state */
    float last_conf;
    int pending;                    /* outlier candidates agreeing so far */
    float cand_x, cand_y;
    double hist_t[8];               /* recent accepted samples, for the velocity */
    float hist_x[8], hist_y[8];
    int nhist;
    fv_gaze_out out;
} fv_gaze_filter;

void fv_gaze_filter_default_params(fv_gaze_filter_params *p);
void fv_gaze_filter_init(fv_gaze_filter *f, const fv_gaze_filter_params *p); /* NULL: defaults */
/* One tracker sample at t_ms (increasing). valid = 0 for blink / lost frames (yaw/pitch ignored). */
void fv_gaze_filter_update(fv_gaze_filter *f, double t_ms, int valid, float yaw_deg, float pitch_deg,
                           float confidence, fv_gaze_out *out);

/* How much to widen the fovea (multiplies its radius) for a tracking confidence:
 *   1 for confidence >= 0.8, linearly up to 2 at confidence <= 0.2 (and for NaN).
 * At full confidence the acuity model's fovea is used as is; a doubtful gaze gets a fovea wide
 * enough to cover the typical error of a degraded tracker. */
float fv_fovea_radius_scale(float confidence);

#endif
