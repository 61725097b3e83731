/* fovea-replay: renders a scene along a recorded gaze / head trace, frame by frame, into PNGs
 * and a per-frame stats CSV. The development and evaluation loop on a PC without a headset. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "output.h"
#include "pipeline.h"
#include "scene.h"
#include "trace.h"

static const char *prog = "fovea-replay";

static void usage(FILE *f)
{
    fprintf(f,
            "usage: fovea-replay --scene FILE --out DIR [--trace FILE] [--frames N] [options]\n"
            "Renders the scene along a gaze/head trace; writes DIR/frame_NNNNN.png (left eye, or\n"
            "both eyes side by side with --stereo) and DIR/stats.csv (per-stage ms and samples).\n"
            "  --scene FILE       glTF 2.0 scene (.gltf or .glb)\n"
            "  --trace FILE       CSV t_ms,gaze_x,gaze_y[,head pose]; without it the gaze rests at the\n"
            "                     image centre and the head at the scene's default viewpoint\n"
            "  --frames N         frames to render (default: the trace's length at --hz, or 1)\n"
            "  --hz HZ            display rate that maps frames to trace time (default 90)\n"
            "  --out DIR          output directory (created)\n"
            "  --full             sample every pixel (no foveation)\n"
            "  --stereo           render both eyes, side by side\n"
            "  --y4m FILE         also write the frames as a YUV4MPEG2 video\n"
            "  --reference SPP    ground-truth depth of field (not built yet)\n"
            "  --window           show frames in a window (not built yet)\n"
            "  --quiet            no progress output\n" FV_COMMON_HELP "  --help             this text\n");
}

enum { OPT_SCENE = 1, OPT_TRACE, OPT_FRAMES, OPT_OUT, OPT_FULL, OPT_STEREO, OPT_Y4M, OPT_REF, OPT_WINDOW, OPT_HZ,
       OPT_QUIET, OPT_HELP };

int main(int argc, char **argv)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    const char *scene_path = NULL, *trace_path = NULL, *out_dir = NULL, *y4m_path = NULL;
    long frames = -1;
    int stereo = 0, quiet = 0;
    float hz = 90.0f;
    static const struct option opts[] = {
        {"scene", required_argument, 0, OPT_SCENE}, {"trace", required_argument, 0, OPT_TRACE},
        {"frames", required_argument, 0, OPT_FRAMES}, {"out", required_argument, 0, OPT_OUT},
        {"full", no_argument, 0, OPT_FULL}, {"stereo", no_argument, 0, OPT_STEREO},
        {"y4m", required_argument, 0, OPT_Y4M}, {"reference", required_argument, 0, OPT_REF},
        {"window", no_argument, 0, OPT_WINDOW}, {"hz", required_argument, 0, OPT_HZ},
        {"quiet", no_argument, 0, OPT_QUIET}, {"help", no_argument, 0, OPT_HELP}, FV_COMMON_LONGOPTS, {0, 0, 0, 0}};
    opterr = 0;
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case OPT_SCENE: scene_path = optarg; break;
        case OPT_TRACE: trace_path = optarg; break;
        case OPT_FRAMES: frames = fv_arg_long(prog, "--frames", optarg, 1, 10000000); break;
        case OPT_OUT: out_dir = optarg; break;
        case OPT_FULL: cfg.samp.full = 1; break;
        case OPT_STEREO: stereo = 1; break;
        case OPT_Y4M: y4m_path = optarg; break;
        case OPT_HZ: hz = fv_arg_float(prog, "--hz", optarg, 1.0f, 1000.0f); break;
        case OPT_QUIET: quiet = 1; break;
        case OPT_REF:
            fv_arg_long(prog, "--reference", optarg, 1, 65536);
            fv_usage_error(prog, "--reference: the ground-truth depth-of-field renderer is not built yet");
        case OPT_WINDOW: fv_usage_error(prog, "--window: the window display is not built yet; use --out / --y4m");
        case OPT_HELP: usage(stdout); return FV_EXIT_OK;
        case '?': fv_bad_option(prog, argv);
        default:
            if (!fv_common_option(prog, o, optarg, &cfg))
                fv_usage_error(prog, "unhandled option (see --help)");
        }
    }
    fv_common_validate(prog, argc, argv, scene_path, &cfg);
    if (!out_dir)
        fv_usage_error(prog, "--out DIR is required (see --help)");
    if (y4m_path && ((cfg.cam.width & 1) || (cfg.cam.height & 1)))
        fv_usage_error(prog, "--y4m: 4:2:0 video needs even frame sizes, got %dx%d", cfg.cam.width, cfg.cam.height);

    char err[512];
    fv_trace tr = {0};
    if (trace_path && fv_trace_load(&tr, trace_path, err, sizeof err))
        fv_usage_error(prog, "%s", err);
    if (frames < 0)
        frames = trace_path ? 1 + (long)floor((tr.s[tr.n - 1].t_ms - tr.s[0].t_ms) * hz / 1000.0) : 1;

    fv_scene *scene = fv_scene_load(scene_path, err, sizeof err);
    if (!scene) {
        fv_trace_free(&tr);
        fv_usage_error(prog, "%s", err);
    }
    int W = cfg.cam.width, H = cfg.cam.height;
    fv_pose view;
    fv_scene_default_view(scene, cfg.cam.fov_y_deg, (float)W / (float)H, view.pos, view.quat);
    fv_pipeline *pl = fv_pipeline_create(scene, &cfg, err, sizeof err);
    if (!pl) {
        fv_scene_free(scene);
        fv_trace_free(&tr);
        fv_usage_error(prog, "%s", err);
    }

    int status = FV_EXIT_FAIL;
    int outw = stereo ? 2 * W : W;
    uint8_t *rgb = malloc((size_t)outw * H * 3);
    fv_afile csv = {0};
    fv_y4m_writer y4m = {0};
    int y4m_open = 0;
    char path[4200];
    if (!rgb) {
        fprintf(stderr, "%s: out of memory\n", prog);
        goto done;
    }
    if (fv_mkdirs(out_dir, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", prog, err);
        goto done;
    }
    snprintf(path, sizeof path, "%s/stats.csv", out_dir);
    if (fv_afile_open(&csv, path, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", prog, err);
        goto done;
    }
    if (y4m_path) {
        if (fv_y4m_open(&y4m, y4m_path, outw, H, (int)lrintf(hz), err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", prog, err);
            goto done;
        }
        y4m_open = 1;
    }
    fprintf(csv.f, "frame,t_ms,gaze_x,gaze_y,samples");
    for (int s = 0; s < FV_STAGE_COUNT; s++)
        fprintf(csv.f, ",%s_ms", fv_stage_names[s]);
    fprintf(csv.f, ",total_ms\n");

    fv_progress prog_bar;
    fv_progress_begin(&prog_bar, "rendering frame", frames);
    double t_first = trace_path ? tr.s[0].t_ms : 0.0;
    for (long f = 0; f < frames; f++) {
        fv_trace_sample smp;
        double t_ms = t_first + (double)f * 1000.0 / hz;
        fv_trace_at(&tr, t_ms, &smp);
        fv_pose head = tr.has_head ? smp.head : view;
        fv_frame_stats st[2], sum;
        memset(&sum, 0, sizeof sum);
        int neyes = stereo ? 2 : 1;
        for (int e = 0; e < neyes; e++) {
            fv_eye eye = stereo ? (e == 0 ? FV_EYE_LEFT : FV_EYE_RIGHT) : FV_EYE_CENTER;
            fv_pipeline_render(pl, eye, &head, smp.gaze_x, smp.gaze_y, &st[e]);
            fv_pipeline_to_rgb8(pl, eye, rgb + (size_t)e * W * 3, (ptrdiff_t)outw * 3);
            for (int s = 0; s < FV_STAGE_COUNT; s++)
                sum.stage_ms[s] = e ? sum.stage_ms[s] + st[e].stage_ms[s] : st[e].stage_ms[s];
            sum.total_ms += st[e].total_ms;
            sum.samples += st[e].samples;
        }
        snprintf(path, sizeof path, "%s/frame_%05ld.png", out_dir, f);
        if (fv_write_png(path, rgb, outw, H, (ptrdiff_t)outw * 3, err, sizeof err) ||
            (y4m_open && fv_y4m_write_rgb(&y4m, rgb, (ptrdiff_t)outw * 3, err, sizeof err))) {
            fprintf(stderr, "%s: %s\n", prog, err);
            goto done;
        }
        fprintf(csv.f, "%ld,%.3f,%.5f,%.5f,%ld", f, t_ms, (double)smp.gaze_x, (double)smp.gaze_y, sum.samples);
        for (int s = 0; s < FV_STAGE_COUNT; s++) {
            if (isnan(sum.stage_ms[s]))
                fputs(",", csv.f); /* stage not built: empty field */
            else
                fprintf(csv.f, ",%.3f", sum.stage_ms[s]);
        }
        fprintf(csv.f, ",%.3f\n", sum.total_ms);
        if (!quiet)
            fv_progress_update(&prog_bar, f + 1);
    }
    fv_progress_end(&prog_bar);
    if (fv_afile_commit(&csv, err, sizeof err) || (y4m_open && (y4m_open = 0, fv_y4m_close(&y4m, err, sizeof err)))) {
        fprintf(stderr, "%s: %s\n", prog, err);
        goto done;
    }
    if (!quiet)
        printf("%s: %ld frame%s of %dx%d%s in %s/ (stats.csv)\n", prog, frames, frames == 1 ? "" : "s", W, H,
               stereo ? " x 2 eyes" : "", out_dir);
    status = FV_EXIT_OK;
done:
    fv_afile_abort(&csv);
    if (y4m_open)
        fv_y4m_abort(&y4m);
    free(rgb);
    fv_pipeline_destroy(pl);
    fv_scene_free(scene);
    fv_trace_free(&tr);
    return status;
}
