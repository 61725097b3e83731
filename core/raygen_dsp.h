/* fovea: the ray-generation kernel (one table per module, dav1d style; core/cpu.h has the pattern
 * and the contract every ISA version keeps): a packet's camera ray directions straight from the
 * tile's pixel list (core/raycast.c). C reference: core/raygen_ref.c. */
#ifndef FOVEA_RAYGEN_DSP_H
#define FOVEA_RAYGEN_DSP_H

#include <stdint.h>

#include "cpu.h"

/* The pinhole part of a camera (core/camera.h: fv_camera_ray without the lens). */
typedef struct fv_raygen_cam {
    float tan_left, tan_top, px_tan;
    float right[3], up[3], back[3];
    float ox, oy; /* where in the pixel the ray goes: 0.5, 0.5 the centre (fovea AA jitters it) */
} fv_raygen_cam;

/* camera_rays: for i < n (n = 8 or 16), pixel p = px[i] = (y << 4 | x) of the tile at (x0, y0):
 *   tx = tan_left + ((float)(x0 + x) + ox) px_tan,  ty = tan_top - ((float)(y0 + y) + oy) px_tan,
 *   d[k][i] = tx right[k] + ty up[k] - back[k]
 * (fv_camera_ray's operations in its order; ox = oy = 0.5 gives its pixel-centre rays). Reads px[0 .. n), writes d[k][0 .. n). Exact. */
typedef void (*fv_camera_rays_fn)(const fv_raygen_cam *c, const uint8_t *px, int x0, int y0, float *dx, float *dy,
                                  float *dz, int n);
typedef struct fv_raygen_dsp {
    fv_camera_rays_fn camera_rays;
} fv_raygen_dsp;

void fv_raygen_dsp_init(fv_raygen_dsp *d, unsigned isa_mask);

/* ---- internal ---- */
void fv_camera_rays_c(const fv_raygen_cam *c, const uint8_t *px, int x0, int y0, float *dx, float *dy, float *dz, int n);
#if defined(__x86_64__)
void fv_raygen_dsp_init_sse41(fv_raygen_dsp *d);
void fv_raygen_dsp_init_avx2(fv_raygen_dsp *d);
#elif defined(__aarch64__)
void fv_raygen_dsp_init_neon(fv_raygen_dsp *d);
#endif

#endif
