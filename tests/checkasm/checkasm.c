/* fovea checkasm: the driver (cmocka; one group so tests/run.sh counts every test) and the shared
 * helpers of checkasm.h.
 *   checkasm                    every module's tests
 *   checkasm --bench [options]  the kernels' speed (bench.h; the options of fovea-bench --kernels) */
#include "checkasm.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "dof/dof_dsp.h"
#include "eyetrack/eyetrack_dsp.h"
#include "pullpush_dsp.h"
#include "reproject_dsp.h"

uint64_t checkasm_rng;

const unsigned checkasm_isas[] = {
#if defined(__x86_64__)
    FV_ISA_SSE41, FV_ISA_AVX2,
#elif defined(__aarch64__)
    FV_ISA_NEON,
#endif
    0,
};

static const uint32_t canary = 0x7fc0dead;

int checkasm_cpu_runs(unsigned isa, const char *kernel)
{
    if (fv_cpu_isas() & isa)
        return 1;
    printf("[ checkasm ] %s: %-7s not on this CPU, skipped\n", kernel, fv_isa_name(isa));
    return 0;
}

static unsigned char canary_at(const unsigned char *q) /* the pattern by address: any buffer, any offset */
{
    return (unsigned char)(canary >> (8 * ((uintptr_t)q & 3)));
}

void *checkasm_out(size_t bytes, size_t off_bytes, void **base)
{
    const size_t all = CHECKASM_GUARD + off_bytes + bytes + CHECKASM_GUARD;
    unsigned char *b = malloc(all);
    assert_non_null(b);
    for (size_t i = 0; i < all; i++)
        b[i] = canary_at(b + i);
    *base = b;
    return b + CHECKASM_GUARD + off_bytes;
}

void checkasm_check_guards(const void *p, size_t bytes, const char *isa, const char *kernel, int n)
{
    const unsigned char *q = p;
    for (int i = 1; i <= CHECKASM_GUARD; i++) {
        if (q[-i] != canary_at(q - i))
            fail_msg("%s %s n=%d: wrote before its output (guard byte -%d clobbered)", isa, kernel, n, i);
        if (q[bytes + (size_t)i - 1] != canary_at(q + bytes + i - 1))
            fail_msg("%s %s n=%d: wrote past its output (guard byte end+%d clobbered)", isa, kernel, n, i - 1);
    }
}

static int64_t f32_ordered(uint32_t u) /* the float's position on a line where adjacent floats differ by 1 */
{
    return u & 0x80000000u ? -(int64_t)(u & 0x7fffffffu) - 1 : (int64_t)u;
}

void checkasm_compare(const void *ref, const void *got, size_t count, checkasm_type type, size_t per_px,
                      unsigned max_ulp, const char *ctx, ...)
{
    for (size_t i = 0; i < count; i++) {
        uint32_t a = 0, b = 0;
        int64_t d;
        if (type == CHECKASM_U8) {
            a = ((const uint8_t *)ref)[i], b = ((const uint8_t *)got)[i];
            d = (int64_t)a - (int64_t)b;
        } else {
            memcpy(&a, (const char *)ref + 4 * i, 4);
            memcpy(&b, (const char *)got + 4 * i, 4);
            const int nan = type == CHECKASM_F32 && (((a >> 23) & 0xff) == 0xff || ((b >> 23) & 0xff) == 0xff);
            d = type == CHECKASM_F32 && !nan ? f32_ordered(a) - f32_ordered(b) : a == b ? 0 : (int64_t)max_ulp + 1;
        }
        if ((d < 0 ? -d : d) > (int64_t)max_ulp) {
            char what[256];
            va_list ap;
            va_start(ap, ctx);
            vsnprintf(what, sizeof what, ctx, ap);
            va_end(ap);
            if (type == CHECKASM_F32) {
                float fa, fb;
                memcpy(&fa, &a, 4), memcpy(&fb, &b, 4);
                fail_msg("%s: element %zu (pixel %zu channel %zu): c=%.9g (%a) got %.9g (%a), bound %u ulp", what, i,
                         i / per_px, i % per_px, (double)fa, (double)fa, (double)fb, (double)fb, max_ulp);
            } else {
                fail_msg("%s: element %zu (pixel %zu channel %zu): c=%u got %u, bound %u", what, i, i / per_px,
                         i % per_px, a, b, max_ulp);
            }
        }
    }
}

void checkasm_check_table(const char *module, unsigned isa, const void *own, const void *ref, size_t size,
                          const char *const *names)
{
    typedef void (*fn)(void);
    const size_t n = size / sizeof(fn);
    for (size_t i = 0; i < n; i++) {
        fn a, r;
        memcpy(&a, (const char *)own + i * sizeof(fn), sizeof a);
        memcpy(&r, (const char *)ref + i * sizeof(fn), sizeof r);
        if (!a)
            fail_msg("%s: fv_%s_dsp_init_%s leaves %s NULL (an ISA that has an init must implement every kernel)",
                     module, module, fv_isa_name(isa), names[i]);
        if (a == r)
            fail_msg("%s: fv_%s_dsp_init_%s sets %s to the C reference", module, module, fv_isa_name(isa), names[i]);
    }
    printf("[ checkasm ] %s: %-7s has its own version of all %zu kernels\n", module, fv_isa_name(isa), n);
}

/* ------------------------------------------------------------------ selection and the bench table */

/* The C tables are the references; ~0 selects the highest ISA this CPU has. */
static void test_dispatch(void **state)
{
    (void)state;
    const unsigned have = fv_cpu_isas();
    checkasm_dsp d;
    checkasm_dsp_init(&d, FV_ISA_C);
    assert_int_equal(d.isa, FV_ISA_C);
    assert_true(d.pp.pull_row == fv_pull_row_c && d.pp.push_row == fv_push_row_c);
    assert_true(d.taa.taa_blend == fv_taa_blend_c && d.taa.taa_fill == fv_taa_fill_c);
    assert_true(d.dof.dof_coc_row == fv_dof_coc_row_c && d.et.et_box3_row == fv_et_box3_row_c);
    checkasm_dsp_init(&d, ~0u);
    unsigned best = 0;
    for (unsigned b = 1; b <= FV_ISA_NEON; b <<= 1)
        if (have & b)
            best = b;
    assert_int_equal(d.isa, best);
    assert_int_equal(fv_cpu_best_isa(FV_ISA_SSE41), have & FV_ISA_SSE41);
    printf("[ checkasm ] init(~0) selects %s\n", fv_isa_name(d.isa));
    assert_string_equal(fv_isa_name(FV_ISA_C), "c");
    assert_string_equal(fv_isa_name(12345), "?");
#if defined(__aarch64__)
    assert_true(have & FV_ISA_NEON);
#endif
}

static void test_bench_table(void **state)
{
    (void)state;
    checkasm_dsp c, best;
    checkasm_dsp_init(&c, FV_ISA_C);
    checkasm_dsp_init(&best, ~0u);
    assert_true(checkasm_bench_count >= 10);
    for (int i = 0; i < checkasm_bench_count; i++) {
        const checkasm_bench_kernel *k = &checkasm_bench_kernels[i];
        assert_ptr_equal(checkasm_bench_find(k->name), k);
        assert_false(checkasm_bench_differs(k, &c, &c));
        assert_true(k->field[0] > 0 && k->calls_per_frame > 0);
        /* wherever the CPU has an ISA, every benched kernel has a version of it */
        if (best.isa != FV_ISA_C)
            assert_true(checkasm_bench_differs(k, &best, &c));
    }
    assert_null(checkasm_bench_find("nope"));
    /* one kernel end to end (the smallest: the eye tracker's threshold), both tables */
    const checkasm_bench_kernel *k = checkasm_bench_find("et_thresh_row");
    void *st = k->setup();
    assert_non_null(st);
    k->run(st, &c, 0, k->calls_per_frame);
    k->run(st, &best, 0, 3);
    k->free(st);
}

const struct CMUnitTest checkasm_bench_tests[] = {
    cmocka_unit_test(test_dispatch),
    cmocka_unit_test(test_bench_table),
    {0},
};

static size_t count_tests(const struct CMUnitTest *t)
{
    size_t n = 0;
    while (t[n].name)
        n++;
    return n;
}

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "--bench"))
        return checkasm_bench_main("checkasm --bench", argc - 1, argv + 1);
    if (argc > 1) {
        fprintf(stderr, "usage: checkasm [--bench [--json FILE] [--kernel-reps N] [--kernel NAME [--calls N]\n"
                        "                [--isa c|sse41|avx2|neon]]]\n");
        return 2;
    }
    const struct CMUnitTest *mods[] = {checkasm_pullpush_tests, checkasm_reproject_tests, checkasm_dof_tests,
                                       checkasm_eyetrack_tests, checkasm_shade_tests, checkasm_raygen_tests,
                                       checkasm_output_tests, checkasm_timewarp_tests, checkasm_bench_tests};
    size_t n = 0;
    for (size_t m = 0; m < sizeof mods / sizeof mods[0]; m++)
        n += count_tests(mods[m]);
    struct CMUnitTest *all = calloc(n, sizeof *all);
    assert_non_null(all);
    n = 0;
    for (size_t m = 0; m < sizeof mods / sizeof mods[0]; m++)
        for (size_t i = 0; mods[m][i].name; i++)
            all[n++] = mods[m][i];
    printf("[ checkasm ] cpu ISAs:");
    for (unsigned b = 1; b <= FV_ISA_NEON; b <<= 1)
        if (fv_cpu_isas() & b)
            printf(" %s", fv_isa_name(b));
    printf("%s\n", fv_cpu_isas() ? "" : " (none: plain C only)");
    const int r = _cmocka_run_group_tests("checkasm", all, n, NULL, NULL);
    free(all);
    return r;
}
