/* The calibration procedure (core/eyetrack/calibproc.c): the schedule, fixation detection, the
 * fit and its validation, repeats and refusals; on tracker results made from the synthetic eye's
 * ground truth (fast, exact expectations) and end to end on rendered frames of a scripted wearer
 * (core/eyetrack/synth.c) through the real tracker, including a 2 mm camera slip afterwards. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "eyetrack/calibproc.h"
#include "eyetrack/synth.h"
#include "testutil.h"

/* A tracker result from the synthetic eye's truth: pupil centre, and the pupil-glint vector from
 * the visible glints (as the tracker defines it: pupil minus the glints' mean). */
static fv_eye_result result_of(const fv_synth_params *p, const fv_synth_state *s)
{
    fv_synth_truth t;
    fv_synth_truth_of(p, s, &t);
    fv_eye_result r;
    memset(&r, 0, sizeof r);
    r.status = s->open > 0.5f ? FV_EYE_OK : FV_EYE_BLINK;
    r.found = r.status == FV_EYE_OK;
    r.pupil_x = t.pupil_x, r.pupil_y = t.pupil_y;
    float gx = 0, gy = 0;
    int n = 0;
    for (int k = 0; k < t.n_glints; k++)
        if (t.glint_visible[k])
            gx += t.glint_x[k], gy += t.glint_y[k], n++;
    r.has_pg = n > 0;
    (void)0;
    if (n)
        r.pg_x = t.pupil_x - gx / n, r.pg_y = t.pupil_y - gy / n;
    return r;
}

static void script_of(const fv_calproc *c, fv_synth_script *sc, float dwell_ms)
{
    fv_synth_script_default(sc, dwell_ms);
    sc->n = fv_calproc_slots(c);
    for (int k = 0; k < sc->n; k++)
        fv_calproc_slot_target(c, k, &sc->yaw_deg[k], &sc->pitch_deg[k]);
}

/* Runs the procedure on truth-made results at fps until the schedule ends. */
static int run_truth(fv_calproc *c, const fv_synth_params *p, const fv_synth_script *sc, int fps, fv_calib *out,
                     fv_calproc_report *rep, char *err, size_t err_len)
{
    fv_calproc_start(c, 0);
    for (long i = 0;; i++) {
        const int64_t t_ns = i * 1000000000LL / fps;
        int slot;
        float y, pt;
        if (!fv_calproc_target(c, t_ns, &slot, &y, &pt))
            break;
        fv_synth_state s;
        fv_synth_script_state(sc, (double)t_ns * 1e-6, &s);
        const fv_eye_result r = result_of(p, &s);
        fv_calproc_feed(c, t_ns, &r);
    }
    return fv_calproc_finish(c, out, rep, err, err_len);
}

static void test_schedule_and_fit(void **state)
{
    (void)state;
    fv_calproc_params cp;
    fv_calproc_default_params(&cp);
    fv_calproc *c = fv_calproc_create(&cp);
    assert_non_null(c);
    assert_int_equal(fv_calproc_slots(c), 13);
    /* the schedule: grid row by row from the top left, then validation between rows and columns */
    int slot;
    float yaw, pitch;
    fv_calproc_start(c, 1000);
    assert_int_equal(fv_calproc_target(c, 1000, &slot, &yaw, &pitch), 1);
    assert_int_equal(slot, 0);
    assert_true(yaw == -15.0f && pitch == 10.0f);
    assert_int_equal(fv_calproc_target(c, 1000 + 1500000000LL * 4 + 1, &slot, &yaw, &pitch), 1);
    assert_true(slot == 4 && yaw == 0.0f && pitch == 0.0f);
    assert_int_equal(fv_calproc_target(c, 1000 + 1500000000LL * 9, &slot, &yaw, &pitch), 1);
    assert_true(slot == 9 && yaw == -7.5f && pitch == 5.0f);

    fv_synth_params p;
    fv_synth_default_params(&p, 320, 240);
    fv_synth_script sc;
    script_of(c, &sc, 1500.0f);
    fv_calib cal;
    fv_calproc_report rep;
    char err[512];
    if (run_truth(c, &p, &sc, 120, &cal, &rep, err, sizeof err))
        fail_msg("%s", err);
    /* exact features, jitter 0.05 deg: the quadratic maps the validation points to within a few
     * tenths of a degree (the model is not exactly quadratic) */
    printf("[ calib ] truth features: validation mean %.3f max %.3f deg, %d grid, %d validation\n",
           (double)rep.valid_mean_deg, (double)rep.valid_max_deg, rep.n_grid_ok, rep.n_valid_ok);
    assert_int_equal(rep.n_grid_ok, 9);
    assert_int_equal(rep.n_valid_ok, 4);
    assert_int_equal(rep.n_repeated, 0);
    assert_true(rep.valid_mean_deg < 0.3f && rep.valid_max_deg < 0.5f);
    assert_int_equal(cal.input, FV_CALIB_PUPIL_GLINT);
    fv_calproc_destroy(c);
}

/* A blink through one grid point's fixation: the point is shown again at the end and the run
 * succeeds; blinks on every target: refused, naming the points; a wearer who looks around at
 * the validation points: refused as not reaching them. */
static void test_repeats_and_refusals(void **state)
{
    (void)state;
    fv_calproc_params cp;
    fv_calproc_default_params(&cp);
    fv_calproc *c = fv_calproc_create(&cp);
    fv_synth_params p;
    fv_synth_default_params(&p, 320, 240);
    fv_synth_script sc;
    fv_calib cal;
    fv_calproc_report rep;
    char err[512];

    script_of(c, &sc, 1500.0f);
    sc.n = 13 + 1; /* the wearer follows the repeat of point 3 (index 2) too */
    sc.yaw_deg[13] = sc.yaw_deg[2], sc.pitch_deg[13] = sc.pitch_deg[2];
    for (int b = 0; b < 8; b++) /* point 3 blinked through from 350 ms on: no 300 ms window is left */
        sc.blink_ms[sc.n_blinks++] = 2 * 1500.0f + 320.0f + 150.0f * b;
    if (run_truth(c, &p, &sc, 120, &cal, &rep, err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(rep.n_repeated, 1);
    assert_int_equal(rep.n_grid_ok, 9);

    script_of(c, &sc, 1500.0f);
    for (int b = 0; b < FV_SYNTH_SCRIPT_MAX; b++) /* blinks every 150 ms through the first 6 targets */
        sc.blink_ms[sc.n_blinks++] = 300.0f + 150.0f * b;
    sc.wander_mask = ~0u << 3; /* and a wearer looking around (from the 4th on) */
    assert_int_equal(run_truth(c, &p, &sc, 120, &cal, &rep, err, sizeof err), -1);
    printf("[ calib ] refused: %s\n", err);
    assert_non_null(strstr(err, "only 0 of the 9 grid points had a stable fixation (no fixation at points 1, 2, 3"));
    assert_int_equal(rep.n_repeated, 9);

    script_of(c, &sc, 1500.0f);
    for (int k = 0; k < 4; k++) /* validation targets shifted 4 deg: the wearer looked elsewhere */
        sc.yaw_deg[9 + k] += 4.0f;
    assert_int_equal(run_truth(c, &p, &sc, 120, &cal, &rep, err, sizeof err), -1);
    assert_non_null(strstr(err, "the mapping does not reach the validation points"));
    assert_true(rep.valid_mean_deg > 3.5f && rep.valid_mean_deg < 4.5f);
    fv_calproc_destroy(c);
}

/* End to end: rendered frames of a scripted wearer through the real tracker, pupil-glint and
 * pupil-only calibrations fitted from the same frames; then the camera slips 2 mm and the
 * validation targets are looked at again without recalibrating. */
static void test_end_to_end_and_slip(void **state)
{
    (void)state;
    enum { W = 320, H = 240, FPS = 60 };
    fv_calproc_params cp;
    fv_calproc_default_params(&cp);
    cp.dwell_ms = 900, cp.settle_ms = 400, cp.fix_ms = 250;
    fv_calproc *cg = fv_calproc_create(&cp);
    cp.input = FV_CALIB_PUPIL;
    fv_calproc *cpu = fv_calproc_create(&cp);
    assert_non_null(cg);
    assert_non_null(cpu);
    fv_synth_params p;
    fv_synth_default_params(&p, W, H);
    p.supersample = 1;
    fv_synth_script sc;
    script_of(cg, &sc, 900.0f);
    fv_eye_tracker *tr = fv_eye_create(NULL, FV_EYE_MODE_HEADSET);
    uint8_t *img = malloc(W * H);
    fv_calproc_start(cg, 0);
    fv_calproc_start(cpu, 0);
    for (long i = 0;; i++) {
        const int64_t t_ns = i * 1000000000LL / FPS;
        int slot;
        float y, pt;
        if (!fv_calproc_target(cg, t_ns, &slot, &y, &pt))
            break;
        fv_synth_state s;
        fv_synth_script_state(&sc, (double)t_ns * 1e-6, &s);
        fv_synth_truth t;
        fv_synth_render(&p, &s, (uint64_t)i, img, W, &t);
        fv_eye_result r;
        assert_int_equal(fv_track_frame(tr, img, W, H, W, &r), 0);
        fv_calproc_feed(cg, t_ns, &r);
        fv_calproc_feed(cpu, t_ns, &r);
    }
    fv_calib cal_pg, cal_p;
    fv_calproc_report rep;
    char err[512];
    if (fv_calproc_finish(cg, &cal_pg, &rep, err, sizeof err))
        fail_msg("pupil-glint: %s", err);
    printf("[ calib ] rendered, pupil-glint: validation mean %.3f max %.3f deg\n", (double)rep.valid_mean_deg,
           (double)rep.valid_max_deg);
    assert_true(rep.valid_mean_deg <= 0.5f && rep.valid_max_deg <= 1.0f); /* the targets */
    if (fv_calproc_finish(cpu, &cal_p, &rep, err, sizeof err))
        fail_msg("pupil only: %s", err);
    printf("[ calib ] rendered, pupil only: validation mean %.3f max %.3f deg\n", (double)rep.valid_mean_deg,
           (double)rep.valid_max_deg);

    /* slip: the camera 2 mm right, then 2 mm up; 20 frames of steady fixation per target */
    for (int dir = 0; dir < 2; dir++) {
        p.cam_shift_mm[0] = dir == 0 ? 2.0f : 0.0f, p.cam_shift_mm[1] = dir == 1 ? 2.0f : 0.0f;
        double e_pg = 0, e_p = 0, e_k[4] = {0};
        int n = 0;
        for (int k = 0; k < 13; k++) {
            fv_eye_reset(tr);
            fv_synth_state s = {sc.yaw_deg[k], sc.pitch_deg[k], 2.2f, 1.0f};
            float sx = 0, sy = 0, qx = 0, qy = 0;
            int m = 0;
            for (int f = 0; f < 6; f++) {
                fv_synth_truth t;
                fv_synth_render(&p, &s, 1000u + (uint64_t)(k * 8 + f), img, W, &t);
                fv_eye_result r;
                fv_track_frame(tr, img, W, H, W, &r);
                float ax, ay, bx, by;
                if (fv_calib_feature(&cal_pg, &r, &ax, &ay) && fv_calib_feature(&cal_p, &r, &bx, &by))
                    sx += ax, sy += ay, qx += bx, qy += by, m++;
            }
            assert_true(m >= 4);
            float yaw, pitch;
            fv_calib_apply(&cal_pg, sx / m, sy / m, &yaw, &pitch);
            e_pg += fv_gaze_angle_deg(yaw, pitch, s.yaw_deg, s.pitch_deg);
            fv_calib_apply(&cal_p, qx / m, qy / m, &yaw, &pitch);
            e_p += fv_gaze_angle_deg(yaw, pitch, s.yaw_deg, s.pitch_deg);
            (void)e_k;
            n++;
        }
        printf("[ calib ] camera slipped 2 mm %s: mean error pupil-glint %.3f deg, pupil only %.3f deg\n",
               dir ? "up" : "right", e_pg / n, e_p / n);
        assert_true(e_pg / n <= 1.0); /* the target */
        assert_true(e_p / n > 3.0 * (e_pg / n)); /* and why the pupil-glint vector drives the gaze */
    }
    free(img);
    fv_eye_destroy(tr);
    fv_calproc_destroy(cg);
    fv_calproc_destroy(cpu);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_schedule_and_fit),
        cmocka_unit_test(test_repeats_and_refusals),
        cmocka_unit_test(test_end_to_end_and_slip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
