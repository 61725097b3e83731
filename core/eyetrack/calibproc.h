/* fovea eye tracker: the calibration procedure a wearer goes through (fovea-headset --calibrate).
 * Pure and clock-driven, so it runs the same live, on a replayed eye video and in tests:
 *
 *   targets   9 points of a 3x3 grid (fv_calib_targets_3x3), then n_valid validation points
 *             elsewhere (between the grid's rows and columns), each shown for dwell_ms from the
 *             start, one after the other (a fixed schedule: a replayed video can follow it);
 *   fixation  in each target's slot, after settle_ms (the wearer's reaction and saccade), the
 *             most stable window of fix_ms: frames in blinks or without the feature (no pupil, no
 *             glint) excluded, at least 60 % of the window's frames usable, the spread (largest
 *             distance of a frame's feature from the window's median) smallest; the median is the
 *             point's feature. The spread must stay within fix_disp_deg, converted to feature
 *             pixels by the grid's own scale (the median of |feature difference| / angle over
 *             neighbouring grid points: the camera's scale is not known before calibrating). A
 *             slot with no such window (saccades, blinks, a wandering gaze) fails;
 *   repeats   grid points that failed are shown again once, appended to the schedule;
 *   fit       fv_calib_fit on the grid points that have a feature (at least 6, and the grid's
 *             corners or its middle rows and columns covered, else the fit is refused);
 *   check     the mapping applied to each validation point's feature, angular error against
 *             its target: mean and max. Above valid_mean_max_deg / valid_max_max_deg the
 *             calibration is refused ("does not reach the validation points").
 * Degrees: yaw positive right, pitch positive up, as fv_calib. */
#ifndef FOVEA_EYETRACK_CALIBPROC_H
#define FOVEA_EYETRACK_CALIBPROC_H

#include <stdint.h>

#include "eyetrack/calib.h"
#include "eyetrack/eyetrack.h"

#define FV_CALPROC_MAX_VALID 8
#define FV_CALPROC_MAX_SLOTS (9 + FV_CALPROC_MAX_VALID + 9)

typedef struct fv_calproc_params {
    float span_x_deg, span_y_deg; /* grid: yaw +-span_x, pitch +-span_y (default 15, 10) */
    int n_valid;                  /* validation points, 0..8 (default 4) */
    int dwell_ms;                 /* each target on screen (default 1500) */
    int settle_ms;                /* ignored after a target appears (default 400) */
    int fix_ms;                   /* the stable window (default 300) */
    float fix_disp_deg;           /* how far a fixation's samples may lie from their median (default 1) */
    int input;                    /* FV_CALIB_PUPIL_GLINT (default) or FV_CALIB_PUPIL */
    float slip_gain;              /* pupil-glint: fv_calib.slip_gain (default fv_calib_slip_gain(35):
                                     LEDs about 35 mm from the eye) */
    float valid_mean_max_deg;     /* refusal thresholds (default 1.5, 3.0) */
    float valid_max_max_deg;
} fv_calproc_params;

enum { FV_CALPROC_GRID = 0, FV_CALPROC_VALID = 1 };

typedef struct fv_calproc_point {
    int kind;                 /* FV_CALPROC_GRID or FV_CALPROC_VALID */
    float yaw_deg, pitch_deg; /* the target */
    int ok;                   /* a fixation was found */
    float fx, fy;             /* its feature (median) */
    float disp_px;            /* its window's spread (feature pixels) */
    int frames;               /* usable frames in its slot */
    float err_deg;            /* validation points: the mapping's error there */
} fv_calproc_point;

typedef struct fv_calproc_report {
    int n_grid_ok, n_valid_ok;   /* points with a fixation */
    float valid_mean_deg, valid_max_deg;
    fv_calproc_point points[9 + FV_CALPROC_MAX_VALID]; /* grid then validation, final state */
    int n_points;
    int n_repeated;              /* grid points shown a second time */
    float px_per_deg;            /* the feature's scale found on the grid */
} fv_calproc_report;

typedef struct fv_calproc fv_calproc;

void fv_calproc_default_params(fv_calproc_params *p);
/* NULL on bad parameters or no memory. */
fv_calproc *fv_calproc_create(const fv_calproc_params *p);
void fv_calproc_destroy(fv_calproc *c);

/* The schedule from t0_ns (the first target's onset). */
void fv_calproc_start(fv_calproc *c, int64_t t0_ns);
/* The target on screen at t_ns: 1 with its slot index, yaw and pitch; 0 when the schedule is
 * over (then fv_calproc_finish). Before t0 the first target. Once the main schedule is over it
 * appends the grid points that found no fixation, once. */
int fv_calproc_target(fv_calproc *c, int64_t t_ns, int *slot, float *yaw_deg, float *pitch_deg);
/* The schedule as the generator of a scripted eye video needs it: the target of slot k (k in
 * [0, slots)), without repeats. */
int fv_calproc_slots(const fv_calproc *c);
void fv_calproc_slot_target(const fv_calproc *c, int k, float *yaw_deg, float *pitch_deg);

/* One tracked eye-camera frame taken at t_ns (frames may come at any rate, in time order). */
void fv_calproc_feed(fv_calproc *c, int64_t t_ns, const fv_eye_result *r);

/* After the schedule: fits and checks. 0 with *out and *rep filled; -1 with the reason in err
 * (and *rep filled as far as it got: which points failed, the validation figures). */
int fv_calproc_finish(fv_calproc *c, fv_calib *out, fv_calproc_report *rep, char *err, size_t err_len);

#endif
