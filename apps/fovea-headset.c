/* fovea-headset: the live headset runtime. Wires a vsync source, the gaze (eye camera, trace
 * or mouse), the stereo pipeline and a display to the vsync-locked frame loop
 * (core/frameloop.h), and accounts gaze-to-photon latency. */
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "benchio.h"
#include "calibfile.h"
#include "cli.h"
#include "display.h"
#include "eyetrack/gazefilter.h"
#include "frameloop.h"
#include "gazesrc.h"
#include "calibrun.h"
#include "lensfile.h"
#include "output.h"
#include "pipeline.h"
#include "prof.h"
#include "proftrace.h"
#include "scene.h"
#include "tracefile.h"
#include "vsync.h"

static const char *prog = "fovea-headset";

static void usage(FILE *f)
{
    fprintf(f,
            "usage: fovea-headset --scene FILE [--camera /dev/videoN|replay:FILE.y4m|none]\n"
            "                     [--vsync gpio:CHIP:LINE[:rising|falling]|timer:HZ|replay:FILE]\n"
            "                     [--display kms[:CARD]|fbdev[:DEV]|window|png:DIR|y4m:FILE|none]\n"
            "                     [--calibration FILE] [--seconds S] [options]\n"
            "Renders both eyes locked to vsync with the newest gaze; prints a latency summary at exit.\n"
            "  --scene FILE        glTF 2.0 scene\n"
            FV_ASSET_ROOT_HELP
            "  --camera SRC        eye camera (V4L2 device or a Y4M replayed at --camera-fps); default\n"
            "                      none: gaze from --trace, the mouse (--display window) or the centre\n"
            "  --vsync SRC         vsync source (default timer:90)\n"
            "  --display DST       where frames go (default none)\n"
            "  --calibration FILE  gaze calibration (fovea-calibration text); without it the camera's\n"
            "                      pupil position maps linearly over the field of view (uncalibrated)\n"
            "  --calibrate FILE    run the calibration procedure instead of rendering (needs --camera;\n"
            "                      no scene): 9 grid targets and 4 validation targets on --display,\n"
            "                      then FILE is written, or the points to repeat are named\n"
            "  --calibrate-dwell-ms MS  each target's time on screen (default 1500)\n"
            "  --seconds S         run time (default: until SIGINT)\n"
            "  --trace FILE        gaze/head trace (CSV, looped); head pose from it with a camera too\n"
            "  --lens FILE         HMD lens profile: rays along the distorted directions, each eye's\n"
            "                      axis through its lens centre (turns reprojection off: it does\n"
            "                      not model the lens yet)\n"
            "  --latency-csv FILE  per-frame gaze/ray/done/photon times\n"
            "  --hz HZ             nominal refresh for gpio/replay vsync (default 90)\n"
            "  --camera-fps F      frame rate of a replayed eye video (default 120)\n"
            "  --trace-out FILE    write a Chrome trace-event JSON of the run (Perfetto): worker\n"
            "                      and stage tracks, gaze-latch / vsync / late markers\n" FV_COMMON_HELP
            "  --help              this text\n");
}

enum { OPT_SCENE = 1, OPT_CAMERA, OPT_VSYNC, OPT_DISPLAY, OPT_CALIB, OPT_SECONDS, OPT_TRACE, OPT_LENS, OPT_CSV,
       OPT_HZ, OPT_CAMFPS, OPT_TRACE_OUT, OPT_HELP, OPT_CALIBRATE, OPT_CALIB_DWELL };

static volatile sig_atomic_t stop_requested;
static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

typedef struct app {
    fv_pipeline *pl;
    fv_vsync *vsync;
    fv_display *disp;
    fv_gazesrc *cam;
    const fv_trace *trace;
    fv_pose view;
    int W, H;
    uint8_t *img[2]; /* front (on screen) and back (being rendered), side by side */
    int back;
    int64_t t_start_ns, end_ns;
    fv_gaze_ring *ring;
    int reported_vsync, reported_cam, reported_scale;
    long display_failures;
    long frame;        /* frames rendered (the frame loop's numbering) */
    int render_failed; /* a render failed: the run ends with status 1 */
} app;

static int64_t a_now(void *c)
{
    (void)c;
    return fv_time_ns();
}
static void a_sleep(void *c, int64_t t)
{
    (void)c;
    fv_clock_sleep_until_ns(t);
}
static int a_wait_edge(void *c, int64_t deadline, int64_t *t)
{
    app *a = c;
    char err[512];
    int rc = fv_vsync_wait(a->vsync, deadline - fv_time_ns(), t, err, sizeof err);
    if (rc < 0 && !a->reported_vsync) {
        fprintf(stderr, "%s: vsync %s failed (%s); running on the predictor and the timer\n", prog,
                fv_vsync_kind(a->vsync), err);
        a->reported_vsync = 1;
    }
    return rc;
}
static double trace_t_ms(const app *a, int64_t t_ns)
{
    return fv_trace_loop_ms(a->trace, (double)(t_ns - a->t_start_ns) * 1e-6);
}
static void a_sample_gaze(void *c, int64_t now)
{
    app *a = c;
    if (a->cam) {
        const char *why = fv_gazesrc_failed(a->cam);
        if (why && !a->reported_cam) {
            fprintf(stderr, "%s: camera failed (%s); keeping the last good gaze\n", prog, why);
            a->reported_cam = 1;
        }
        return; /* the camera thread pushes its own samples */
    }
    fv_gaze_sample s = {.t_ns = now, .x = 0.5f, .y = 0.5f, .confidence = 1.0f};
    if (a->disp && fv_display_mouse_gaze(a->disp, &s.x, &s.y)) {
    } else if (a->trace) {
        fv_trace_sample ts;
        fv_trace_at(a->trace, trace_t_ms(a, now), &ts);
        s.x = ts.gaze_x;
        s.y = ts.gaze_y;
    }
    fv_gaze_ring_push(a->ring, &s);
}
static int a_render(void *c, const fv_gaze_sample *g, int64_t t_ns)
{
    app *a = c;
    if (stop_requested || fv_time_ns() >= a->end_ns || (a->disp && fv_display_quit_requested(a->disp)))
        return -1;
    fv_pose head = a->view;
    if (a->trace && a->trace->has_head) {
        fv_trace_sample ts;
        fv_trace_at(a->trace, trace_t_ms(a, t_ns), &ts); /* the head where it will be at the photon time */
        head = ts.head;
    }
    const float gx = g ? g->x : 0.5f, gy = g ? g->y : 0.5f;
    /* the focus filter accommodates in photon time; a doubtful gaze widens the fovea */
    fv_pipeline_set_time_ns(a->pl, t_ns);
    if (fv_pipeline_set_fovea_scale(a->pl, fv_fovea_radius_scale(g ? g->confidence : 0.0f)) && !a->reported_scale) {
        fprintf(stderr, "%s: no memory to widen the fovea for a doubtful gaze; keeping its size\n", prog);
        a->reported_scale = 1;
    }
    uint8_t *dst = a->img[a->back];
    for (int e = 0; e < 2; e++) {
        const fv_eye eye = e ? FV_EYE_RIGHT : FV_EYE_LEFT;
        fv_frame_stats st;
        if (fv_pipeline_render(a->pl, eye, &head, gx, gy, &st)) {
            fprintf(stderr, "%s: frame %ld (%s eye): rendering failed\n", prog, a->frame, e ? "right" : "left");
            a->render_failed = 1;
            return -1;
        }
        fv_pipeline_to_rgb8(a->pl, eye, dst + (size_t)e * a->W * 3, (ptrdiff_t)a->W * 6);
    }
    a->frame++;
    return 0;
}
static int a_present(void *c, int which, int64_t vsync_ns)
{
    (void)vsync_ns;
    app *a = c;
    if (which == FV_PRESENT_PREVIOUS || !a->disp)
        return 0; /* the front image stays on screen: nothing to do, no tearing */
    char err[512];
    if (fv_display_present(a->disp, a->img[a->back], 2 * a->W, a->H, (ptrdiff_t)a->W * 6, err, sizeof err)) {
        fprintf(stderr, "%s: display %s failed (%s); continuing without a display\n", prog, fv_display_kind(a->disp),
                err);
        fv_display_close(a->disp, NULL, 0);
        char e2[64];
        if (fv_display_open(&a->disp, "none", 2 * a->W, a->H, 90, e2, sizeof e2))
            a->disp = NULL; /* out of memory: present nothing */
        a->display_failures++;
        return -1;
    }
    a->back ^= 1;
    return 0;
}

int main(int argc, char **argv)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    const char *asset_root = NULL; /* --asset-root */
    const char *scene_path = NULL, *camera = "none", *vsync_spec = "timer:90", *display_spec = "none";
    const char *calib_path = NULL, *trace_path = NULL, *lens_path = NULL, *csv_path = NULL, *prof_path = NULL;
    double seconds = 0.0;
    float hz = 90.0f, cam_fps = 120.0f;
    fv_prof *prof = NULL; /* --trace-out's recorder */
    int reproject_given = 0;
    const char *calibrate_path = NULL; /* --calibrate */
    int calib_dwell_ms = 1500;
    static const struct option opts[] = {
        {"scene", required_argument, 0, OPT_SCENE}, FV_ASSET_ROOT_LONGOPT, {"camera", required_argument, 0, OPT_CAMERA},
        {"vsync", required_argument, 0, OPT_VSYNC}, {"display", required_argument, 0, OPT_DISPLAY},
        {"calibration", required_argument, 0, OPT_CALIB}, {"seconds", required_argument, 0, OPT_SECONDS},
        {"trace", required_argument, 0, OPT_TRACE}, {"lens", required_argument, 0, OPT_LENS},
        {"latency-csv", required_argument, 0, OPT_CSV}, {"hz", required_argument, 0, OPT_HZ},
        {"camera-fps", required_argument, 0, OPT_CAMFPS}, {"trace-out", required_argument, 0, OPT_TRACE_OUT},
        {"help", no_argument, 0, OPT_HELP}, {"calibrate", required_argument, 0, OPT_CALIBRATE},
        {"calibrate-dwell-ms", required_argument, 0, OPT_CALIB_DWELL},
        FV_COMMON_LONGOPTS, {0, 0, 0, 0}};
    opterr = 0;
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case OPT_SCENE: scene_path = optarg; break;
        case FV_OPT_ASSET_ROOT: asset_root = optarg; break;
        case OPT_CAMERA: camera = optarg; break;
        case OPT_VSYNC: vsync_spec = optarg; break;
        case OPT_DISPLAY: display_spec = optarg; break;
        case OPT_CALIB: calib_path = optarg; break;
        case OPT_SECONDS: seconds = fv_arg_float(prog, "--seconds", optarg, 0.01f, 1e7f); break;
        case OPT_TRACE: trace_path = optarg; break;
        case OPT_LENS: lens_path = optarg; break;
        case OPT_CSV: csv_path = optarg; break;
        case OPT_HZ: hz = fv_arg_float(prog, "--hz", optarg, 1.0f, 1000.0f); break;
        case OPT_CAMFPS: cam_fps = fv_arg_float(prog, "--camera-fps", optarg, 1.0f, 1000.0f); break;
        case OPT_TRACE_OUT: prof_path = optarg; break;
        case OPT_CALIBRATE: calibrate_path = optarg; break;
        case OPT_CALIB_DWELL: calib_dwell_ms = (int)fv_arg_long(prog, "--calibrate-dwell-ms", optarg, 300, 10000); break;
        case OPT_HELP: usage(stdout); return FV_EXIT_OK;
        case '?': fv_bad_option(prog, argv);
        default:
            if (o == FV_OPT_REPROJECT)
                reproject_given = 1;
            if (!fv_common_option(prog, o, optarg, &cfg))
                fv_usage_error(prog, "unhandled option (see --help)");
        }
    }
    /* a calibration run renders no scene */
    fv_common_validate(prog, argc, argv, calibrate_path && !scene_path ? "(none: --calibrate)" : scene_path, &cfg);
    const int have_camera = strcmp(camera, "none") != 0;
    if (calib_path && !have_camera)
        fv_usage_error(prog, "--calibration only applies with --camera");
    if (calibrate_path && !have_camera)
        fv_usage_error(prog, "--calibrate needs --camera (/dev/videoN or replay:FILE.y4m)");
    if (calibrate_path && calib_path)
        fv_usage_error(prog, "--calibrate and --calibration exclude each other");

    /* from here on SIGINT ends the run cleanly (start-up included: the loop stops at once) */
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    char err[1024];
    /* every input is checked before anything opens hardware; outputs too (bad usage now, not after the run) */
    if ((csv_path && fv_output_probe(csv_path, err, sizeof err)) || (prof_path && fv_output_probe(prof_path, err, sizeof err)) ||
        (calibrate_path && fv_output_probe(calibrate_path, err, sizeof err)))
        fv_usage_error(prog, "%s", err);
    if (calibrate_path) { /* the calibration procedure (platform/calibrun.h) instead of rendering */
        fv_calibrate_opts co = {.out_path = calibrate_path, .camera = camera, .replay_fps = cam_fps, .cam = cfg.cam,
                                .stop = &stop_requested, .out = stdout};
        fv_calproc_default_params(&co.proc);
        co.proc.dwell_ms = calib_dwell_ms;
        co.proc.settle_ms = co.proc.settle_ms < calib_dwell_ms / 2 ? co.proc.settle_ms : calib_dwell_ms / 2;
        co.proc.fix_ms = co.proc.fix_ms < calib_dwell_ms / 4 ? co.proc.fix_ms : calib_dwell_ms / 4;
        co.realtime = !strncmp(display_spec, "window", 6) || !strncmp(display_spec, "kms", 3) ||
                      !strncmp(display_spec, "fbdev", 5);
        if (fv_display_open(&co.display, display_spec, 2 * cfg.cam.width, cfg.cam.height, (int)lrintf(hz), err,
                            sizeof err))
            fv_usage_error(prog, "%s", err);
        const int rc = fv_calibrate_run(&co, err, sizeof err);
        fv_display_close(co.display, NULL, 0);
        if (rc == 2)
            fv_usage_error(prog, "%s", err);
        if (rc)
            fv_fail(prog, FV_EXIT_FAIL, "%s", err);
        return FV_EXIT_OK;
    }
    fv_calib calib;
    if (calib_path && fv_calib_load(&calib, calib_path, err, sizeof err))
        fv_usage_error(prog, "--calibration %s", err);
    fv_trace tr = {0};
    if (trace_path && fv_trace_load(&tr, trace_path, err, sizeof err))
        fv_usage_error(prog, "%s", err);
    fv_lens lens;
    if (lens_path)
        fv_cli_lens(prog, lens_path, &lens, &cfg, reproject_given);
    app a = {0};
    a.trace = trace_path ? &tr : NULL;
    a.W = cfg.cam.width;
    a.H = cfg.cam.height;
    if (fv_vsync_open(&a.vsync, vsync_spec, err, sizeof err))
        fv_usage_error(prog, "%s", err);
    if (fv_display_open(&a.disp, display_spec, 2 * a.W, a.H, (int)lrintf(hz), err, sizeof err)) {
        fv_vsync_close(a.vsync);
        fv_usage_error(prog, "%s", err);
    }
    fv_scene *scene = fv_scene_load_in(scene_path, asset_root, err, sizeof err);
    if (!scene) {
        fv_display_close(a.disp, NULL, 0);
        fv_vsync_close(a.vsync);
        fv_usage_error(prog, "%s", err);
    }
    if (fv_scene_warning(scene)[0]) /* once, before any output */
        fprintf(stderr, "%s: %s: warning: %s\n", prog, scene_path, fv_scene_warning(scene));
    fv_scene_default_view(scene, cfg.cam.fov_y_deg, (float)a.W / (float)a.H, a.view.pos, a.view.quat);
    a.pl = fv_pipeline_create(scene, &cfg, err, sizeof err);
    fv_gaze_ring ring;
    if (fv_gaze_ring_init(&ring)) {
        fv_pipeline_destroy(a.pl);
        fv_scene_free(scene);
        fv_display_close(a.disp, NULL, 0);
        fv_vsync_close(a.vsync);
        fv_trace_free(&tr);
        fv_fail(prog, FV_EXIT_FAIL, "cannot create the gaze ring's lock");
    }
    a.ring = &ring;
    if (a.pl && have_camera) {
        /* gaze maps to the left eye's image (the one the trace format describes) */
        fv_camera_desc cd = cfg.cam;
        cd.eye = FV_EYE_LEFT;
        fv_camera lc;
        if (fv_camera_setup(&lc, &cd, &a.view)) {
            snprintf(err, sizeof err, "the left eye's camera for the gaze mapping: bad size or field of view");
            fv_pipeline_destroy(a.pl);
            a.pl = NULL;
        } else if (fv_gazesrc_start(&a.cam, camera, calib_path ? &calib : NULL, &lc, cam_fps, &ring, err, sizeof err)) {
            fv_pipeline_destroy(a.pl);
            a.pl = NULL;
        }
    }
    if (!a.pl) {
        fv_gaze_ring_destroy(&ring);
        fv_scene_free(scene);
        fv_display_close(a.disp, NULL, 0);
        fv_vsync_close(a.vsync);
        fv_trace_free(&tr);
        fv_usage_error(prog, "%s", err);
    }
    int status = FV_EXIT_FAIL;
    fv_frame_record *rec = NULL;
    long nrec = 0, caprec = 0;
    a.img[0] = calloc((size_t)a.W * 2 * a.H, 3);
    a.img[1] = calloc((size_t)a.W * 2 * a.H, 3);
    if (!a.img[0] || !a.img[1]) {
        fprintf(stderr, "%s: out of memory\n", prog);
        goto done;
    }

    int64_t period = fv_vsync_nominal_period_ns(a.vsync);
    if (period <= 0)
        period = (int64_t)(1e9 / hz + 0.5);
    fv_frameloop_params lp;
    fv_frameloop_default_params(&lp, period);
    fv_frameloop_ops ops = {&a, a_now, a_sleep, a_wait_edge, a_sample_gaze, a_render, a_present};
    a.t_start_ns = fv_time_ns();
    a.end_ns = seconds > 0 ? a.t_start_ns + (int64_t)(seconds * 1e9) : INT64_MAX;
    /* the trace recorder (--trace-out): one slot per worker of the pipeline's pool; a 2^20-event
     * ring per worker (40 MB) holds about 80 stereo frames at 1280x1440 (the newest are kept) */
    if (prof_path) {
        if (!(prof = fv_prof_create(fv_pool_threads(fv_pipeline_pool(a.pl)), (size_t)1 << 20))) {
            fprintf(stderr, "%s: out of memory for the trace recorder\n", prog);
            goto done;
        }
        fv_pipeline_set_prof(a.pl, prof);
    }
    fv_frameloop loop;
    fv_frameloop_init(&loop, &lp, &ops, &ring);
    for (;;) {
        if (nrec == caprec) {
            caprec = caprec ? 2 * caprec : 1024;
            fv_frame_record *n = realloc(rec, (size_t)caprec * sizeof *n);
            if (!n) {
                fprintf(stderr, "%s: out of memory for frame records\n", prog);
                goto done;
            }
            rec = n;
        }
        if (fv_frameloop_frame(&loop, &rec[nrec]))
            break;
        if (prof) /* gaze latch, vsync (photon) and late markers of this frame */
            fv_prof_frame_markers(prof, rec[nrec].frame, rec[nrec].ray_start_ns, rec[nrec].photon_ns, rec[nrec].late);
        nrec++;
    }
    status = a.render_failed ? FV_EXIT_FAIL : FV_EXIT_OK; /* the summary of the frames shown, either way */
    /* the summary: the first frames (acquiring the line, the first renders' cold caches still in
     * the 16-frame budget) left out */
    const long skip = nrec > 40 ? 20 : 0;
    fv_latency_summary s;
    fv_latency_summarise(rec + skip, nrec - skip, &s);
    const double run_s = (double)(fv_time_ns() - a.t_start_ns) * 1e-9;
    printf("fovea-headset: %ld frames in %.2f s, %dx%d per eye, vsync %s (%.2f Hz nominal), display %s\n", nrec,
           run_s, a.W, a.H, vsync_spec, 1e9 / (double)period, a.disp ? fv_display_kind(a.disp) : "none");
    printf("  frame rate %.2f fps; late %ld of %ld (%.1f %%)\n", s.fps, s.late, s.frames,
           s.frames ? 100.0 * (double)s.late / (double)s.frames : 0.0);
    printf("  gaze-to-photon p50 %.2f ms, p99 %.2f ms, max %.2f ms; render p50 %.2f ms, p99 %.2f ms\n", s.p50_ms,
           s.p99_ms, s.max_ms, s.render_p50_ms, s.render_p99_ms);
    printf("  vsync: %ld edges, missed %ld, spurious %ld, doubled %ld, relocks %ld, jitter %.1f us, period %.1f us, "
           "state %s%s\n",
           loop.pred.edges, loop.pred.missed, loop.pred.spurious, loop.pred.doubled, loop.pred.relocks,
           fv_vsync_pred_jitter_ns(&loop.pred) * 1e-3, fv_vsync_pred_period_ns(&loop.pred) * 1e-3,
           fv_vsync_state_name(fv_vsync_pred_state(&loop.pred, fv_time_ns())),
           loop.source_dead ? " (source failed)" : "");
    if (a.cam)
        printf("  camera: %ld frames tracked%s\n", fv_gazesrc_frames(a.cam),
               fv_gazesrc_failed(a.cam) ? " (failed mid-run)" : "");
    if (csv_path) {
        if (fv_latency_csv_write(csv_path, rec, nrec, a.t_start_ns, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", prog, err);
            status = FV_EXIT_FAIL;
        }
    }
    if (prof) {
        char label[600];
        snprintf(label, sizeof label, "fovea-headset %s", scene_path);
        fv_pipeline_set_prof(a.pl, NULL);
        if (fv_prof_write_json(prof, prof_path, label, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", prog, err);
            status = FV_EXIT_FAIL;
        }
    }
done:
    fv_pipeline_set_prof(a.pl, NULL);
    fv_prof_destroy(prof);
    fv_gazesrc_stop(a.cam);
    if (fv_display_close(a.disp, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", prog, err);
        status = FV_EXIT_FAIL;
    }
    fv_vsync_close(a.vsync);
    fv_pipeline_destroy(a.pl);
    fv_gaze_ring_destroy(&ring);
    fv_scene_free(scene);
    fv_trace_free(&tr);
    free(a.img[0]);
    free(a.img[1]);
    free(rec);
    return status;
}
