/* fovea platform: the calibration run (calibrun.h). */
#include "calibrun.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "base/clock.h"
#include "base/err.h"
#include "calibfile.h"
#include "eyesrc.h"
#include "eyetrack/eyetrack.h"
#include "eyetrack/gazemap.h"
#include "v4l2.h"

/* The stereo image of one target: grey, a white ring of 1 deg with a black centre of 0.25 deg on
 * each eye at the target's direction. */
static void draw_target(uint8_t *rgb, int w, int h, const fv_camera cams[2], float yaw, float pitch)
{
    memset(rgb, 48, (size_t)w * 2 * h * 3);
    for (int e = 0; e < 2; e++) {
        float gx, gy;
        fv_gaze_dir_to_image(&cams[e], yaw, pitch, &gx, &gy);
        const float cx = gx * (float)w, cy = gy * (float)h;
        const float r1 = cams[e].focal_px * tanf(1.0f * 0.01745329f), r0 = r1 * 0.25f;
        const int x0 = (int)floorf(cx - r1 - 1), x1 = (int)ceilf(cx + r1 + 1);
        const int y0 = (int)floorf(cy - r1 - 1), y1 = (int)ceilf(cy + r1 + 1);
        for (int y = y0 < 0 ? 0 : y0; y <= y1 && y < h; y++)
            for (int x = x0 < 0 ? 0 : x0; x <= x1 && x < w; x++) {
                const float d = hypotf((float)x + 0.5f - cx, (float)y + 0.5f - cy);
                if (d > r1)
                    continue;
                const uint8_t v = d < r0 ? 0 : 255;
                uint8_t *px = rgb + ((size_t)y * 2 * (size_t)w + (size_t)e * (size_t)w + (size_t)x) * 3;
                px[0] = px[1] = px[2] = v;
            }
    }
}

int fv_calibrate_run(const fv_calibrate_opts *o, char *err, size_t err_len)
{
    const int replay = !strncmp(o->camera, "replay:", 7);
    fv_eyesrc *src = NULL;
    static const volatile sig_atomic_t never = 0;
    if (replay) {
        if (fv_eyesrc_open_y4m(&src, o->camera + 7, err, err_len))
            return 2;
    } else {
        fv_v4l2_config vc;
        fv_v4l2_config_default(&vc, o->camera);
        if (fv_eyesrc_open_v4l2(&src, &vc, 2000, o->stop ? o->stop : &never, err, err_len))
            return 2;
    }
    fv_calproc *c = fv_calproc_create(&o->proc);
    fv_eye_tracker *tr = fv_eye_create(NULL, FV_EYE_MODE_HEADSET);
    fv_camera cams[2];
    fv_pose head = {{0, 0, 0}, {0, 0, 0, 1}};
    const int w = o->cam.width, h = o->cam.height;
    uint8_t *rgb = malloc((size_t)w * 2 * (size_t)h * 3);
    int rc = 1;
    for (int e = 0; e < 2; e++) {
        fv_camera_desc d = o->cam;
        d.eye = e ? FV_EYE_RIGHT : FV_EYE_LEFT;
        if (fv_camera_setup(&cams[e], &d, &head)) {
            fv_err(err, err_len, "calibration: bad display size or field of view");
            goto out;
        }
    }
    if (!c || !tr || !rgb) {
        fv_err(err, err_len, "calibration: %s", !c ? "bad procedure settings" : "out of memory");
        goto out;
    }
    const double fps = o->replay_fps > 0 ? o->replay_fps : 120.0;
    int64_t t0 = 0, wall0 = fv_time_ns();
    int shown = -1, started = 0;
    for (long i = 0;; i++) {
        if (o->stop && *o->stop) {
            fv_err(err, err_len, "calibration: interrupted (no file written)");
            goto out;
        }
        fv_eye_frame f;
        char ferr[256];
        const int got = fv_eyesrc_next(src, &f, ferr, sizeof ferr);
        if (got != 1) {
            int slot;
            float y, p;
            fv_err(err, err_len, "calibration: the eye camera stopped%s%s before the procedure ended (at target %d)",
                   got < 0 ? ": " : "", got < 0 ? ferr : "",
                   fv_calproc_target(c, started ? t0 + (int64_t)((double)i * 1e9 / fps) : 0, &slot, &y, &p) ? slot + 1
                                                                                                            : -1);
            goto out;
        }
        /* a replayed video runs on its own clock (frame i at i / fps); a camera stamps its frames */
        const int64_t t = replay ? (int64_t)((double)i * 1e9 / fps) : f.t_ns;
        if (!started)
            t0 = t, started = 1, fv_calproc_start(c, t0);
        if (replay && o->realtime) {
            const int64_t due = wall0 + (t - t0);
            while (fv_time_ns() < due) {
                struct timespec ts = {0, 1000000};
                nanosleep(&ts, NULL);
            }
        }
        int slot;
        float yaw, pitch;
        if (!fv_calproc_target(c, t, &slot, &yaw, &pitch))
            break;
        if (slot != shown && o->display) {
            draw_target(rgb, w, h, cams, yaw, pitch);
            if (fv_display_present(o->display, rgb, 2 * w, h, (ptrdiff_t)w * 2 * 3, err, err_len))
                goto out;
            shown = slot;
        }
        fv_eye_result r;
        if (fv_track_frame(tr, f.luma, f.w, f.h, f.stride, &r)) {
            fv_err(err, err_len, "calibration: eye frame %ld: size %dx%d cannot be tracked", i, f.w, f.h);
            goto out;
        }
        fv_calproc_feed(c, t, &r);
    }
    fv_calib cal;
    fv_calproc_report rep;
    char why[400];
    const int bad = fv_calproc_finish(c, &cal, &rep, why, sizeof why);
    FILE *out = o->out ? o->out : stdout;
    /* frames: usable tracked frames in the point's slot (how fast the camera and tracker ran) */
    fprintf(out, "point  kind        target (deg)     fixation  frames  spread (deg)  error (deg)\n");
    for (int k = 0; k < rep.n_points; k++) {
        const fv_calproc_point *pt = &rep.points[k];
        char spread[16] = "-", error[16] = "";
        if (rep.px_per_deg > 0 && isfinite(pt->disp_px))
            snprintf(spread, sizeof spread, "%.2f", (double)(pt->disp_px / rep.px_per_deg));
        if (pt->kind == FV_CALPROC_VALID && pt->ok && isfinite(pt->err_deg))
            snprintf(error, sizeof error, "%.2f", (double)pt->err_deg);
        fprintf(out, "%5d  %-10s  %6.1f %6.1f    %-8s  %6d  %12s  %11s\n", k + 1,
                pt->kind == FV_CALPROC_GRID ? "grid" : "validation", (double)pt->yaw_deg, (double)pt->pitch_deg,
                pt->ok ? "yes" : "NONE", pt->frames, spread, error);
    }
    if (bad) {
        fv_err(err, err_len, "calibration failed: %s", why);
        goto out;
    }
    if (fv_calib_save(&cal, o->out_path, err, err_len))
        goto out;
    fprintf(out, "calibration: %d points, validation mean %.2f deg, max %.2f deg\n", rep.n_grid_ok,
            (double)rep.valid_mean_deg, (double)rep.valid_max_deg);
    rc = 0;
out:
    free(rgb);
    fv_eye_destroy(tr);
    fv_calproc_destroy(c);
    fv_eyesrc_close(src);
    return rc;
}
