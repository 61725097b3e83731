/* Sampling pattern (Weier 2018, section 3.1): eq. (1), fovea coverage, transition density,
 * S_out density and evenness, and the row extraction against a per-pixel definition. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "camera.h"
#include "sampling.h"

#define W 1280
#define H 1440

static void make(fv_sampler *s, const fv_sampling_params *p)
{
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    fv_camera c;
    fv_pose pose = {{0, 0, 0}, {0, 0, 0, 1}};
    assert_int_equal(fv_camera_setup(&c, &d, &pose), 0);
    assert_int_equal(fv_sampler_init(s, W, H, c.focal_px, p), 0);
}

static int bit(const fv_sampler *s, int x, int y, int gx, int gy)
{
    return (int)(fv_sampler_row(s, x, y, 1, gx, gy, 0) & 1);
}

/* Eq. (1) inverts the CDF F(x) = c (x - (1 - p) x^2 / 2), c = 2 / (1 + p), of f(x) = 1 - x(1 - p). */
static void test_eq1_inverts_cdf(void **st)
{
    (void)st;
    fv_sampling_params p;
    fv_sampling_params_default(&p);
    const float pm[] = {0.05f, 0.2f, 0.5f, 0.9f};
    for (int k = 0; k < 4; k++) {
        p.p_min = pm[k];
        assert_float_equal(fv_sampling_radius(&p, 0.0f), p.r0_deg, 1e-5);
        assert_float_equal(fv_sampling_radius(&p, 1.0f), p.r1_deg, 1e-4);
        for (int i = 1; i < 20; i++) {
            double u = i / 20.0;
            double x = (fv_sampling_radius(&p, (float)u) - p.r0_deg) / (p.r1_deg - p.r0_deg);
            double F = 2.0 / (1.0 + pm[k]) * (x - (1.0 - pm[k]) * x * x / 2.0);
            assert_float_equal(F, u, 1e-5);
        }
    }
}

static void test_fovea_full(void **st)
{
    (void)st;
    fv_sampling_params p;
    fv_sampling_params_default(&p);
    fv_sampler s;
    make(&s, &p);
    const int gaze[][2] = {{640, 720}, {100, 200}, {1270, 1430}, {0, 0}};
    for (int g = 0; g < 4; g++) {
        int gx = gaze[g][0], gy = gaze[g][1], n = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                double d2 = (double)(x - gx) * (x - gx) + (double)(y - gy) * (y - gy);
                if (d2 < (double)s.r0_px * s.r0_px) {
                    assert_int_equal(bit(&s, x, y, gx, gy), 1);
                    n++;
                }
            }
        assert_true(n > 1000);
    }
    fv_sampler_free(&s);
}

/* Per-ring density of the transition against eq. (1)'s expected density lambda(r) (samples per
 * pixel): collisions can only lose samples, so d <= min(1, lambda); a Halton sequence collides
 * no more than independent points, so d >= 1 - exp(-lambda) (Poisson coverage). */
static void test_transition_density(void **st)
{
    (void)st;
    const float pms[] = {0.2f, 0.4f};
    for (int k = 0; k < 2; k++) {
        fv_sampling_params p;
        fv_sampling_params_default(&p);
        p.p_min = pms[k];
        fv_sampler s;
        make(&s, &p);
        int gx = 640, gy = 720;
        int rings = 10;
        for (int r = 0; r < rings; r++) {
            double ra = p.r0_deg + (p.r1_deg - p.r0_deg) * r / rings;
            double rb = p.r0_deg + (p.r1_deg - p.r0_deg) * (r + 1) / rings;
            long set = 0, tot = 0;
            double lam = 0.0;
            for (int y = gy - s.rin; y <= gy + s.rin; y++)
                for (int x = gx - s.rin; x <= gx + s.rin; x++) {
                    double e = sqrt((double)(x - gx) * (x - gx) + (double)(y - gy) * (y - gy)) / s.ppd;
                    if (e < ra || e >= rb || e >= p.r1_deg - 1e-6)
                        continue;
                    tot++;
                    set += bit(&s, x, y, gx, gy);
                    lam += fv_sampling_transition_density(&p, (float)e);
                }
            lam /= (double)tot;
            double d = (double)set / (double)tot;
            double lo = 1.0 - exp(-lam) - 0.02, hi = (lam < 1.0 ? lam : 1.0) + 0.02;
            if (d < lo || d > hi)
                fprintf(stderr, "p_min %.2f ring %.1f-%.1f deg: density %.3f, expected [%.3f, %.3f]\n", (double)p.p_min, ra,
                        rb, d, lo, hi);
            assert_true(d >= lo && d <= hi);
        }
        /* continuity at r1: the last ring meets S_out's p_min */
        assert_float_equal(fv_sampling_transition_density(&p, p.r1_deg), p.p_min, 1e-6);
        fv_sampler_free(&s);
    }
}

/* fv_sampler_rows (a tile's rows at once, the ray stage's call) gives fv_sampler_row's bits for
 * 16x16 tiles (and a narrower edge tile) all over the image, gazes at the centre, an edge and
 * outside, every phase, full and foveated. */
static void test_tile_rows_match_rows(void **st)
{
    (void)st;
    for (int variant = 0; variant < 2; variant++) {
        fv_sampling_params p;
        fv_sampling_params_default(&p);
        p.rotate = 1;
        p.full = variant == 1;
        fv_sampler s;
        make(&s, &p);
        static const int gaze[][2] = {{W / 2, H / 2}, {3, H - 2}, {W + 40, -30}, {W / 3, H / 4}};
        long inside = 0;
        for (int g = 0; g < 4; g++)
            for (int ph = 0; ph < s.phases + 1; ph++)
                for (int y0 = 0; y0 < H; y0 += 16)
                    for (int x0 = 0; x0 < W; x0 += 16) {
                        const int tw = W - x0 < 16 ? W - x0 : 16, th = H - y0 < 16 ? H - y0 : 16;
                        uint32_t rows[16];
                        fv_sampler_rows(&s, x0, y0, tw, th, gaze[g][0], gaze[g][1], ph, rows);
                        for (int y = 0; y < th; y++) {
                            const uint32_t want = (uint32_t)fv_sampler_row(&s, x0, y0 + y, tw, gaze[g][0], gaze[g][1], ph);
                            if (rows[y] != want)
                                fail_msg("tile %d,%d row %d gaze %d phase %d: %#x, want %#x", x0, y0, y, g, ph,
                                         rows[y], want);
                        }
                        const double dx = x0 + 8 - gaze[g][0], dy = y0 + 8 - gaze[g][1];
                        inside += dx * dx + dy * dy < (double)s.r1_px * s.r1_px;
                    }
        assert_true(inside > 0); /* tiles with S_in rows were among them */
        fv_sampler_free(&s);
    }
}

/* Rotating pattern (temporal reprojection): every phase keeps the static pattern's statistics,
 * phase 0 is the static pattern, the phases are periodic, and together they sample every
 * pixel of the periphery within K = ceil(1/p_min) frames. */
static void test_rotating_phases(void **st)
{
    (void)st;
    const float pms[] = {0.2f, 0.3f};
    for (int k = 0; k < 2; k++) {
        fv_sampling_params p;
        fv_sampling_params_default(&p);
        p.p_min = pms[k];
        fv_sampler st0, s;
        make(&st0, &p);
        p.rotate = 1;
        make(&s, &p);
        int K = (int)ceil(1.0 / p.p_min - 1e-6);
        assert_int_equal(st0.phases, 1);
        assert_int_equal(s.phases, K);
        int gx = 640, gy = 720;
        static uint64_t cover[H][(W + 63) / 64];
        memset(cover, 0, sizeof cover);
        for (int ph = 0; ph < K; ph++) {
            long set = 0, tot = 0;
            for (int y = 0; y < H; y++)
                for (int x = 0; x < W; x += 64) {
                    int n = W - x < 64 ? W - x : 64;
                    uint64_t b = fv_sampler_row(&s, x, y, n, gx, gy, ph);
                    cover[y][x >> 6] |= b;
                    assert_true(b == fv_sampler_row(&s, x, y, n, gx, gy, ph + K)); /* periodic */
                    if (ph == 0)
                        assert_true(b == fv_sampler_row(&st0, x, y, n, gx, gy, 0));
                    /* periphery density: pixels beyond r1 + 1 only */
                    for (int i = 0; i < n; i++) {
                        double dx = x + i - gx, dy = y - gy;
                        if (dx * dx + dy * dy < (s.r1_px + 1.0) * (s.r1_px + 1.0))
                            continue;
                        tot++;
                        set += (long)((b >> i) & 1);
                    }
                }
            assert_float_equal((double)set / tot, p.p_min, 0.003);
        }
        /* outside r1 every pixel is covered by the K phases together */
        long holes = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                double dx = x - gx, dy = y - gy;
                if (dx * dx + dy * dy >= (double)s.r1_px * s.r1_px && !((cover[y][x >> 6] >> (x & 63)) & 1))
                    holes++;
            }
        assert_int_equal(holes, 0);
        /* the acuity probability the reprojection uses */
        assert_float_equal(fv_sampler_probability(&s, 0.0f, 0.0f), 1.0f, 0.0);
        assert_float_equal(fv_sampler_probability(&s, s.r1_px + 5.0f, 0.0f), p.p_min, 0.0);
        float rmid = 0.5f * (s.r0_px + s.r1_px);
        float want = fv_sampling_transition_density(&p, rmid / s.ppd);
        want = want > 1.0f ? 1.0f : want;
        assert_float_equal(fv_sampler_probability(&s, 0.0f, rmid), want, 1e-5);
        fv_sampler_free(&st0);
        fv_sampler_free(&s);
    }
}

static void test_sout_density_and_evenness(void **st)
{
    (void)st;
    const float pms[] = {0.05f, 0.2f, 0.5f};
    for (int k = 0; k < 3; k++) {
        fv_sampling_params p;
        fv_sampling_params_default(&p);
        p.p_min = pms[k];
        fv_sampler s;
        make(&s, &p);
        long set = 0;
        int gx = -100000, gy = -100000; /* gaze far away: periphery everywhere */
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x += 64) {
                int n = W - x < 64 ? W - x : 64;
                set += __builtin_popcountll(fv_sampler_row(&s, x, y, n, gx, gy, 0));
            }
        double d = (double)set / ((double)W * H);
        assert_float_equal(d, p.p_min, 0.002);
        /* Evenness: no window of side ceil(2/sqrt(p)) is empty (white noise leaves ~e^-4 of them
         * empty, thousands per image). */
        int win = (int)ceil(2.0 / sqrt(p.p_min));
        for (int y = 0; y + win <= H; y += 3)
            for (int x = 0; x + win <= W; x += 3) {
                uint64_t any = 0;
                for (int j = 0; j < win; j++)
                    any |= fv_sampler_row(&s, x, y + j, win, gx, gy, 0);
                if (!any)
                    fprintf(stderr, "empty %dx%d window at %d,%d (p_min %.2f)\n", win, win, x, y, (double)p.p_min);
                assert_true(any != 0);
            }
        fv_sampler_free(&s);
    }
}

/* Row extraction against the per-pixel definition: S_in inside the r1 disc around the gaze,
 * S_out elsewhere; arbitrary spans, gazes near and past the edges. */
static void test_row_matches_per_pixel(void **st)
{
    (void)st;
    fv_sampling_params p;
    fv_sampling_params_default(&p);
    fv_sampler s;
    make(&s, &p);
    uint64_t rng = 7;
    double r1sq = (double)s.r1_px * s.r1_px;
    for (int it = 0; it < 20000; it++) {
        int gx = (int)(fv_test_rand(&rng) % (W + 600)) - 300, gy = (int)(fv_test_rand(&rng) % (H + 600)) - 300;
        int y = (int)(fv_test_rand(&rng) % H);
        int n = 1 + (int)(fv_test_rand(&rng) % 64);
        int x0 = (int)(fv_test_rand(&rng) % (W - n + 1));
        uint64_t row = fv_sampler_row(&s, x0, y, n, gx, gy, 0);
        for (int i = 0; i < n; i++) {
            int x = x0 + i, dx = x - gx, dy = y - gy, want;
            if ((double)dx * dx + (double)dy * dy < r1sq)
                want = (int)((s.s_in[(size_t)(dy + s.rin) * s.in_stride + ((dx + s.rin) >> 6)] >> ((dx + s.rin) & 63)) & 1);
            else
                want = (int)((s.s_out[(size_t)y * s.out_stride + (x >> 6)] >> (x & 63)) & 1);
            assert_int_equal((int)((row >> i) & 1), want);
        }
        if (n < 64)
            assert_int_equal(row >> n, 0);
    }
    fv_sampler_free(&s);
}

static void test_full_and_ratio(void **st)
{
    (void)st;
    fv_sampling_params p;
    fv_sampling_params_default(&p);
    fv_sampler s;
    make(&s, &p);
    long set = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x += 64)
            set += __builtin_popcountll(fv_sampler_row(&s, x, y, W - x < 64 ? W - x : 64, 640, 720, 0));
    double ratio = (double)set / ((double)W * H);
    printf("samples at the defaults, gaze centred: %ld of %d (%.3f)\n", set, W * H, ratio);
    /* p_min everywhere plus the fovea and transition: above p_min, far below full */
    assert_true(ratio > p.p_min + 0.01 && ratio < 0.4);
    fv_sampler_free(&s);
    p.full = 1;
    make(&s, &p);
    assert_true(fv_sampler_row(&s, 0, 0, 64, 640, 720, 0) == ~0ull);
    assert_true(fv_sampler_row(&s, 1216, 1439, 64, 0, 0, 0) == ~0ull);
    fv_sampler_free(&s);
    /* bad parameters are refused */
    p.full = 0;
    p.r0_deg = 30.0f;
    assert_int_equal(fv_sampler_init(&s, W, H, 600.0f, &p), -1);
    p.r0_deg = 10.0f;
    p.p_min = 0.0f;
    assert_int_equal(fv_sampler_init(&s, W, H, 600.0f, &p), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_eq1_inverts_cdf),        cmocka_unit_test(test_fovea_full),
        cmocka_unit_test(test_transition_density),     cmocka_unit_test(test_sout_density_and_evenness),
        cmocka_unit_test(test_row_matches_per_pixel),  cmocka_unit_test(test_full_and_ratio),
        cmocka_unit_test(test_rotating_phases),        cmocka_unit_test(test_tile_rows_match_rows),
    };
    return cmocka_run_group_tests_name("sampling", tests, NULL, NULL);
}
