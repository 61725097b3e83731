/* fovea checkasm: the eye tracker's kernels (eyetrack/eyetrack_dsp.h), every ISA version against
 * the plain-C reference, on random and edge inputs (all 0, all 255, thresholds 0, 1, 255, 256),
 * odd sizes, unaligned rows, with canaries around every output. The bound is exact equality
 * (bits, for the float one too: it rounds the same operations in the same order). The references
 * themselves are checked against the formulas on hand-computed cases (et_box_score_row: against
 * sums straight from the image). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkasm.h"

#include "eyetrack/eyetrack_dsp.h"

#define CANARY 32
static const uint32_t canary32 = 0xdeadbeefu;

static const int sizes[] = { 1, 2, 3, 7, 8, 9, 15, 16, 17, 31, 32, 33, 47, 63, 64, 65, 95, 127, 160, 319, 320, 641 };
#define NSIZES ((int)(sizeof sizes / sizeof sizes[0]))

enum { M_RANDOM, M_ZERO, M_FULL, M_EXTREME, M_COUNT };

static void fill8(uint8_t *p, int n, int mode)
{
    for (int i = 0; i < n; i++) {
        const uint64_t r = fv_test_rand(&checkasm_rng);
        p[i] = mode == M_ZERO ? 0 : mode == M_FULL ? 255 : mode == M_EXTREME ? ((r & 1) ? 255 : 0) : (uint8_t)r;
    }
}

/* exact-size input at an offset into its allocation (unaligned rows; ASan sees over-reads) */
static uint8_t *in8(int n, int off, uint8_t **base)
{
    *base = malloc((size_t)n + (size_t)off);
    assert_non_null(*base);
    return *base + off;
}

/* ------------------------------------------------------------------ tables */

static const char *const names[] = {"et_down2_row", "et_integral_row", "et_thresh_row", "et_box_score_row", "et_box3_row"};

/* Every ISA this build has an init for must implement every kernel (checkasm.h); the C table
 * holds the references. Also seeds the module's inputs. */
static void test_tables(void **state)
{
    (void)state;
    checkasm_rng = 0xe7e5eedull;
    fv_eyetrack_dsp ref;
    fv_eyetrack_dsp_init(&ref, FV_ISA_C);
    assert_true(ref.et_down2_row == fv_et_down2_row_c);
    assert_true(ref.et_integral_row == fv_et_integral_row_c);
    assert_true(ref.et_thresh_row == fv_et_thresh_row_c);
    assert_true(ref.et_box_score_row == fv_et_box_score_row_c);
    assert_true(ref.et_box3_row == fv_et_box3_row_c);
    CHECKASM_CHECK_ISA_TABLES("eyetrack", fv_eyetrack_dsp, &ref, names);
}

typedef void (*runner)(const fv_eyetrack_dsp *d, const char *isa, int n, int off, int mode);

static void run_down2(const fv_eyetrack_dsp *d, const char *isa, int n, int off, int mode)
{
    uint8_t *ba, *bb, *br, *bt;
    uint8_t *a = in8(2 * n, off, &ba), *b = in8(2 * n, off, &bb);
    fill8(a, 2 * n, mode);
    fill8(b, 2 * n, mode);
    uint8_t *r = checkasm_out_u8(n, off, &br), *t = checkasm_out_u8(n, off, &bt);
    fv_et_down2_row_c(r, a, b, n);
    d->et_down2_row(t, a, b, n);
    checkasm_check_guards(t, (size_t)n, isa, "et_down2_row", n);
    for (int i = 0; i < n; i++) {
        /* the reference against the formula too */
        const int want = (a[2 * i] + a[2 * i + 1] + b[2 * i] + b[2 * i + 1] + 2) >> 2;
        assert_int_equal(r[i], want);
        if (t[i] != r[i])
            fail_msg("%s et_down2_row n=%d off=%d mode=%d: pixel %d: c=%d %s=%d", isa, n, off, mode, i, r[i], isa, t[i]);
    }
    free(ba), free(bb), free(br), free(bt);
}

static void run_integral(const fv_eyetrack_dsp *d, const char *isa, int n, int off, int mode)
{
    uint8_t *bs;
    uint8_t *s = in8(n, off, &bs);
    fill8(s, n, mode);
    uint32_t *above = malloc(((size_t)n + 1) * sizeof *above);
    uint32_t *r = malloc(((size_t)n + 2 * CANARY) * sizeof *r), *t = malloc(((size_t)n + 2 * CANARY + 1) * sizeof *t);
    assert_non_null(above);
    assert_non_null(r);
    assert_non_null(t);
    for (int i = 0; i < n; i++) /* near the top of the range too: the sums wrap mod 2^32 alike */
        above[i] = mode == M_EXTREME ? 0xffffff00u + (uint32_t)i : (uint32_t)(fv_test_rand(&checkasm_rng) >> 40);
    uint32_t *tp = t + CANARY + (off & 1); /* 4-byte aligned, not 16 */
    for (int i = 0; i < n + 2 * CANARY; i++)
        r[i] = canary32;
    for (int i = 0; i < n + 2 * CANARY + 1; i++)
        t[i] = canary32;
    fv_et_integral_row_c(r + CANARY, above, s, n);
    d->et_integral_row(tp, above, s, n);
    for (int i = 1; i <= CANARY; i++)
        if (tp[-i] != canary32 || tp[n + i - 1] != canary32)
            fail_msg("%s et_integral_row n=%d: wrote outside its output", isa, n);
    uint32_t run = 0;
    for (int i = 0; i < n; i++) {
        run += s[i];
        assert_int_equal(r[CANARY + i], above[i] + run);
        if (tp[i] != r[CANARY + i])
            fail_msg("%s et_integral_row n=%d off=%d mode=%d: %d: c=%u %s=%u", isa, n, off, mode, i, r[CANARY + i], isa,
                     tp[i]);
    }
    free(bs), free(above), free(r), free(t);
}

static void run_thresh(const fv_eyetrack_dsp *d, const char *isa, int n, int off, int mode)
{
    static const int ts[] = { 0, 1, 2, 127, 128, 129, 200, 254, 255, 256, -1 };
    uint8_t *bs, *br, *bt;
    uint8_t *s = in8(n, off, &bs);
    fill8(s, n, mode);
    uint8_t *r = checkasm_out_u8(n, off, &br), *t = checkasm_out_u8(n, off, &bt);
    for (int k = 0; k < (int)(sizeof ts / sizeof ts[0]); k++) {
        const int th = ts[k] < 0 ? (int)(fv_test_rand(&checkasm_rng) % 257) : ts[k];
        const int cr = fv_et_thresh_row_c(r, s, n, th), ct = d->et_thresh_row(t, s, n, th);
        checkasm_check_guards(t, (size_t)n, isa, "et_thresh_row", n);
        int want = 0;
        for (int i = 0; i < n; i++) {
            assert_int_equal(r[i], s[i] >= th ? 255 : 0);
            want += s[i] >= th;
            if (t[i] != r[i])
                fail_msg("%s et_thresh_row n=%d t=%d: pixel %d (%d): c=%d %s=%d", isa, n, th, i, s[i], r[i], isa, t[i]);
        }
        assert_int_equal(cr, want);
        if (ct != cr)
            fail_msg("%s et_thresh_row n=%d t=%d: count c=%d %s=%d", isa, n, th, cr, isa, ct);
    }
    free(bs), free(br), free(bt);
}

/* Box and ring scores over the integral image of a random (dout + 1) x (n + dout) image: ring
 * half-size ko >= box half-size k, the box centred in the ring. M_EXTREME offsets the integral
 * image by nearly 2^32 (its sums wrap; the box sums do not). */
static void run_box_score(const fv_eyetrack_dsp *d, const char *isa, int n, int off, int mode)
{
    const int k = (int)(fv_test_rand(&checkasm_rng) % 12), ko = k + (int)(fv_test_rand(&checkasm_rng) % 8);
    const int din = 2 * k + 1, dout = 2 * ko + 1, iw = n + dout, ih = dout + 1;
    uint8_t *bimg;
    uint8_t *img = in8(iw * ih, off, &bimg);
    fill8(img, iw * ih, mode);
    const uint32_t base = mode == M_EXTREME ? 0xfffff000u : (uint32_t)(fv_test_rand(&checkasm_rng) >> 48);
    uint32_t *bii = malloc(((size_t)iw * (ih + 1) + (size_t)off) * sizeof *bii);
    assert_non_null(bii);
    uint32_t *ii = bii + off; /* rows (ih + 1) of iw: a zero-sum first row and column */
    for (int y = 0; y <= ih; y++)
        for (int x = 0; x < iw; x++)
            ii[y * iw + x] = base + (y && x ? (ii[(y - 1) * iw + x] - base) + (ii[y * iw + x - 1] - base) -
                                                  (ii[(y - 1) * iw + x - 1] - base) + img[(y - 1) * iw + x - 1]
                                            : 0);
    const uint32_t *ot = ii, *ob = ii + dout * iw, *it = ii + (ko - k) * iw + (ko - k), *ib = it + din * iw;
    const float inv_a = 1.0f / (float)(din * din), inv_r = 1.0f / (float)(dout * dout - din * din + (ko == k));
    const float dark = mode == M_ZERO ? 0.0f : 255.0f * fv_test_randf(&checkasm_rng);
    float *r = malloc(((size_t)n + 2 * CANARY) * sizeof *r), *t = malloc(((size_t)n + 2 * CANARY + 1) * sizeof *t);
    assert_non_null(r);
    assert_non_null(t);
    const float fcanary = -12345.678f;
    for (int i = 0; i < n + 2 * CANARY + 1; i++)
        t[i] = fcanary;
    float *tp = t + CANARY + (off & 1); /* 4-byte aligned, not 16 */
    const float mr = fv_et_box_score_row_c(r, it, ib, din, ot, ob, dout, n, inv_a, inv_r, dark);
    const float mt = d->et_box_score_row(tp, it, ib, din, ot, ob, dout, n, inv_a, inv_r, dark);
    for (int i = 1; i <= CANARY; i++)
        if (memcmp(&tp[-i], &fcanary, sizeof fcanary) || memcmp(&tp[n + i - 1], &fcanary, sizeof fcanary))
            fail_msg("%s et_box_score_row n=%d: wrote outside its output", isa, n);
    float want_max = -INFINITY;
    for (int i = 0; i < n; i++) {
        /* the reference against the formula, the sums straight from the image */
        uint32_t si = 0, so = 0;
        for (int y = 0; y < dout; y++)
            for (int x = 0; x < dout; x++) {
                const int v = img[y * iw + i + x];
                if (y >= ko - k && y < ko + k + 1 && x >= ko - k && x < ko + k + 1)
                    si += (uint32_t)v;
                else
                    so += (uint32_t)v;
            }
        const float mi = (float)si * inv_a, mo = (float)so * inv_r, want = (mo - mi) - (mi - dark);
        if (memcmp(&r[i], &want, sizeof want))
            fail_msg("c et_box_score_row n=%d: %d: %.9g, formula %.9g", n, i, (double)r[i], (double)want);
        want_max = want > want_max ? want : want_max;
        if (memcmp(&tp[i], &r[i], sizeof r[i]))
            fail_msg("%s et_box_score_row n=%d off=%d mode=%d k=%d ko=%d: %d: c=%.9g %s=%.9g", isa, n, off, mode, k, ko, i,
                     (double)r[i], isa, (double)tp[i]);
    }
    if (!(mr == want_max))
        fail_msg("c et_box_score_row n=%d: max %.9g, want %.9g", n, (double)mr, (double)want_max);
    if (!(mt == mr))
        fail_msg("%s et_box_score_row n=%d: max c=%.9g %s=%.9g", isa, n, (double)mr, isa, (double)mt);
    free(bimg), free(bii), free(r), free(t);
}

static void run_all(const char *kernel, runner fn, size_t member)
{
    int tested = 0;
    fv_eyetrack_dsp ref;
    fv_eyetrack_dsp_init(&ref, FV_ISA_C);
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, kernel))
            continue;
        fv_eyetrack_dsp d;
        fv_eyetrack_dsp_init(&d, isa);
        void *pr, *pd;
        memcpy(&pr, (char *)&ref + member, sizeof pr);
        memcpy(&pd, (char *)&d + member, sizeof pd);
        if (!pd || pr == pd) /* an ISA this build has must implement the kernel: a failure, not a skip */
            fail_msg("%s: %s has no version of its own", kernel, fv_isa_name(isa));
        int runs = 0;
        for (int si = 0; si < NSIZES; si++)
            for (int off = 0; off < 3; off++)
                for (int mode = 0; mode < M_COUNT; mode++, runs++)
                    fn(&d, fv_isa_name(isa), sizes[si], off, mode);
        for (int r = 0; r < 100; r++, runs++)
            fn(&d, fv_isa_name(isa), 1 + (int)(fv_test_rand(&checkasm_rng) % 400), (int)(fv_test_rand(&checkasm_rng) % 17), M_RANDOM);
        printf("[ checkasm ] %s: %-7s == c on %d rows (exact)\n", kernel, fv_isa_name(isa), runs);
        tested++;
    }
    printf("[ checkasm ] %s: %d ISA version(s) tested\n", kernel, tested);
}

static void run_box3(const fv_eyetrack_dsp *d, const char *isa, int n, int off, int mode)
{
    uint8_t *b0, *b1, *b2, *br, *bt;
    uint8_t *r0 = in8(n, off, &b0), *r1 = in8(n, off + 1, &b1), *r2 = in8(n, off + 2, &b2);
    fill8(r0, n, mode);
    fill8(r1, n, mode);
    fill8(r2, n, mode);
    uint8_t *r = checkasm_out_u8(n, off, &br), *t = checkasm_out_u8(n, off, &bt);
    fv_et_box3_row_c(r, r0, r1, r2, n);
    d->et_box3_row(t, r0, r1, r2, n);
    checkasm_check_guards(t, (size_t)n, isa, "et_box3_row", n);
    for (int i = 0; i < n; i++) {
        /* the reference against the formula, edges replicated */
        int s = 0;
        for (int k = -1; k <= 1; k++) {
            const int c = i + k < 0 ? 0 : i + k >= n ? n - 1 : i + k;
            s += r0[c] + r1[c] + r2[c];
        }
        assert_int_equal(r[i], (s * 3641 + 16384) >> 15);
        if (t[i] != r[i])
            fail_msg("%s et_box3_row n=%d off=%d mode=%d: pixel %d: c=%d %s=%d", isa, n, off, mode, i, r[i], isa, t[i]);
    }
    free(b0), free(b1), free(b2), free(br), free(bt);
}

static void test_down2(void **state)
{
    (void)state;
    run_all("et_down2_row", run_down2, offsetof(fv_eyetrack_dsp, et_down2_row));
}
static void test_integral(void **state)
{
    (void)state;
    run_all("et_integral_row", run_integral, offsetof(fv_eyetrack_dsp, et_integral_row));
}
static void test_thresh(void **state)
{
    (void)state;
    run_all("et_thresh_row", run_thresh, offsetof(fv_eyetrack_dsp, et_thresh_row));
}

static void test_box_score(void **state)
{
    (void)state;
    run_all("et_box_score_row", run_box_score, offsetof(fv_eyetrack_dsp, et_box_score_row));
}

static void test_box3(void **state)
{
    (void)state;
    run_all("et_box3_row", run_box3, offsetof(fv_eyetrack_dsp, et_box3_row));
}

static void test_reference_by_hand(void **state)
{
    (void)state;
    /* (0+1+2+3+2)>>2 = 2, (255*4+2)>>2 = 255, (1+0+0+0+2)>>2 = 0, (1+1+0+0+2)>>2 = 1 */
    const uint8_t a[8] = { 0, 1, 255, 255, 1, 0, 1, 1 }, b[8] = { 2, 3, 255, 255, 0, 0, 0, 0 };
    uint8_t o[4];
    fv_et_down2_row_c(o, a, b, 4);
    assert_int_equal(o[0], 2);
    assert_int_equal(o[1], 255);
    assert_int_equal(o[2], 0);
    assert_int_equal(o[3], 1);
    const uint32_t above[4] = { 10, 20, 30, 0xffffffffu };
    const uint8_t s[4] = { 1, 2, 3, 4 };
    uint32_t ii[4];
    fv_et_integral_row_c(ii, above, s, 4);
    assert_int_equal(ii[0], 11);
    assert_int_equal(ii[1], 23);
    assert_int_equal(ii[2], 36);
    assert_int_equal(ii[3], 9); /* 0xffffffff + 10 wraps */
    uint8_t m[4];
    assert_int_equal(fv_et_thresh_row_c(m, s, 4, 3), 2);
    assert_int_equal(m[0], 0);
    assert_int_equal(m[2], 255);
    /* box3: a constant v comes back as v (9 v 3641 = 32769 v), for every v; a lone 255 in the
     * middle row gives 255 / 9 = 28.33 -> 28 at it and its two neighbours, 0 beyond; at the left
     * edge the replicated column counts twice: 2 * 90 / 9 = 20 */
    uint8_t c0[5], c1[5], c2[5], bo[5];
    for (int v = 0; v < 256; v++) {
        memset(c0, v, 5), memset(c1, v, 5), memset(c2, v, 5);
        fv_et_box3_row_c(bo, c0, c1, c2, 5);
        for (int i = 0; i < 5; i++)
            assert_int_equal(bo[i], v);
    }
    memset(c0, 0, 5), memset(c1, 0, 5), memset(c2, 0, 5);
    c1[2] = 255;
    fv_et_box3_row_c(bo, c0, c1, c2, 5);
    assert_int_equal(bo[0], 0);
    assert_int_equal(bo[1], 28);
    assert_int_equal(bo[2], 28);
    assert_int_equal(bo[3], 28);
    assert_int_equal(bo[4], 0);
    c1[2] = 0, c0[0] = 90;
    fv_et_box3_row_c(bo, c0, c1, c2, 5);
    assert_int_equal(bo[0], 20);
    assert_int_equal(bo[1], 10);
    assert_int_equal(bo[2], 0);
}

const struct CMUnitTest checkasm_eyetrack_tests[] = {
    cmocka_unit_test(test_tables),
    cmocka_unit_test(test_reference_by_hand),
    cmocka_unit_test(test_down2),
    cmocka_unit_test(test_integral),
    cmocka_unit_test(test_thresh),
    cmocka_unit_test(test_box_score),
    cmocka_unit_test(test_box3),
    {0},
};
