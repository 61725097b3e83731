/* Gaze mapping (core/eyetrack/gazemap.c): tracker result -> gaze direction (calibrated and
 * uncalibrated) and gaze direction -> normalised image coordinates, against hand-computed values. */
#include <math.h>
#include <string.h>

#include "eyetrack/gazemap.h"
#include "testutil.h"

static fv_camera cam_of(float l, float r, float b, float t)
{
    fv_camera c;
    memset(&c, 0, sizeof c);
    c.tan_left = l, c.tan_right = r, c.tan_bottom = b, c.tan_top = t;
    return c;
}

static void test_dir_to_image(void **st)
{
    (void)st;
    const fv_camera c = cam_of(-1.0f, 1.0f, -1.0f, 1.0f); /* 90 x 90 degrees, symmetric */
    float gx, gy;
    fv_gaze_dir_to_image(&c, 0.0f, 0.0f, &gx, &gy);
    assert_float_equal(gx, 0.5f, 1e-6);
    assert_float_equal(gy, 0.5f, 1e-6);
    /* tan(yaw) = 0.5: x = (0.5 + 1) / 2 */
    fv_gaze_dir_to_image(&c, 26.565051f, 0.0f, &gx, &gy);
    assert_float_equal(gx, 0.75f, 1e-6);
    assert_float_equal(gy, 0.5f, 1e-6);
    /* pitch up: y goes down the image; tan(pitch) = 0.5 -> (1 - 0.5) / 2 */
    fv_gaze_dir_to_image(&c, 0.0f, 26.565051f, &gx, &gy);
    assert_float_equal(gx, 0.5f, 1e-6);
    assert_float_equal(gy, 0.25f, 1e-6);
    /* yaw 45, pitch 30: y/z = tan 30 / cos 45 = 0.8164966 -> (1 - 0.8164966) / 2 */
    fv_gaze_dir_to_image(&c, 45.0f, 30.0f, &gx, &gy);
    assert_float_equal(gx, 1.0f, 1e-6);
    assert_float_equal(gy, 0.0917517f, 1e-6);
    /* clamped to the image */
    fv_gaze_dir_to_image(&c, 80.0f, -80.0f, &gx, &gy);
    assert_float_equal(gx, 1.0f, 0);
    assert_float_equal(gy, 1.0f, 0);
    fv_gaze_dir_to_image(&c, -80.0f, 60.0f, &gx, &gy);
    assert_float_equal(gx, 0.0f, 0);
    assert_float_equal(gy, 0.0f, 0);
    /* asymmetric frustum: straight ahead is 0.8 / 2.0 across and 0.6 / 1.6 down */
    const fv_camera a = cam_of(-0.8f, 1.2f, -1.0f, 0.6f);
    fv_gaze_dir_to_image(&a, 0.0f, 0.0f, &gx, &gy);
    assert_float_equal(gx, 0.4f, 1e-6);
    assert_float_equal(gy, 0.375f, 1e-6);
}

static fv_eye_result eye(float px, float py)
{
    fv_eye_result r;
    memset(&r, 0, sizeof r);
    r.status = FV_EYE_OK;
    r.found = 1;
    r.pupil_x = px, r.pupil_y = py;
    return r;
}

static void test_uncalibrated(void **st)
{
    (void)st;
    /* half-angles 45 (tan 1) and 30 degrees (tan 0.57735) */
    const fv_camera c = cam_of(-1.0f, 1.0f, -0.5773503f, 0.5773503f);
    float yaw, pitch;
    fv_eye_result r = eye(160.0f, 120.0f); /* the camera image's centre */
    assert_int_equal(fv_gaze_from_eye(&r, 320, 240, NULL, &c, &yaw, &pitch), 1);
    assert_float_equal(yaw, 0.0f, 1e-5);
    assert_float_equal(pitch, 0.0f, 1e-5);
    r = eye(240.0f, 60.0f); /* 3/4 across, 1/4 down: (2 * 0.75 - 1) * 45, (1 - 2 * 0.25) * 30 */
    assert_int_equal(fv_gaze_from_eye(&r, 320, 240, NULL, &c, &yaw, &pitch), 1);
    assert_float_equal(yaw, 22.5f, 1e-4);
    assert_float_equal(pitch, 15.0f, 1e-4);
    r = eye(0.0f, 240.0f); /* the corner: the field of view's edge */
    assert_int_equal(fv_gaze_from_eye(&r, 320, 240, NULL, &c, &yaw, &pitch), 1);
    assert_float_equal(yaw, -45.0f, 1e-4);
    assert_float_equal(pitch, -30.0f, 1e-4);
    /* no pupil, blink, lost: no gaze, and 0, 0 */
    r = eye(240.0f, 60.0f);
    r.found = 0;
    assert_int_equal(fv_gaze_from_eye(&r, 320, 240, NULL, &c, &yaw, &pitch), 0);
    assert_float_equal(yaw, 0.0f, 0);
    assert_float_equal(pitch, 0.0f, 0);
    r = eye(240.0f, 60.0f);
    r.status = FV_EYE_BLINK;
    assert_int_equal(fv_gaze_from_eye(&r, 320, 240, NULL, &c, &yaw, &pitch), 0);
    r.status = FV_EYE_LOST;
    assert_int_equal(fv_gaze_from_eye(&r, 320, 240, NULL, &c, &yaw, &pitch), 0);
}

static void test_calibrated(void **st)
{
    (void)st;
    const fv_camera c = cam_of(-1.0f, 1.0f, -1.0f, 1.0f);
    /* yaw = 1 + 2 u, pitch = -1 + 3 v with u = (in_x - 1) / 2, v = (in_y + 1) / 2 */
    fv_calib cal;
    memset(&cal, 0, sizeof cal);
    cal.input = FV_CALIB_PUPIL_GLINT;
    cal.u0 = 1.0, cal.v0 = -1.0, cal.s = 2.0;
    cal.a[0] = 1.0, cal.a[1] = 2.0;
    cal.b[0] = -1.0, cal.b[2] = 3.0;
    float yaw, pitch;
    fv_eye_result r = eye(100.0f, 80.0f);
    r.has_pg = 1, r.pg_x = 5.0f, r.pg_y = 1.0f; /* u = 2, v = 1 */
    assert_int_equal(fv_gaze_from_eye(&r, 320, 240, &cal, &c, &yaw, &pitch), 1);
    assert_float_equal(yaw, 5.0f, 1e-6);
    assert_float_equal(pitch, 2.0f, 1e-6);
    /* a pupil-glint calibration and no glint this frame: no gaze (not the pupil centre) */
    r.has_pg = 0;
    assert_int_equal(fv_gaze_from_eye(&r, 320, 240, &cal, &c, &yaw, &pitch), 0);
    assert_float_equal(yaw, 0.0f, 0);
    /* a pupil-only calibration maps the pupil centre: u = 3, v = 2 */
    cal.input = FV_CALIB_PUPIL;
    r = eye(7.0f, 3.0f);
    assert_int_equal(fv_gaze_from_eye(&r, 320, 240, &cal, &c, &yaw, &pitch), 1);
    assert_float_equal(yaw, 7.0f, 1e-6);
    assert_float_equal(pitch, 5.0f, 1e-6);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dir_to_image),
        cmocka_unit_test(test_uncalibrated),
        cmocka_unit_test(test_calibrated),
    };
    return cmocka_run_group_tests_name("gazemap", tests, NULL, NULL);
}
