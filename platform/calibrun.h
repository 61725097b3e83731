/* fovea platform: the calibration procedure run against a real (or replayed) eye camera and a
 * display (fovea-headset --calibrate). Shows each target of core/eyetrack/calibproc.h on both
 * eyes' images (a white ring with a dark centre at the target's direction, on grey), tracks
 * every camera frame, feeds the procedure, and at the end writes the calibration file or says
 * why not. A replayed video is read at its frame rate on its own clock (as fast as it decodes
 * unless `realtime`, for a window or a panel someone watches). */
#ifndef FOVEA_CALIBRUN_H
#define FOVEA_CALIBRUN_H

#include <signal.h>
#include <stdio.h>

#include "camera.h"
#include "display.h"
#include "eyetrack/calibproc.h"

typedef struct fv_calibrate_opts {
    const char *out_path;       /* the calibration file written on success (atomically) */
    const char *camera;         /* "/dev/videoN" or "replay:FILE.y4m" */
    float replay_fps;           /* a replayed video's frame rate */
    fv_display *display;        /* open, 2 * cam.width x cam.height (the stereo pair); may be NULL */
    fv_camera_desc cam;         /* one eye's camera (size, field of view, lens) */
    fv_calproc_params proc;
    int realtime;               /* pace a replayed video in real time */
    const volatile sig_atomic_t *stop; /* set by a signal: end early (no file) */
    FILE *out;                  /* the per-point table and the summary line (stdout) */
} fv_calibrate_opts;

/* 0 with the file written and "calibration: N points, validation mean X deg, max Y deg" printed;
 * 2 when the camera cannot be opened (err); 1 when the procedure failed (err says why and which
 * points to repeat; no file is written) or the camera stopped. */
int fv_calibrate_run(const fv_calibrate_opts *o, char *err, size_t err_len);

#endif
