/* Private to core/eyetrack/: what the tracker's steps share. track.c runs them in this order:
 *   search.c  coarse dark-pupil box search over integral images (reflections inpainted first)
 *   refine.c  sub-pixel outline in a window around it: levels, centroid, edge points, lid cuts,
 *             RANSAC, ellipse fit (ellipse.c)
 *   glints.c  bright spots: reflection inpainting, corneal glints, the crop mode's bright spot
 *   blink.c   confidence, loss and blinks against the tracker's running reference
 * Kernels are reached through the dispatch table (const fv_eyetrack_dsp *, dsp->et_*). */
#ifndef FOVEA_EYETRACK_TRACK_IMPL_H
#define FOVEA_EYETRACK_TRACK_IMPL_H

#include <stddef.h>
#include <stdint.h>

#include "eyetrack/eyetrack_dsp.h"
#include "eyetrack/eyetrack.h"

#define FV_ET_SEARCH_MAX_SIDE 160 /* search image F: min side at most this */
#define FV_ET_NRAYS 48            /* edge-point rays of the refinement */

typedef struct fv_et_history { /* running reference of the pupil (fv_track_frame only) */
    int n;
    float contrast, radius, inner, ring;
} fv_et_history;

struct fv_eye_tracker {
    fv_eye_params p;
    fv_eye_mode mode; /* as created: AUTO is resolved per frame */
    fv_eyetrack_dsp dsp;
    uint8_t *mem;
    size_t cap;
    fv_et_history ref;
};

/* Scratch for one frame of w x h (track.c carves it from the tracker's buffer). */
typedef struct fv_et_scratch {
    uint8_t *work, *mask, *lowres; /* w * h bytes each */
    uint32_t *ii;                  /* (w + 1) * (h + 1): integral images, later a pixel list */
    int *stack;                    /* w * h: pixel lists */
    float *rowf;                   /* w */
    fv_eye_glint *gl;              /* FV_EYE_MAX_GLINTS */
} fv_et_scratch;

/* ---- search.c */

typedef struct fv_et_candidate {
    float x, y, r;     /* full-resolution pixels (corner origin) */
    float inner, ring; /* mean grey of the box and of its ring */
    int scale;         /* full resolution / search image F */
    int sw, sh;        /* F's size; F is left in the scratch's work buffer */
    int ok;
} fv_et_candidate;

fv_et_candidate fv_et_search(const fv_eyetrack_dsp *d, const fv_eye_params *p, const uint8_t *luma, int w, int h,
                             ptrdiff_t stride, const fv_et_scratch *s, const fv_eye_mode_settings *set);

/* ---- glints.c */

typedef struct fv_et_levels {
    int median, dark; /* grey levels: median, 1st percentile */
} fv_et_levels;

/* Levels of img (w x h, row length w), then its reflections (pixels >= max(median + 40,
 * median + (255 - median) / 2), grown by grow_px) inpainted when its brightest 0.5% reach that.
 * mask: w * h bytes, idx and fr: w * h ints of scratch. 1 when it inpainted. */
int fv_et_inpaint_reflections(const fv_eyetrack_dsp *d, uint8_t *img, int w, int h, int grow_px, uint8_t *mask, int *idx,
                              int *fr, fv_et_levels *lv);

typedef struct fv_et_pupil {
    float x, y, r; /* centroid and radius, pixels */
    float inner, ring;
    int fit;
    fv_ellipse e;
    float inliers; /* fraction of rays giving inlier edge points */
} fv_et_pupil;

/* Corneal reflections near the pupil, nearest first (at most max_glints). lab: scratch bytes
 * and stack ints for the pupil's window (4.4r + 1 squared). */
int fv_et_find_glints(const fv_eyetrack_dsp *d, const uint8_t *luma, int w, int h, ptrdiff_t stride, const fv_et_pupil *pp,
                      int max_glints, uint8_t *lab, int *stack, fv_eye_glint *g);

/* The most prominent small reflection within r of (cx, cy): 1 and its pixel centre, or 0. */
int fv_et_bright_spot(const uint8_t *img, int w, int h, ptrdiff_t stride, float cx, float cy, float r,
                      int min_grey, float *ox, float *oy);

/* The same spots (contrast >= min_grey) within r of (cx, cy) whose 3 px ring's median is at most
 * max_ring_grey (on the dark eye, not on skin or a spectacle rim), in raster order, at most
 * max_n: their pixels in xs, ys; the count. */
int fv_et_dark_spots(const uint8_t *img, int w, int h, ptrdiff_t stride, float cx, float cy, float r, int min_grey,
                     int max_ring_grey, int max_n, int *xs, int *ys);

/* ---- refine.c */

typedef struct fv_et_refine_args {
    const fv_eyetrack_dsp *dsp;
    const fv_eye_mode_settings *set;
    const uint8_t *img; /* the image refined on (the frame, halved, or the search image) */
    int w, h;
    ptrdiff_t stride;
    fv_et_candidate c;  /* in img's pixels; c.scale: img / search image */
    /* scratch: win, mask w * h bytes; idx, fr w * h ints (fr: the search's integral image
     * buffer, free by now); dxx w floats */
    uint8_t *win, *mask;
    int *idx, *fr;
    float *dxx;
} fv_et_refine_args;

/* 0 and the pupil (out->fit: whether the ellipse was accepted); -1 when no dark region stands
 * out in the window. */
int fv_et_refine(const fv_et_refine_args *a, fv_et_pupil *out);

/* ---- blink.c */

/* Confidence, then loss (too little contrast) and, with history, blinks against the running
 * reference, which a good frame updates. r: position, contrast and glints filled in. */
void fv_et_judge(fv_et_history *ref, const fv_et_pupil *p, int history, float lost_contrast, fv_eye_result *r);

#endif
