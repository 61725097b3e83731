/* fovea: timewarp, the display path's late correction. A rendered frame (8-bit RGB and a 16-bit
 * inverse depth plane, from a source camera) is warped to the camera of the newest head pose
 * right before a refresh: a backward warp per display pixel (fixed-point iteration on the
 * source's depth; the kernel and its contract: timewarp_dsp.h). Disocclusions are filled from
 * the farther surface beside the hole. OS-free. */
#ifndef FOVEA_TIMEWARP_H
#define FOVEA_TIMEWARP_H

#include <stddef.h>
#include <stdint.h>

#include "camera.h"
#include "timewarp_dsp.h"

/* The mapping from display camera pixels to source camera pixels (both without a lens: the warp
 * is linear; cameras of equal size). tol: the disocclusion tolerance (0.05 = 5 % in inverse depth). */
void fv_tw_setup(fv_tw_map *m, const fv_camera *display, const fv_camera *source, float tol);

/* The 16-bit inverse depth of an image of (r, g, b, depth_m) floats (fv_pipeline_depth): round
 * (FV_TW_INVD_PER_M / depth_m), clamped to [0, 65535] (nearer than 6.25 cm: the nearest). */
void fv_tw_pack_invd(uint16_t *dst, ptrdiff_t dst_stride, const float *rgbd, ptrdiff_t rgbd_stride, int w, int h);

/* Warps rows [y0, y1) of the display image (rows of dst_stride bytes, src->w pixels each).
 * Returns the disoccluded pixels. */
long fv_tw_warp_rows(const fv_timewarp_dsp *d, uint8_t *dst, ptrdiff_t dst_stride, int y0, int y1, const fv_tw_map *m,
                     const fv_tw_src *src);

/* Bytes a plane must have past its last pixel / element for the kernels' word reads. */
#define FV_TW_RGB_PAD 16
#define FV_TW_INVD_PAD 32

#endif

/* ---- a rendered stereo frame kept for the warp (one mailbox slot of the headset) ---- */
struct fv_pipeline;
typedef struct fv_tw_frame {
    int w, h;               /* per eye */
    uint8_t *rgb[2];        /* left, right: display bytes, w * 3 a row, FV_TW_RGB_PAD past the end */
    uint16_t *invd[2];      /* w a row, FV_TW_INVD_PAD bytes past the end */
    fv_camera cam[2];       /* the cameras they were rendered from */
} fv_tw_frame;

int fv_tw_frame_alloc(fv_tw_frame *f, int w, int h); /* 0, or -1 out of memory */
void fv_tw_frame_free(fv_tw_frame *f);
/* After fv_pipeline_render of eye e (0 left, 1 right): keep its display bytes, inverse depth and
 * camera. */
void fv_tw_frame_capture(fv_tw_frame *f, const struct fv_pipeline *pl, int e);
/* Warps eye e of f to camera `display` (same size, no lens) into dst (rows of dst_stride bytes).
 * Returns the disoccluded pixels. */
long fv_tw_frame_warp(const fv_timewarp_dsp *d, const fv_tw_frame *f, int e, const fv_camera *display, uint8_t *dst,
                      ptrdiff_t dst_stride, float tol);

/* The warp's image quality: luma PSNR (dB) of `warped` against `ref` (a frame rendered directly
 * at the display camera), both w x h 8-bit RGB rows of w * 3 bytes, over the pixels the warp
 * (map m, source src) did not fill as disocclusions; *disocc_frac gets the disoccluded fraction.
 * INFINITY when identical, NAN when every pixel is disoccluded or out of memory. */
double fv_tw_psnr_outside_holes(const uint8_t *warped, const uint8_t *ref, const fv_tw_map *m, const fv_tw_src *src,
                                double *disocc_frac);
