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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_srgb_values),
        cmocka_unit_test(test_no_lca_without_lens),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
