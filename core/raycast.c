#include "raycast.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <string.h>

#include "base/clock.h"
#include "blend.h"
#include "render_dsp.h"

const float fv_background_rgb[3] = {0.02f, 0.025f, 0.035f};

/* Whether this library traces rtcIntersect16 at all: natively (its AVX-512 path) or, built with
 * AVX-512 kernels but run on a CPU without them, through its ray-stream filter, which with the
 * coherent flag traces the 16 rays as one frustum (on an AVX2 host measured ~1.5x faster than two
 * rtcIntersect8 hybrid packets, which is Embree's packet traversal: docs/raystage.md 2026-11-28).
 * A library built without 16-wide kernels refuses the call (RTC_ERROR_INVALID_OPERATION): asked
 * once, with a packet of no valid lane on an empty scene. */
static int intersect16_works(RTCDevice d)
{
    if (rtcGetDeviceProperty(d, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED))
        return 1;
    RTCScene sc = rtcNewScene(d);
    if (!sc)
        return 0;
    rtcCommitScene(sc);
    (void)rtcGetDeviceError(d); /* clear */
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    ictx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    _Alignas(64) struct RTCRayHit16 rh;
    _Alignas(64) int valid[16];
    memset(&rh, 0, sizeof rh);
    memset(valid, 0, sizeof valid);
    rtcIntersect16(valid, sc, &ictx, &rh);
    const int ok = rtcGetDeviceError(d) == RTC_ERROR_NONE;
    rtcReleaseScene(sc);
    return ok;
}

int fv_raycast_packet_width(void)
{
    static atomic_int width; /* 0: not asked yet; every device of one library answers the same */
    int w = atomic_load_explicit(&width, memory_order_relaxed);
    if (!w) {
        RTCDevice d = rtcNewDevice(NULL);
        w = d && intersect16_works(d) ? 16 : 8;
        if (d)
            rtcReleaseDevice(d);
        atomic_store_explicit(&width, w, memory_order_relaxed);
    }
    return w;
}

/* Block mask (bit i: pixel i & 3, i >> 2 of a 4x2 block) -> its set pixels' offsets (y << 4 | x)
 * in bit order, 8 bytes (the unused ones 0), as one little-endian word. */
static uint64_t block_lut[256];
static uint8_t block_count[256]; /* popcount: a call into libgcc without -mpopcnt */
static pthread_once_t block_lut_once = PTHREAD_ONCE_INIT;
static void block_lut_init(void)
{
    for (unsigned m = 0; m < 256; m++) {
        uint64_t v = 0;
        int n = 0;
        for (unsigned b = 0; b < 8; b++)
            if (m >> b & 1u)
                v |= (uint64_t)((b >> 2) << 4 | (b & 3)) << (8 * n++);
        block_lut[m] = v;
        block_count[m] = (uint8_t)n;
    }
}

/* (raycast.h) The sampled pixels of a tile as (y << 4 | x) in 4x2-block order, so a full packet of 8 is a
 * compact 4x2 footprint (16: 8x2) and a sparse tile's packets still gather nearby pixels
 * (coherent rays). Each block's 8-bit mask looks its offsets up; the block's corner is added to
 * all 8 bytes at once (no carries: corner + offset < 256) and the word stored whole, n advancing
 * by the mask's pixel count: no branch per pixel. px needs 8 bytes of slack. */
int fv_raycast_pixels(const uint32_t rows[FV_TILE], int tw, int th, uint8_t px[FV_TILE * FV_TILE + 8])
{
    pthread_once(&block_lut_once, block_lut_init);
    const uint32_t keep = tw >= 32 ? ~0u : (1u << tw) - 1u;
    int n = 0;
    for (int by = 0; by < FV_TILE / 2; by++) {
        const uint32_t r0 = 2 * by < th ? rows[2 * by] & keep : 0, r1 = 2 * by + 1 < th ? rows[2 * by + 1] & keep : 0;
        for (int bx = 0; bx < FV_TILE / 4; bx++) {
            const unsigned m = (r0 >> (4 * bx) & 15u) | (r1 >> (4 * bx) & 15u) << 4;
            const uint64_t v = block_lut[m] + (uint64_t)(2 * by << 4 | 4 * bx) * 0x0101010101010101ull;
            memcpy(px + n, &v, 8);
            n += block_count[m];
        }
    }
    return n;
}

/* 4 weights from 4 bits */
static const float nibble_w[16][4] = {
    {0, 0, 0, 0}, {1, 0, 0, 0}, {0, 1, 0, 0}, {1, 1, 0, 0}, {0, 0, 1, 0}, {1, 0, 1, 0}, {0, 1, 1, 0}, {1, 1, 1, 0},
    {0, 0, 0, 1}, {1, 0, 0, 1}, {0, 1, 0, 1}, {1, 1, 0, 1}, {0, 0, 1, 1}, {1, 0, 1, 1}, {0, 1, 1, 1}, {1, 1, 1, 1}};

_Static_assert(RTC_INVALID_GEOMETRY_ID == 0xffffffffu, "memset to all ones");
static const float lane_inf[16] = {INFINITY, INFINITY, INFINITY, INFINITY, INFINITY, INFINITY, INFINITY, INFINITY,
                                   INFINITY, INFINITY, INFINITY, INFINITY, INFINITY, INFINITY, INFINITY, INFINITY};
/* lane_valid(16 - k): a valid mask with the first k lanes on, for packets of 8 or 16 */
static const int lane_valid_all[32] = {-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1};
#define lane_valid(j) (lane_valid_all + (j))

/* One sample: a hit's colour and view depth (t: dir.z_eye = -1), or the background at the miss
 * depth. */
static inline __attribute__((always_inline)) void write1(float *dst, unsigned geom, float t, const float rgb[3][16], int q)
{
    if (geom == RTC_INVALID_GEOMETRY_ID) {
        dst[0] = fv_background_rgb[0], dst[1] = fv_background_rgb[1], dst[2] = fv_background_rgb[2];
        dst[3] = FV_DEPTH_MISS_M;
    } else {
        dst[0] = rgb[0][q], dst[1] = rgb[1][q], dst[2] = rgb[2][q];
        dst[3] = t < FV_DEPTH_MISS_M ? t : FV_DEPTH_MISS_M;
    }
}

/* Lanes q .. q+3 as 4 pixels in a row (a 4x2 block's full row: px[q + i] = px[q] + i, px[q]
 * at x = 4j; without that, (y, 15) and (y + 1, 0) would pass as neighbours): written from one
 * address, all hits or all misses without a test per pixel (1; else 0 and nothing written). */
static inline __attribute__((always_inline)) int write4(float *dst, const uint8_t *px, const unsigned *geom, const float *t,
                         const float rgb[3][16], int q)
{
    uint32_t run;
    memcpy(&run, px, 4);
    if ((px[0] & 3) || run != (uint32_t)px[0] * 0x01010101u + 0x03020100u) /* x = 4j .. 4j+3, one row */
        return 0;
    const unsigned misses = (geom[0] == RTC_INVALID_GEOMETRY_ID) | (geom[1] == RTC_INVALID_GEOMETRY_ID) << 1 |
                            (geom[2] == RTC_INVALID_GEOMETRY_ID) << 2 | (geom[3] == RTC_INVALID_GEOMETRY_ID) << 3;
    if (!misses) { /* written out: the compiler kept the loop of 4 */
#define FV_HIT1(i)                                                                                             \
    dst[4 * (i)] = rgb[0][q + (i)], dst[4 * (i) + 1] = rgb[1][q + (i)], dst[4 * (i) + 2] = rgb[2][q + (i)],         \
    dst[4 * (i) + 3] = t[i] < FV_DEPTH_MISS_M ? t[i] : FV_DEPTH_MISS_M
        FV_HIT1(0), FV_HIT1(1), FV_HIT1(2), FV_HIT1(3);
#undef FV_HIT1
    } else if (misses == 15) {
        const float bg[4] = {fv_background_rgb[0], fv_background_rgb[1], fv_background_rgb[2], FV_DEPTH_MISS_M};
        memcpy(dst, bg, sizeof bg), memcpy(dst + 4, bg, sizeof bg);
        memcpy(dst + 8, bg, sizeof bg), memcpy(dst + 12, bg, sizeof bg);
    } else {
        for (int i = 0; i < 4; i++)
            write1(dst + 4 * i, geom[i], t[i], rgb, q + i);
    }
    return 1;
}

/* Packets of N lanes (Embree's RTCRayHitN: one routine for both widths). A tile's packets are all
 * traced first, then all shaded, then written: the triangle records and image lines of every hit,
 * prefetched right after its packet was traced, have the rest of the tile's tracing to arrive
 * (they were the shading's main cost), and shading, when asked, is timed with two clock reads per tile. */
#define FV_TILE_PACKETS(N) (FV_TILE * FV_TILE / (N))
#define DEF_PACKETS(N)                                                                                            \
    /* Camera rays through the pixels px[0 .. N) at (ox, oy) in each (the centres: as fv_camera_ray) into   \
     * the SoA packet, lanes from k on invalid; px holds N copies of its last pixel past the end. The        \
     * pinhole by the ray kernel; a lens lane by lane. */                                                    \
    static void trace_##N(const fv_scene *scene, const fv_camera *cam, const fv_render_dsp *dsp,             \
                          const fv_raygen_cam *rc, struct RTCIntersectContext *ictx, struct RTCRayHit##N *rh,  \
                          int *valid, const uint8_t *px, int k, int x0, int y0)                               \
    {                                                                                                         \
        if (!cam->lens_on) {                                                                                  \
            dsp->ray.camera_rays(rc, px, x0, y0, rh->ray.dir_x, rh->ray.dir_y, rh->ray.dir_z, N);             \
        } else {                                                                                              \
            for (int q = 0; q < N; q++) {                                                                     \
                const int p = px[q];                                                                          \
                float tx = cam->tan_left + ((float)(x0 + (p & 15)) + rc->ox) * cam->px_tan;                   \
                float ty = cam->tan_top - ((float)(y0 + (p >> 4)) + rc->oy) * cam->px_tan;                    \
                fv_lens_distort(cam->lens_k1, cam->lens_k2, cam->lens_scale, cam->lens_cx, cam->lens_cy, tx, ty, \
                                &tx, &ty);                                                                    \
                rh->ray.dir_x[q] = tx * cam->right[0] + ty * cam->up[0] - cam->back[0];                       \
                rh->ray.dir_y[q] = tx * cam->right[1] + ty * cam->up[1] - cam->back[1];                       \
                rh->ray.dir_z[q] = tx * cam->right[2] + ty * cam->up[2] - cam->back[2];                       \
            }                                                                                                 \
        }                                                                                                     \
        /* whole-vector copies: lane-by-lane stores here stalled (the lines are cold after shading) */       \
        memcpy(rh->ray.tfar, lane_inf, sizeof(float) * N);                                                    \
        memset(rh->hit.geomID, 0xff, sizeof(unsigned) * N); /* RTC_INVALID_GEOMETRY_ID */                    \
        memset(rh->hit.instID[0], 0xff, sizeof(unsigned) * N);                                                \
        memcpy(valid, lane_valid(16 - k), sizeof(int) * N);                                                      \
        fv_scene_intersect##N(scene, valid, ictx, rh);                                                     \
        fv_scene_shade_prefetch(scene, rh->hit.geomID, rh->hit.primID, k);                                    \
    }                                                                                                         \
    /* Writes lanes 0 .. k-1 (shaded into rgb) to level 0. */                                               \
    static void write_##N(const fv_pyr_level *l0, const struct RTCRayHit##N *rh, const float rgb[3][16],      \
                          const uint8_t *px, int k, int x0, int y0)                                           \
    {                                                                                                         \
        for (int q = 0; q < k;) {                                                                             \
            const int p = px[q];                                                                              \
            float *dst = l0->rgbd + 4 * ((y0 + (p >> 4)) * l0->stride + x0 + (p & 15));                       \
            if (q + 4 <= k && write4(dst, px + q, rh->hit.geomID + q, rh->ray.tfar + q, rgb, q)) {               \
                q += 4;                                                                                       \
                continue;                                                                                     \
            }                                                                                                 \
            write1(dst, rh->hit.geomID[q], rh->ray.tfar[q], rgb, q);                                          \
            q++;                                                                                              \
        }                                                                                                     \
    }                                                                                                         \
    /* Per thread: a whole tile's packets (20 KiB) and their colours. */                                     \
    static _Thread_local _Alignas(64) struct RTCRayHit##N tile_rh_##N[FV_TILE_PACKETS(N)];                   \
    static _Thread_local _Alignas(64) float tile_rgb_##N[FV_TILE_PACKETS(N)][3][16];                         \
    static _Thread_local float tile_org_##N[3] = {NAN, NAN, NAN};                                            \
    static _Thread_local fv_blend_packet tile_blend_##N[FV_TILE_PACKETS(N)]; /* alpha BLEND: blend.c */     \
    static void packets_##N(const fv_scene *scene, const fv_camera *cam, const fv_render_dsp *dsp,           \
                            const fv_pyr_level *l0, int x0, int y0, const uint8_t *px, int n, float ox, float oy,  \
                            int64_t *shade_ns, void (*before_write)(void *), void *bw_ctx)                 \
    {                                                                                                         \
        struct RTCIntersectContext ictx;                                                                      \
        rtcInitIntersectContext(&ictx);                                                                       \
        ictx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;                                                     \
        struct RTCRayHit##N *rh = tile_rh_##N;                                                                \
        _Alignas(64) int valid[N];                                                                            \
        const fv_raygen_cam rc = {cam->tan_left, cam->tan_top, cam->px_tan, {cam->right[0], cam->right[1],    \
                                  cam->right[2]}, {cam->up[0], cam->up[1], cam->up[2]},                       \
                                  {cam->back[0], cam->back[1], cam->back[2]}, ox, oy};                        \
        if (memcmp(tile_org_##N, cam->eye_pos, sizeof tile_org_##N)) { /* what no lane changes: once per eye */ \
            for (int b = 0; b < FV_TILE_PACKETS(N); b++)                                                      \
                for (int q = 0; q < N; q++) {                                                                 \
                    rh[b].ray.org_x[q] = cam->eye_pos[0], rh[b].ray.org_y[q] = cam->eye_pos[1];               \
                    rh[b].ray.org_z[q] = cam->eye_pos[2], rh[b].ray.tnear[q] = 0.0f, rh[b].ray.time[q] = 0.0f; \
                    rh[b].ray.mask[q] = ~0u, rh[b].ray.flags[q] = 0, rh[b].ray.id[q] = (unsigned)q;           \
                }                                                                                             \
            memcpy(tile_org_##N, cam->eye_pos, sizeof tile_org_##N);                                          \
        }                                                                                                     \
        const int np = (n + N - 1) / N, blend = fv_scene_has_blend(scene);                                    \
        for (int b = 0; b < np; b++) {                                                                        \
            if (blend)                                                                                        \
                fv_blend_begin(&tile_blend_##N[b]);                                                            \
            trace_##N(scene, cam, dsp, &rc, &ictx, &rh[b], valid, px + b * N, n - b * N < N ? n - b * N : N,     \
                      x0, y0);                                                                                \
        }                                                                                                     \
        if (blend)                                                                                            \
            fv_blend_end();                                                                                   \
        const int64_t t0 = shade_ns ? fv_time_ns() : 0;                                                       \
        for (int b = 0; b < np; b++) {                                                                        \
            const fv_hit_packet hp = {rh[b].hit.geomID, rh[b].hit.primID, rh[b].hit.u, rh[b].hit.v,           \
                                      rh[b].ray.tfar, {rh[b].ray.dir_x, rh[b].ray.dir_y, rh[b].ray.dir_z}};   \
            fv_scene_shade_packet(scene, &dsp->shade, &hp, n - b * N < N ? n - b * N : N, cam->px_tan,        \
                                  cam->eye_pos, tile_rgb_##N[b]);                                             \
            if (blend) { /* blended layers over the shaded hits (misses become the nearest layer's hits) */    \
                const float *const dirs[3] = {rh[b].ray.dir_x, rh[b].ray.dir_y, rh[b].ray.dir_z};             \
                fv_blend_composite(scene, &tile_blend_##N[b], rh[b].hit.geomID, rh[b].ray.tfar, NULL, dirs,     \
                                   n - b * N < N ? n - b * N : N, cam->px_tan, cam->eye_pos, fv_background_rgb, \
                                   tile_rgb_##N[b]);                                                          \
            }                                                                                                 \
        }                                                                                                     \
        if (shade_ns)                                                                                         \
            *shade_ns += fv_time_ns() - t0;                                                                   \
        if (before_write)                                                                                     \
            before_write(bw_ctx);                                                                             \
        for (int b = 0; b < np; b++)                                                                          \
            write_##N(l0, &rh[b], (const float(*)[16])tile_rgb_##N[b], px + b * N,                             \
                      n - b * N < N ? n - b * N : N, x0, y0);                                                 \
    }
DEF_PACKETS(8)
DEF_PACKETS(16)

long fv_raycast_tile(const fv_scene *scene, const fv_camera *cam, const fv_render_dsp *dsp, const fv_pyr_level *l0,
                     int x0, int y0, int tw, int th, const uint32_t rows[FV_TILE], int64_t *shade_ns)
{
    return fv_raycast_tile_at(scene, cam, dsp, l0, x0, y0, tw, th, rows, 0.5f, 0.5f, shade_ns);
}

typedef struct {
    void (*before_write)(void *);
    void *ctx;
    const fv_pyr_level *l0;
    int x0, y0, th;
    const uint32_t *rows;
} still_ctx;

static void still_weights(void *vc)
{
    const still_ctx *c = vc;
    if (c->before_write)
        c->before_write(c->ctx);
    for (int y = 0; y < c->th; y++) {
        float *w = c->l0->wgt + (ptrdiff_t)(c->y0 + y) * c->l0->stride + c->x0;
        for (uint32_t r = c->rows[y]; r; r &= r - 1)
            w[__builtin_ctz(r)] = 1.0f;
    }
}

static long tile_cast(const fv_scene *scene, const fv_camera *cam, const fv_render_dsp *dsp, const fv_pyr_level *l0,
                      int x0, int y0, int tw, int th, const uint32_t rows[FV_TILE], float ox, float oy,
                      int64_t *shade_ns, int keep_holes, void (*before_write)(void *), void *bw_ctx)
{
    /* every pixel's weight, from the rows' bits (pull-push never reads the colour of a zero-weight
     * pixel, so the others' colours are left alone); keep_holes: the samples' only, written with
     * their colours (below) */
    for (int y = 0; y < th && !keep_holes; y++) {
        float *w = l0->wgt + (ptrdiff_t)(y0 + y) * l0->stride + x0;
        if (tw == FV_TILE)
            for (int x = 0; x < FV_TILE; x += 4)
                memcpy(w + x, nibble_w[rows[y] >> x & 15u], sizeof nibble_w[0]);
        else
            for (int x = 0; x < tw; x++)
                w[x] = (float)(rows[y] >> x & 1u);
    }
    uint8_t px[FV_TILE * FV_TILE + 16];
    const int n = fv_raycast_pixels(rows, tw, th, px);
    if (n == 0)
        return 0;
    /* the image lines the samples will be written to (cold: each store would wait for its line),
     * asked for before the rays are traced: every line (4 pixels) of a row with a sample; a test
     * per line mispredicted in the sparse periphery */
    for (int y = 0; y < th; y++)
        if (rows[y]) {
            for (int x = 0; x < tw; x += 4)
                __builtin_prefetch(l0->rgbd + 4 * ((ptrdiff_t)(y0 + y) * l0->stride + x0 + x), 1);
            if (keep_holes) { /* the weights too: before_write reads them (a row spans <= 2 lines) */
                const float *w = l0->wgt + (ptrdiff_t)(y0 + y) * l0->stride + x0;
                __builtin_prefetch(w, 1);
                __builtin_prefetch(w + tw - 1, 1);
            }
        }
    for (int q = n; q < n + 16; q++) /* the padding lanes trace the last pixel again, invalid */
        px[q] = px[n - 1];
    still_ctx sc = {before_write, bw_ctx, l0, x0, y0, th, rows};
    if (keep_holes) /* before_write first sees the pixels as they were, then the samples' weights */
        bw_ctx = &sc, before_write = still_weights;
    if (fv_raycast_packet_width() == 16)
        packets_16(scene, cam, dsp, l0, x0, y0, px, n, ox, oy, shade_ns, before_write, bw_ctx);
    else
        packets_8(scene, cam, dsp, l0, x0, y0, px, n, ox, oy, shade_ns, before_write, bw_ctx);
    return n;
}

long fv_raycast_tile_at(const fv_scene *scene, const fv_camera *cam, const fv_render_dsp *dsp, const fv_pyr_level *l0,
                        int x0, int y0, int tw, int th, const uint32_t rows[FV_TILE], float ox, float oy,
                        int64_t *shade_ns)
{
    return tile_cast(scene, cam, dsp, l0, x0, y0, tw, th, rows, ox, oy, shade_ns, 0, NULL, NULL);
}

long fv_raycast_tile_keep_holes(const fv_scene *scene, const fv_camera *cam, const fv_render_dsp *dsp,
                                const fv_pyr_level *l0, int x0, int y0, int tw, int th, const uint32_t rows[FV_TILE],
                                float ox, float oy, int64_t *shade_ns, void (*before_write)(void *ctx), void *ctx)
{
    return tile_cast(scene, cam, dsp, l0, x0, y0, tw, th, rows, ox, oy, shade_ns, 1, before_write, ctx);
}
