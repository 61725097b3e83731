/* fovea eye tracker: dark-pupil + corneal-glint tracking on infrared luma images (no OS I/O).
 *
 * Coordinates: pixels, origin at the top-left CORNER of the image, x right, y down, so the
 * centre of pixel (i, j) is at (i + 0.5, j + 0.5). This is the convention of the MRL pupil
 * labels (../shared/assets/README.md) and of tools/gen_eye's ground truth.
 *
 * Use: t = fv_eye_create(NULL); per frame fv_track_frame(t, luma, w, h, stride, &r); then
 * fv_eye_destroy(t). A tracker keeps a little history (pupil size, contrast) for blink/loss
 * detection and scratch buffers; one tracker per camera, not shared between threads. */
#ifndef FOVEA_EYETRACK_H
#define FOVEA_EYETRACK_H

#include <stddef.h>
#include <stdint.h>

#define FV_EYE_MAX_GLINTS 8

typedef struct fv_eye_glint {
    float x, y;    /* intensity-weighted centroid */
    float area_px; /* pixels in the blob */
} fv_eye_glint;

enum { FV_EYE_OK = 0, FV_EYE_BLINK = 1, FV_EYE_LOST = 2 };

typedef struct fv_eye_result {
    int status;             /* FV_EYE_OK, FV_EYE_BLINK (eye closed / pupil covered), FV_EYE_LOST */
    int found;              /* a pupil position is given (status OK, possibly with low confidence) */
    float pupil_x, pupil_y; /* sub-pixel pupil centre */
    float pupil_a_px, pupil_b_px, pupil_angle_rad; /* ellipse semi-axes and angle (a >= b) */
    int ellipse_fit;        /* 1: centre from the ellipse fit; 0: from the dark-region centroid */
    float contrast;         /* surround minus pupil mean grey level */
    float confidence;       /* 0 (useless) .. 1 */
    int n_glints;           /* glints near the pupil, nearest first */
    fv_eye_glint glints[FV_EYE_MAX_GLINTS];
    int has_pg;             /* pupil-glint vector available (at least one glint) */
    float pg_x, pg_y;       /* pupil centre minus the mean of the glints, pixels */
} fv_eye_result;

typedef struct fv_eye_params {
    unsigned isa_mask;       /* kernels allowed (FV_ISA_* bits; ~0u = best) */
    float min_radius_frac;   /* pupil search radii as fractions of min(w, h) */
    float max_radius_frac;
    float border_frac;       /* no pupil centre nearer the image border than this fraction of
                                min(w, h) (vignetted corners are dark) */
    float centre_prior;      /* search score penalty, grey levels per min(w, h) of distance
                                from the image centre (the eye is roughly centred) */
    float crop_centre_weight; /* small frames (min side <= 160: crops an eye detector centred on
                                 the eye): the reported centre moves this fraction of the way
                                 from the detection to the image centre (a second, independent
                                 estimate of the pupil) and stays on pixel centres; 0 = off */
    float glint_weight;      /* small frames: and this fraction of the way toward the most
                                prominent bright spot (a corneal reflection) within the search
                                box's half-size of its centre; 0 = off. Set both to 0 for a
                                headset camera whose frames are this small. */
    int max_glints;          /* <= FV_EYE_MAX_GLINTS */
} fv_eye_params;

typedef struct fv_eye_tracker fv_eye_tracker;

void fv_eye_default_params(fv_eye_params *p);
fv_eye_tracker *fv_eye_create(const fv_eye_params *p); /* NULL: defaults; NULL on no memory */
void fv_eye_destroy(fv_eye_tracker *t);
/* Forget the history (new video / new image set). */
void fv_eye_reset(fv_eye_tracker *t);
/* Track one frame. 0 on success (even when no pupil is found: see r->status), -1 on bad
 * arguments (w or h < 8 or > 8192, |stride| < w, NULL) or no memory. */
int fv_track_frame(fv_eye_tracker *t, const uint8_t *luma, int w, int h, ptrdiff_t stride, fv_eye_result *r);
/* Same, but without blink history (each image on its own: image sets such as MRL). */
int fv_track_image(fv_eye_tracker *t, const uint8_t *luma, int w, int h, ptrdiff_t stride, fv_eye_result *r);

/* ---- pieces, exposed for tests ---- */

/* Direct least-squares ellipse fit (Fitzgibbon 1999, numerically stable form of Halir & Flusser
 * 1998) to n >= 5 points. Returns 0 and the centre, semi-axes (a >= b) and angle of the major
 * axis from +x; -1 when the points determine no ellipse. */
typedef struct fv_ellipse {
    double cx, cy, a, b, angle;
} fv_ellipse;
int fv_ellipse_fit(const float *x, const float *y, int n, fv_ellipse *e);
/* Approximate geometric distance of (x, y) from the ellipse (Sampson distance of the conic). */
double fv_ellipse_distance(const fv_ellipse *e, double x, double y);

#endif
