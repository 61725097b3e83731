#include "reference.h"

#include "blend.h"
#include "output_convert.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "base/util.h"
#include "raycast.h" /* FV_TILE, FV_DEPTH_MISS_M, fv_background_rgb */

#define PI_F 3.14159265358979323846f

typedef struct {
    const fv_scene *scene;
    const fv_camera *cam;
    const fv_reference_params *prm;
    float *rgbd;
    float lens_r_m; /* aperture radius */
    int tiles_x, tiles;
    atomic_long rays, done;
    fv_reference_progress_fn progress;
    void *progress_ctx;
} ref_job;


static inline float radical_inverse2(uint32_t i)
{
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
    return (float)(i >> 8) * (1.0f / 16777216.0f);
}

/* Shirley & Chiu 1997: the unit square onto the unit disc, area-preserving, low distortion, so
 * the stratification of the point set survives. */
static inline void concentric_disc(float u, float v, float *x, float *y)
{
    const float a = 2.0f * u - 1.0f, b = 2.0f * v - 1.0f;
    float r, phi;
    if (a == 0.0f && b == 0.0f) {
        *x = *y = 0.0f;
        return;
    }
    if (fabsf(a) > fabsf(b)) {
        r = a;
        phi = (PI_F / 4.0f) * (b / a);
    } else {
        r = b;
        phi = PI_F / 2.0f - (PI_F / 4.0f) * (a / b);
    }
    *x = r * cosf(phi);
    *y = r * sinf(phi);
}

/* Lens sample s of pixel (x, y): offset in the lens plane (eye x, y) in metres. */
static inline void lens_point(const ref_job *j, int x, int y, int s, float *lx, float *ly)
{
    const uint32_t h = fv_hash32((uint32_t)x * 0x8da6b343u ^ (uint32_t)y * 0xd8163841u ^ j->prm->seed * 0xcb1ab31fu);
    const float sx = (float)(h >> 8) * (1.0f / 16777216.0f);
    const float sy = (float)(fv_hash32(h ^ 0x9e3779b9u) >> 8) * (1.0f / 16777216.0f);
    float u = ((float)s + 0.5f) / (float)j->prm->spp + sx, v = radical_inverse2((uint32_t)s) + sy;
    u -= u >= 1.0f ? 1.0f : 0.0f;
    v -= v >= 1.0f ? 1.0f : 0.0f;
    concentric_disc(u, v, lx, ly);
    *lx *= j->lens_r_m;
    *ly *= j->lens_r_m;
}

/* Pixel sample s of pixel (x, y) (pixel_aa): a point of the pixel's area, [0, 1)^2, the same
 * Hammersley set under a shift of its own. */
static inline void pixel_point(const ref_job *j, int x, int y, int s, float *px, float *py)
{
    const uint32_t h = fv_hash32((uint32_t)x * 0x2c1b3c6du ^ (uint32_t)y * 0x297a2d39u ^ j->prm->seed * 0x68e31da4u ^
                                 0x5bd1e995u);
    const float sx = (float)(h >> 8) * (1.0f / 16777216.0f);
    const float sy = (float)(fv_hash32(h ^ 0x85ebca6bu) >> 8) * (1.0f / 16777216.0f);
    float u = ((float)s + 0.5f) / (float)j->prm->spp + sx, v = radical_inverse2((uint32_t)s) + sy;
    u -= u >= 1.0f ? 1.0f : 0.0f;
    v -= v >= 1.0f ? 1.0f : 0.0f;
    *px = u;
    *py = v;
}

static void ref_tile(void *ctx, int index, int thread_id)
{
    ref_job *j = ctx;
    const fv_camera *cam = j->cam;
    const int spp = j->prm->spp;
    const float inv_focus = 1.0f / j->prm->focus_m;
    const int x0 = (index % j->tiles_x) * FV_TILE, y0 = (index / j->tiles_x) * FV_TILE;
    const int tw = cam->width - x0 < FV_TILE ? cam->width - x0 : FV_TILE;
    const int th = cam->height - y0 < FV_TILE ? cam->height - y0 : FV_TILE;
    double acc[FV_TILE * FV_TILE][3] = {{0}}; /* double: SPP may reach 65536 */

    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    ictx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    struct RTCRayHit8 rh;
    int valid[8], lane_px[8], lane_s[8];
    /* alpha BLEND as the ray stage does it (core/blend.h), from each ray's own origin */
    const int blend = fv_scene_has_blend(j->scene);
    fv_blend_packet bl;
    int k = 0;
    long rays = 0;
    /* per pixel: ray -1 is the pinhole ray (depth), 0..spp-1 the lens samples, in this order,
     * so each pixel's sum is accumulated in a fixed order */
    const long n = (long)tw * th * (spp + 1);
    for (long r = 0; r <= n; r++) {
        if (r < n) {
            const int p = (int)(r / (spp + 1)), s = (int)(r % (spp + 1)) - 1;
            const int x = x0 + p % tw, y = y0 + p / tw;
            float d[3], o[3] = {cam->eye_pos[0], cam->eye_pos[1], cam->eye_pos[2]};
            float ox = 0.5f, oy = 0.5f;
            if (s >= 0 && j->prm->pixel_aa && !(j->lens_r_m > 0.0f) && j->prm->spp > 1) /* one ray: the centre */
                pixel_point(j, x, y, s, &ox, &oy);
            fv_camera_ray(cam, (float)x + ox, (float)y + oy, d);
            if (s >= 0 && j->lens_r_m > 0.0f) {
                /* from the lens point a through the pixel's point on the focus plane, eye + d *
                 * focus; the pinhole ray (else) stays bit for bit the pipeline's */
                float lx, ly;
                lens_point(j, x, y, s, &lx, &ly);
                for (int c = 0; c < 3; c++) {
                    const float a = lx * cam->right[c] + ly * cam->up[c];
                    o[c] += a;
                    d[c] -= a * inv_focus;
                }
            }
            fv_ray8_set(&rh, k, o, d);
            valid[k] = -1;
            lane_px[k] = p;
            lane_s[k] = s;
            if (++k < 8)
                continue;
        }
        if (k == 0)
            break;
        for (int q = k; q < 8; q++)
            valid[q] = 0;
        if (blend)
            fv_blend_begin(&bl);
        fv_scene_intersect8(j->scene, valid, &ictx, &rh);
        if (blend)
            fv_blend_end();
        float rgb[3][16];
        for (int q = 0; q < k; q++) {
            const int hit = rh.hit.geomID[q] != RTC_INVALID_GEOMETRY_ID;
            const float t = rh.ray.tfar[q];
            for (int c = 0; c < 3; c++)
                rgb[c][q] = fv_background_rgb[c];
            if (lane_s[q] < 0)
                continue; /* the depth ray: below, after the blended layers */
            if (hit) {
                const float org[3] = {rh.ray.org_x[q], rh.ray.org_y[q], rh.ray.org_z[q]};
                const float dir[3] = {rh.ray.dir_x[q], rh.ray.dir_y[q], rh.ray.dir_z[q]};
                const float len = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
                float c3[3];
                fv_scene_shade(j->scene, rh.hit.geomID[q], rh.hit.primID[q], rh.hit.u[q], rh.hit.v[q], org, dir, t,
                               cam->px_tan / len, cam->eye_pos, c3);
                for (int c = 0; c < 3; c++)
                    rgb[c][q] = c3[c];
            }
        }
        /* the depth lanes' colours are composited too, and not used; a miss behind a blended
         * layer takes the layer's depth, as in the ray stage */
        if (blend) {
            const float *const orgs[3] = {rh.ray.org_x, rh.ray.org_y, rh.ray.org_z};
            const float *const dirs[3] = {rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z};
            fv_blend_composite(j->scene, &bl, rh.hit.geomID, rh.ray.tfar, orgs, dirs, k, cam->px_tan, cam->eye_pos,
                               fv_background_rgb, rgb);
        }
        for (int q = 0; q < k; q++) {
            if (lane_s[q] < 0) {
                const float t = rh.ray.tfar[q];
                j->rgbd[4 * ((size_t)(y0 + lane_px[q] / tw) * cam->width + x0 + lane_px[q] % tw) + 3] =
                    rh.hit.geomID[q] != RTC_INVALID_GEOMETRY_ID && t < FV_DEPTH_MISS_M ? t : FV_DEPTH_MISS_M;
                continue;
            }
            for (int c = 0; c < 3; c++)
                acc[lane_px[q]][c] += rgb[c][q];
        }
        rays += k;
        k = 0;
    }
    for (int p = 0; p < tw * th; p++) {
        float *dst = j->rgbd + 4 * ((size_t)(y0 + p / tw) * cam->width + x0 + p % tw);
        for (int c = 0; c < 3; c++)
            dst[c] = (float)(acc[p][c] / spp);
    }
    atomic_fetch_add_explicit(&j->rays, rays, memory_order_relaxed);
    const long done = atomic_fetch_add_explicit(&j->done, 1, memory_order_relaxed) + 1;
    if (thread_id == 0 && j->progress)
        j->progress(j->progress_ctx, done, j->tiles);
}

long fv_reference_render(const fv_scene *scene, const fv_camera *cam, const fv_reference_params *prm, fv_pool *pool,
                         float *rgbd, fv_reference_progress_fn progress, void *progress_ctx)
{
    if (prm->spp < 1 || !(prm->pupil_mm >= 0.0f && prm->pupil_mm < 1000.0f) || !(prm->focus_m > 0.0f) ||
        !isfinite(prm->focus_m))
        return -1;
    ref_job j = {.scene = scene, .cam = cam, .prm = prm, .rgbd = rgbd, .progress = progress,
                 .progress_ctx = progress_ctx};
    j.lens_r_m = 0.0005f * prm->pupil_mm;
    j.tiles_x = (cam->width + FV_TILE - 1) / FV_TILE;
    j.tiles = j.tiles_x * ((cam->height + FV_TILE - 1) / FV_TILE);
    atomic_init(&j.rays, 0);
    atomic_init(&j.done, 0);
    fv_pool_run(pool, j.tiles, ref_tile, &j);
    if (progress)
        progress(progress_ctx, j.tiles, j.tiles);
    return atomic_load(&j.rays);
}

float fv_reference_depth_at(const fv_scene *scene, const fv_camera *cam, float px, float py)
{
    float d[3];
    fv_camera_ray(cam, px, py, d);
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    struct RTCRayHit rh = {0};
    rh.ray.org_x = cam->eye_pos[0];
    rh.ray.org_y = cam->eye_pos[1];
    rh.ray.org_z = cam->eye_pos[2];
    rh.ray.dir_x = d[0];
    rh.ray.dir_y = d[1];
    rh.ray.dir_z = d[2];
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = INFINITY;
    rh.ray.mask = ~0u;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    fv_scene_intersect1(scene, &ictx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || !(rh.ray.tfar < FV_DEPTH_MISS_M))
        return FV_DEPTH_MISS_M;
    return rh.ray.tfar;
}

void fv_reference_to_rgb8(const float *rgbd, int w, int h, uint8_t *dst, ptrdiff_t dst_stride, unsigned isa_mask)
{
    fv_output_conv conv;
    fv_output_conv_init(&conv, isa_mask);
    fv_output_convert(&conv, rgbd, w, w, h, NULL, NULL, dst, dst_stride);
}
