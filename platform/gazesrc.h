/* fovea platform: the eye-camera gaze source of the headset. A thread reads the eye camera
 * (V4L2, or a Y4M file replayed in real time at fps and looped), tracks the pupil
 * (core/eyetrack/), maps it to a gaze direction (core/eyetrack/gazemap.h: through the
 * calibration, or without one the uncalibrated linear stand-in), filters it
 * (core/eyetrack/gazefilter.h) and pushes samples stamped with the capture time into a gaze
 * ring (core/frameloop.h). A camera that fails mid-run stops the thread with a one-line reason
 * (fv_gazesrc_failed): the ring keeps the last good gaze. */
#ifndef FOVEA_GAZESRC_H
#define FOVEA_GAZESRC_H

#include <stddef.h>

#include "camera.h"
#include "eyetrack/calib.h"
#include "frameloop.h"

typedef struct fv_gazesrc fv_gazesrc;

/* spec: "/dev/videoN" (any path not starting with "replay:") or "replay:FILE.y4m". calib may be
 * NULL (copied). cam: the display eye's camera, to map gaze directions to image coordinates
 * (copied). The camera is opened here, so a missing one fails at start-up: -1 with a reason. */
int fv_gazesrc_start(fv_gazesrc **g, const char *spec, const fv_calib *calib, const fv_camera *cam, float replay_fps,
                     fv_gaze_ring *ring, char *err, size_t err_len);
/* A one-line reason once the camera has failed mid-run, else NULL. */
const char *fv_gazesrc_failed(fv_gazesrc *g);
long fv_gazesrc_frames(fv_gazesrc *g); /* camera frames tracked so far */
void fv_gazesrc_stop(fv_gazesrc *g);

#endif
