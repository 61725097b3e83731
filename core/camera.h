/* fovea: per-eye pinhole camera of a head-mounted display. Asymmetric frusta (lens centres
 * are rarely on the panel centre), head pose from a trace or tracker, eyes offset by IPD/2
 * along the head's right axis. Eye space looks down -Z with +Y up (glTF). */
#ifndef FOVEA_CAMERA_H
#define FOVEA_CAMERA_H

#include "lens.h"

typedef struct fv_pose {
    float pos[3];  /* metres, world */
    float quat[4]; /* x, y, z, w: rotates head/eye space into world space */
} fv_pose;

typedef enum { FV_EYE_CENTER = 0, FV_EYE_LEFT = 1, FV_EYE_RIGHT = 2 } fv_eye;

typedef struct fv_camera {
    int width, height;          /* pixels */
    float tan_left, tan_right;  /* frustum extents at unit distance: x = tan_left..tan_right */
    float tan_bottom, tan_top;  /* y = tan_bottom..tan_top */
    float eye_pos[3];           /* world, metres */
    float right[3], up[3], back[3]; /* world axes of eye space (+X, +Y, +Z) */
    float px_tan;               /* tan-space size of one pixel (square pixels) */
    float focal_px;             /* pixels per unit tan at the optical axis */
    /* lens distortion (fv_camera_desc.lens): rays go along the distorted directions */
    int lens_on;
    float lens_k1, lens_k2, lens_scale; /* the green channel's */
    float lens_scale_rgb[3];            /* all three (lateral chromatic aberration) */
    float lens_cx, lens_cy;             /* lens centre, tangent units */
} fv_camera;

typedef struct fv_camera_desc {
    int width, height;  /* default 1280 x 1440 */
    float fov_y_deg;    /* vertical field of view, default 100 */
    float ipd_m;        /* default 0.063 */
    fv_eye eye;
    /* Horizontal offset of the optical axis as a fraction of the half-width, signed toward
     * the nose for the left eye; 0 = symmetric. Negated for the right eye (mirror image). */
    float axis_shift;
    /* HMD lens (core/lens.h), NULL = none (the default): each eye uses its own lens centre,
     * which also places that eye's optical axis (an asymmetric frustum; axis_shift is then not
     * used). Must outlive the cameras set up from this description. */
    const fv_lens *lens;
} fv_camera_desc;

void fv_camera_desc_default(fv_camera_desc *d);
/* Returns 0, or -1 for a size or FOV out of range. */
int fv_camera_setup(fv_camera *c, const fv_camera_desc *d, const fv_pose *head);

/* Unnormalised world-space ray direction through the centre of pixel (px, py), scaled so its
 * component along the view axis is 1: the hit distance t is then the view depth in metres. */
static inline void fv_camera_ray(const fv_camera *c, float px, float py, float dir[3])
{
    float tx = c->tan_left + px * c->px_tan;
    float ty = c->tan_top - py * c->px_tan;
    if (c->lens_on)
        fv_lens_distort(c->lens_k1, c->lens_k2, c->lens_scale, c->lens_cx, c->lens_cy, tx, ty, &tx, &ty);
    for (int i = 0; i < 3; i++)
        dir[i] = tx * c->right[i] + ty * c->up[i] - c->back[i];
}

/* Projects a world point to pixel coordinates (through the inverse lens mapping when there is a
 * lens); returns its view depth (<= 0: behind the eye). */
float fv_camera_project(const fv_camera *c, const float p[3], float *px, float *py);

void fv_quat_rotate(const float q[4], const float v[3], float out[3]);
/* out = a * b (Hamilton product, x, y, z, w): the rotation b, then a. out may alias a or b. */
void fv_quat_mul(const float a[4], const float b[4], float out[4]);
void fv_quat_normalize(float q[4]);
void fv_quat_slerp(const float a[4], const float b[4], float t, float out[4]);

#endif
