/* fovea eye tracker: from a tracked eye-camera frame to a gaze direction, and from a gaze
 * direction to normalised display-image coordinates. Pure math (the headset's camera thread,
 * platform/gazesrc.c, calls it per frame). */
#ifndef FOVEA_EYETRACK_GAZEMAP_H
#define FOVEA_EYETRACK_GAZEMAP_H

#include "camera.h"
#include "eyetrack/calib.h"
#include "eyetrack/eyetrack.h"

/* The gaze direction (yaw right, pitch up, degrees) of one tracker result r on a w x h camera
 * frame. With a calibration: fv_calib_apply to the pupil-glint vector (a pupil-glint
 * calibration; a frame without a glint gives no gaze) or to the pupil centre. Without one
 * (calib NULL): the pupil centre's place in the camera image spread linearly over cam's field
 * of view (an uncalibrated stand-in for demos). Returns 1 with the direction, or 0 with 0, 0
 * when the frame gives none (pupil not found, blink, lost, or no glint as above). */
int fv_gaze_from_eye(const fv_eye_result *r, int w, int h, const fv_calib *calib, const fv_camera *cam,
                     float *yaw_deg, float *pitch_deg);

/* Gaze direction (yaw right, pitch up, degrees) to normalised image coordinates of cam (x right,
 * y down), clamped to [0, 1]. */
void fv_gaze_dir_to_image(const fv_camera *cam, float yaw_deg, float pitch_deg, float *gx, float *gy);

#endif
