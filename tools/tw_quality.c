/* tw_quality: the timewarp's image quality on a scene. Renders a frame (full sampling, no
 * reprojection, no depth of field: the only difference left is the warp's), warps it to the head
 * turned by RATE deg/s for one and two refreshes (yaw about the head's centre, so the eyes also
 * move), renders directly at that pose and prints the luma PSNR outside disocclusions, the
 * disoccluded share, and the PSNR of showing the old frame unwarped.
 *   tw_quality [--scene FILE] [--size WxH] [--rate DEG_PER_S] [--hz HZ] [--eye left|right] [--png DIR]
 * (--png: DIR/warped_K.png, DIR/direct_K.png and DIR/error_K.png, the luma error x8 around grey) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "metrics.h"
#include "output.h"
#include "pipeline.h"
#include "scene.h"
#include "timewarp.h"

static const char *prog = "tw_quality";

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
    double rate = 30.0, hz = 90.0;
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
        else if (!strcmp(argv[i], "--png") && i + 1 < argc)
            png_dir = argv[++i];
        else if (!strcmp(argv[i], "--eye") && i + 1 < argc)
            right = !strcmp(argv[++i], "right");
        else
            fv_usage_error(prog, "usage: tw_quality [--scene FILE] [--size WxH] [--rate DEG_PER_S] [--hz HZ] "
                                 "[--eye left|right]");
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
    fv_pipeline *pl = fv_pipeline_create(scene, &cfg, err, sizeof err);
    if (!pl)
        fv_usage_error(prog, "%s", err);
    fv_pose p0;
    fv_scene_default_view(scene, cfg.cam.fov_y_deg, (float)w / (float)h, p0.pos, p0.quat);
    const fv_eye eye = right ? FV_EYE_RIGHT : FV_EYE_LEFT;
    fv_tw_frame f0, f1;
    uint8_t *out = malloc((size_t)w * h * 3);
    if (!out || fv_tw_frame_alloc(&f0, w, h) || fv_tw_frame_alloc(&f1, w, h) || render(pl, eye, &p0, &f0, right))
        fv_fail(prog, FV_EXIT_FAIL, "out of memory or render failed");
    fv_timewarp_dsp d;
    fv_timewarp_dsp_init(&d, ~0u);
    printf("%s %dx%d %s eye, head turning %.1f deg/s at %.1f Hz (full sampling, no TAA, no DoF)\n", scene_path, w, h,
           right ? "right" : "left", rate, hz);
    for (int k = 1; k <= 2; k++) {
        const double a = rate * k / hz * 3.14159265358979 / 180.0; /* yaw about world +Y */
        const float q[4] = {0, (float)sin(a / 2), 0, (float)cos(a / 2)};
        fv_pose p1 = p0;
        fv_quat_mul(q, p0.quat, p1.quat);
        if (render(pl, eye, &p1, &f1, right))
            fv_fail(prog, FV_EXIT_FAIL, "render failed");
        fv_tw_map m;
        fv_tw_setup(&m, &f1.cam[right], &f0.cam[right], 0.05f);
        const fv_tw_src s = {f0.rgb[right], (ptrdiff_t)w * 3, f0.invd[right], w, w, h};
        fv_tw_warp_rows(&d, out, (ptrdiff_t)w * 3, 0, h, &m, &s);
        double holes;
        const double psnr = fv_tw_psnr_outside_holes(out, f1.rgb[right], &m, &s, &holes);
        const double stale = fv_luma_psnr(f0.rgb[right], f1.rgb[right], w, h, (ptrdiff_t)w * 3, NULL);
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
        printf("  %d refresh%s old (%.3f deg): warped %.2f dB luma PSNR outside disocclusions, disoccluded %.4f %% "
               "of pixels; unwarped %.2f dB\n",
               k, k > 1 ? "es" : "", rate * k / hz, psnr, 100.0 * holes, stale);
    }
    fv_tw_frame_free(&f0);
    fv_tw_frame_free(&f1);
    free(out);
    fv_pipeline_destroy(pl);
    fv_scene_free(scene);
    return 0;
}
