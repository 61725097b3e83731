/* Tracker accuracy bookkeeping (core/eyetrack/labelstats.c) against hand-computed counts and
 * medians, and the --isa name table (core/cpu.c). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <cmocka.h>

#include "cpu.h"
#include "eyetrack/labelstats.h"

static void test_groups_and_rates(void **state)
{
    (void)state;
    fv_eye_label_stats s;
    assert_int_equal(fv_eye_label_stats_init(&s, 10), 0);
    /* two MRL sensors and one plain name; errors 0.5, 1.5, 2.5, 4, miss */
    assert_int_equal(fv_eye_label_stats_add(&s, "a/s0001_00001_0_0_0_0_0_01.png", 0.5), 0);
    assert_int_equal(fv_eye_label_stats_add(&s, "s0001_00002_0_0_0_0_0_02.png", 1.5), 0);
    assert_int_equal(fv_eye_label_stats_add(&s, "b/s0002_00003_1_0_1_0_1_01.png", 2.5), 0);
    assert_int_equal(fv_eye_label_stats_add(&s, "plain.png", 4.0), 0);
    assert_int_equal(fv_eye_label_stats_add(&s, "s0003_00004_0_0_0_0_0_02.png", INFINITY), 0);
    assert_int_equal(s.n, 3);
    assert_string_equal(s.g[0].name, "all");
    assert_string_equal(s.g[1].name, "sensor 01");
    assert_string_equal(s.g[2].name, "sensor 02");
    assert_int_equal(s.g[0].n, 5);
    /* within 1, 2, 3, 5 px: 1, 2, 3, 4 of 5 */
    assert_int_equal(s.g[0].within[0], 1);
    assert_int_equal(s.g[0].within[1], 2);
    assert_int_equal(s.g[0].within[2], 3);
    assert_int_equal(s.g[0].within[3], 4);
    assert_float_equal(fv_eye_label_median(&s.g[0]), 2.5, 0.0);
    assert_float_equal(fv_eye_label_median(&s.g[1]), 1.5, 0.0);      /* 0.5, 2.5 */
    assert_true(isinf(fv_eye_label_median(&s.g[2])));                /* 1.5, miss: (1.5 + inf) / 2 */
    fv_eye_label_stats_free(&s);
}

static void test_cap_and_groups_full(void **state)
{
    (void)state;
    fv_eye_label_stats s;
    assert_int_equal(fv_eye_label_stats_init(&s, 12), 0);
    char name[64];
    for (int i = 0; i < 12; i++) { /* 12 sensors: 7 groups besides "all", the rest only in "all" */
        snprintf(name, sizeof name, "s0001_%05d_0_0_0_0_0_%02d.png", i, i);
        assert_int_equal(fv_eye_label_stats_add(&s, name, 1.0), 0);
    }
    assert_int_equal(s.n, FV_EYE_LABEL_GROUPS);
    assert_int_equal(s.g[0].n, 12);
    assert_int_equal(fv_eye_label_stats_add(&s, "x.png", 1.0), -1); /* past cap */
    fv_eye_label_group empty = {.n = 0};
    assert_true(isnan(fv_eye_label_median(&empty)));
    fv_eye_label_stats_free(&s);
}

static void test_mrl_sensor(void **state)
{
    (void)state;
    char out[16];
    assert_int_equal(fv_eye_mrl_sensor("dir/s0014_03021_0_0_1_0_1_03.png", out), 1);
    assert_string_equal(out, "03");
    assert_int_equal(fv_eye_mrl_sensor("s0014_03021_0_0_1_0_1.png", out), 0);    /* 6 fields */
    assert_int_equal(fv_eye_mrl_sensor("a_b_c_d_e_f_g_123456789.png", out), 0); /* sensor too long */
    assert_int_equal(fv_eye_mrl_sensor("eye.png", out), 0);
}

static void test_isa_names(void **state)
{
    (void)state;
    unsigned m = 12345;
    assert_int_equal(fv_isa_mask_parse("c", &m), 0);
    assert_int_equal(m, FV_ISA_C);
    assert_int_equal(fv_isa_mask_parse("sse41", &m), 0);
    assert_int_equal(m, FV_ISA_SSE41);
    assert_int_equal(fv_isa_mask_parse("avx2", &m), 0);
    assert_int_equal(m, FV_ISA_SSE41 | FV_ISA_AVX2);
    assert_int_equal(fv_isa_mask_parse("neon", &m), 0);
    assert_int_equal(m, FV_ISA_NEON);
    assert_int_equal(fv_isa_mask_parse("avx512", &m), -1);
    assert_int_equal(m, FV_ISA_NEON); /* untouched */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_groups_and_rates),
        cmocka_unit_test(test_cap_and_groups_full),
        cmocka_unit_test(test_mrl_sensor),
        cmocka_unit_test(test_isa_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
