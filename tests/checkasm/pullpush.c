/* fovea checkasm: the pull-push kernels (pullpush_dsp.h), every ISA version against the C
 * reference on random and edge-case inputs, bit for bit (so -0 vs +0 counts). Inputs live in
 * exact-size heap buffers (ASan catches any over-read); outputs are canaried (checkasm.h). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkasm.h"

#include "pullpush_dsp.h"

static const int sizes[] = { 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 15, 16, 17, 31, 32, 33, 63, 64, 65, 640, 641, 1281 };
#define NSIZES ((int)(sizeof sizes / sizeof sizes[0]))

/* M_GARBAGE: zero-weight pixels hold NaN / Inf / huge colours, which the contract says are never used */
/* M_BINARY_EXTREME: weights 0/1 only (the ray tracer's level 0, a separate fast path in some
 * kernels) with extreme colours */
enum { M_RANDOM, M_BINARY, M_ZERO_W, M_ONE_W, M_EXTREME, M_GARBAGE, M_BINARY_EXTREME, M_COUNT };
static const char *mode_name[M_COUNT] = { "random",       "binary-w", "all-w-0",        "all-w-1",
                                          "extreme",      "hole-garbage", "binary-w-extreme" };

static float rnd(void) { return fv_test_randf(&checkasm_rng); }

static float gen_weight(int mode)
{
    static const float ext[] = { 0.0f, 1.0f, 1.0f, 0.0f, 1e-30f, 1e-7f, 0.5f, 0.99999994f, 1e-38f };
    switch (mode) {
    case M_BINARY:
    case M_BINARY_EXTREME: return (fv_test_rand(&checkasm_rng) & 1) ? 1.0f : 0.0f;
    case M_ZERO_W: return 0.0f;
    case M_ONE_W: return 1.0f;
    case M_EXTREME: return ext[fv_test_rand(&checkasm_rng) % (sizeof ext / sizeof ext[0])];
    default: {
        const float u = rnd();
        return u < 0.3f ? 0.0f : u < 0.5f ? 1.0f : rnd();
    }
    }
}

static float gen_value(int mode, int channel)
{
    static const float ext[] = { 0.0f, -0.0f, 1e-30f, 1.4e-45f, 1e-38f, 1e4f, 3e4f, 0.5f, 1e-7f, 65504.0f, 1.0f };
    if (mode == M_EXTREME || mode == M_BINARY_EXTREME)
        return ext[fv_test_rand(&checkasm_rng) % (sizeof ext / sizeof ext[0])];
    return channel == 3 ? 0.1f + 100.0f * rnd() : rnd();
}

static void compare(const float *ref, const float *got, size_t count, int per_px, const char *isa,
                    const char *kernel, const char *what, int n, int off, int mode)
{
    checkasm_compare(ref, got, count, CHECKASM_F32, (size_t)per_px, CHECKASM_EXACT, "%s %s (%s) n=%d offset=%d mode=%s",
                     isa, kernel, what, n, off, mode_name[mode]);
}

/* Zero-weight pixels get colours that must never be used. */
static void garbage(float *rgbd, const float *w, size_t px, int mode)
{
    if (mode != M_GARBAGE)
        return;
    const float bad[] = { NAN, -NAN, INFINITY, -INFINITY, 3e38f, -3e38f };
    for (size_t i = 0; i < px; i++)
        if (w[i] == 0.0f)
            for (int c = 0; c < 4; c++)
                rgbd[4 * i + (size_t)c] = bad[fv_test_rand(&checkasm_rng) % (sizeof bad / sizeof bad[0])];
}

static void assert_finite(const float *v, size_t count, const char *kernel, int n)
{
    for (size_t i = 0; i < count; i++)
        if (!isfinite(v[i]))
            fail_msg("c %s n=%d: reference output %zu is %g although every used input is finite", kernel, n, i,
                     (double)v[i]);
}

static void fill(float *p, size_t px, int channels, int mode, int weights)
{
    for (size_t i = 0; i < px; i++)
        for (int c = 0; c < channels; c++)
            p[i * (size_t)channels + (size_t)c] = weights ? gen_weight(mode) : gen_value(mode, c);
}

/* ------------------------------------------------------------------ tables */

static const char *const names[] = {"pull_row", "push_row"};

/* Every ISA this build has an init for must implement every kernel (checkasm.h); the C table
 * holds the references. Also seeds the module's inputs. */
static void test_tables(void **state)
{
    (void)state;
    checkasm_rng = 0x5eed0f0bea2018ull;
    fv_pullpush_dsp ref;
    fv_pullpush_dsp_init(&ref, FV_ISA_C);
    assert_true(ref.pull_row == fv_pull_row_c);
    assert_true(ref.push_row == fv_push_row_c);
    CHECKASM_CHECK_ISA_TABLES("pullpush", fv_pullpush_dsp, &ref, names);
}

/* ------------------------------------------------------------------ pull_row */

static int run_pull(fv_pull_row_fn fn, const char *isa, int n, int off, int mode)
{
    const size_t sn = 2 * (size_t)n;
    buf a = buf_new(4 * sn, off), aw = buf_new(sn, off), b = buf_new(4 * sn, off), bw = buf_new(sn, off);
    fill(a.p, sn, 4, mode, 0);
    fill(b.p, sn, 4, mode, 0);
    fill(aw.p, sn, 1, mode, 1);
    fill(bw.p, sn, 1, mode, 1);
    garbage(a.p, aw.p, sn, mode);
    garbage(b.p, bw.p, sn, mode);
    buf rc = checkasm_out_f32(4 * (size_t)n, off), rw = checkasm_out_f32((size_t)n, off);
    buf tc = checkasm_out_f32(4 * (size_t)n, off), tw = checkasm_out_f32((size_t)n, off);
    fv_pull_row_c(rc.p, rw.p, a.p, aw.p, b.p, bw.p, n);
    fn(tc.p, tw.p, a.p, aw.p, b.p, bw.p, n);
    checkasm_check_guards_f32(&tc, 4 * (size_t)n, isa, "pull_row", n);
    checkasm_check_guards_f32(&tw, (size_t)n, isa, "pull_row", n);
    compare(rc.p, tc.p, 4 * (size_t)n, 4, isa, "pull_row", "rgbd", n, off, mode);
    compare(rw.p, tw.p, (size_t)n, 1, isa, "pull_row", "weight", n, off, mode);
    assert_finite(rc.p, 4 * (size_t)n, "pull_row", n);
    /* sanity of the reference itself on this input: weights in [0,1], all-zero -> zeros */
    for (int i = 0; i < n; i++) {
        assert_true(rw.p[i] >= 0.0f && rw.p[i] <= 1.0f);
        if (mode == M_ZERO_W)
            for (int c = 0; c < 4; c++)
                assert_true(rc.p[4 * i + c] == 0.0f);
    }
    free(a.base), free(aw.base), free(b.base), free(bw.base);
    free(rc.base), free(rw.base), free(tc.base), free(tw.base);
    return 1;
}

static void test_pull_row(void **state)
{
    (void)state;
    int tested = 0;
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "pull_row"))
            continue;
        fv_pullpush_dsp d;
        fv_pullpush_dsp_init(&d, isa);
        if (!d.pull_row || d.pull_row == fv_pull_row_c) /* an ISA this build has must implement it: a failure */
            fail_msg("pull_row: %s has no version of its own", fv_isa_name(isa));
        int runs = 0;
        for (int si = 0; si < NSIZES; si++)
            for (int off = 0; off < 2; off++)
                for (int mode = 0; mode < M_COUNT; mode++)
                    runs += run_pull(d.pull_row, fv_isa_name(isa), sizes[si], off, mode);
        for (int r = 0; r < 200; r++) /* random sizes, offsets and modes */
            runs += run_pull(d.pull_row, fv_isa_name(isa), 1 + (int)(fv_test_rand(&checkasm_rng) % 300),
                             (int)(fv_test_rand(&checkasm_rng) % 4), (int)(fv_test_rand(&checkasm_rng) % M_COUNT));
        printf("[ checkasm ] pull_row: %-7s == c on %d rows (bit-exact)\n", fv_isa_name(isa), runs);
        tested++;
    }
    printf("[ checkasm ] pull_row: %d ISA version(s) tested\n", tested);
}

/* ------------------------------------------------------------------ push_row */

static int run_push(fv_push_row_fn fn, const char *isa, int n, int off, int mode)
{
    const size_t cn = (size_t)(n + 1) / 2 + 2; /* coarse pixels -1 .. (n+1)/2 */
    buf nr = buf_new(4 * cn, off), fr = buf_new(4 * cn, off), w = buf_new((size_t)n, off);
    fill(nr.p, cn, 4, mode, 0);
    fill(fr.p, cn, 4, mode, 0);
    fill(w.p, (size_t)n, 1, mode, 1);
    buf rc = checkasm_out_f32(4 * (size_t)n, off), tc = checkasm_out_f32(4 * (size_t)n, off);
    fill(rc.p, (size_t)n, 4, mode, 0);
    garbage(rc.p, w.p, (size_t)n, mode);
    memcpy(tc.p, rc.p, 4 * (size_t)n * sizeof(float));
    float *orig = malloc(4 * (size_t)n * sizeof(float));
    assert_non_null(orig);
    memcpy(orig, rc.p, 4 * (size_t)n * sizeof(float));
    fv_push_row_c(rc.p, w.p, nr.p + 4, fr.p + 4, n);
    fn(tc.p, w.p, nr.p + 4, fr.p + 4, n);
    checkasm_check_guards_f32(&tc, 4 * (size_t)n, isa, "push_row", n);
    compare(rc.p, tc.p, 4 * (size_t)n, 4, isa, "push_row", "rgbd", n, off, mode);
    /* sanity of the reference: w = 1 pixels keep their bits, the rest is finite */
    for (int i = 0; i < n; i++)
        if (w.p[i] == 1.0f)
            assert_memory_equal(orig + 4 * i, rc.p + 4 * i, 4 * sizeof(float));
        else
            assert_finite(rc.p + 4 * i, 4, "push_row", n);
    free(orig);
    free(nr.base), free(fr.base), free(w.base), free(rc.base), free(tc.base);
    return 1;
}

static void test_push_row(void **state)
{
    (void)state;
    int tested = 0;
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "push_row"))
            continue;
        fv_pullpush_dsp d;
        fv_pullpush_dsp_init(&d, isa);
        if (!d.push_row || d.push_row == fv_push_row_c) /* an ISA this build has must implement it: a failure */
            fail_msg("push_row: %s has no version of its own", fv_isa_name(isa));
        int runs = 0;
        for (int si = 0; si < NSIZES; si++)
            for (int off = 0; off < 2; off++)
                for (int mode = 0; mode < M_COUNT; mode++)
                    runs += run_push(d.push_row, fv_isa_name(isa), sizes[si], off, mode);
        for (int r = 0; r < 200; r++)
            runs += run_push(d.push_row, fv_isa_name(isa), 1 + (int)(fv_test_rand(&checkasm_rng) % 300),
                             (int)(fv_test_rand(&checkasm_rng) % 4), (int)(fv_test_rand(&checkasm_rng) % M_COUNT));
        printf("[ checkasm ] push_row: %-7s == c on %d rows (bit-exact)\n", fv_isa_name(isa), runs);
        tested++;
    }
    printf("[ checkasm ] push_row: %d ISA version(s) tested\n", tested);
}

const struct CMUnitTest checkasm_pullpush_tests[] = {
    cmocka_unit_test(test_tables),
    cmocka_unit_test(test_pull_row),
    cmocka_unit_test(test_push_row),
    {0},
};
