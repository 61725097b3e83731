/* tw_quality: the timewarp's image quality and cost on a scene. Renders a frame (full sampling,
 * no reprojection, no depth of field: the only difference left is the warp's), warps it to the
 * head turned by RATE deg/s for one and two refreshes (yaw about the head's centre, so the eyes
 * also move; --step adds a sideways head step of MM per refresh), renders directly at that pose
 * and prints the luma PSNR outside disocclusions of the block warp (fv_tw_warp_rows) and of the
 * per-pixel reference, the disoccluded share, the share of translated blocks, and the PSNR of
 * showing the old frame unwarped.
 *   tw_quality [--scene FILE] [--size WxH] [--rate DEG_PER_S] [--hz HZ] [--step MM] [--eye left|right]
 *              [--png DIR] [--bench N] [--lens FILE]
 * --png: DIR/warped_K.png, DIR/direct_K.png and DIR/error_K.png (the luma error x8 around grey).
 * --bench N: times the stereo pair (both eyes of the frame, one refresh old) warped on this one
 * thread, block warp and per-pixel, against a copy of the same bytes (memcpy of both eyes), each
 * N times alternately; prints medians of thread CPU time and of wall time and the ratios.
 * --lens FILE: every camera with the HMD lens profile (the warp through it, core/timewarp.h). */
#define _DEFAULT_SOURCE /* getloadavg */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "lens.h"
#include "metrics.h"
#include "output.h"
#include "pipeline.h"
#include "scene.h"
#include "timewarp.h"

static const char *prog = "tw_quality";

static double now_ms(clockid_t c)
{
    struct timespec ts;
    clock_gettime(c, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static int cmp_d(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_d);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* the head after k refreshes: turned about world +Y by rate k / hz, stepped along its right by
 * step_mm k */
static void moved(const fv_pose *p0, double rate, double hz, double step_mm, int k, fv_pose *p1)
{
    const double a = rate * k / hz * 3.14159265358979 / 180.0;
    const float q[4] = {0, (float)sin(a / 2), 0, (float)cos(a / 2)};
    *p1 = *p0;
    fv_quat_mul(q, p0->quat, p1->quat);
    float right[3];
    const float x[3] = {1, 0, 0};
    fv_quat_rotate(p0->quat, x, right);
    for (int j = 0; j < 3; j++)
        p1->pos[j] += right[j] * (float)(step_mm * 1e-3 * k);
}

/* the share of the display's pixels in translated blocks */
static double translated_share(const fv_timewarp_dsp *d, const fv_tw_map *m, const fv_tw_src *s, const fv_tw_tiles *tiles)
{
    const int nbx = (s->w + FV_TW_BLOCK_W - 1) / FV_TW_BLOCK_W, nby = (s->h + FV_TW_BLOCK_H - 1) / FV_TW_BLOCK_H;
    fv_tw_block *b = malloc(FV_TW_BLOCK_SPLIT * (size_t)nbx * sizeof *b);
    if (!b)
        return NAN;
    double px = 0;
    for (int by = 0; by < nby; by++) {
        float g = 0.0f;
        const int n = fv_tw_plan_blocks(d, m, s, tiles, by, 0, nbx, b, &g);
        for (int i = 0; i < n; i++)
            px += b[i].fast ? (double)(b[i].x1 - b[i].x0) * (b[i].y1 - b[i].y0) : 0.0;
    }
    free(b);
    return px / ((double)s->w * s->h);
}

static int render(fv_pipeline *pl, fv_eye eye, const fv_pose *head, fv_tw_frame *f, int e)
{
    fv_frame_stats st;
    if (fv_pipeline_render(pl, eye, head, 0.5f, 0.5f, &st))
        return -1;
    fv_tw_frame_capture(f, pl, e);
    return 0;
}

int main(int argc, char **argv)
{
    const char *scene_path = "assets/range.glb";
    int w = 1280, h = 1440, right = 0;
    const char *png_dir = NULL;
    double rate = 30.0, hz = 90.0, step_mm = 0.0;
    int bench = 0, bench_pixel = 1;
    long budget = LONG_MAX; /* --budget: the bounded warp's per-pixel pixels an eye */
    const char *lens_path = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--scene") && i + 1 < argc)
            scene_path = argv[++i];
        else if (!strcmp(argv[i], "--size") && i + 1 < argc) {
            if (sscanf(argv[++i], "%dx%d", &w, &h) != 2 || w < 16 || h < 16)
                fv_usage_error(prog, "--size: want WxH, at least 16x16");
        } else if (!strcmp(argv[i], "--rate") && i + 1 < argc)
            rate = fv_arg_float(prog, "--rate", argv[++i], 0.0f, 1000.0f);
        else if (!strcmp(argv[i], "--hz") && i + 1 < argc)
            hz = fv_arg_float(prog, "--hz", argv[++i], 1.0f, 1000.0f);
        else if (!strcmp(argv[i], "--step") && i + 1 < argc)
            step_mm = fv_arg_float(prog, "--step", argv[++i], -100.0f, 100.0f);
        else if (!strcmp(argv[i], "--bench") && i + 1 < argc)
            bench = (int)fv_arg_long(prog, "--bench", argv[++i], 1, 1000);
        else if (!strcmp(argv[i], "--lens") && i + 1 < argc)
            lens_path = argv[++i];
        else if (!strcmp(argv[i], "--budget") && i + 1 < argc)
            budget = fv_arg_long(prog, "--budget", argv[++i], 0, 1L << 40);
        else if (!strcmp(argv[i], "--no-per-pixel"))
            bench_pixel = 0;
        else if (!strcmp(argv[i], "--png") && i + 1 < argc)
            png_dir = argv[++i];
        else if (!strcmp(argv[i], "--eye") && i + 1 < argc)
            right = !strcmp(argv[++i], "right");
        else if (!strcmp(argv[i], "--help")) {
            printf("usage: tw_quality [--scene FILE] [--size WxH] [--rate DEG_PER_S] [--hz HZ] [--step MM]\n"
                   "                  [--eye left|right] [--png DIR] [--bench N [--no-per-pixel]]\n"
                   "  --step MM   a sideways head step of MM a refresh besides the turn (default 0)\n"
                   "  --png DIR   DIR/warped_K.png, direct_K.png, error_K.png (the luma error x8)\n"
                   "  --bench N   time the stereo pair one refresh old on this thread, block warp,\n"
                   "              per-pixel warp and a copy of the pair's bytes, N times each\n"
                   "  --no-per-pixel  --bench leaves the per-pixel warp out (profiling the block warp)\n"
                   "  --budget PX the bounded warp (the headset's): at most PX pixels an eye per pixel,\n"
                   "              the rest of the failed parts as grid cells (default: no bound)\n"
                   "  --lens FILE HMD lens profile: rendered through it, warped through it\n");
            return 0;
        } else
            fv_usage_error(prog, "usage: tw_quality [--scene FILE] [--size WxH] [--rate DEG_PER_S] [--hz HZ] "
                                 "[--step MM] [--eye left|right] [--png DIR] [--bench N]");
    }
    char err[512];
    fv_scene *scene = fv_scene_load(scene_path, err, sizeof err);
    if (!scene)
        fv_usage_error(prog, "%s", err);
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    cfg.cam.width = w, cfg.cam.height = h;
    cfg.samp.full = 1;
    cfg.taa.enabled = 0;
    fv_lens lens;
    if (lens_path)
        fv_cli_lens(prog, lens_path, &lens, &cfg);
    fv_pipeline *pl = fv_pipeline_create(scene, &cfg, err, sizeof err);
    if (!pl)
        fv_usage_error(prog, "%s", err);
    fv_pose p0;
    fv_scene_default_view(scene, cfg.cam.fov_y_deg, (float)w / (float)h, p0.pos, p0.quat);
    const fv_eye eye = right ? FV_EYE_RIGHT : FV_EYE_LEFT;
    fv_tw_frame f0, f1;
    uint8_t *out = malloc((size_t)w * h * 3), *outp = malloc((size_t)w * h * 3);
    if (!out || !outp || fv_tw_frame_alloc(&f0, w, h) || fv_tw_frame_alloc(&f1, w, h) ||
        render(pl, eye, &p0, &f0, right))
        fv_fail(prog, FV_EXIT_FAIL, "out of memory or render failed");
    fv_timewarp_dsp d;
    fv_timewarp_dsp_init(&d, ~0u);
    printf("%s %dx%d %s eye, head turning %.1f deg/s, stepping %.2f mm a refresh, at %.1f Hz (full sampling, no TAA, "
           "no DoF)%s%s\n", scene_path, w, h, right ? "right" : "left", rate, step_mm, hz, lens_path ? ", lens " : "",
           lens_path ? lens_path : "");
    for (int k = 1; k <= 2; k++) {
        fv_pose p1;
        moved(&p0, rate, hz, step_mm, k, &p1);
        if (render(pl, eye, &p1, &f1, right))
            fv_fail(prog, FV_EXIT_FAIL, "render failed");
        fv_tw_map m;
        fv_tw_setup(&m, &f1.cam[right], &f0.cam[right], 0.05f);
        if (lens_path)
            fv_tw_map_set_lens(&m, &f0.lmap[right]);
        const fv_tw_src s = {f0.rgb[right], (ptrdiff_t)w * 3, f0.invd[right], w, w, h};
        fv_tw_warp_stats ws = {0, 0};
        fv_tw_warp_rows_bounded(&d, out, (ptrdiff_t)w * 3, 0, h, &m, &s, &f0.tiles[right], budget, &ws);
        fv_tw_warp_rows_pixel(&d, outp, (ptrdiff_t)w * 3, 0, h, &m, &s);
        double holes;
        const double psnr = fv_tw_psnr_outside_holes(out, f1.rgb[right], &m, &s, &holes);
        const double psnr_px = fv_tw_psnr_outside_holes(outp, f1.rgb[right], &m, &s, &holes);
        const double stale = fv_luma_psnr(f0.rgb[right], f1.rgb[right], w, h, (ptrdiff_t)w * 3, NULL);
        const double fast = translated_share(&d, &m, &s, &f0.tiles[right]);
        if (png_dir) {
            char path[1024];
            float *e = malloc((size_t)w * h * sizeof *e);
            uint8_t *vis = malloc((size_t)w * h * 3);
            if (e && vis) {
                fv_luma_error(f1.rgb[right], out, w, h, (ptrdiff_t)w * 3, e);
                for (size_t i = 0; i < (size_t)w * h; i++) {
                    const float v = 128.0f + 8.0f * e[i];
                    vis[3 * i] = vis[3 * i + 1] = vis[3 * i + 2] = (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : v);
                }
                snprintf(path, sizeof path, "%s/warped_%d.png", png_dir, k);
                int bad = fv_write_png(path, out, w, h, (ptrdiff_t)w * 3, err, sizeof err);
                snprintf(path, sizeof path, "%s/direct_%d.png", png_dir, k);
                bad = bad || fv_write_png(path, f1.rgb[right], w, h, (ptrdiff_t)w * 3, err, sizeof err);
                snprintf(path, sizeof path, "%s/error_%d.png", png_dir, k);
                bad = bad || fv_write_png(path, vis, w, h, (ptrdiff_t)w * 3, err, sizeof err);
                if (bad)
                    fprintf(stderr, "%s: %s\n", prog, err);
            }
            free(e);
            free(vis);
        }
        printf("  %d refresh%s old (%.3f deg): block warp %.2f dB luma PSNR outside disocclusions (%.1f %% of pixels "
               "translated, %.1f %% grid cells), per-pixel %.2f dB; disoccluded %.4f %% of pixels; unwarped %.2f dB\n",
               k, k > 1 ? "es" : "", rate * k / hz, psnr, 100.0 * fast, 100.0 * (double)ws.grid_px / ((double)w * h),
               psnr_px, 100.0 * holes, stale);
    }
    if (bench) {
        /* the pair: the other eye's frame too, both warped one refresh */
        const int other = !right;
        if (render(pl, other ? FV_EYE_RIGHT : FV_EYE_LEFT, &p0, &f0, other))
            fv_fail(prog, FV_EXIT_FAIL, "render failed");
        fv_pose p1;
        moved(&p0, rate, hz, step_mm, 1, &p1);
        fv_camera_desc cd = cfg.cam;
        fv_tw_map m[2];
        fv_tw_src s[2];
        for (int e = 0; e < 2; e++) {
            fv_camera c;
            cd.eye = e ? FV_EYE_RIGHT : FV_EYE_LEFT;
            if (fv_camera_setup(&c, &cd, &p1))
                fv_fail(prog, FV_EXIT_FAIL, "camera set-up failed");
            fv_tw_setup(&m[e], &c, &f0.cam[e], 0.05f);
            if (lens_path)
                fv_tw_map_set_lens(&m[e], &f0.lmap[e]);
            s[e] = (fv_tw_src){f0.rgb[e], (ptrdiff_t)w * 3, f0.invd[e], w, w, h};
        }
        uint8_t *pair = malloc((size_t)w * h * 6);
        double *t[7];
        for (int j = 0; j < 7; j++)
            t[j] = calloc((size_t)bench, sizeof(double));
        if (!pair || !t[0] || !t[1] || !t[2] || !t[3] || !t[4] || !t[5] || !t[6])
            fv_fail(prog, FV_EXIT_FAIL, "out of memory");
        long hb = 0, hp = 0;
        for (int r = 0; r < bench; r++)
            for (int v = 0; v < 2 + bench_pixel; v++) { /* 0 copy, 1 block warp, 2 per-pixel: alternately */
                const double c0 = now_ms(CLOCK_THREAD_CPUTIME_ID), w0 = now_ms(CLOCK_MONOTONIC);
                for (int e = 0; e < 2; e++) {
                    uint8_t *o = pair + (size_t)e * w * h * 3;
                    if (v == 0)
                        memcpy(o, f0.rgb[e], (size_t)w * h * 3);
                    else if (v == 1)
                        hb = fv_tw_warp_rows_bounded(&d, o, (ptrdiff_t)w * 3, 0, h, &m[e], &s[e], &f0.tiles[e], budget,
                                                     NULL);
                    else
                        hp = fv_tw_warp_rows_pixel(&d, o, (ptrdiff_t)w * 3, 0, h, &m[e], &s[e]);
                }
                t[v][r] = now_ms(CLOCK_THREAD_CPUTIME_ID) - c0, t[3 + v][r] = now_ms(CLOCK_MONOTONIC) - w0;
                if (v == 1) { /* the block warp's planning alone */
                    const double p0c = now_ms(CLOCK_THREAD_CPUTIME_ID);
                    translated_share(&d, &m[0], &s[0], &f0.tiles[0]), translated_share(&d, &m[1], &s[1], &f0.tiles[1]);
                    t[6][r] = now_ms(CLOCK_THREAD_CPUTIME_ID) - p0c;
                }
            }
        double med[7];
        for (int j = 0; j < 7; j++)
            med[j] = median(t[j], bench);
        const double fast = 0.5 * (translated_share(&d, &m[0], &s[0], &f0.tiles[0]) +
                                   translated_share(&d, &m[1], &s[1], &f0.tiles[1]));
        double la[3] = {0, 0, 0};
        if (getloadavg(la, 3) != 3)
            la[0] = -1;
        printf("  pair (2 x %dx%d, one refresh), one thread, %s, median of %d, load %.2f: thread CPU ms / wall ms\n",
               w, h, fv_isa_name(fv_cpu_best_isa(~0u)), bench, la[0]);
        printf("    copy of the pair's bytes (2 x %.1f MB): %.3f / %.3f ms\n", (double)w * h * 3 / 1e6, med[0], med[3]);
        if (budget != LONG_MAX)
            printf("    bounded warp, at most %ld pixels an eye per pixel (--budget)\n", budget);
        printf("    block warp: %.3f / %.3f ms (%.2fx the copy; planning %.3f ms of it; %.1f %% of pixels translated; "
               "%ld disoccluded)\n",
               med[1], med[4], med[1] / med[0], med[6], 100.0 * fast, hb);
        if (bench_pixel)
            printf("    per-pixel warp: %.3f / %.3f ms (%.1fx the copy; %ld disoccluded)\n", med[2], med[5],
                   med[2] / med[0], hp);
        for (int j = 0; j < 7; j++)
            free(t[j]);
        free(pair);
    }
    fv_tw_frame_free(&f0);
    fv_tw_frame_free(&f1);
    free(out);
    free(outp);
    fv_pipeline_destroy(pl);
    fv_scene_free(scene);
    return 0;
}
