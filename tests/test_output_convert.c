/* The display-format conversion (core/output_convert.c) against the sRGB formula. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "output_convert.h"
#include "pipeline.h"
#include "testscene.h"

/* IEC 61966-2-1, rounded to 8 bits */
static uint8_t srgb_ref(double v)
{
    v = v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v;
    const double s = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return (uint8_t)lround(s * 255.0);
}

static void test_srgb_values(void **state)
{
    (void)state;
    static fv_output_conv c;
    fv_output_conv_init(&c, FV_ISA_C);
    /* 3 pixels a row, 2 rows, a padded stride; depth is ignored */
    const float in[2][4][4] = {{{0.0f, 1.0f, 0.5f, 9.0f}, {0.2140411f, 0.0031308f, 0.75f, 1.0f}, {-1.0f, 2.0f, NAN, 1.0f}},
                               {{0.001f, 0.04f, 0.9f, 1.0f}, {1.0f / 4096.0f, 0.25f, 0.999f, 1.0f}, {0.1f, 0.3f, 0.6f, 1.0f}}};
    uint8_t out[2][12];
    memset(out, 0xAA, sizeof out);
    fv_output_convert(&c, &in[0][0][0], 4, 3, 2, NULL, NULL, &out[0][0], 12);
    for (int y = 0; y < 2; y++)
        for (int x = 0; x < 3; x++)
            for (int ch = 0; ch < 3; ch++) {
                const float v = in[y][x][ch];
                /* the table has 4096 steps: the nearest step's value, within one level of the formula */
                const int want = isnan(v) ? 0 : srgb_ref(v);
                assert_true(abs((int)out[y][3 * x + ch] - want) <= 1);
            }
    /* exact at the ends and the clamps; 0.5 is 188 (0.7354 * 255 = 187.5: the table rounds up) */
    assert_int_equal(out[0][0], 0);
    assert_int_equal(out[0][1], 255);
    assert_int_equal(out[0][2], 188);
    assert_int_equal(out[0][6], 0);   /* negative */
    assert_int_equal(out[0][7], 255); /* above 1 */
    assert_int_equal(out[0][8], 0);   /* NaN never indexes out of the table */
    assert_int_equal(out[0][9], 0xAA); /* nothing written past w pixels */
}

/* a camera without a lens has no chromatic aberration tables */
static void test_no_lca_without_lens(void **state)
{
    (void)state;
    fv_camera cam;
    memset(&cam, 0, sizeof cam);
    assert_null(fv_output_lca_create(&cam));
}

/* With the layered DoF the output stage runs fused into its last pass, row by row; every model
 * (fused or not) must give the bytes of converting its final float image in one go, and report
 * the output stage's time */
static void test_fused_output_matches(void **state)
{
    (void)state;
    fv_scene *scene = fv_scene_create();
    assert_non_null(scene);
    static const float a[3] = {0.8f, 0.3f, 0.2f}, b[3] = {0.1f, 0.5f, 0.9f};
    fv_test_add_quad(scene, -3.0f, -3.0f, 3.0f, 3.0f, -6.0f, a, -1); /* far wall: blurred */
    fv_test_add_quad(scene, -0.3f, -0.3f, 0.3f, 0.3f, -1.0f, b, -1); /* near card under the gaze */
    char err[256];
    assert_int_equal(fv_scene_commit(scene, err, sizeof err), 0);
    enum { W = 96, H = 80 };
    static uint8_t want[W * H * 3];
    for (int model = 0; model < FV_DOF_MODEL_COUNT; model++) {
        fv_pipeline_config cfg;
        fv_pipeline_config_default(&cfg);
        cfg.cam.width = W, cfg.cam.height = H, cfg.threads = 3;
        cfg.dof.preset = FV_DOF_STRONG;
        cfg.dof.model = (fv_dof_model)model;
        cfg.keep_image = 1;
        fv_pipeline *pl = fv_pipeline_create(scene, &cfg, err, sizeof err);
        assert_non_null(pl);
        static const fv_pose origin = {{0, 0, 0}, {0, 0, 0, 1}};
        fv_frame_stats st;
        for (int f = 0; f < 2; f++)
            assert_int_equal(fv_pipeline_render(pl, FV_EYE_LEFT, &origin, 0.5f, 0.5f, &st), 0);
        assert_false(isnan(st.stage_ms[FV_STAGE_OUTPUT]));
        ptrdiff_t fstride, bstride;
        const float *img = fv_pipeline_image(pl, FV_EYE_LEFT, &fstride);
        fv_output_conv conv; /* the pipeline's kernels (AVX2's is within 1 of the others') */
        fv_output_conv_init(&conv, cfg.isa_mask);
        fv_output_convert(&conv, img, fstride, W, H, fv_pipeline_camera(pl, FV_EYE_LEFT), NULL, want, W * 3);
        const uint8_t *got = fv_pipeline_rgb8(pl, FV_EYE_LEFT, &bstride);
        assert_int_equal(bstride, W * 3);
        assert_memory_equal(got, want, sizeof want);
        fv_pipeline_destroy(pl);
        /* the default keeps no float image: the layered model's rows go straight to the
         * display format, the same bytes */
        cfg.keep_image = 0;
        pl = fv_pipeline_create(scene, &cfg, err, sizeof err);
        assert_non_null(pl);
        for (int f = 0; f < 2; f++)
            assert_int_equal(fv_pipeline_render(pl, FV_EYE_LEFT, &origin, 0.5f, 0.5f, &st), 0);
        assert_false(isnan(st.stage_ms[FV_STAGE_OUTPUT]));
        if (model == FV_DOF_MODEL_WEIER)
            assert_null(fv_pipeline_image(pl, FV_EYE_LEFT, &fstride));
        assert_memory_equal(fv_pipeline_rgb8(pl, FV_EYE_LEFT, &bstride), want, sizeof want);
        fv_pipeline_destroy(pl);
    }
    fv_scene_free(scene);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_srgb_values),
        cmocka_unit_test(test_no_lca_without_lens),
        cmocka_unit_test(test_fused_output_matches),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
