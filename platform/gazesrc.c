/* fovea platform: eye-camera gaze source thread (see gazesrc.h). */
#include "gazesrc.h"
#include "base/clock.h"

#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/err.h"
#include "eyesrc.h"
#include "eyetrack/eyetrack.h"
#include "eyetrack/gazefilter.h"
#include "eyetrack/gazemap.h"
#include "vsync.h"

struct fv_gazesrc {
    pthread_t th;
    int started;
    fv_eyesrc *src;
    char path[4096];
    int replay;
    float fps;
    fv_calib calib;
    int has_calib;
    fv_camera cam;
    fv_gaze_ring *ring;
    fv_eye_tracker *trk;
    fv_gaze_filter filt;
    atomic_int stop;
    volatile sig_atomic_t v4l2_stop; /* the V4L2 source's stop flag (set with stop) */
    atomic_int failed;
    atomic_long frames;
    char why[512];
};

static void fail(fv_gazesrc *g, const char *why)
{
    snprintf(g->why, sizeof g->why, "%s", why);
    atomic_store(&g->failed, 1);
}

static void *run(void *arg)
{
    fv_gazesrc *g = arg;
    char err[512];
    int64_t next_t = fv_time_ns();
    const int64_t frame_ns = (int64_t)(1e9 / g->fps);
    while (!atomic_load(&g->stop)) {
        fv_eye_frame fr;
        int rc = fv_eyesrc_next(g->src, &fr, err, sizeof err);
        if (rc == 0 && g->replay && !atomic_load(&g->stop)) { /* loop the recording */
            fv_eyesrc_close(g->src);
            g->src = NULL;
            if (fv_eyesrc_open_y4m(&g->src, g->path, err, sizeof err)) {
                fail(g, err);
                return NULL;
            }
            fv_eye_reset(g->trk);
            continue;
        }
        if (rc <= 0) {
            if (rc < 0)
                fail(g, err);
            return NULL;
        }
        int64_t t = fr.t_ns;
        if (g->replay) { /* a camera at fps: the frame exists from its slot's time on */
            fv_clock_sleep_until_ns(next_t);
            t = next_t;
            next_t += frame_ns;
        } else if (t == 0) {
            t = fv_time_ns();
        }
        fv_eye_result r;
        if (fv_track_frame(g->trk, fr.luma, fr.w, fr.h, fr.stride, &r)) {
            fail(g, "eye tracker: bad frame or out of memory");
            return NULL;
        }
        float yaw, pitch;
        const int valid =
            fv_gaze_from_eye(&r, fr.w, fr.h, g->has_calib ? &g->calib : NULL, &g->cam, &yaw, &pitch);
        fv_gaze_out out;
        fv_gaze_filter_update(&g->filt, (double)t * 1e-6, valid, yaw, pitch, r.confidence, &out);
        if (out.state != FV_GAZE_NONE) {
            fv_gaze_sample s = {.t_ns = t, .confidence = out.confidence};
            fv_gaze_dir_to_image(&g->cam, out.yaw_deg, out.pitch_deg, &s.x, &s.y);
            fv_gaze_ring_push(g->ring, &s);
        }
        atomic_fetch_add(&g->frames, 1);
    }
    return NULL;
}

int fv_gazesrc_start(fv_gazesrc **out, const char *spec, const fv_calib *calib, const fv_camera *cam, float replay_fps,
                     fv_gaze_ring *ring, char *err, size_t err_len)
{
    *out = NULL;
    fv_gazesrc *g = calloc(1, sizeof *g);
    if (!g)
        return fv_err(err, err_len, "camera: out of memory");
    g->replay = !strncmp(spec, "replay:", 7);
    snprintf(g->path, sizeof g->path, "%s", g->replay ? spec + 7 : spec);
    g->fps = replay_fps > 0 ? replay_fps : 120.0f;
    if (calib) {
        g->calib = *calib;
        g->has_calib = 1;
    }
    g->cam = *cam;
    g->ring = ring;
    int rc;
    if (g->replay) {
        rc = fv_eyesrc_open_y4m(&g->src, g->path, err, err_len);
    } else {
        fv_v4l2_config vc;
        fv_v4l2_config_default(&vc, g->path);
        /* a live camera: silent this long (also while reopening after an unplug) = failed */
        rc = fv_eyesrc_open_v4l2(&g->src, &vc, 2000, &g->v4l2_stop, err, err_len);
    }
    if (rc) {
        free(g);
        return -1;
    }
    g->trk = fv_eye_create(NULL, FV_EYE_MODE_HEADSET);
    if (!g->trk) {
        fv_eyesrc_close(g->src);
        free(g);
        return fv_err(err, err_len, "camera: out of memory for the eye tracker");
    }
    fv_gaze_filter_init(&g->filt, NULL);
    if (pthread_create(&g->th, NULL, run, g)) {
        fv_eye_destroy(g->trk);
        fv_eyesrc_close(g->src);
        free(g);
        return fv_err(err, err_len, "pthread_create(camera thread) failed");
    }
    g->started = 1;
    *out = g;
    return 0;
}

const char *fv_gazesrc_failed(fv_gazesrc *g) { return atomic_load(&g->failed) ? g->why : NULL; }

long fv_gazesrc_frames(fv_gazesrc *g) { return atomic_load(&g->frames); }

void fv_gazesrc_stop(fv_gazesrc *g)
{
    if (!g)
        return;
    atomic_store(&g->stop, 1);
    g->v4l2_stop = 1;
    if (g->started)
        pthread_join(g->th, NULL);
    fv_eye_destroy(g->trk);
    fv_eyesrc_close(g->src);
    free(g);
}
