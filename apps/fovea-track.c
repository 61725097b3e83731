/* fovea-track: runs the eye tracker over an image list or a Y4M eye video; writes one CSV line
 * per image / frame (PATH_OR_FRAME,X,Y,CONF; X,Y empty when no pupil) and prints a summary,
 * with detection rates when the list carries pupil labels. */
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "base/clock.h"
#include "cli.h"
#include "cpu.h"
#include "eyesrc.h"
#include "eyetrack/eyetrack.h"
#include "eyetrack/labelstats.h"
#include "output.h"

static const char *prog = "fovea-track";

static void usage(FILE *f)
{
    fprintf(f,
            "usage: fovea-track (--images LIST | --video FILE.y4m | --device /dev/videoN) [--out FILE.csv]\n"
            "Tracks the pupil (and glints) in every image or frame; writes PATH_OR_FRAME,X,Y,CONF lines\n"
            "(X,Y in pixels of that image, origin at the image's top-left corner, so pixel (i,j) has its\n"
            "centre at (i+0.5, j+0.5); empty when no pupil) and prints a summary. With labels in LIST\n"
            "(lines PATH X Y) it prints detection rates within 1, 2, 3 and 5 px and the median error.\n"
            "  --images LIST      image list: lines PATH [X Y], PATH relative to the list's folder\n"
            "  --video FILE       YUV4MPEG2 video (C420*, C422, C444, Cmono; luma is used)\n"
            "  --device DEV       V4L2 camera (GREY, Y10/Y12/Y16, YUYV/UYVY or MJPEG; runs until --frames\n"
            "                     or Ctrl-C, then writes the CSV and the summary)\n"
            "  --ctrl NAME=VALUE  camera control, e.g. exposure_time_absolute=100 (repeatable)\n"
            "  --camera-size WxH  camera frame size to ask for (default 640x480)\n"
            "  --out FILE         CSV output (written atomically)\n"
            "  --frames N         stop after N images / frames\n"
            "  --bench N          track each frame N times and report the median time per frame\n"
            "  --mode auto|headset|crop  what the frames are: a headset eye camera's, or tight crops\n"
            "                     around one eye (like the MRL set); auto (default) decides per frame:\n"
            "                     crop when its short side is at most 160 px\n"
            "  --isa c|sse41|avx2|neon  cap the SIMD kernels (default: best available)\n"
            "  --quiet            no progress output\n"
            "  --help             this text\n");
}

enum { OPT_IMAGES = 1, OPT_VIDEO, OPT_DEVICE, OPT_OUT, OPT_FRAMES, OPT_BENCH, OPT_ISA, OPT_QUIET, OPT_CTRL, OPT_CSIZE,
       OPT_MODE, OPT_HELP };

/* Ctrl-C ends a live capture cleanly (CSV committed, summary printed). */
static volatile sig_atomic_t stop_requested;
static void on_sigint(int sig)
{
    (void)sig;
    stop_requested = 1;
}


static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static void print_group(fv_eye_label_group *g)
{
    if (!g->n)
        return;
    const double med = fv_eye_label_median(g);
    printf("  %-10s %6ld labelled:", g->name, g->n);
    for (int k = 0; k < FV_EYE_LABEL_RADII; k++)
        printf("  <=%gpx %5.1f%%", fv_eye_label_radii_px[k], 100.0 * g->within[k] / g->n);
    if (isfinite(med))
        printf("  median error %.2f px\n", med);
    else
        printf("  median error n/a (most not found)\n");
}

int main(int argc, char **argv)
{
    const char *images = NULL, *video = NULL, *device = NULL, *out_path = NULL;
    long max_frames = -1, bench = 1;
    fv_v4l2_config cam_cfg;
    fv_v4l2_config_default(&cam_cfg, NULL);
    unsigned isa_mask = ~0u;
    fv_eye_mode mode = FV_EYE_MODE_AUTO;
    int quiet = 0;
    static const struct option opts[] = {
        {"images", required_argument, 0, OPT_IMAGES}, {"video", required_argument, 0, OPT_VIDEO},
        {"device", required_argument, 0, OPT_DEVICE}, {"out", required_argument, 0, OPT_OUT},
        {"frames", required_argument, 0, OPT_FRAMES}, {"bench", required_argument, 0, OPT_BENCH},
        {"isa", required_argument, 0, OPT_ISA}, {"quiet", no_argument, 0, OPT_QUIET},
        {"ctrl", required_argument, 0, OPT_CTRL}, {"camera-size", required_argument, 0, OPT_CSIZE},
        {"mode", required_argument, 0, OPT_MODE}, {"help", no_argument, 0, OPT_HELP}, {0, 0, 0, 0}};
    opterr = 0;
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case OPT_IMAGES: images = optarg; break;
        case OPT_VIDEO: video = optarg; break;
        case OPT_DEVICE: device = optarg; break;
        case OPT_OUT: out_path = optarg; break;
        case OPT_FRAMES: max_frames = fv_arg_long(prog, "--frames", optarg, 1, 100000000); break;
        case OPT_BENCH: bench = fv_arg_long(prog, "--bench", optarg, 1, 1000); break;
        case OPT_ISA:
            if (fv_isa_mask_parse(optarg, &isa_mask))
                fv_usage_error(prog, "--isa: '%s' is not one of c, sse41, avx2, neon", optarg);
            break;
        case OPT_MODE:
            if (fv_eye_mode_parse(optarg, &mode))
                fv_usage_error(prog, "--mode: '%s' is not one of auto, headset, crop", optarg);
            break;
        case OPT_QUIET: quiet = 1; break;
        case OPT_CTRL: {
            char e[256];
            if (fv_v4l2_config_ctrl(&cam_cfg, optarg, e, sizeof e))
                fv_usage_error(prog, "--ctrl: %s", e);
            break;
        }
        case OPT_CSIZE: fv_arg_size(prog, "--camera-size", optarg, &cam_cfg.width, &cam_cfg.height); break;
        case OPT_HELP: usage(stdout); return FV_EXIT_OK;
        default: fv_bad_option(prog, argv);
        }
    }
    if (optind < argc)
        fv_usage_error(prog, "unexpected argument '%s' (see --help)", argv[optind]);
    const int nsrc = !!images + !!video + !!device;
    if (nsrc == 0)
        fv_usage_error(prog, "one of --images LIST, --video FILE or --device DEV is required");
    if (nsrc > 1)
        fv_usage_error(prog, "give only one of --images, --video and --device");
    if (!device && (cam_cfg.n_ctrls || cam_cfg.width != 640 || cam_cfg.height != 480))
        fv_usage_error(prog, "--ctrl and --camera-size only apply to --device");

    char err[512];
    if (out_path && fv_output_probe(out_path, err, sizeof err)) /* bad usage now, not after the run */
        fv_usage_error(prog, "%s", err);
    fv_eyesrc *src = NULL;
    if (device) {
        cam_cfg.path = device;
        /* a live camera: a few seconds without a frame (also while it is being reopened) end the run */
        if (fv_eyesrc_open_v4l2(&src, &cam_cfg, 5000, &stop_requested, err, sizeof err)) {
            char list[512];
            if (fv_v4l2_list(NULL, NULL, list, sizeof list) > 0)
                fv_usage_error(prog, "%s (capture devices here: %s)", err, list);
            fv_usage_error(prog, "%s (no V4L2 capture device found here)", err);
        }
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_sigint;
        sigemptyset(&sa.sa_mask);
        sigaction(SIGINT, &sa, NULL);
        sigaction(SIGTERM, &sa, NULL);
    } else if ((images ? fv_eyesrc_open_list(&src, images, err, sizeof err)
                       : fv_eyesrc_open_y4m(&src, video, err, sizeof err))) {
        fv_usage_error(prog, "%s", err);
    }
    fv_eye_params par;
    fv_eye_default_params(&par);
    par.isa_mask = isa_mask;
    fv_eye_tracker *trk = fv_eye_create(&par, mode);
    if (!trk)
        fv_fail(prog, FV_EXIT_FAIL, "out of memory");
    fv_afile out;
    if (out_path && fv_afile_open(&out, out_path, err, sizeof err))
        fv_fail(prog, FV_EXIT_FAIL, "%s", err);

    const long count = fv_eyesrc_count(src);
    const long cap = count > 0 ? count : 1;
    fv_eye_label_stats labels;
    const int labelled = fv_eyesrc_has_labels(src);
    if (labelled && fv_eye_label_stats_init(&labels, cap))
        fv_fail(prog, FV_EXIT_FAIL, "out of memory");
    double *run_ns = calloc((size_t)bench, sizeof(double));
    if (!run_ns)
        fv_fail(prog, FV_EXIT_FAIL, "out of memory");
    fv_progress prog_bar;
    if (!quiet)
        fv_progress_begin(&prog_bar, "tracking", count > 0 ? count : 0);
    long frames = 0, found = 0, with_glints = 0, blinks = 0;
    double conf_sum = 0;
    fv_eye_frame fr;
    int rc = 0;
    while ((max_frames < 0 || frames < max_frames) && (rc = fv_eyesrc_next(src, &fr, err, sizeof err)) == 1) {
        /* run 0 gives the result (with blink history for videos); extra --bench runs only time */
        fv_eye_result r, scratch_r;
        for (long k = 0; k < bench; k++) {
            fv_eye_result *rr = k ? &scratch_r : &r;
            const int64_t t0 = fv_time_ns();
            const int st = (images || k) ? fv_track_image(trk, fr.luma, fr.w, fr.h, fr.stride, rr)
                                         : fv_track_frame(trk, fr.luma, fr.w, fr.h, fr.stride, rr);
            run_ns[k] += (double)(fv_time_ns() - t0);
            if (st)
                fv_fail(prog, FV_EXIT_FAIL, "frame %ld (%dx%d): the tracker failed", fr.index, fr.w, fr.h);
        }
        frames++;
        found += r.found;
        with_glints += r.n_glints > 0;
        blinks += r.status == FV_EYE_BLINK;
        conf_sum += r.confidence;
        if (out_path) {
            if (fr.name)
                fprintf(out.f, "%s,", fr.name);
            else
                fprintf(out.f, "%ld,", fr.index);
            if (r.found)
                fprintf(out.f, "%.3f,%.3f,%.3f\n", (double)r.pupil_x, (double)r.pupil_y, (double)r.confidence);
            else
                fprintf(out.f, ",,%.3f\n", (double)r.confidence);
        }
        if (labelled && fr.has_label &&
            fv_eye_label_stats_add(&labels, fr.name,
                                   r.found ? hypot(r.pupil_x - fr.label_x, r.pupil_y - fr.label_y) : INFINITY))
            fv_fail(prog, FV_EXIT_FAIL, "out of memory");
        if (!quiet)
            fv_progress_update(&prog_bar, frames);
    }
    if (!quiet)
        fv_progress_end(&prog_bar);
    if (!(max_frames >= 0 && frames >= max_frames) && rc < 0) {
        if (out_path)
            fv_afile_abort(&out);
        fv_usage_error(prog, "%s", err);
    }
    if (frames == 0) {
        if (out_path)
            fv_afile_abort(&out);
        fv_usage_error(prog, "%s: no frames", images ? images : video ? video : device);
    }
    if (out_path && fv_afile_commit(&out, err, sizeof err))
        fv_fail(prog, FV_EXIT_FAIL, "%s", err);

    printf("%s: %ld %s, pupil found in %ld (%.1f%%), glints in %ld (%.1f%%), blinks %ld, mean confidence %.3f\n",
           prog, frames, images ? "images" : "frames", found, 100.0 * found / frames, with_glints,
           100.0 * with_glints / frames, blinks, conf_sum / frames);
    if (labelled) {
        printf("detection rate (error = distance to the label, not found = miss):\n");
        for (int i = 0; i < labels.n; i++)
            print_group(&labels.g[i]);
    }
    for (long k = 0; k < bench; k++)
        run_ns[k] /= (double)frames;
    qsort(run_ns, (size_t)bench, sizeof(double), cmp_double);
    printf("time per frame: %.4f ms (median of %ld run%s, one thread, kernels %s)\n", run_ns[bench / 2] * 1e-6, bench,
           bench > 1 ? "s" : "", fv_isa_name(fv_cpu_best_isa(isa_mask)));
    if (labelled)
        fv_eye_label_stats_free(&labels);
    free(run_ns);
    fv_eye_destroy(trk);
    fv_eyesrc_close(src);
    return FV_EXIT_OK;
}
