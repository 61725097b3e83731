/* fovea: ground-truth depth of field by ray casting a thin lens (the reference the DoF filters
 * are measured against). Every pixel, SPP rays through points of the eye's pupil.
 *
 * Lens model. The eye's thin lens sits at the pinhole camera's eye position, its aperture a
 * disc of diameter pupil_mm in the eye's x/y plane (perpendicular to the view axis). The
 * accommodated eye images the plane at view depth focus_m sharply on the retina: the pinhole
 * camera's image plane maps to that focus plane (pixel (px, py) <-> the point where the pinhole
 * ray through the pixel centre meets view depth focus_m). A lens sample at offset a (world,
 * metres, in the lens plane) casts the ray from eye + a through that point, with the direction
 * dir_pinhole - a / focus_m: its view-axis component stays 1, so the hit distance is still the
 * view depth. A point at view depth g then spreads over a disc of pupil_m |1/g - 1/focus_m|
 * in tan units, i.e. that times focal_px pixels, everywhere in the image: exactly Weier's
 * retinal CoC k d_i |1/g - 1/d| times E = focal_px / d_i (core/dof/coc.h). Pixels are sampled at
 * their centres only (no pixel-area anti-aliasing), like the pinhole pipeline, so a plane at
 * the focus distance renders as the pinhole image does.
 *
 * Samples. A Hammersley set of SPP points ((i + 1/2)/SPP, radical inverse of i), shifted per
 * pixel modulo 1 by a hash of (x, y, seed) (Cranley-Patterson rotation: noise instead of
 * banding), mapped to the disc with Shirley and Chiu's concentric map. Each pixel's value
 * depends only on its coordinates: the image is identical for any thread count. */
#ifndef FOVEA_REFERENCE_H
#define FOVEA_REFERENCE_H

#include <stddef.h>
#include <stdint.h>

#include "camera.h"
#include "pool.h"
#include "scene.h"

typedef struct fv_reference_params {
    int spp;        /* lens samples per pixel, >= 1 */
    float pupil_mm; /* aperture diameter; 0 = pinhole */
    float focus_m;  /* view depth of the focus plane, > 0 */
    uint32_t seed;  /* varies the per-pixel shifts */
    /* pinhole only (pupil_mm 0): 1 spreads the SPP rays over the pixel's area (a box filter, the
     * same stratified point set as the lens samples, with its own per-pixel shift): the
     * supersampled reference of the fovea's anti-aliasing (`fovea-replay --reference SPP --dof
     * none`; SPP 1: the one ray through the centre); 0: every ray through the pixel centre, the
     * pinhole image */
    int pixel_aa;
} fv_reference_params;

/* Called on the calling thread (pool worker 0) after each of its tiles: tiles done, tiles. */
typedef void (*fv_reference_progress_fn)(void *ctx, long done, long total);

/* Renders cam->width x cam->height pixels into rgbd (4 floats a pixel, row-major, no padding):
 * the mean linear RGB of the SPP lens rays (background fv_background_rgb where they miss) and
 * the view depth of the pixel's pinhole ray (one extra ray; FV_DEPTH_MISS_M on a miss), the
 * depth a CoC would be computed from. Returns the rays cast, or -1 for parameters out of range.
 * pool may be NULL (serial); progress may be NULL. */
long fv_reference_render(const fv_scene *scene, const fv_camera *cam, const fv_reference_params *prm, fv_pool *pool,
                         float *rgbd, fv_reference_progress_fn progress, void *progress_ctx);

/* View depth at pixel coordinates (px, py) (one pinhole ray; FV_DEPTH_MISS_M on a miss): the
 * default focus distance is this at the point of regard. */
float fv_reference_depth_at(const fv_scene *scene, const fv_camera *cam, float px, float py);

/* rgbd (as above) to sRGB 8-bit RGB, rows of dst_stride bytes: the output stage's conversion
 * (core/output_convert.h) with the kernels isa_mask allows, so with the pipeline's mask equal
 * linear values give the pipeline's bytes. */
void fv_reference_to_rgb8(const float *rgbd, int w, int h, uint8_t *dst, ptrdiff_t dst_stride, unsigned isa_mask);

#endif
