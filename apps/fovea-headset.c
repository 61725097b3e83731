/* fovea-headset: the live headset runtime. Wires a vsync source, the gaze (eye camera, trace
 * or mouse), the stereo pipeline and a display to the vsync-locked frame loop
 * (core/frameloop.h), and accounts gaze-to-photon latency. */
#include <dirent.h>
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "base/clock.h"
#include "base/parse.h"
#include "displayloop.h"
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
#include "posepred.h"
#include "prof.h"
#include "proftrace.h"
#include "scene.h"
#include "timewarp.h"
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
            FV_ASSET_ROOT_HELP FV_SHADOWS_HELP
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
            "                      axis through its lens centre; reprojection and the timewarp\n"
            "                      model the lens (docs/headset.md)\n"
            "  --latency-csv FILE  per-frame gaze/ray/done/photon times\n"
            "  --hz HZ             nominal refresh for gpio/replay vsync (default 90)\n"
            "  --camera-fps F      frame rate of a replayed eye video (default 120)\n"
            "  --trace-out FILE    write a Chrome trace-event JSON of the run (Perfetto): worker\n"
            "                      and stage tracks, gaze-latch / vsync / late markers\n"
            "  --timewarp on|off   on (default): rendering runs on its own thread at its own rate;\n"
            "                      at every vsync the newest complete frame is warped to the head\n"
            "                      pose predicted for that refresh (per-pixel depth) and shown.\n"
            "                      off: one frame rendered per shown frame, aimed at a vsync.\n"
            "  --warp-threads N    1 or 2 (default: 2 with two or more CPUs online): with 2 the right\n"
            "                      eye is warped on a second display-priority thread while the\n"
            "                      display thread warps the left (a refresh's composition in half the time)\n" FV_COMMON_HELP
            "  --help              this text\n");
}

enum { OPT_SCENE = 1, OPT_CAMERA, OPT_VSYNC, OPT_DISPLAY, OPT_CALIB, OPT_SECONDS, OPT_TRACE, OPT_LENS, OPT_CSV,
       OPT_HZ, OPT_CAMFPS, OPT_TRACE_OUT, OPT_TIMEWARP, OPT_WARP_THREADS, OPT_HELP, OPT_CALIBRATE, OPT_CALIB_DWELL };

/* The display path's warp is bounded (fv_tw_warp_rows_bounded): at most 1 / HS_PIXEL_SHARE of an
 * eye's pixels run the per-pixel kernel (7200 at 1280x1440: 0.04-0.1 ms an eye with AVX2, cache hot
 * or cold); the rest of what fails the block proof (a frame far from the display's pose) is warped
 * as grid cells, so a refresh costs about the same whatever the frame's age. */
#define HS_PIXEL_SHARE 256

/* Records kept for the summary: the newest HS_KEEP (1.5 to 3 minutes at 90 Hz); older ones are
 * folded into running totals. Their CSV rows are written as they complete, so memory stays flat for a
 * run of any length (a 10-minute soak grew 9.5 MiB/h when every record was kept). */
#ifndef HS_KEEP /* (a build can lower it to exercise the folding) */
#define HS_KEEP (1L << 14)
#endif

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
    /* head pose: the trace read as a 1 kHz pose source, predicted to the photon time; one
     * predictor per thread (0: the display's or the serial loop's, 1: the renderer's), so the
     * display never waits on a lock the renderer holds (it runs above it) */
    fv_posepred pp[2];
    int64_t pp_fed_ns[2];
    int64_t head_t_ns;  /* the pose sample of the frame being rendered (timewarp off) */
    fv_pose head_pred;  /* its prediction */
    /* --timewarp on */
    fv_camera_desc cd;
    fv_frame_mailbox mb;
    fv_tw_frame slot[FV_MAILBOX_SLOTS];
    struct {
        int has_gaze;
        fv_gaze_sample g;
        int64_t start_ns, done_ns;
    } meta[FV_MAILBOX_SLOTS];
    fv_timewarp_dsp twd;
    int mouse;          /* the gaze is the mouse over a window (read on the display's thread only) */
    int64_t period_ns;  /* the nominal refresh period */
    /* the right eye's warp on a second display-priority thread (--warp-threads 2) */
    int helper_on, helper_job, helper_quit;
    pthread_mutex_t helper_mu;
    pthread_cond_t helper_cv;
    const fv_tw_frame *helper_f;
    fv_camera helper_cam;
    uint8_t *helper_dst;
    long helper_holes, helper_grid;
    int stop;           /* the render thread ends (atomic) */
    int64_t *done_ns;   /* completion times of the newest rendered frames (render thread; read after join) */
    double *render_ms;
    long ndone, capdone, done_base; /* frames rendered; entries held; frame of done_ns[0] */
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
static int has_head(const app *a) { return a->trace && a->trace->has_head; }
/* the true head pose at t_ns (the trace; without one the default view) */
static void head_true(const app *a, int64_t t_ns, fv_pose *out)
{
    if (!has_head(a)) {
        *out = a->view;
        return;
    }
    fv_trace_sample ts;
    fv_trace_at(a->trace, trace_t_ms(a, t_ns), &ts);
    *out = ts.head;
}
/* Feeds thread `th`'s predictor the pose source's 1 kHz samples up to now and predicts the pose
 * at photon_ns; returns the newest sample's time (the start of motion-to-photon). */
static int64_t head_latch(app *a, int th, int64_t now, int64_t photon_ns, fv_pose *out)
{
    if (!has_head(a)) {
        *out = a->view;
        return now; /* a fixed head, sampled now */
    }
    const int64_t fed = a->pp_fed_ns[th];
    int64_t t = fed && fed > now - 20000000 ? fed + 1000000 : now - 20000000;
    for (; t <= now; t += 1000000) {
        fv_pose p;
        head_true(a, t, &p);
        fv_posepred_push(&a->pp[th], t, &p);
        a->pp_fed_ns[th] = t;
    }
    int64_t ts = now;
    if (!fv_posepred_predict(&a->pp[th], photon_ns, out, &ts))
        *out = a->view;
    return ts;
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
    fv_pose head; /* sampled now, predicted to the photon time */
    a->head_t_ns = head_latch(a, 0, fv_time_ns(), t_ns, &head);
    a->head_pred = head;
    const float gx = g ? g->x : 0.5f, gy = g ? g->y : 0.5f;
    /* the focus filter accommodates in photon time; a doubtful gaze widens the fovea */
    fv_pipeline_set_time_ns(a->pl, t_ns);
    if (fv_pipeline_set_fovea_scale(a->pl, fv_fovea_radius_scale(g ? g->confidence : 0.0f)) && !a->reported_scale) {
        fprintf(stderr, "%s: no memory to widen the fovea for a doubtful gaze; keeping its size\n", prog);
        a->reported_scale = 1;
    }
    uint8_t *dst = a->img[a->back];
    fv_frame_stats st[2];
    if (fv_pipeline_render_stereo(a->pl, &head, gx, gy, st)) { /* both eyes' tiles in one pool job */
        fprintf(stderr, "%s: frame %ld: rendering the stereo pair failed\n", prog, a->frame);
        a->render_failed = 1;
        return -1;
    }
    for (int e = 0; e < 2; e++)
        fv_pipeline_to_rgb8(a->pl, e ? FV_EYE_RIGHT : FV_EYE_LEFT, dst + (size_t)e * a->W * 3, (ptrdiff_t)a->W * 6);
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

/* ---- --timewarp on: the render thread and the display's composition ---- */
static int stopping(app *a) { return __atomic_load_n(&a->stop, __ATOMIC_ACQUIRE); }

static void *render_main(void *arg)
{
    app *a = arg;
    const int64_t period = a->period_ns;
    int64_t last_ns = 3 * period;
    while (!stopping(a)) {
        const int64_t start = fv_time_ns();
        if (!a->cam && !a->mouse) { /* trace (or centre) gaze, sampled just before the rays */
            fv_gaze_sample ts = {.t_ns = start, .x = 0.5f, .y = 0.5f, .confidence = 1.0f};
            if (a->trace) {
                fv_trace_sample t;
                fv_trace_at(a->trace, trace_t_ms(a, start), &t);
                ts.x = t.gaze_x;
                ts.y = t.gaze_y;
            }
            fv_gaze_ring_push(a->ring, &ts);
        }
        fv_gaze_sample g;
        const int hg = fv_gaze_ring_latest(a->ring, start, &g);
        /* aimed at about when it will be shown: a render time and a refresh ahead (the warp
         * corrects the rest) */
        const int64_t aim = start + last_ns + period;
        fv_pose head;
        head_latch(a, 1, start, aim, &head);
        fv_pipeline_set_time_ns(a->pl, aim);
        if (fv_pipeline_set_fovea_scale(a->pl, fv_fovea_radius_scale(hg ? g.confidence : 0.0f)) && !a->reported_scale) {
            fprintf(stderr, "%s: no memory to widen the fovea for a doubtful gaze; keeping its size\n", prog);
            a->reported_scale = 1;
        }
        const int s = fv_mailbox_begin_write(&a->mb);
        fv_frame_stats st[2];
        if (fv_pipeline_render_stereo(a->pl, &head, hg ? g.x : 0.5f, hg ? g.y : 0.5f, st)) {
            fprintf(stderr, "%s: frame %ld: rendering the stereo pair failed\n", prog, a->ndone);
            __atomic_store_n(&a->render_failed, 1, __ATOMIC_RELEASE);
            __atomic_store_n(&a->stop, 1, __ATOMIC_RELEASE);
            return NULL;
        }
        for (int e = 0; e < 2; e++)
            fv_tw_frame_capture(&a->slot[s], a->pl, e);
        const int64_t done = fv_time_ns();
        a->meta[s].has_gaze = hg;
        if (hg)
            a->meta[s].g = g;
        a->meta[s].start_ns = start;
        a->meta[s].done_ns = done;
        if (a->ndone - a->done_base == HS_KEEP) { /* keep the newest half: memory stays flat */
            memmove(a->done_ns, a->done_ns + HS_KEEP / 2, sizeof *a->done_ns * (size_t)(HS_KEEP / 2));
            memmove(a->render_ms, a->render_ms + HS_KEEP / 2, sizeof *a->render_ms * (size_t)(HS_KEEP / 2));
            a->done_base += HS_KEEP / 2;
        }
        if (a->ndone - a->done_base == a->capdone) { /* the summary's record (only this thread touches it until the join) */
            const long cap = a->capdone ? 2 * a->capdone : 1024;
            int64_t *d = realloc(a->done_ns, (size_t)cap * sizeof *d);
            if (d)
                a->done_ns = d;
            double *r = d ? realloc(a->render_ms, (size_t)cap * sizeof *r) : NULL;
            if (r)
                a->render_ms = r, a->capdone = cap;
        }
        if (a->ndone - a->done_base < a->capdone) {
            a->done_ns[a->ndone - a->done_base] = done;
            a->render_ms[a->ndone - a->done_base] = (double)(done - start) * 1e-6;
        }
        fv_mailbox_publish(&a->mb, s, a->ndone);
        a->ndone++;
        last_ns = done - start;
    }
    return NULL;
}

static long warp_budget(const app *a) { return (long)a->W * a->H / HS_PIXEL_SHARE; }

static int a_compose(void *c, int64_t vsync_ns, fv_refresh_record *rec)
{
    app *a = c;
    const int64_t now = fv_time_ns();
    if (stop_requested || now >= a->end_ns || stopping(a) || (a->disp && fv_display_quit_requested(a->disp)))
        return -1;
    if (a->cam || a->mouse)
        a_sample_gaze(a, now); /* the camera's health, or the mouse (SDL wants its own thread) */
    long seq;
    const int s = fv_mailbox_acquire(&a->mb, &seq);
    if (s < 0)
        return 0; /* nothing rendered yet: the panel keeps what it shows */
    rec->frame = seq;
    rec->head_t_ns = head_latch(a, 0, now, vsync_ns, &a->head_pred);
    rec->has_gaze = a->meta[s].has_gaze;
    rec->gaze_t_ns = a->meta[s].g.t_ns;
    rec->gaze_x = a->meta[s].g.x;
    rec->gaze_y = a->meta[s].g.y;
    rec->frame_start_ns = a->meta[s].start_ns;
    rec->frame_done_ns = a->meta[s].done_ns;
    uint8_t *dst = a->img[a->back];
    fv_camera cam[2];
    for (int e = 0; e < 2; e++) {
        fv_camera_desc cd = a->cd;
        cd.eye = e ? FV_EYE_RIGHT : FV_EYE_LEFT;
        fv_camera_setup(&cam[e], &cd, &a->head_pred);
    }
    if (a->helper_on) { /* the right eye on the helper meanwhile */
        pthread_mutex_lock(&a->helper_mu);
        a->helper_f = &a->slot[s], a->helper_cam = cam[1], a->helper_dst = dst + (size_t)a->W * 3;
        a->helper_job = 1;
        pthread_cond_broadcast(&a->helper_cv);
        pthread_mutex_unlock(&a->helper_mu);
    }
    for (int e = 0; e < (a->helper_on ? 1 : 2); e++) {
        fv_tw_warp_stats ws = {0, 0};
        rec->disoccluded += fv_tw_frame_warp_bounded(&a->twd, &a->slot[s], e, &cam[e], dst + (size_t)e * a->W * 3,
                                                     (ptrdiff_t)a->W * 6, 0.05f, warp_budget(a), &ws);
        rec->grid_px += ws.grid_px;
    }
    if (a->helper_on) {
        pthread_mutex_lock(&a->helper_mu);
        while (a->helper_job)
            pthread_cond_wait(&a->helper_cv, &a->helper_mu);
        rec->disoccluded += a->helper_holes;
        rec->grid_px += a->helper_grid;
        pthread_mutex_unlock(&a->helper_mu);
    }
    a_present(a, FV_PRESENT_NEW, vsync_ns);
    return 0;
}

/* --warp-threads 2: warps the right eye while the display thread warps the left */
static void *warp_helper_main(void *arg)
{
    app *a = arg;
    pthread_mutex_lock(&a->helper_mu);
    for (;;) {
        while (!a->helper_job && !a->helper_quit)
            pthread_cond_wait(&a->helper_cv, &a->helper_mu);
        if (a->helper_quit)
            break;
        const fv_tw_frame *f = a->helper_f;
        const fv_camera cam = a->helper_cam;
        uint8_t *dst = a->helper_dst;
        pthread_mutex_unlock(&a->helper_mu);
        fv_tw_warp_stats ws = {0, 0};
        const long h = fv_tw_frame_warp_bounded(&a->twd, f, 1, &cam, dst, (ptrdiff_t)a->W * 6, 0.05f, warp_budget(a), &ws);
        pthread_mutex_lock(&a->helper_mu);
        a->helper_holes = h, a->helper_grid = ws.grid_px;
        a->helper_job = 0;
        pthread_cond_broadcast(&a->helper_cv);
    }
    pthread_mutex_unlock(&a->helper_mu);
    return NULL;
}

/* The threads of this process (Linux: /proc/self/task), at most n, into tid; their count. */
static int task_ids(int *tid, int n)
{
    DIR *d = opendir("/proc/self/task");
    int k = 0;
    if (!d)
        return 0;
    for (struct dirent *e; (e = readdir(d)) && k < n;)
        if (e->d_name[0] >= '0' && e->d_name[0] <= '9')
            tid[k++] = atoi(e->d_name);
    closedir(d);
    return k;
}

/* The display thread above the renderer's: SCHED_FIFO where allowed (root, CAP_SYS_NICE). Where
 * it is refused, the renderer's threads go below instead (nice 10: an unprivileged process may
 * lower its own threads), so on a 2-core board the display thread still gets a core when it wakes
 * (the summary says which). Set after the render thread and the pool exist, so they do not inherit
 * the display's priority; render_tids: the renderer's threads (the pool's workers and the render
 * thread), n of them. */
#define HS_RENDER_NICE 10
static const char *display_priority(const int *render_tids, int n)
{
    struct sched_param sp = {.sched_priority = 10};
    if (!pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp))
        return "SCHED_FIFO 10";
    int ok = n > 0;
    for (int i = 0; i < n; i++)
        ok = ok && !setpriority(PRIO_PROCESS, (id_t)render_tids[i], HS_RENDER_NICE);
    fprintf(stderr, "%s: SCHED_FIFO refused for the display thread (needs CAP_SYS_NICE); %s\n", prog,
            ok ? "the render threads run at nice 10 instead" : "the render threads could not be lowered either");
    return ok ? "normal, render threads nice 10 (SCHED_FIFO refused)" : "normal (SCHED_FIFO refused)";
}

static void summary_line(const char *what, double p50, double p99)
{
    printf("%s p50 %.2f ms p99 %.2f ms", what, p50, p99);
}

int main(int argc, char **argv)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    const char *asset_root = NULL; /* --asset-root */
    int shadows = 0;               /* --shadows */
    const char *scene_path = NULL, *camera = "none", *vsync_spec = "timer:90", *display_spec = "none";
    const char *calib_path = NULL, *trace_path = NULL, *lens_path = NULL, *csv_path = NULL, *prof_path = NULL;
    double seconds = 0.0;
    float hz = 90.0f, cam_fps = 120.0f;
    fv_prof *prof = NULL; /* --trace-out's recorder */
    int nwarp = 1; /* warp threads running */
    int timewarp = 1, warp_threads = 0; /* 0: 2 where 2 or more CPUs are online, else 1 */
    const char *calibrate_path = NULL; /* --calibrate */
    int calib_dwell_ms = 1500;
    static const struct option opts[] = {
        {"scene", required_argument, 0, OPT_SCENE}, FV_ASSET_ROOT_LONGOPT, FV_SHADOWS_LONGOPT, {"camera", required_argument, 0, OPT_CAMERA},
        {"vsync", required_argument, 0, OPT_VSYNC}, {"display", required_argument, 0, OPT_DISPLAY},
        {"calibration", required_argument, 0, OPT_CALIB}, {"seconds", required_argument, 0, OPT_SECONDS},
        {"trace", required_argument, 0, OPT_TRACE}, {"lens", required_argument, 0, OPT_LENS},
        {"latency-csv", required_argument, 0, OPT_CSV}, {"hz", required_argument, 0, OPT_HZ},
        {"camera-fps", required_argument, 0, OPT_CAMFPS}, {"trace-out", required_argument, 0, OPT_TRACE_OUT},
        {"timewarp", required_argument, 0, OPT_TIMEWARP}, {"warp-threads", required_argument, 0, OPT_WARP_THREADS},
        {"help", no_argument, 0, OPT_HELP}, {"calibrate", required_argument, 0, OPT_CALIBRATE},
        {"calibrate-dwell-ms", required_argument, 0, OPT_CALIB_DWELL},
        FV_COMMON_LONGOPTS, {0, 0, 0, 0}};
    opterr = 0;
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case OPT_SCENE: scene_path = optarg; break;
        case FV_OPT_ASSET_ROOT: asset_root = optarg; break;
        case FV_OPT_SHADOWS: shadows = fv_arg_onoff(prog, "--shadows", optarg); break;
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
        case OPT_WARP_THREADS: {
            long v;
            char e[256];
            if (fv_parse_long("--warp-threads", optarg, 1, 2, &v, e, sizeof e))
                fv_usage_error(prog, "%s", e);
            warp_threads = (int)v;
            break;
        }
        case OPT_TIMEWARP:
            timewarp = fv_arg_onoff(prog, "--timewarp", optarg);
            break;
        case OPT_HELP: usage(stdout); return FV_EXIT_OK;
        case '?': fv_bad_option(prog, argv);
        default:
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
        fv_cli_lens(prog, lens_path, &lens, &cfg);
    app a = {0};
    a.trace = trace_path ? &tr : NULL;
    for (int k = 0; k < 2; k++)
        fv_posepred_init(&a.pp[k], 8000000, 50000000);
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
    if (shadows && fv_scene_set_shadows(scene, 1))
        fprintf(stderr, "%s: %s: warning: more than 16 KHR lights, shadows off\n", prog, scene_path);
    fv_scene_default_view(scene, cfg.cam.fov_y_deg, (float)a.W / (float)a.H, a.view.pos, a.view.quat);
    enum { HS_MAX_TASKS = 256 };
    int tids0[HS_MAX_TASKS], tids1[HS_MAX_TASKS], render_tids[HS_MAX_TASKS], nrender = 0;
    const int ntid0 = task_ids(tids0, HS_MAX_TASKS);
    a.pl = fv_pipeline_create(scene, &cfg, err, sizeof err);
    { /* the pool's workers: the threads the pipeline started */
        const int ntid1 = task_ids(tids1, HS_MAX_TASKS);
        for (int i = 0; i < ntid1; i++) {
            int old_task = 0;
            for (int j = 0; j < ntid0; j++)
                old_task = old_task || tids1[i] == tids0[j];
            if (!old_task)
                render_tids[nrender++] = tids1[i];
        }
    }
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
    fv_refresh_record *rr = NULL; /* --timewarp on: one per refresh */
    long nrr = 0, caprr = 0;
    long folded_frames = 0, folded_late = 0, folded_refreshes = 0; /* records dropped from memory (HS_KEEP) */
    int pending_markers = 0;
    fv_afile csv = {0}; /* --latency-csv: rows written as each record completes */
    if (csv_path) {
        if (fv_afile_open(&csv, csv_path, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", prog, err);
            goto done;
        }
        if (timewarp)
            fv_refresh_csv_header(csv.f);
        else
            fv_latency_csv_header(csv.f);
    }
    a.img[0] = calloc((size_t)a.W * 2 * a.H, 3);
    a.img[1] = calloc((size_t)a.W * 2 * a.H, 3);
    if (!a.img[0] || !a.img[1]) {
        fprintf(stderr, "%s: out of memory\n", prog);
        goto done;
    }
    for (int k = 0; k < 2; k++) /* their pages now, not in the first refreshes (~2700 faults an image) */
        for (size_t i = 0; i < (size_t)a.W * 2 * a.H * 3; i += 4096)
            ((volatile uint8_t *)a.img[k])[i] = 0;

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
    const double run_hz = 1e9 / (double)period;
    fv_vsync_pred *pred = NULL;
    int source_dead = 0;
    fv_frameloop loop;
    fv_displayloop dl;
    pthread_t render_thread;
    const char *prio = "-";
    if (!timewarp) {
        fv_frameloop_init(&loop, &lp, &ops, &ring);
        for (;;) {
            if (nrec == HS_KEEP) { /* fold the oldest half into the totals */
                fv_latency_summary h;
                fv_latency_summarise(rec, HS_KEEP / 2, &h);
                folded_frames += h.frames, folded_late += h.late;
                memmove(rec, rec + HS_KEEP / 2, sizeof *rec * (size_t)(HS_KEEP / 2));
                nrec -= HS_KEEP / 2;
            }
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
            fv_frame_record *q = &rec[nrec];
            q->head_t_ns = a.head_t_ns;
            q->pose_err_deg = NAN;
            if (has_head(&a)) {
                fv_pose truth;
                head_true(&a, q->photon_ns, &truth);
                q->pose_err_deg = fv_pose_angle_deg(&a.head_pred, &truth);
            }
            if (prof) /* gaze latch, vsync (photon) and late markers of this frame */
                fv_prof_frame_markers(prof, q->frame, q->ray_start_ns, q->photon_ns, q->late);
            if (csv.f)
                fv_latency_csv_row(csv.f, q, a.t_start_ns);
            nrec++;
        }
        pred = &loop.pred;
        source_dead = loop.source_dead;
    } else {
        /* the renderer on its own thread, the display loop on this one, above it */
        a.cd = cfg.cam;
        a.period_ns = period;
        a.mouse = a.disp && !strcmp(fv_display_kind(a.disp), "window");
        fv_timewarp_dsp_init(&a.twd, cfg.isa_mask);
        int slots_ok = 1;
        for (int k = 0; k < FV_MAILBOX_SLOTS; k++)
            slots_ok = slots_ok && !fv_tw_frame_alloc(&a.slot[k], a.W, a.H);
        if (!slots_ok || fv_mailbox_init(&a.mb)) {
            fprintf(stderr, "%s: out of memory for the timewarp's frames\n", prog);
            goto done;
        }
        const int ntid2 = task_ids(tids1, HS_MAX_TASKS); /* the tasks before the render thread */
        if (pthread_create(&render_thread, NULL, render_main, &a)) {
            fprintf(stderr, "%s: cannot start the render thread\n", prog);
            fv_mailbox_destroy(&a.mb);
            goto done;
        }
        { /* the render thread: the task that was not there before it */
            int tids3[HS_MAX_TASKS];
            const int n3 = task_ids(tids3, HS_MAX_TASKS);
            for (int i = 0; i < n3 && nrender < HS_MAX_TASKS; i++) {
                int known = 0;
                for (int j = 0; j < ntid2; j++)
                    known = known || tids3[i] == tids1[j];
                if (!known)
                    render_tids[nrender++] = tids3[i];
            }
        }
        prio = display_priority(render_tids, nrender);
        pthread_t helper;
        if (!warp_threads) /* a composition's wall time halved: a slow spell of memory fits the margin */
            warp_threads = sysconf(_SC_NPROCESSORS_ONLN) >= 2 ? 2 : 1;
        if (warp_threads > 1) { /* created by the display thread: inherits its priority */
            pthread_mutexattr_t at;
            pthread_mutexattr_init(&at);
            pthread_mutexattr_setprotocol(&at, PTHREAD_PRIO_INHERIT);
            a.helper_on = !pthread_mutex_init(&a.helper_mu, &at) && !pthread_cond_init(&a.helper_cv, NULL) &&
                          !pthread_create(&helper, NULL, warp_helper_main, &a);
            pthread_mutexattr_destroy(&at);
            if (!a.helper_on)
                fprintf(stderr, "%s: cannot start the second warp thread; warping both eyes on one\n", prog);
        }
        nwarp = a.helper_on ? 2 : 1;
        fv_displayloop_params dp;
        fv_displayloop_default_params(&dp, period);
        fv_displayloop_ops dops = {&a, a_now, a_sleep, a_wait_edge, a_compose};
        fv_displayloop_init(&dl, &dp, &dops);
        for (;;) {
            if (nrr == HS_KEEP) { /* fold the oldest half into the totals */
                fv_display_summary h;
                fv_display_summarise(rr, HS_KEEP / 2, 2.0 * a.W * a.H, period, &h);
                folded_frames += h.displayed, folded_late += h.missed, folded_refreshes += HS_KEEP / 2;
                memmove(rr, rr + HS_KEEP / 2, sizeof *rr * (size_t)(HS_KEEP / 2));
                nrr -= HS_KEEP / 2;
            }
            if (nrr == caprr) {
                caprr = caprr ? 2 * caprr : 4096;
                fv_refresh_record *n = realloc(rr, (size_t)caprr * sizeof *n);
                if (!n) {
                    fprintf(stderr, "%s: out of memory for refresh records\n", prog);
                    break;
                }
                rr = n;
            }
            if (fv_displayloop_refresh(&dl, &rr[nrr]))
                break;
            fv_refresh_record *q = &rr[nrr];
            if (q->frame >= 0 && has_head(&a)) { /* the prediction against the trace's true pose */
                fv_pose truth;
                head_true(&a, q->photon_ns, &truth);
                q->pose_err_deg = fv_pose_angle_deg(&a.head_pred, &truth);
                q->pose_err_mm = fv_pose_dist_m(&a.head_pred, &truth) * 1e3;
            }
            if (csv.f)
                fv_refresh_csv_row(csv.f, q, a.t_start_ns);
            if (prof && q->frame >= 0) /* (written after the run: the recorder's slot 0 is a worker's while rendering) */
                pending_markers = 1;
            nrr++;
        }
        if (a.helper_on) {
            pthread_mutex_lock(&a.helper_mu);
            a.helper_quit = 1;
            pthread_cond_broadcast(&a.helper_cv);
            pthread_mutex_unlock(&a.helper_mu);
            pthread_join(helper, NULL);
            a.helper_on = 0;
        }
        __atomic_store_n(&a.stop, 1, __ATOMIC_RELEASE);
        pthread_join(render_thread, NULL);
        fv_mailbox_destroy(&a.mb);
        a.render_failed = __atomic_load_n(&a.render_failed, __ATOMIC_ACQUIRE);
        pred = &dl.pred;
        source_dead = dl.source_dead;
        if (prof && pending_markers) /* markers after the run: the recorder's slot 0 is a worker's while rendering */
            for (long k = 0; k < nrr; k++)
                if (rr[k].frame >= 0)
                    fv_prof_frame_markers(prof, rr[k].refresh, rr[k].frame_start_ns, rr[k].photon_ns, rr[k].late);
    }
    status = a.render_failed ? FV_EXIT_FAIL : FV_EXIT_OK; /* the summary of the frames shown, either way */
    /* the summary leaves out the first frames (acquiring the line, the first renders' cold caches
     * still in the budget / margin) */
    const double run_s = (double)(fv_time_ns() - a.t_start_ns) * 1e-9;
    const char *disp_kind = a.disp ? fv_display_kind(a.disp) : "none";
    if (!timewarp) {
        const long skip = nrec > 40 && !folded_frames ? 20 : 0; /* (folded: the first frames are long gone) */
        fv_latency_summary s;
        fv_latency_summarise(rec + skip, nrec - skip, &s);
        double *v = malloc((size_t)(nrec + 1) * sizeof *v);
        double mtp50 = NAN, mtp99 = NAN, pe50 = NAN, pe99 = NAN;
        if (v) {
            long m = 0;
            for (long k = skip; k < nrec; k++)
                v[m++] = (double)(rec[k].photon_ns - rec[k].head_t_ns) * 1e-6;
            mtp50 = fv_percentile(v, m, 0.5), mtp99 = fv_percentile(v, m, 0.99);
            m = 0;
            for (long k = skip; k < nrec; k++)
                if (!isnan(rec[k].pose_err_deg))
                    v[m++] = rec[k].pose_err_deg;
            pe50 = fv_percentile(v, m, 0.5), pe99 = fv_percentile(v, m, 0.99);
            free(v);
        }
        /* every frame rendered is shown: displayed = rendered */
        printf("fovea-headset: displayed %ld frames (%.2f Hz), rendered %ld frames (%.2f Hz), late %ld\n",
               s.frames + folded_frames, s.fps, s.frames + folded_frames, s.fps, s.late + folded_late);
        printf("  %ld frames in %.2f s, %dx%d per eye, vsync %s (%.2f Hz nominal), display %s, timewarp off\n",
               nrec + folded_frames, run_s, a.W, a.H, vsync_spec, run_hz, disp_kind);
        if (folded_frames)
            printf("  rates and percentiles over the newest %ld frames (older ones are counted, not kept)\n", nrec);
        printf("  ");
        summary_line("motion-to-photon", mtp50, mtp99);
        printf("; ");
        summary_line("gaze-to-photon", s.p50_ms, s.p99_ms);
        printf("\n");
        printf("  late %ld of %ld (%.1f %%); gaze-to-photon max %.2f ms; render p50 %.2f ms, p99 %.2f ms\n", s.late,
               s.frames, s.frames ? 100.0 * (double)s.late / (double)s.frames : 0.0, s.max_ms, s.render_p50_ms,
               s.render_p99_ms);
        if (has_head(&a))
            printf("  head pose prediction error at the photon time p50 %.3f deg, p99 %.3f deg\n", pe50, pe99);
    } else {
        const long skip = nrr > 40 && !folded_refreshes ? 20 : 0; /* (folded: the first refreshes are long gone) */
        fv_display_summary s;
        fv_display_summarise(rr + skip, nrr - skip, 2.0 * a.W * a.H, period, &s);
        /* rendered frames completed within the summarised photon span */
        long rendered = 0;
        double rhz = NAN, rp50 = NAN, rp99 = NAN;
        const long nd = a.ndone - a.done_base < a.capdone ? a.ndone - a.done_base : a.capdone;
        if (nrr - skip > 1) {
            /* the span both records still cover (the render times kept may start later) */
            int64_t t0 = rr[skip].photon_ns;
            const int64_t t1 = rr[nrr - 1].photon_ns;
            if (a.done_base && nd && a.done_ns[0] > t0)
                t0 = a.done_ns[0];
            double *v = malloc((size_t)(nd + 1) * sizeof *v);
            long m = 0;
            for (long k = 0; k < nd; k++)
                if (a.done_ns[k] >= t0 && a.done_ns[k] <= t1) {
                    rendered++;
                    if (v)
                        v[m++] = a.render_ms[k];
                }
            if (t1 > t0)
                rhz = (double)rendered * 1e9 / (double)(t1 - t0);
            if (v) {
                rp50 = fv_percentile(v, m, 0.5), rp99 = fv_percentile(v, m, 0.99);
                free(v);
            }
        }
        /* late: vsyncs without a newly composed image (composed after its vsync, or skipped) */
        printf("fovea-headset: displayed %ld frames (%.2f Hz), rendered %ld frames (%.2f Hz), late %ld\n",
               s.displayed + folded_frames, s.displayed_hz, folded_refreshes ? a.ndone : rendered, rhz,
               s.missed + folded_late);
        printf("  %ld refreshes in %.2f s (%ld frames rendered in all), %dx%d per eye, vsync %s (%.2f Hz nominal), "
               "display %s, timewarp on, display thread %s, %d warp thread%s\n",
               nrr + folded_refreshes, run_s, a.ndone, a.W, a.H, vsync_spec, run_hz, disp_kind, prio,
               nwarp, nwarp > 1 ? "s" : "");
        if (folded_refreshes)
            printf("  rates and percentiles over the newest %ld refreshes (older ones are counted, not kept)\n", nrr);
        printf("  ");
        summary_line("motion-to-photon", s.mtp_p50_ms, s.mtp_p99_ms);
        printf("; ");
        summary_line("gaze-to-photon", s.g2p_p50_ms, s.g2p_p99_ms);
        printf("\n");
        printf("  late: %ld refreshes composed after their vsync, %ld vsyncs skipped (a composition longer than a "
               "period)\n",
               s.late, s.skipped);
        printf("  reused %ld refreshes (an old frame warped again); render p50 %.2f ms, p99 %.2f ms; warp+present "
               "p50 %.2f ms, p99 %.2f ms; frame age at the photons p50 %.2f ms; disoccluded %.3f %% of pixels; "
               "grid-warped %.2f %% of pixels\n",
               s.reused, rp50, rp99, s.compose_p50_ms, s.compose_p99_ms, s.age_p50_ms, 100.0 * s.disoccluded_frac,
               100.0 * s.grid_frac);
        if (has_head(&a))
            printf("  head pose prediction error at the photon time p50 %.3f deg, p99 %.3f deg\n", s.pose_err_p50_deg,
                   s.pose_err_p99_deg);
    }
    printf("  vsync: %ld edges, missed %ld, spurious %ld, doubled %ld, relocks %ld, jitter %.1f us, period %.1f us, "
           "state %s%s\n",
           pred->edges, pred->missed, pred->spurious, pred->doubled, pred->relocks,
           fv_vsync_pred_jitter_ns(pred) * 1e-3, fv_vsync_pred_period_ns(pred) * 1e-3,
           fv_vsync_state_name(fv_vsync_pred_state(pred, fv_time_ns())), source_dead ? " (source failed)" : "");
    if (a.cam)
        printf("  camera: %ld frames tracked%s\n", fv_gazesrc_frames(a.cam),
               fv_gazesrc_failed(a.cam) ? " (failed mid-run)" : "");
    if (csv.f && fv_afile_commit(&csv, err, sizeof err)) { /* every row is complete: the run's file */
        fprintf(stderr, "%s: %s\n", prog, err);
        status = FV_EXIT_FAIL;
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
    fv_afile_abort(&csv); /* (nothing when committed) */
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
    free(rr);
    for (int k = 0; k < FV_MAILBOX_SLOTS; k++)
        fv_tw_frame_free(&a.slot[k]);
    free(a.done_ns);
    free(a.render_ms);
    return status;
}
