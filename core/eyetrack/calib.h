/* fovea eye tracker: gaze calibration. A second-order polynomial per axis (6 coefficients, least
 * squares) from the pupil-glint vector (or the pupil centre alone, the fallback when no glint is
 * found) to the gaze direction in degrees:
 *   yaw_deg   = a . [1, u, v, u v, u^2, v^2]      u = (in_x - u0) / s, v = (in_y - v0) / s
 *   pitch_deg = b . [1, u, v, u v, u^2, v^2]
 * (u0, v0, s) normalise the inputs so the fit is well conditioned. Gaze: yaw positive towards
 * +x of the eye image, pitch positive up; direction (sin yaw cos pitch, sin pitch, cos yaw cos pitch).
 * The text form (fv_calib_format / fv_calib_parse) is what --calibration files hold. */
#ifndef FOVEA_EYETRACK_CALIB_H
#define FOVEA_EYETRACK_CALIB_H

#include <stddef.h>

enum { FV_CALIB_PUPIL_GLINT = 0, FV_CALIB_PUPIL = 1 };

/* The largest sample count a calibration file may state (far above any procedure's). */
#define FV_CALIB_MAX_SAMPLES 1000000

typedef struct fv_calib {
    int input;          /* FV_CALIB_PUPIL_GLINT or FV_CALIB_PUPIL */
    double u0, v0, s;   /* input normalisation */
    double a[6], b[6];  /* yaw and pitch coefficients */
    double rms_deg, max_deg; /* angular residuals of the fit (the samples kept) */
    int n_used;         /* samples kept after outlier rejection */
    /* pupil-glint input: the feature is k pg - (k - 1) pupil (k = slip_gain; 1: the plain
     * pupil-glint vector). Under a camera slip s the glints move by (1 - 1/k) s less than the
     * pupil (a corneal reflection of LEDs at distance d moves by R / (2 d) of the slip, R the
     * corneal radius), so k = 1 / (1 - R / (2 d)) cancels the slip: fv_calib_slip_gain. */
    double slip_gain;
} fv_calib;

/* k for LEDs d_led_mm from the cornea, corneal radius 7.8 mm (Le Grand's eye). */
double fv_calib_slip_gain(double d_led_mm);

/* The 3x3 calibration targets: yaw in {-span_x, 0, +span_x}, pitch in {+span_y, 0, -span_y},
 * row by row from the top left. */
void fv_calib_targets_3x3(float span_x_deg, float span_y_deg, float yaw_deg[9], float pitch_deg[9]);

/* Least-squares fit to n >= 6 samples (input (in_x, in_y) looking at (yaw, pitch)); samples
 * whose residual exceeds 3x the median residual (and 1 degree) are dropped once and the fit
 * redone. resid_deg (n, optional) receives every sample's angular residual. 0 on success, -1
 * when the samples do not determine the polynomial (too few, or degenerate layout). */
int fv_calib_fit(fv_calib *c, int input, const float *in_x, const float *in_y, const float *yaw_deg,
                 const float *pitch_deg, int n, float *resid_deg);
void fv_calib_apply(const fv_calib *c, float in_x, float in_y, float *yaw_deg, float *pitch_deg);
/* The input feature of a tracker result for c's input kind and slip gain: 1 with it, 0 when the
 * frame has none (no pupil, a blink, no glint for a pupil-glint input). */
struct fv_eye_result;
int fv_calib_feature(const fv_calib *c, const struct fv_eye_result *r, float *fx, float *fy);

/* Angle between two gaze directions, degrees. */
double fv_gaze_angle_deg(double yaw1, double pitch1, double yaw2, double pitch2);

/* Text form: returns the length written (as snprintf) */
int fv_calib_format(const fv_calib *c, char *buf, size_t len);
/* 0, or -1 with "line N: reason" in err. */
int fv_calib_parse(fv_calib *c, const char *text, char *err, size_t err_len);

#endif
