#include "ceiling.h"

#include <math.h>
#include <stdatomic.h>
#include <stdint.h>

#include "raycast.h"
#include "tile.h"

typedef struct {
    const fv_scene *scene;
    const fv_camera *cam;
    fv_ceiling_opts o;
    int tiles_x;
    float *depth;
    atomic_long rays;
} ceil_job;

/* Packets of N lanes filled from one tile's pixel list; the lanes' layout is Embree's SoA
 * RTCRayHitN, so one routine serves both widths. */
#define DEF_TILE_N(N)                                                                                   \
    static long tile_##N(const ceil_job *j, const uint8_t *px, int n, int x0, int y0) \
    {                                                                                                   \
        const fv_camera *cam = j->cam;                                                                  \
        struct RTCIntersectContext ictx;                                                                \
        rtcInitIntersectContext(&ictx);                                                                 \
        ictx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;                                               \
        _Alignas(64) struct RTCRayHit##N rh; /* Embree wants packets aligned to their width */          \
        _Alignas(64) int valid[N];                                                                      \
        for (int i = 0; i < n; i += N) {                                                                \
            const int k = n - i < N ? n - i : N;                                                        \
            for (int q = 0; q < N; q++) {                                                               \
                const int p = q < k ? px[i + q] : px[i];                                                \
                float d[3];                                                                             \
                fv_camera_ray(cam, (float)(x0 + (p & 15)) + 0.5f, (float)(y0 + (p >> 4)) + 0.5f, d);    \
                rh.ray.org_x[q] = cam->eye_pos[0], rh.ray.org_y[q] = cam->eye_pos[1];                   \
                rh.ray.org_z[q] = cam->eye_pos[2];                                                      \
                rh.ray.dir_x[q] = d[0], rh.ray.dir_y[q] = d[1], rh.ray.dir_z[q] = d[2];                 \
                rh.ray.tnear[q] = 0.0f, rh.ray.tfar[q] = INFINITY, rh.ray.time[q] = 0.0f;               \
                rh.ray.mask[q] = ~0u, rh.ray.id[q] = (unsigned)q, rh.ray.flags[q] = 0;                  \
                rh.hit.geomID[q] = RTC_INVALID_GEOMETRY_ID;                                             \
                rh.hit.instID[0][q] = RTC_INVALID_GEOMETRY_ID;                                          \
                valid[q] = q < k ? -1 : 0;                                                              \
            }                                                                                           \
            fv_scene_intersect##N(j->scene, valid, &ictx, &rh);                                                     \
            if (j->depth)                                                                               \
                for (int q = 0; q < k; q++) {                                                           \
                    const int p = px[i + q];                                                            \
                    j->depth[(ptrdiff_t)(y0 + (p >> 4)) * cam->width + x0 + (p & 15)] =                 \
                        rh.hit.geomID[q] == RTC_INVALID_GEOMETRY_ID ? INFINITY : rh.ray.tfar[q];        \
                }                                                                                       \
        }                                                                                               \
        return n;                                                                                       \
    }
DEF_TILE_N(8)
DEF_TILE_N(16)

static void ceil_tile(void *ctx, int index, int thread_id)
{
    (void)thread_id;
    ceil_job *j = ctx;
    const fv_camera *cam = j->cam;
    const int x0 = index % j->tiles_x * FV_TILE, y0 = index / j->tiles_x * FV_TILE;
    const int tw = cam->width - x0 < FV_TILE ? cam->width - x0 : FV_TILE;
    const int th = cam->height - y0 < FV_TILE ? cam->height - y0 : FV_TILE;
    /* the tile's pixels in the real stage's order (fv_raycast_pixels): the same packets */
    uint32_t rows[FV_TILE];
    for (int y = 0; y < th; y++)
        rows[y] = j->o.rows ? j->o.rows[(size_t)index * FV_TILE + y] : j->o.smp ? (uint32_t)fv_sampler_row(j->o.smp, x0, y0 + y, tw, j->o.gx, j->o.gy, j->o.phase) : ~0u;
    uint8_t px[FV_TILE * FV_TILE + 8];
    const int n = fv_raycast_pixels(rows, tw, th, px);
    if (n == 0)
        return;
    const long r = j->o.packet == 8 ? tile_8(j, px, n, x0, y0) : tile_16(j, px, n, x0, y0);
    atomic_fetch_add_explicit(&j->rays, r, memory_order_relaxed);
}

long fv_ceiling_trace(const fv_scene *scene, const fv_camera *cam, fv_pool *pool, const fv_ceiling_opts *opt,
                      float *depth_m)
{
    ceil_job j = {.scene = scene, .cam = cam, .depth = depth_m};
    if (opt)
        j.o = *opt;
    if (j.o.packet != 8)
        j.o.packet = 16;
    j.tiles_x = (cam->width + FV_TILE - 1) / FV_TILE;
    const int tiles_y = (cam->height + FV_TILE - 1) / FV_TILE;
    atomic_init(&j.rays, 0);
    fv_pool_run(pool, j.tiles_x * tiles_y, ceil_tile, &j);
    return atomic_load(&j.rays);
}
