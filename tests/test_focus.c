/* Focus depth from the point of regard (core/dof/focus.h): a plane, a thin pole under a noisy
 * gaze, a change of fixation against the accommodation filter's time constant, the override. */
#include <math.h>
#include <stdio.h>

#include "testutil.h"
#include "dof/focus.h"

/* A wall at 5 m with a pole at 1 m covering x in [pole_x0, pole_x1) (all y). */
typedef struct {
    float wall_m, pole_m, pole_x0, pole_x1;
} scene;

static float depth_at(void *ctx, float x, float y)
{
    (void)y;
    const scene *s = ctx;
    return x >= s->pole_x0 && x < s->pole_x1 ? s->pole_m : s->wall_m;
}

static float gauss(uint64_t *r) /* Box-Muller, unit variance */
{
    const float u1 = fv_test_randf(r) + 1e-7f, u2 = fv_test_randf(r);
    return sqrtf(-2.0f * logf(u1)) * cosf(6.2831853f * u2);
}

static void test_plane(void **st)
{
    (void)st;
    fv_focus_params p;
    fv_focus_params_default(&p);
    fv_focus f;
    fv_focus_init(&f, &p);
    scene s = {2.0f, 2.0f, 0, 0};
    const float m = fv_focus_update(&f, depth_at, &s, 100.0f, 100.0f, 10.0f, 11.1f);
    assert_float_equal(m, 2.0f, 1e-4); /* the first frame jumps to the target */
    assert_int_equal(f.samples_used, 17);
    /* nothing under the gaze yet: no focus */
    fv_focus g;
    fv_focus_init(&g, &p);
    scene none = {-1.0f, -1.0f, 0, 0};
    assert_true(isnan(fv_focus_update(&g, depth_at, &none, 100.0f, 100.0f, 10.0f, 11.1f)));
}

/* The test: gaze fixating a thin pole (0.6 deg wide at 10 px/deg) in front of a far wall,
 * with tracker noise of the stated error (1 deg, Gaussian per axis): after settling, the focus
 * stays within t = 0.2 m of the pole every frame. Sampling the depth at the gaze alone (what
 * Mantiuk et al. found unusable) jumps to the wall in most frames. */
static void test_thin_pole_noisy_gaze(void **st)
{
    (void)st;
    fv_focus_params p;
    fv_focus_params_default(&p);
    const float ppd = 10.0f, err_px = p.error_deg * ppd;
    scene s = {5.0f, 1.0f, 97.0f, 103.0f};
    fv_focus f;
    fv_focus_init(&f, &p);
    uint64_t r = 11;
    float lo = 1e9f, hi = 0.0f;
    int naive_far = 0, frames = 0;
    for (int i = 0; i < 600; i++) { /* 6.7 s at 90 Hz */
        const float gx = 100.0f + err_px * gauss(&r), gy = 100.0f + err_px * gauss(&r);
        const float m = fv_focus_update(&f, depth_at, &s, gx, gy, ppd, 1000.0f / 90.0f);
        if (i < 90) /* the first second: the first frames' gaze may land on the wall */
            continue;
        lo = m < lo ? m : lo;
        hi = m > hi ? m : hi;
        naive_far += depth_at(&s, gx, gy) > 2.0f;
        frames++;
    }
    printf("thin pole at 1 m, gaze noise 1 deg: focus %.3f .. %.3f m; the depth at the gaze alone was the wall in %d "
           "of %d frames\n", (double)lo, (double)hi, naive_far, frames);
    assert_true(lo >= 0.8f && hi <= 1.2f);
    assert_true(naive_far > frames / 2);
}

/* A change of fixation from the pole to the open wall: the focus follows with the accommodation
 * filter's time constant, in dioptres (1 D -> 0.2 D: after tau, 63 % of the way). */
static void test_accommodation(void **st)
{
    (void)st;
    fv_focus_params p;
    fv_focus_params_default(&p);
    scene s = {5.0f, 1.0f, 97.0f, 103.0f};
    fv_focus f;
    fv_focus_init(&f, &p);
    const float dt = 1.0f;
    for (int i = 0; i < 50; i++)
        fv_focus_update(&f, depth_at, &s, 100.0f, 100.0f, 10.0f, dt);
    assert_float_equal(f.focus_dpt, 1.0f, 1e-4);
    /* look at the wall, far from the pole: the evidence fades (100 ms half-life), then the eye
     * accommodates; check the dioptres against the first-order response once the target moved */
    int t_switch = -1;
    float at_tau = NAN, final_m = NAN;
    for (int i = 1; i <= 3000; i++) {
        final_m = fv_focus_update(&f, depth_at, &s, 400.0f, 100.0f, 10.0f, dt);
        if (t_switch < 0 && f.target_dpt < 0.3f)
            t_switch = i;
        if (t_switch >= 0 && i == t_switch + (int)p.tau_ms)
            at_tau = f.focus_dpt;
    }
    printf("fixation 1 m -> 5 m: target switched after %d ms; focus %.3f D one time constant later (first-order: "
           "%.3f D); %.3f m after 3 s\n", t_switch, (double)at_tau, 0.2 + 0.8 * exp(-1.0) * 1.0, (double)final_m);
    assert_true(t_switch > 0 && t_switch < 400); /* the pole's evidence fades within a few half-lives */
    /* between the target switch and tau later, the focus covered 1 - 1/e of the remaining way */
    assert_true(at_tau < 0.2f + 0.8f * (float)exp(-1.0) + 0.05f && at_tau > 0.2f + 0.8f * (float)exp(-1.0) * 0.5f);
    assert_float_equal(final_m, 5.0f, 0.05);
}

static void test_fixed_override(void **st)
{
    (void)st;
    fv_focus_params p;
    fv_focus_params_default(&p);
    p.fixed_m = 3.0f;
    fv_focus f;
    fv_focus_init(&f, &p);
    scene s = {5.0f, 1.0f, 97.0f, 103.0f};
    for (int i = 0; i < 10; i++)
        assert_float_equal(fv_focus_update(&f, depth_at, &s, 100.0f, 100.0f, 10.0f, 11.1f), 3.0f, 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plane),
        cmocka_unit_test(test_thin_pole_noisy_gaze),
        cmocka_unit_test(test_accommodation),
        cmocka_unit_test(test_fixed_override),
    };
    return cmocka_run_group_tests_name("focus", tests, NULL, NULL);
}
