/* fovea checkasm: the output kernel (output_dsp.h), every ISA version against the C reference
 * on random and edge-case values (negative, zero, the table's step edges, 1 and above, NaN, Inf,
 * huge): with the sRGB table, within the contract's bound (AVX2 computes sRGB: 1; the others
 * read the table: bit for bit), and with a table of unrelated bytes, where a wrong index shows,
 * bit for bit for the versions that read it; outputs canaried, inputs exact-size. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkasm.h"

#include "output_dsp.h"

static const char *const names[] = {"rgb8_row", "lca_row"};
static const int sizes[] = {1, 2, 3, 7, 8, 9, 15, 16, 17, 31, 33, 64, 641, 1280, 1281};
#define NSIZES ((int)(sizeof sizes / sizeof sizes[0]))

/* a table with every entry distinct enough that a wrong index shows, or the sRGB table; padded
 * as the contract says */
static uint8_t lut[FV_SRGB_LUT + 1 + FV_SRGB_LUT_PAD];

/* the versions that compute sRGB rather than read the table (their bound against it) */
static unsigned computed_bound(unsigned isa) { return isa == FV_ISA_AVX2 ? 1u : CHECKASM_EXACT; }

static void test_tables(void **state)
{
    (void)state;
    checkasm_rng = 0x7b8c0de5ull;
    fv_output_dsp ref;
    fv_output_dsp_init(&ref, FV_ISA_C);
    assert_true(ref.rgb8_row == fv_rgb8_row_c);
    CHECKASM_CHECK_ISA_TABLES("output", fv_output_dsp, &ref, names);
}

static float gen(int mode)
{
    static const float edge[] = {0.0f, -0.0f, 1.0f, 0.99999994f, 1.0000001f, -1.0f, 2.0f, 1e30f, -1e30f,
                                 1.4e-45f, 1e-38f, 0.5f / 4096.0f, 1.5f / 4096.0f, 0.49999997f / 4096.0f,
                                 4095.5f / 4096.0f, 4095.4999f / 4096.0f, NAN, -NAN, INFINITY, -INFINITY};
    const float u = checkasm_randf();
    if (mode == 1)
        return edge[checkasm_rand() % (sizeof edge / sizeof edge[0])];
    if (mode == 2) /* exactly on and around the table's rounding edges */
        return ((float)(checkasm_rand() % 4097) + (checkasm_rand() & 1 ? 0.5f : 0.4999f)) / 4096.0f;
    return u * 1.2f - 0.1f;
}

static void run_rgb8(int srgb)
{
    if (srgb)
        fv_srgb_lut_init(lut);
    else
        for (int i = 0; i < (int)sizeof lut; i++)
            lut[i] = (uint8_t)(i * 7 + (i >> 8));
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "rgb8_row") || (!srgb && computed_bound(isa) != CHECKASM_EXACT))
            continue;
        fv_output_dsp d;
        fv_output_dsp_init(&d, isa == FV_ISA_AVX2 ? FV_ISA_SSE41 | FV_ISA_AVX2 : isa);
        long differ = 0, total = 0;
        for (int mode = 0; mode < 3; mode++)
            for (int s = 0; s < NSIZES; s++)
                for (int off = 0; off < 3; off++) {
                    const int n = sizes[s];
                    buf in = buf_new(4 * (size_t)n, off);
                    for (int i = 0; i < 4 * n; i++)
                        in.p[i] = gen(mode);
                    uint8_t *rb, *tb;
                    uint8_t *r = checkasm_out_u8(3 * (size_t)n, off, &rb), *t = checkasm_out_u8(3 * (size_t)n, off, &tb);
                    fv_rgb8_row_c(r, in.p, n, lut);
                    d.rgb8_row(t, in.p, n, lut);
                    checkasm_check_guards(t, 3 * (size_t)n, fv_isa_name(isa), "rgb8_row", n);
                    checkasm_compare(r, t, 3 * (size_t)n, CHECKASM_U8, 3, srgb ? computed_bound(isa) : CHECKASM_EXACT,
                                     "%s rgb8_row %s table n=%d off=%d mode=%d", fv_isa_name(isa),
                                     srgb ? "sRGB" : "test", n, off, mode);
                    for (int i = 0; i < 3 * n; i++) {
                        differ += r[i] != t[i];
                        /* the exact ends: v <= 0 or NaN gives 0, v >= 1 gives 255 */
                        const float v = in.p[4 * (i / 3) + i % 3];
                        if (srgb && !(v > 0.0f))
                            assert_int_equal(t[i], 0);
                        if (srgb && v >= 1.0f)
                            assert_int_equal(t[i], 255);
                    }
                    total += 3 * n;
                    free(rb), free(tb), free(in.base);
                }
        if (srgb && computed_bound(isa) != CHECKASM_EXACT) {
            printf("[ checkasm ] rgb8_row %s: %ld of %ld bytes 1 off the table\n", fv_isa_name(isa), differ, total);
            assert_true(differ < total / 10); /* a bound of 1 is not a licence to be off everywhere */
        }
    }
}

static void test_rgb8_row(void **state)
{
    (void)state;
    run_rgb8(0);
    run_rgb8(1);
}

/* the reference against the formula: index = round-half-up of v * 4096, clamped, NaN -> 0 */
static void test_reference(void **state)
{
    (void)state;
    for (int i = 0; i < (int)sizeof lut; i++)
        lut[i] = (uint8_t)i; /* low byte of the index */
    const float v[] = {-1.0f, 0.0f, 0.25f / 4096.0f, 0.5f / 4096.0f, 0.5f, 1.0f, 7.0f, NAN};
    const int want[] = {0, 0, 0, 1, 2048, 4096, 4096, 0};
    float in[4 * 8];
    for (int i = 0; i < 8; i++)
        in[4 * i] = in[4 * i + 1] = in[4 * i + 2] = v[i], in[4 * i + 3] = NAN; /* depth never read */
    uint8_t out[24];
    fv_rgb8_row_c(out, in, 8, lut);
    for (int i = 0; i < 8; i++)
        for (int c = 0; c < 3; c++)
            assert_int_equal(out[3 * i + c], (uint8_t)want[i]);
}

/* lca_row: a w x h image of random and edge values, a lens whose centre lies inside, on the
 * edge or outside the image, ratio tables around 1 (and far off it, so that taps leave the
 * image and clamp); every ISA version gives the reference's bytes (the contract: the same
 * operations in the same order) */
static void fill_lca(fv_lens_lca *l, int mode)
{
    memset(l, 0, sizeof *l);
    l->on = 1;
    l->r_max = 1.2f + checkasm_randf();
    l->inv_step = (float)FV_LENS_LCA_STEPS / l->r_max;
    for (int ch = 0; ch < 2; ch++)
        for (int i = 0; i <= FV_LENS_LCA_STEPS; i++) {
            const float r = (float)i / FV_LENS_LCA_STEPS;
            l->ratio[ch][i] = mode == 0 ? 1.0f + (ch ? -0.01f : 0.012f) * r * r : 0.5f + 1.5f * checkasm_randf();
        }
}

static void test_lca_row(void **state)
{
    (void)state;
    checkasm_rng = 0x1ca0f00dull;
    fv_srgb_lut_init(lut);
    static const int ws[] = {1, 7, 8, 9, 17, 64, 131};
    static fv_lens_lca lca;
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "lca_row"))
            continue;
        fv_output_dsp d;
        fv_output_dsp_init(&d, isa == FV_ISA_AVX2 ? FV_ISA_SSE41 | FV_ISA_AVX2 : isa);
        for (int trial = 0; trial < 42; trial++) {
            const int w = ws[trial % 7], h = 1 + (int)(checkasm_rand() % 23), mode = trial % 3;
            const ptrdiff_t stride = w + (ptrdiff_t)(checkasm_rand() % 3);
            buf img = buf_new(4 * (size_t)stride * (size_t)h, trial % 3);
            for (ptrdiff_t i = 0; i < 4 * stride * h; i++)
                img.p[i] = gen(mode == 2 ? 1 : 0);
            fill_lca(&lca, mode == 1);
            const float pt = 0.01f + 0.02f * checkasm_randf(), tl = -0.5f * pt * (float)w, tt = 0.5f * pt * (float)h;
            const float where = (float)(checkasm_rand() % 3); /* the lens centre: inside, on a corner, outside */
            const fv_lca_geom g = {tl, tt, pt, 1.0f / pt, tl + where * 0.6f * pt * (float)w, tt - where * 0.5f * pt * (float)h,
                                   img.p, stride, w, h};
            for (int y = 0; y < h; y++) {
                uint8_t *rb, *tb;
                uint8_t *r = checkasm_out_u8(3 * (size_t)w, y % 3, &rb), *t = checkasm_out_u8(3 * (size_t)w, y % 3, &tb);
                fv_lca_row_c(r, y, &g, &lca, lut);
                d.lca_row(t, y, &g, &lca, lut);
                checkasm_check_guards(t, 3 * (size_t)w, fv_isa_name(isa), "lca_row", w);
                checkasm_compare(r, t, 3 * (size_t)w, CHECKASM_U8, 3, CHECKASM_EXACT, "%s lca_row trial=%d w=%d h=%d y=%d",
                                 fv_isa_name(isa), trial, w, h, y);
                free(rb), free(tb);
            }
            free(img.base);
        }
    }
}

/* the reference on a hand case: ratios of exactly 1 (no aberration) and a pixel grid whose
 * coordinates are exact in binary, so red and blue read their own pixel: the bytes of the plain
 * conversion (fv_rgb8_row_c) */
static void test_lca_identity(void **state)
{
    (void)state;
    fv_srgb_lut_init(lut);
    enum { W = 37, H = 5 };
    static float img[4 * W * H];
    for (int i = 0; i < 4 * W * H; i++)
        img[i] = (float)((i * 2654435761u) % 1000u) / 900.0f - 0.05f;
    static fv_lens_lca lca;
    lca.on = 1, lca.r_max = 1.0f, lca.inv_step = (float)FV_LENS_LCA_STEPS;
    for (int ch = 0; ch < 2; ch++)
        for (int i = 0; i <= FV_LENS_LCA_STEPS; i++)
            lca.ratio[ch][i] = 1.0f;
    const fv_lca_geom g = {-0.0625f, 0.03125f, 1.0f / 256.0f, 256.0f, 0.01171875f, -0.0078125f, img, W, W, H};
    for (int y = 0; y < H; y++) {
        uint8_t a[3 * W], b[3 * W];
        fv_lca_row_c(a, y, &g, &lca, lut);
        fv_rgb8_row_c(b, img + 4 * W * y, W, lut);
        assert_memory_equal(a, b, sizeof a);
    }
    /* and a shift that cannot be identity: ratios of 2 move red and blue away from the centre */
    for (int ch = 0; ch < 2; ch++)
        for (int i = 0; i <= FV_LENS_LCA_STEPS; i++)
            lca.ratio[ch][i] = 2.0f;
    int moved = 0;
    for (int y = 0; y < H; y++) {
        uint8_t a[3 * W], b[3 * W];
        fv_lca_row_c(a, y, &g, &lca, lut);
        fv_rgb8_row_c(b, img + 4 * W * y, W, lut);
        for (int x = 0; x < W; x++)
            moved += a[3 * x] != b[3 * x], assert_int_equal(a[3 * x + 1], b[3 * x + 1]); /* green is its own */
    }
    assert_true(moved > W);
}

const struct CMUnitTest checkasm_output_tests[] = {
    cmocka_unit_test(test_tables),
    cmocka_unit_test(test_reference),
    cmocka_unit_test(test_rgb8_row),
    cmocka_unit_test(test_lca_row),
    cmocka_unit_test(test_lca_identity),
    {0},
};
