#include "raycast.h"
#include "base/clock.h"
#include "prof.h"

#include <math.h>
#include <stdatomic.h>
#include <string.h>


const float fv_background_rgb[3] = {0.02f, 0.025f, 0.035f};

typedef struct {
    const fv_scene *scene;
    const fv_camera *cam;
    const fv_sampler *smp;
    int gx, gy, tiles_x, tiles_y;
    fv_pyramid *pyr;
    const fv_render_dsp *dsp;
    int phase;
    const fv_taa_frame *taa;
    const fv_taa_params *taa_prm;
    atomic_long rays;
    atomic_llong taa_ns;
    struct fv_prof *prof; /* NULL: no trace recording */
} rc_job;

/* The history a tile will read lies around the tile moved by the head motion: guess the move
 * from the previous frame's depth at the tile (one level-4 texel) and prefetch those level-0
 * rows, so they arrive while the tile's rays are traced (the reads are otherwise latency-bound
 * misses: each history row is a separate 4-line stretch of a ~37 MB image). */
static void prefetch_history(const rc_job *j, int x0, int y0, int tw, int th)
{
    const fv_taa_frame *f = j->taa;
    const fv_pyr_level *h0 = &f->hist->lv[0];
    int dx = 0, dy = 0;
    if (!f->identity) {
        const int l = f->hist->levels - 1 < FV_TILE_PULL_LEVELS ? f->hist->levels - 1 : FV_TILE_PULL_LEVELS;
        const fv_pyr_level *hl = &f->hist->lv[l];
        const float cx = (float)x0 + 0.5f * (float)tw, cy = (float)y0 + 0.5f * (float)th;
        int hx = (int)cx >> l, hy = (int)cy >> l;
        hx = hx < hl->w ? hx : hl->w - 1;
        hy = hy < hl->h ? hy : hl->h - 1;
        float u, v;
        if (fv_taa_project(f, cx, cy, hl->rgbd[4 * ((ptrdiff_t)hy * hl->stride + hx) + 3], &u, &v) <= 0.0f ||
            !(fabsf(u - cx) < 4096.0f && fabsf(v - cy) < 4096.0f))
            return;
        dx = (int)floorf(u - cx);
        dy = (int)floorf(v - cy);
    }
    int xa = x0 + dx - 1, xb = x0 + dx + tw + 1, ya = y0 + dy - 1, yb = y0 + dy + th + 1;
    xa = xa < -1 ? -1 : xa;
    xb = xb > h0->w ? h0->w : xb;
    ya = ya < -1 ? -1 : ya;
    yb = yb > h0->h ? h0->h : yb;
    if (xa > xb)
        return;
    for (int y = ya; y <= yb; y++) {
        const float *r = h0->rgbd + 4 * ((ptrdiff_t)y * h0->stride + xa);
        for (int x = 0; x <= 4 * (xb - xa); x += 16) /* one 64-byte line = 4 pixels */
            __builtin_prefetch(r + x);
        __builtin_prefetch(r + 4 * (xb - xa));
        __builtin_prefetch(h0->wgt + (ptrdiff_t)y * h0->stride + xa);
        __builtin_prefetch(h0->wgt + (ptrdiff_t)y * h0->stride + xb);
    }
}

/* Pixels of a tile in 4x2 blocks, so a full packet of 8 is a compact 4x2 footprint and a
 * sparse tile's packets still gather nearby pixels (coherent rays). */
static const unsigned char *tile_order(void)
{
    static const unsigned char order[FV_TILE * FV_TILE][2] = {
#define B(bx, by) {bx*4+0,by*2+0},{bx*4+1,by*2+0},{bx*4+2,by*2+0},{bx*4+3,by*2+0}, \
                  {bx*4+0,by*2+1},{bx*4+1,by*2+1},{bx*4+2,by*2+1},{bx*4+3,by*2+1}
#define R(by) B(0,by),B(1,by),B(2,by),B(3,by)
        R(0), R(1), R(2), R(3), R(4), R(5), R(6), R(7)
#undef R
#undef B
    };
    return &order[0][0];
}

static void trace_tile(void *ctx, int index, int thread_id)
{
    rc_job *j = ctx;
    const int64_t tile_t0 = j->prof ? fv_time_ns() : 0;
    const fv_camera *cam = j->cam;
    const fv_pyr_level *l0 = &j->pyr->lv[0];
    int tx = index % j->tiles_x, ty = index / j->tiles_x;
    int x0 = tx * FV_TILE, y0 = ty * FV_TILE;
    int tw = cam->width - x0 < FV_TILE ? cam->width - x0 : FV_TILE;
    int th = cam->height - y0 < FV_TILE ? cam->height - y0 : FV_TILE;

    if (j->taa) /* early: the lines arrive while the rays are traced */
        prefetch_history(j, x0, y0, tw, th);
    uint32_t rows[FV_TILE];
    for (int y = 0; y < th; y++) {
        rows[y] = (uint32_t)fv_sampler_row(j->smp, x0, y0 + y, tw, j->gx, j->gy, j->phase);
        /* Pixels without a sample carry weight 0 into pull-push, which never reads the colour of
         * a zero-weight pixel: clearing the weights is enough (a quarter of the bytes). */
        memset(l0->wgt + (y0 + y) * l0->stride + x0, 0, sizeof(float) * (size_t)tw);
    }

    const unsigned char *order = tile_order();
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    ictx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    struct RTCRayHit8 rh;
    int valid[8];
    int px[8], py[8];
    long rays = 0;
    int k = 0;
    for (int i = 0; i <= FV_TILE * FV_TILE; i++) {
        if (i < FV_TILE * FV_TILE) {
            int lx = order[2 * i], ly = order[2 * i + 1];
            if (lx >= tw || ly >= th || !((rows[ly] >> lx) & 1u))
                continue;
            px[k] = x0 + lx;
            py[k] = y0 + ly;
            float d[3];
            fv_camera_ray(cam, (float)px[k] + 0.5f, (float)py[k] + 0.5f, d);
            fv_ray8_set(&rh, k, cam->eye_pos, d);
            valid[k] = -1;
            if (++k < 8)
                continue;
        }
        if (k == 0)
            break;
        for (int q = k; q < 8; q++)
            valid[q] = 0;
        rtcIntersect8(valid, fv_scene_rtc(j->scene), &ictx, &rh);
        for (int q = 0; q < k; q++) {
            float *dst = l0->rgbd + 4 * (py[q] * l0->stride + px[q]);
            if (rh.hit.geomID[q] == RTC_INVALID_GEOMETRY_ID) {
                dst[0] = fv_background_rgb[0];
                dst[1] = fv_background_rgb[1];
                dst[2] = fv_background_rgb[2];
                dst[3] = FV_DEPTH_MISS_M;
            } else {
                float org[3] = {rh.ray.org_x[q], rh.ray.org_y[q], rh.ray.org_z[q]};
                float dir[3] = {rh.ray.dir_x[q], rh.ray.dir_y[q], rh.ray.dir_z[q]};
                float len = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
                float t = rh.ray.tfar[q];
                fv_scene_shade(j->scene, rh.hit.geomID[q], rh.hit.primID[q], rh.hit.u[q], rh.hit.v[q], org, dir, t,
                               cam->px_tan / len, cam->eye_pos, dst);
                dst[3] = t < FV_DEPTH_MISS_M ? t : FV_DEPTH_MISS_M; /* t is the view depth: dir.z_eye = -1 */
            }
            l0->wgt[py[q] * l0->stride + px[q]] = 1.0f;
        }
        rays += k;
        k = 0;
    }
    if (j->taa) {
        const int64_t t0 = fv_time_ns();
        fv_taa_tile_run(j->taa, j->taa_prm, j->smp, j->gx, j->gy, &j->pyr->lv[0], &j->dsp->taa, x0, y0, tw, th);
        const int64_t t1 = fv_time_ns();
        atomic_fetch_add_explicit(&j->taa_ns, t1 - t0, memory_order_relaxed);
        if (j->prof)
            fv_prof_span(j->prof, thread_id, thread_id, "reproject", t0, t1, index);
    }
    /* Pull the tile up the pyramid while it is in cache: a 16x16 tile is a 1x1 block of level
     * 4. Tiles start on multiples of 16, so every block starts on even coordinates. */
    int xl = x0, yl = y0, wl = tw, hl = th;
    for (int l = 0; l < FV_TILE_PULL_LEVELS && l + 1 < j->pyr->levels; l++) {
        fv_pull_block(j->pyr, &j->dsp->pp, l, xl, yl, wl, hl);
        xl >>= 1, yl >>= 1, wl = (wl + 1) >> 1, hl = (hl + 1) >> 1;
    }
    atomic_fetch_add_explicit(&j->rays, rays, memory_order_relaxed);
    if (j->prof)
        fv_prof_span(j->prof, thread_id, thread_id, "tile", tile_t0, fv_time_ns(), index);
}

long fv_raycast(const fv_scene *scene, const fv_camera *cam, const fv_sampler *smp, int gx, int gy,
                fv_pyramid *pyr, const fv_render_dsp *dsp, fv_pool *pool, const fv_raycast_opts *opt, double *taa_ms)
{
    rc_job j = {.scene = scene, .cam = cam, .smp = smp, .gx = gx, .gy = gy, .pyr = pyr, .dsp = dsp};
    if (opt) {
        j.phase = opt->phase;
        j.taa = opt->taa;
        j.taa_prm = opt->taa_prm;
        j.prof = opt->prof;
    }
    j.tiles_x = (cam->width + FV_TILE - 1) / FV_TILE;
    j.tiles_y = (cam->height + FV_TILE - 1) / FV_TILE;
    atomic_init(&j.rays, 0);
    atomic_init(&j.taa_ns, 0);
    fv_pool_run(pool, j.tiles_x * j.tiles_y, trace_tile, &j);
    if (taa_ms)
        *taa_ms = j.taa ? (double)atomic_load(&j.taa_ns) * 1e-6 / fv_pool_threads(pool) : NAN;
    return atomic_load(&j.rays);
}
