/* bench_taa: times the temporal reprojection kernels of every ISA this CPU runs on one real frame
 * (single thread, tile by tile as the pipeline runs them, each tile's data in cache first as in
 * the pipeline, where the tile was just traced and its history prefetched while tracing):
 * renders a static view of the scene until the history has converged, ray casts the next frame
 * with the head turned by --yaw degrees, then runs fv_taa_tile_run over all tiles of a copy of
 * its level 0 for each ISA, best of --reps. A developer tool for the reprojection's kernels
 * (docs/reproject.md); the pipeline's own figure is fovea-bench's reproject column.
 *
 *   build/tools/bench_taa [--scene assets/range.glb] [--yaw DEG] [--reps N]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pipeline.h"
#include "base/clock.h"
#include "raycast.h"
#include "reproject.h"
#include "scene.h"

static volatile float sink;

/* Reads the tile's current rows and the history rows around it (a few pixels of margin covers
 * the head motions this tool takes), untimed. */
static void warm(const fv_pyr_level *l0, const fv_taa_frame *f, int x0, int y0, int tw, int th)
{
    float acc = 0.0f;
    const fv_pyr_level *h = &f->hist->lv[0];
    for (int y = y0; y < y0 + th; y++)
        for (int x = x0; x < x0 + tw; x++)
            acc += l0->rgbd[4 * ((ptrdiff_t)y * l0->stride + x)] + l0->wgt[(ptrdiff_t)y * l0->stride + x];
    float u, v;
    const float cx = (float)x0 + 0.5f * (float)tw, cy = (float)y0 + 0.5f * (float)th;
    int dx = 0, dy = 0;
    if (fv_taa_project(f, cx, cy, 10.0f, &u, &v) > 0.0f) {
        dx = (int)floorf(u - cx);
        dy = (int)floorf(v - cy);
    }
    for (int y = y0 + dy - 2; y < y0 + dy + th + 2; y++)
        for (int x = x0 + dx - 2; x < x0 + dx + tw + 2; x++)
            if (y >= -1 && y <= h->h && x >= -1 && x <= h->w)
                acc += h->rgbd[4 * ((ptrdiff_t)y * h->stride + x)] + h->wgt[(ptrdiff_t)y * h->stride + x];
    sink = acc;
}

int main(int argc, char **argv)
{
    const char *scene_path = "assets/range.glb";
    float yaw_deg = 0.0f;
    int reps = 5;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--scene") && i + 1 < argc)
            scene_path = argv[++i];
        else if (!strcmp(argv[i], "--yaw") && i + 1 < argc)
            yaw_deg = strtof(argv[++i], NULL);
        else if (!strcmp(argv[i], "--reps") && i + 1 < argc)
            reps = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: bench_taa [--scene FILE] [--yaw DEG] [--reps N]\n");
            return strcmp(argv[i], "--help") ? 2 : 0;
        }
    }
    if (reps < 1 || !(fabsf(yaw_deg) <= 45.0f)) {
        fprintf(stderr, "bench_taa: --reps must be >= 1 and --yaw within 45 degrees\n");
        return 2;
    }
    char err[512];
    fv_scene *s = fv_scene_load(scene_path, err, sizeof err);
    if (!s) {
        fprintf(stderr, "bench_taa: %s\n", err);
        return 2;
    }
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    cfg.threads = 1;
    const int W = cfg.cam.width, H = cfg.cam.height;
    fv_pose view, turned;
    fv_scene_default_view(s, cfg.cam.fov_y_deg, (float)W / (float)H, view.pos, view.quat);
    turned = view;
    const float a = yaw_deg * 3.14159265f / 180.0f; /* the view turned about its own up axis */
    const float q[4] = {0.0f, sinf(0.5f * a), 0.0f, cosf(0.5f * a)};
    fv_quat_mul(view.quat, q, turned.quat);

    /* history: a converged static view (one pattern cycle and one more frame) */
    fv_pipeline *hp = fv_pipeline_create(s, &cfg, err, sizeof err);
    fv_pipeline_config nc = cfg;
    nc.taa.enabled = 0; /* the new frame's samples, before any reprojection */
    fv_pipeline *np = hp ? fv_pipeline_create(s, &nc, err, sizeof err) : NULL;
    if (!hp || !np) {
        fprintf(stderr, "bench_taa: %s\n", err);
        return 1;
    }
    fv_frame_stats st;
    for (int i = 0; i <= fv_pipeline_sampler(hp)->phases; i++)
        fv_pipeline_render(hp, FV_EYE_CENTER, &view, 0.5f, 0.5f, &st);
    fv_pipeline_render(np, FV_EYE_CENTER, &turned, 0.5f, 0.5f, &st);
    fv_taa_frame f;
    fv_taa_frame_setup(&f, fv_pipeline_camera(np, FV_EYE_CENTER), fv_pipeline_camera(hp, FV_EYE_CENTER),
                       fv_pipeline_pyramid(hp, FV_EYE_CENTER), cfg.taa.depth_tol);
    /* the new frame's level 0 as the ray caster leaves it: samples (weight 1) and holes (weight
     * 0; pull-push filled their colours, which the kernels never read) */
    fv_pyramid cur;
    if (fv_pyramid_init(&cur, W, H)) {
        fprintf(stderr, "bench_taa: out of memory\n");
        return 1;
    }
    const fv_pyr_level *src = &fv_pipeline_pyramid(np, FV_EYE_CENTER)->lv[0];
    const size_t px = (size_t)src->stride * (size_t)H;
    const fv_sampler *smp = fv_pipeline_sampler(hp);
    const int gx = W / 2, gy = H / 2;
    const unsigned isas[] = {FV_ISA_C, FV_ISA_SSE41, FV_ISA_SSE41 | FV_ISA_AVX2, FV_ISA_NEON};
    printf("bench_taa: %s, %dx%d, head turned %.2f deg, %ld samples, best of %d, one thread\n", scene_path, W, H,
           (double)yaw_deg, st.samples, reps);
    double ref_ms = 0.0;
    for (int k = 0; k < 4; k++) {
        fv_dsp d;
        fv_dsp_init(&d, isas[k]);
        if (k > 0 && d.isa == FV_ISA_C)
            continue; /* that ISA is not on this CPU */
        double best = 1e30;
        long filled = 0;
        for (int r = 0; r < reps; r++) {
            memcpy(cur.lv[0].rgbd, src->rgbd, px * 4 * sizeof(float));
            memcpy(cur.lv[0].wgt, src->wgt, px * sizeof(float));
            int64_t ns = 0;
            for (int y0 = 0; y0 < H; y0 += FV_TILE)
                for (int x0 = 0; x0 < W; x0 += FV_TILE) {
                    const int tw = W - x0 < FV_TILE ? W - x0 : FV_TILE, th = H - y0 < FV_TILE ? H - y0 : FV_TILE;
                    warm(&cur.lv[0], &f, x0, y0, tw, th);
                    const int64_t t0 = fv_time_ns();
                    fv_taa_tile_run(&f, &cfg.taa, smp, gx, gy, &cur.lv[0], &d, x0, y0, tw, th);
                    ns += fv_time_ns() - t0;
                }
            const double ms = (double)ns * 1e-6;
            best = ms < best ? ms : best;
        }
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const ptrdiff_t o = (ptrdiff_t)y * src->stride + x;
                filled += src->wgt[o] == 0.0f && cur.lv[0].wgt[o] > 0.0f;
            }
        if (d.isa == FV_ISA_C)
            ref_ms = best;
        printf("  %-7s %7.2f ms  (%.2fx the C reference)  %ld holes filled\n", fv_isa_name(d.isa), best,
               ref_ms / best, filled);
    }
    fv_pyramid_free(&cur);
    fv_pipeline_destroy(np);
    fv_pipeline_destroy(hp);
    fv_scene_free(s);
    return 0;
}
