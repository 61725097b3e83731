/* fovea: fovea-replay's per-frame quality bookkeeping on the (left) eye's 8-bit image: the
 * periphery's luma change against the previous frame (temporal stability), with --vs-full the
 * luma PSNR against full sampling of the same frame (whole, fovea < r0, periphery > r1) and the
 * periphery's flicker (how much that error changes between frames), and their means over frames. */
#ifndef FOVEA_QUALITY_H
#define FOVEA_QUALITY_H

#include <stddef.h>
#include <stdint.h>

/* A normalised gaze coordinate in pixels of an image `size` pixels across, as the pipeline
 * centres its sampling pattern (the centre of the pixel it falls in). */
float fv_gaze_px(float g, int size);

/* Mean of the finite values added; infinities (PSNR of identical images) are counted apart:
 * the mean is INFINITY when only they were added, NAN when nothing was. */
typedef struct fv_mean_acc {
    double sum;
    long n, inf;
} fv_mean_acc;
void fv_mean_add(fv_mean_acc *m, double v); /* NAN: left out */
double fv_mean_get(const fv_mean_acc *m);

/* One frame's measures; NAN where not measured (the first frame's changes, PSNR without --vs-full). */
typedef struct fv_quality_row {
    double dluma_periph, psnr_all, psnr_fovea, psnr_periph, flicker_periph;
} fv_quality_row;

typedef struct fv_quality {
    int w, h, vs_full;
    long frames;
    uint8_t *prev, *cur;    /* last and this frame's image, w * 3 bytes a row */
    float *err_prev, *err_cur; /* luma error against full sampling (vs_full) */
    float prev_gx, prev_gy; /* the last frame's gaze, pixels */
    fv_mean_acc dluma, psnr_all, psnr_fovea, psnr_periph, flicker; /* means over frames */
} fv_quality;

/* 0, or -1 when out of memory (fv_quality_free is still safe). */
int fv_quality_init(fv_quality *q, int w, int h, int vs_full);
void fv_quality_free(fv_quality *q);
/* Measures one frame: rgb, this frame's image (rows `stride` bytes apart, its first w pixels
 * used); full, the same eye fully sampled (rows w * 3 bytes, NULL without vs_full); the gaze and
 * the fovea (r0) and periphery (r1) radii in pixels. Adds to the means. */
void fv_quality_frame(fv_quality *q, const uint8_t *rgb, ptrdiff_t stride, const uint8_t *full, float gx_px,
                      float gy_px, float r0_px, float r1_px, fv_quality_row *row);

#endif
