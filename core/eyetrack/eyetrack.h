/* fovea eye tracker: dark-pupil + corneal-glint tracking on infrared luma images (no OS I/O).
 *
 * Coordinates: pixels, origin at the top-left CORNER of the image, x right, y down, so the
 * centre of pixel (i, j) is at (i + 0.5, j + 0.5). This is the convention of the MRL pupil
 * labels (../shared/assets/README.md) and of tools/gen_eye's ground truth.
 *
 * Use: t = fv_eye_create(NULL, FV_EYE_MODE_HEADSET); per frame fv_track_frame(t, luma, w, h,
 * stride, &r); then fv_eye_destroy(t). A tracker keeps a little history (pupil size, contrast) for blink/loss
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

/* What the frames are. The two trackers share the search and differ in the refinement and in
 * which centre they report (docs/eyetrack.md, "Detector"). */
typedef enum fv_eye_mode {
    FV_EYE_MODE_AUTO = 0, /* by frame size: CROP when min(w, h) <= FV_EYE_AUTO_CROP_MAX_SIDE,
                             else HEADSET (the rule from before there were modes) */
    FV_EYE_MODE_HEADSET,  /* a head-mounted eye camera's frame: the ellipse centre, lids handled */
    FV_EYE_MODE_CROP,     /* a tight crop around one eye (remote camera + eye detector, e.g. the
                             MRL set): pupils ~10 px, the search box's centre */
} fv_eye_mode;
#define FV_EYE_AUTO_CROP_MAX_SIDE 160

/* What a mode does; fv_eye_headset_settings and fv_eye_crop_settings are the two. */
typedef struct fv_eye_mode_settings {
    fv_eye_mode mode;
    /* search */
    int search_sides;           /* the pupil box must contrast with its ring on 3 of 4 sides (a
                                   spectacle frame's rim, a dark band, does not) */
    float sides_frac;           /* a side contrasts when brighter than the box by this fraction
                                   of the ring's contrast, */
    float sides_min_grey;       /* and by at least this many grey levels */
    int search_clip_grey;       /* the search image is clipped at its median + this before the
                                   box search (a frame's rim, a lens reflection's halo or bright
                                   skin do not make a ring look bright); 0 = off */
    float spot_margin_grey;     /* when no bright spot (spot_min_grey) lies within the best
                                   box's half-size, the best box near a spot within twice it on
                                   the dark eye (ring median <= the image's) wins if it scores
                                   within this many grey levels of the best; 0 = off */
    float lost_contrast;        /* below this contrast (grey levels) no pupil is reported */
    /* refinement */
    int refine_on_search_image; /* refine on the (inpainted) search image, not the frame */
    int refine_max_side;        /* else on the frame halved while its min side exceeds this
                                   (never below the search image's scale) */
    int window_side_div;        /* refine window half-size >= min(w, h) / this (0: 3r only) */
    int reflect_grow_px;        /* reflections grown by this before inpainting the window, when
                                   it is finer than the search image (1 px otherwise) */
    int centroid_iters;         /* weighted-centroid iterations at most */
    int box_grow_max;           /* times the search box may grow 1.4x while its surround is
                                   still as dark as the pupil */
    int smooth_rays;            /* rays run on the window smoothed by a 3x3 box */
    float edge_search_px;       /* edge = steepest rise within +-this of the level crossing
                                   (0: the crossing) */
    float beyond_frac;          /* drop edge points with something brighter than iris + this
                                   x (iris - pupil) within 0.5r beyond them (0: off) */
    int lid_line;               /* cut a straight run of edge points (a lid) */
    int ransac_iters;           /* 6-point RANSAC draws before the least-squares fit (0: a
                                   median-radius cut instead) */
    double ransac_grad_mincos;  /* RANSAC support: gradient within acos(this) of the normal */
    double min_aspect;          /* fits flatter than b/a < this are rejected */
    /* reported centre */
    int report_box_centre;      /* the search box's centre, moved by the two weights below and
                                   put on a pixel centre; else the ellipse's (or the centroid) */
    float centre_weight;        /* that fraction of the way toward the image centre (a crop is
                                   an eye detector's estimate of where the eye is); 0 = off */
    float glint_weight;         /* that fraction toward the most prominent bright spot within
                                   the box's half-size (a corneal reflection); 0 = off */
    int spot_min_grey;          /* the spot: grey levels above the median of its 3 px ring */
} fv_eye_mode_settings;

extern const fv_eye_mode_settings fv_eye_headset_settings;
extern const fv_eye_mode_settings fv_eye_crop_settings; /* tuned on the MRL crops */

/* HEADSET or CROP: mode itself, or for AUTO the size rule applied to a w x h frame. */
fv_eye_mode fv_eye_resolve_mode(fv_eye_mode mode, int w, int h);
/* The settings of a resolved mode (HEADSET or CROP; AUTO: NULL). */
const fv_eye_mode_settings *fv_eye_mode_get_settings(fv_eye_mode mode);
/* "auto", "headset", "crop" (NULL for anything else); the parse: 0, or -1 on another name. */
const char *fv_eye_mode_name(fv_eye_mode mode);
int fv_eye_mode_parse(const char *name, fv_eye_mode *mode);

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
    fv_eye_mode mode;       /* the mode the frame was tracked in (HEADSET or CROP) */
} fv_eye_result;

typedef struct fv_eye_params {
    unsigned isa_mask;       /* kernels allowed (FV_ISA_* bits; ~0u = best) */
    float min_radius_frac;   /* pupil search radii as fractions of min(w, h) */
    float max_radius_frac;
    float border_frac;       /* no pupil centre nearer the image border than this fraction of
                                min(w, h) (vignetted corners are dark) */
    float centre_prior;      /* search score penalty, grey levels per min(w, h) of distance
                                from the image centre (the eye is roughly centred) */
    int max_glints;          /* <= FV_EYE_MAX_GLINTS */
} fv_eye_params;

typedef struct fv_eye_tracker fv_eye_tracker;

void fv_eye_default_params(fv_eye_params *p);
/* p NULL: defaults; mode: what the frames are (AUTO: decided per frame by its size). NULL on
 * no memory. */
fv_eye_tracker *fv_eye_create(const fv_eye_params *p, fv_eye_mode mode);
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
