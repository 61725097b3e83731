/* fovea eye tracker: tracker result -> gaze direction -> image coordinates (see gazemap.h). */
#include "eyetrack/gazemap.h"

#include <math.h>

#include "base/util.h"

int fv_gaze_from_eye(const fv_eye_result *r, int w, int h, const fv_calib *calib, const fv_camera *cam,
                     float *yaw_deg, float *pitch_deg)
{
    *yaw_deg = *pitch_deg = 0.0f;
    if (r->status != FV_EYE_OK || !r->found)
        return 0;
    if (calib) {
        float fx, fy;
        if (!fv_calib_feature(calib, r, &fx, &fy))
            return 0;
        fv_calib_apply(calib, fx, fy, yaw_deg, pitch_deg);
    } else {
        const float nx = r->pupil_x / (float)w, ny = r->pupil_y / (float)h;
        const float hx = atanf(cam->tan_right) * 57.29578f, hy = atanf(cam->tan_top) * 57.29578f;
        *yaw_deg = (2.0f * nx - 1.0f) * hx;
        *pitch_deg = (1.0f - 2.0f * ny) * hy;
    }
    return 1;
}

void fv_gaze_dir_to_image(const fv_camera *cam, float yaw_deg, float pitch_deg, float *gx, float *gy)
{
    const float d2r = 3.14159265358979f / 180.0f;
    /* direction (sin yaw cos pitch, sin pitch, cos yaw cos pitch): x/z and y/z tangents */
    const float tx = tanf(yaw_deg * d2r), ty = tanf(pitch_deg * d2r) / cosf(yaw_deg * d2r);
    *gx = fv_clampf((tx - cam->tan_left) / (cam->tan_right - cam->tan_left), 0.0f, 1.0f);
    *gy = fv_clampf((cam->tan_top - ty) / (cam->tan_top - cam->tan_bottom), 0.0f, 1.0f);
}
