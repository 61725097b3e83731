/* CoC models (core/dof/coc.c) against hand-computed cases. The expected numbers were worked out
 * step by step outside the code (the literal V_d / V_f formulas, in double) and cross-checked
 * with the closed form the thin lens reduces to: retinal CoC = k d_i (1/g - 1/d) for a point at
 * g when the eye focuses at d (1 - d_i / V_d = d_i (1/g - 1/d), since 1/V_d = 1/d + 1/d_i - 1/g). */
#include <math.h>
#include <string.h>

#include "testutil.h"
#include "dof/coc.h"

/* 1280x1440 at 100 deg vertical: focal_px = 720 / tan(50 deg) = 604.15173 px per unit tan. */
#define FOCAL_PX 604.15173f

static void test_weier_hand_cases(void **st)
{
    (void)st;
    fv_coc_weier p;
    fv_coc_weier_default(&p, FOCAL_PX);
    /* E = 604.15173 / 22.4 = 26.971059 px/mm (10.54 px per degree at the axis) */
    assert_float_equal(p.retina_px_per_mm, 26.971059f, 1e-4f);
    /* near: d_o 1 m, t 0.2 m -> d_n 0.8 m; g 0.5 m.
     * f_n = 1/(1/800 + 1/22.4) = 21.789883 mm; V_d(f_n, 500) = 22.782750 mm; V_f(f_n, 800) = 22.4 mm
     * CoC = (22.4 - 22.782750) * 4.49 / 22.782750 = -0.075432 mm  (= 4.49 * 22.4 * (1/800 - 1/500))
     * in pixels: -0.075432 * 26.971059 = -2.034481 px */
    assert_float_equal(fv_coc_weier_mm(&p, 1.0f, 0.5f), -0.075432f, 2e-6f);
    assert_float_equal(fv_coc_weier_px(&p, 1.0f, 0.5f), -2.034481f, 1e-4f);
    /* far: d_f 1.2 m; g 3 m. f_f = 21.989529 mm; V_d(f_f, 3000) = 22.151899 mm
     * CoC = (22.4 - 22.151899) * 4.49 / 22.151899 = +0.050288 mm  (= 4.49 * 22.4 * (1/1200 - 1/3000)) */
    assert_float_equal(fv_coc_weier_mm(&p, 1.0f, 3.0f), 0.050288f, 2e-6f);
    /* a miss (infinite depth): V_d = f_f, CoC = k d_i / d_f = 4.49 * 22.4 / 1200 = 0.0838133 mm */
    assert_float_equal(fv_coc_weier_mm(&p, 1.0f, INFINITY), 0.0838133f, 2e-6f);
}

static void test_weier_zero_inside_tolerance(void **st)
{
    (void)st;
    fv_coc_weier p;
    fv_coc_weier_default(&p, FOCAL_PX);
    const float g[] = {0.8f, 0.85f, 1.0f, 1.1999f, 1.2f};
    for (size_t i = 0; i < sizeof g / sizeof g[0]; i++)
        assert_true(fv_coc_weier_mm(&p, 1.0f, g[i]) == 0.0f);
    /* just outside: nonzero, with the sign of its side */
    assert_true(fv_coc_weier_mm(&p, 1.0f, 0.79f) < 0.0f);
    assert_true(fv_coc_weier_mm(&p, 1.0f, 1.21f) > 0.0f);
    /* t = 0: only the focus distance itself is sharp */
    p.tolerance_m = 0.0f;
    assert_true(fv_coc_weier_mm(&p, 2.0f, 2.0f) == 0.0f);
    assert_true(fv_coc_weier_mm(&p, 2.0f, 1.99f) < 0.0f);
    assert_true(fv_coc_weier_mm(&p, 2.0f, 2.01f) > 0.0f);
}

/* |CoC| grows strictly away from the in-focus range, on both sides, and is continuous at the
 * bounds (tends to 0). */
static void test_weier_monotonic(void **st)
{
    (void)st;
    fv_coc_weier p;
    fv_coc_weier_default(&p, FOCAL_PX);
    float last = 0.0f;
    for (float g = 2.21f; g < 200.0f; g *= 1.1f) { /* focus 2 m: far field beyond 2.2 m */
        float c = fv_coc_weier_mm(&p, 2.0f, g);
        assert_true(c > last);
        last = c;
    }
    assert_true(fv_coc_weier_mm(&p, 2.0f, 2.2001f) < 1e-4f);
    last = 0.0f;
    for (float g = 1.79f; g > 0.06f; g *= 0.9f) {
        float c = fv_coc_weier_mm(&p, 2.0f, g);
        assert_true(c < last);
        last = c;
    }
    assert_true(fv_coc_weier_mm(&p, 2.0f, 1.7999f) > -1e-4f);
}

/* Liu eq. (12): focus F = 1 m, point D = 0.4 m, f_e 22.3 mm, tau_e 4.49 mm.
 * v = 22.3*1000*400 / (1000*400 + 22.3*400 - 22.3*1000) = 23.071750 mm
 * C_e = |23.071750 - 22.3| * 4.49 / 23.071750 = 0.1501905 mm (= 4.49*22.3*(1/400 - 1/1000)).
 * Eq. (3) with t = 0 and d_i = f_e is the same model: both must agree everywhere. */
static void test_liu_hand_case_and_agreement(void **st)
{
    (void)st;
    fv_coc_liu l;
    fv_coc_liu_default(&l);
    assert_float_equal(l.focal_mm, 22.3f, 0.0f);
    assert_float_equal(l.pupil_mm, 4.49f, 0.0f);
    assert_float_equal(fv_coc_liu_mm(&l, 1.0f, 0.4f), -0.1501905f, 2e-6f);
    assert_true(fv_coc_liu_mm(&l, 1.0f, 1.0f) == 0.0f);
    fv_coc_weier w;
    fv_coc_weier_default(&w, FOCAL_PX);
    w.tolerance_m = 0.0f;
    w.image_dist_mm = 22.3f;
    const float g[] = {0.1f, 0.3f, 0.7f, 1.5f, 4.0f, 30.0f, 1000.0f};
    for (size_t i = 0; i < sizeof g / sizeof g[0]; i++)
        assert_float_equal(fv_coc_liu_mm(&l, 1.5f, g[i]), fv_coc_weier_mm(&w, 1.5f, g[i]), 1e-6f);
}

/* Mantiuk eq. (1): a 4.49, f 22.3 mm, d0 1 m, dp 0.4 m:
 * 4.49 * 22.3/977.7 * |1 - 2.5| = 4.49 * 0.0228086 * 1.5 = 0.1536161; far dp 4 m: |1 - 0.25| = 0.75
 * -> 0.0768081. Camera and eye differ only in what is fixed: Mantiuk's factor f/(d0-f) * d0 is
 * the image distance f d0/(d0 - f) = 22.80864 mm at focus, where the eye keeps d_i. */
static void test_mantiuk_hand_case(void **st)
{
    (void)st;
    fv_coc_mantiuk m;
    fv_coc_mantiuk_default(&m);
    assert_float_equal(fv_coc_mantiuk_size(&m, 1.0f, 0.4f), -0.1536161f, 2e-6f);
    assert_float_equal(fv_coc_mantiuk_size(&m, 1.0f, 4.0f), 0.0768081f, 2e-6f);
    assert_true(fv_coc_mantiuk_size(&m, 1.0f, 1.0f) == 0.0f);
    m.aperture = 19.0f; /* linear in a */
    assert_float_equal(fv_coc_mantiuk_size(&m, 1.0f, 4.0f), 0.0768081f * 19.0f / 4.49f, 1e-5f);
}

/* Hussain: sigma = K |1/d0 - 1/d1|. K 2 px m, d0 1 m: d1 0.5 m -> 2 * |1 - 2| = 2 px (near);
 * d1 4 m -> 2 * 0.75 = 1.5 px (far). Default K for the 4.49 mm pupil and FOCAL_PX:
 * 0.00449 * 604.15173 / 4 = 0.6781603 px m. */
static void test_hussain_hand_case(void **st)
{
    (void)st;
    fv_coc_hussain h = {2.0f};
    assert_float_equal(fv_coc_hussain_sigma_px(&h, 1.0f, 0.5f), -2.0f, 1e-6f);
    assert_float_equal(fv_coc_hussain_sigma_px(&h, 1.0f, 4.0f), 1.5f, 1e-6f);
    assert_true(fv_coc_hussain_sigma_px(&h, 1.0f, 1.0f) == 0.0f);
    fv_coc_hussain_default(&h, 4.49f, FOCAL_PX);
    assert_float_equal(h.k_px_m, 0.6781603f, 1e-6f);
}

static void test_presets(void **st)
{
    (void)st;
    fv_dof_preset pr;
    assert_int_equal(fv_dof_preset_parse("none", &pr), 0);
    assert_int_equal(pr, FV_DOF_NONE);
    assert_int_equal(fv_dof_preset_parse("strong", &pr), 0);
    assert_int_equal(pr, FV_DOF_STRONG);
    assert_int_equal(fv_dof_preset_parse("blurry", &pr), -1);
    float px[FV_DOF_PRESET_COUNT];
    for (int i = 0; i < FV_DOF_PRESET_COUNT; i++) {
        fv_coc_weier p;
        fv_coc_weier_default(&p, FOCAL_PX);
        fv_coc_weier_apply_preset(&p, (fv_dof_preset)i);
        px[i] = fv_coc_weier_px(&p, 1.0f, 0.5f);
    }
    assert_true(px[FV_DOF_NONE] == 0.0f);
    /* weak is the physiological eye (-2.034481 px, above); medium and strong double each step */
    assert_float_equal(px[FV_DOF_WEAK], -2.034481f, 1e-4f);
    assert_float_equal(px[FV_DOF_MEDIUM], 2.0f * px[FV_DOF_WEAK], 1e-5f);
    assert_float_equal(px[FV_DOF_STRONG], 4.0f * px[FV_DOF_WEAK], 1e-5f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_weier_hand_cases),
        cmocka_unit_test(test_weier_zero_inside_tolerance),
        cmocka_unit_test(test_weier_monotonic),
        cmocka_unit_test(test_liu_hand_case_and_agreement),
        cmocka_unit_test(test_mantiuk_hand_case),
        cmocka_unit_test(test_hussain_hand_case),
        cmocka_unit_test(test_presets),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
