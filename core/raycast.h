/* fovea: ray casting and shading of the sampled pixels of one screen tile (Embree packets).
 * The tile driver (core/tile.c) decides which pixels are sampled and runs the later stages of
 * the tile; this file only turns sample positions into colour and depth. */
#ifndef FOVEA_RAYCAST_H
#define FOVEA_RAYCAST_H

#include <math.h>
#include <stdint.h>

#include "camera.h"
#include "pullpush.h"
#include "scene.h"
#include "tile.h"

#define FV_DEPTH_MISS_M 1000.0f /* depth stored where a ray leaves the scene */

/* Background radiance (linear RGB) where rays miss. */
extern const float fv_background_rgb[3];

/* Lane k of an 8-ray packet: a primary ray from org along dir (tnear 0, tfar infinite, all
 * masks), not hit yet. */
static inline void fv_ray8_set(struct RTCRayHit8 *rh, int k, const float org[3], const float dir[3])
{
    rh->ray.org_x[k] = org[0];
    rh->ray.org_y[k] = org[1];
    rh->ray.org_z[k] = org[2];
    rh->ray.dir_x[k] = dir[0];
    rh->ray.dir_y[k] = dir[1];
    rh->ray.dir_z[k] = dir[2];
    rh->ray.tnear[k] = 0.0f;
    rh->ray.tfar[k] = INFINITY;
    rh->ray.time[k] = 0.0f;
    rh->ray.mask[k] = ~0u;
    rh->ray.id[k] = (unsigned)k;
    rh->ray.flags[k] = 0;
    rh->hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
    rh->hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
}

struct fv_render_dsp;

/* The packet width the ray stage traces with: 16 (rtcIntersect16) where this Embree traces
 * 16-wide packets (natively, or through its stream filter on a CPU without AVX-512), else 8. */
int fv_raycast_packet_width(void);
/* The pixels of a tile whose bits are set in rows[y] (bit x; y < th, x < tw) as (y << 4 | x), in
 * 4x2-block order (coherent packets); their count. px needs 8 bytes of slack past the count.
 * The ray stage and the bare-Embree ceiling (core/ceiling.c) both cast in this order. */
int fv_raycast_pixels(const uint32_t rows[FV_TILE], int tw, int th, uint8_t px[FV_TILE * FV_TILE + 8]);

/* Casts a ray through the centre of every pixel of the tile [x0, x0+tw) x [y0, y0+th) whose bit
 * is set in rows[y - y0] (bit x - x0), generates and shades them with dsp's kernels (ray, shade) and writes r, g, b,
 * depth_m with weight 1 into level 0 (l0's planes); every other pixel of the tile gets weight 0
 * and keeps its colour. Returns the number of rays cast. shade_ns: NULL, or the tile's shading
 * time (the packets' fv_scene_shade_packet, not tracing or writing) is added to *shade_ns (two
 * clock reads; NULL reads no clock: the bench asks for the shading share, nothing else pays). */
long fv_raycast_tile(const fv_scene *scene, const fv_camera *cam, const struct fv_render_dsp *dsp,
                     const fv_pyr_level *l0, int x0, int y0, int tw, int th, const uint32_t rows[FV_TILE],
                     int64_t *shade_ns);

/* The same with every ray through (ox, oy) inside its pixel instead of the centre (0.5, 0.5 gives
 * fv_raycast_tile's bits): the fovea's anti-aliasing jitter (fv_sampling_jitter). */
long fv_raycast_tile_at(const fv_scene *scene, const fv_camera *cam, const struct fv_render_dsp *dsp,
                        const fv_pyr_level *l0, int x0, int y0, int tw, int th, const uint32_t rows[FV_TILE], float ox,
                        float oy, int64_t *shade_ns);

/* fv_raycast_tile_at that writes the samples only (colour, depth, weight 1): the other pixels
 * keep their weight and colour (the still head renders over its history in place). When the
 * rays are traced and shaded, before any pixel is written, it calls before_write(ctx) (NULL:
 * none): the still head saves its samples' history there, when their lines, asked for before
 * the rays were traced, are in cache. */
long fv_raycast_tile_keep_holes(const fv_scene *scene, const fv_camera *cam, const struct fv_render_dsp *dsp,
                                const fv_pyr_level *l0, int x0, int y0, int tw, int th, const uint32_t rows[FV_TILE],
                                float ox, float oy, int64_t *shade_ns, void (*before_write)(void *ctx), void *ctx);

#endif
