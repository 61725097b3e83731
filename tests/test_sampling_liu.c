/* Liu et al.'s polar sampler (core/sampling_liu.c): eq. 2 against eq. 1 and eq. 3, the measured
 * density of every ring against eq. 1's lambda(alpha), the saturated fovea, the ray count matched
 * to Weier's, the rotation over frames, and the row extraction (a pattern that moves with the
 * gaze by whole pixels). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "camera.h"
#include "sampling.h"
#include "sampling_liu.h"

#define W 1280
#define H 1440
#define PI_D 3.14159265358979323846

static float focal_default(void)
{
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    fv_camera c;
    fv_pose pose = {{0, 0, 0}, {0, 0, 0, 1}};
    assert_int_equal(fv_camera_setup(&c, &d, &pose), 0);
    return c.focal_px;
}

static void make(fv_sampler *s, float l0, int rotate)
{
    fv_sampling_params p;
    fv_sampling_params_default(&p);
    p.kind = FV_SAMPLER_LIU;
    p.liu_density = l0;
    p.rotate = rotate;
    assert_int_equal(fv_sampler_init(s, W, H, focal_default(), &p), 0);
}

static long count(const fv_sampler *s, int gx, int gy, int phase)
{
    long n = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x += 64)
            n += __builtin_popcountll(fv_sampler_row(s, x, y, W - x < 64 ? W - x : 64, gx, gy, phase));
    return n;
}

/* eq. 2 is the integral of eq. 1 (its derivative, by central differences), continuous at
 * alpha_F, inverted exactly; eq. 1 over the ring 2 pi alpha is 1 in the fovea and 7.49 /
 * (0.3 alpha + 1)^2 beyond; the paper's eq. 3 fits the inverse normalised to 80 deg. */
static void test_equations(void **st)
{
    (void)st;
    for (double a = 0.25; a < 150.0; a += 0.25) {
        if (fabs(a - FV_LIU_ALPHA_F) < 0.01)
            continue;
        const double h = 1e-4, d = (fv_liu_cdf(a + h) - fv_liu_cdf(a - h)) / (2.0 * h);
        assert_float_equal(d, fv_liu_ring_density(a), 1e-5 * fv_liu_ring_density(a));
        const double u = 0.3 * a + 1.0, rel = a <= FV_LIU_ALPHA_F ? 1.0 : 7.49 / (u * u);
        assert_float_equal(fv_liu_ring_density(a) / (2.0 * PI_D * a), rel, 1e-12);
        assert_float_equal(fv_liu_relative_density(a), rel, 1e-12);
        assert_float_equal(fv_liu_cdf_inv(fv_liu_cdf(a)), a, 1e-9 * a);
    }
    const double e = 1e-9, aF = FV_LIU_ALPHA_F;
    assert_float_equal(fv_liu_cdf(aF + e), fv_liu_cdf(aF - e), 1e-6);
    assert_float_equal(fv_liu_cdf(aF), PI_D * aF * aF, 1e-9);
    /* the paper's eq. 2 as printed (166.4 for 14.98 / 0.3^2 = 166.44, 612.3 for 612.03): within
     * 0.1 % at 90 deg */
    const double u90 = 0.3 * 90.0 + 1.0;
    assert_float_equal((1.0 / u90 + log(u90)) * 166.4 * PI_D - 612.3, fv_liu_cdf(90.0), 1.0);
    /* eq. 3 (a least-squares polynomial) within 0.4 deg of the exact inverse for alpha_M = 80 */
    const double total = fv_liu_cdf(80.0);
    for (double r = 0.05; r <= 1.0 + 1e-9; r += 0.01)
        assert_float_equal(fv_liu_eq3(r), fv_liu_cdf_inv(r * total), 0.4);
}

/* Measured density against eq. 1's lambda(alpha) (samples per pixel), gaze at the centre, every
 * phase: every pixel inside the saturated disc; beyond it, in blocks of 8 polar rings (pixels
 * binned by their nearest ring, rho = eq. 2 of their eccentricity, so a block holds exactly 8
 * rings of samples), the density d over the block's pixels against the mean lambda there:
 * polar samples rounded to pixels can only collide, so d <= min(1, lambda), and the grid
 * (cells about a pixel or more apart) collides no more than independent points, d >= 1 -
 * exp(-lambda) (Poisson coverage); where the cells are wider than sqrt(2) px, d = lambda. */
static void test_ring_density(void **st)
{
    (void)st;
    const float l0s[] = {1.0f, 2.0f, 5.0f, 12.0f};
    enum { M = 8, BLOCKS = 400 };
    for (int t = 0; t < 4; t++) {
        fv_sampler s;
        make(&s, l0s[t], 1);
        assert_true(s.phases == 5);
        const int gx = W / 2, gy = H / 2;
        for (int ph = 0; ph < s.phases; ph++) {
            double u, v;
            fv_liu_phase_offset(ph, &u, &v);
            long set[BLOCKS] = {0}, tot[BLOCKS] = {0};
            double lam[BLOCKS] = {0}, rlo[BLOCKS], rhi[BLOCKS];
            for (int i = 0; i < BLOCKS; i++)
                rlo[i] = 1e9, rhi[i] = 0.0;
            for (int y = 0; y < H; y++)
                for (int x = 0; x < W; x++) {
                    const double r = sqrt((double)(x - gx) * (x - gx) + (double)(y - gy) * (y - gy));
                    const int b = (int)(fv_sampler_row(&s, x, y, 1, gx, gy, ph) & 1);
                    const double l = s.liu_l0 * fv_liu_relative_density(r / s.ppd);
                    if (r < s.liu_sat_px) {
                        assert_true(l >= 1.0 - 1e-9);
                        assert_int_equal(b, 1);
                        continue;
                    }
                    const long ring = lround(fv_liu_cdf(r / s.ppd) / s.liu_drho - u);
                    const long blk = ring / M;
                    if (blk >= BLOCKS)
                        continue;
                    set[blk] += b;
                    tot[blk]++;
                    lam[blk] += l;
                    rlo[blk] = fmin(rlo[blk], r);
                    rhi[blk] = fmax(rhi[blk], r);
                }
            int checked = 0, exact = 0;
            for (int i = 0; i < BLOCKS; i++) {
                /* the first block may be cut by the saturated disc; rounding moves samples by
                 * up to 0.7 px: only blocks 4 px wide or more */
                if (tot[i] < 2000 || rhi[i] - rlo[i] < 4.0 || rlo[i] < s.liu_sat_px + 1.0)
                    continue;
                const double l = lam[i] / tot[i], d = (double)set[i] / tot[i];
                const double lo = 1.0 - exp(-l) - 0.01, hi = fmin(1.0, l) + 0.01;
                if (d < lo || d > hi || (ph == 0 && i % 8 == 0))
                    printf("lambda_0 %.1f phase %d, %.1f-%.1f deg: density %.4f, lambda %.4f, bounds [%.4f, %.4f]\n",
                           (double)l0s[t], ph, rlo[i] / s.ppd, rhi[i] / s.ppd, d, l, lo, hi);
                assert_true(d >= lo && d <= hi);
                /* Two samples round to one pixel only if less than sqrt(2) px apart: where a
                 * cell's width 2 pi r / n_phi and height drho / g(alpha) (its ring's distance to
                 * the next) both exceed that, nothing collides and d is lambda itself. */
                const double a = rlo[i] / s.ppd, cw = 2.0 * PI_D * rlo[i] / s.liu_nphi;
                const double chh = s.liu_drho / fv_liu_ring_density(a) * s.ppd;
                if (fmin(cw, chh) > 1.415) {
                    if (fabs(d - l) > 0.02 * l + 0.002)
                        printf("lambda_0 %.1f phase %d, %.1f deg, cells %.2f x %.2f px: density %.4f, lambda %.4f\n",
                               (double)l0s[t], ph, a, cw, chh, d, l);
                    assert_float_equal(d, l, 0.02 * l + 0.002);
                    exact++;
                }
                checked++;
            }
            assert_true(checked >= 10 && exact >= 5);
        }
        fv_sampler_free(&s);
    }
}

/* liu_density 0: lambda_0 is chosen so the pattern casts Weier's ray count (same r0, r1, p_min)
 * for the centred gaze: equal ray counts for the comparison. Checked against a Weier sampler
 * built here, for the defaults and other parameters. */
static void test_matches_weier_count(void **st)
{
    (void)st;
    const float prm[][3] = {{10.0f, 20.0f, 0.2f}, {5.0f, 15.0f, 0.1f}, {10.0f, 30.0f, 0.35f}};
    for (int t = 0; t < 3; t++) {
        fv_sampling_params p;
        fv_sampling_params_default(&p);
        p.r0_deg = prm[t][0];
        p.r1_deg = prm[t][1];
        p.p_min = prm[t][2];
        fv_sampler ws, ls;
        assert_int_equal(fv_sampler_init(&ws, W, H, focal_default(), &p), 0);
        p.kind = FV_SAMPLER_LIU;
        assert_int_equal(fv_sampler_init(&ls, W, H, focal_default(), &p), 0);
        const long nw = count(&ws, W / 2, H / 2, 0), nl = count(&ls, W / 2, H / 2, 0);
        printf("r0 %g r1 %g p_min %g: weier %ld, liu %ld rays (lambda_0 %.3f, full to %.1f deg)\n", (double)p.r0_deg,
               (double)p.r1_deg, (double)p.p_min, nw, nl, ls.liu_l0, ls.liu_sat_px / ls.ppd);
        assert_int_equal(ls.liu_target, nw);
        assert_true(labs(nl - nw) <= nw / 500 + 1);
        /* fv_sampler_probability is the acuity model with the lambda_0 found */
        for (float r = 0.0f; r < 900.0f; r += 37.0f) {
            double l = ls.liu_l0 * fv_liu_relative_density(r / ls.ppd);
            assert_float_equal(fv_sampler_probability(&ls, r * 0.6f, -r * 0.8f), l < 1.0 ? l : 1.0, 1e-6);
        }
        fv_sampler_free(&ws);
        fv_sampler_free(&ls);
    }
}

/* Rotation over frames: K = ceil(1/p_min) phases, periodic, each with the same ray count (within
 * 1 %); phase k differs from phase k+1 in most periphery pixels, and the K phases together reach
 * far more pixels than one: the union's density per ring is at least 1 - exp(-K lambda) (the
 * union of K independent patterns) and is compared with K lambda. */
static void test_rotation(void **st)
{
    (void)st;
    fv_sampler s, st0;
    make(&s, 0.0f, 1);
    make(&st0, 0.0f, 0);
    assert_int_equal(s.phases, 5);
    assert_int_equal(st0.phases, 1);
    const int K = s.phases, gx = 500, gy = 800;
    static uint64_t uni[H][(W + 63) / 64];
    memset(uni, 0, sizeof uni);
    const long n0 = count(&s, gx, gy, 0);
    long same = 0, per = 0;
    for (int k = 0; k < K; k++) {
        assert_true(labs(count(&s, gx, gy, k) - n0) <= n0 / 100);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x += 64) {
                const int n = W - x < 64 ? W - x : 64;
                const uint64_t b = fv_sampler_row(&s, x, y, n, gx, gy, k);
                assert_true(b == fv_sampler_row(&s, x, y, n, gx, gy, k + K));
                assert_true(b == fv_sampler_row(&s, x, y, n, gx, gy, k - K));
                if (k == 0) /* the static pattern is phase 0 */
                    assert_true(b == fv_sampler_row(&st0, x, y, n, gx, gy, 0));
                if (k == 1) {
                    const uint64_t b0 = fv_sampler_row(&s, x, y, n, gx, gy, 0);
                    same += __builtin_popcountll(b & b0);
                    per += __builtin_popcountll(b);
                }
                uni[y][x >> 6] |= b;
            }
    }
    /* consecutive phases share few pixels outside the saturated disc */
    long sat = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const double dx = x - gx, dy = y - gy;
            sat += dx * dx + dy * dy < s.liu_sat_px * s.liu_sat_px;
        }
    const double shared = (double)(same - sat) / (double)(per - sat);
    printf("phases 0 and 1 share %.3f of the samples outside the full disc\n", shared);
    assert_true(shared < 0.5);
    enum { RINGS = 60 };
    long set[RINGS] = {0}, tot[RINGS] = {0};
    double lam[RINGS] = {0};
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const double r = sqrt((double)(x - gx) * (x - gx) + (double)(y - gy) * (y - gy));
            const int ring = (int)(r / s.ppd);
            if (r < s.liu_sat_px || ring >= RINGS)
                continue;
            set[ring] += (long)((uni[y][x >> 6] >> (x & 63)) & 1);
            tot[ring]++;
            lam[ring] += s.liu_l0 * fv_liu_relative_density(r / s.ppd);
        }
    for (int i = 0; i < RINGS; i++) {
        if (tot[i] < 2000)
            continue;
        const double kl = K * lam[i] / tot[i], d = (double)set[i] / tot[i];
        if (i % 10 == 0)
            printf("ring %d deg: union of %d phases %.3f, K lambda %.3f\n", i, K, d, kl);
        assert_true(d >= 1.0 - exp(-kl) - 0.01 && d <= (kl < 1.0 ? kl : 1.0) + 0.01);
    }
    fv_sampler_free(&s);
    fv_sampler_free(&st0);
}

/* Rows: any span equals its pixels one by one, bits past n are 0, and the pattern moves with the
 * gaze by whole pixels (bit at (x, y) for gaze g = bit at (x + t, y + t') for gaze g + (t, t'));
 * a gaze outside the image is its nearest pixel. */
static void test_rows_follow_gaze(void **st)
{
    (void)st;
    fv_sampler s;
    make(&s, 0.0f, 1);
    uint64_t rng = 11;
    for (int it = 0; it < 20000; it++) {
        const int gx = (int)(fv_test_rand(&rng) % W), gy = (int)(fv_test_rand(&rng) % H);
        const int y = (int)(fv_test_rand(&rng) % H), n = 1 + (int)(fv_test_rand(&rng) % 64);
        const int x0 = (int)(fv_test_rand(&rng) % (W - n + 1)), ph = (int)(fv_test_rand(&rng) % 7);
        const uint64_t row = fv_sampler_row(&s, x0, y, n, gx, gy, ph);
        if (n < 64)
            assert_int_equal(row >> n, 0);
        const int tx = (int)(fv_test_rand(&rng) % 201) - 100, ty = (int)(fv_test_rand(&rng) % 201) - 100;
        for (int i = 0; i < n; i++) {
            const int b = (int)((row >> i) & 1);
            assert_int_equal((int)(fv_sampler_row(&s, x0 + i, y, 1, gx, gy, ph) & 1), b);
            const int x = x0 + i + tx, yy = y + ty, hx = gx + tx, hy = gy + ty;
            if (x >= 0 && x < W && yy >= 0 && yy < H && hx >= 0 && hx < W && hy >= 0 && hy < H)
                assert_int_equal((int)(fv_sampler_row(&s, x, yy, 1, hx, hy, ph) & 1), b);
        }
    }
    for (int y = 0; y < H; y += 7)
        for (int x = 0; x < W; x += 64) {
            const int n = W - x < 64 ? W - x : 64;
            assert_true(fv_sampler_row(&s, x, y, n, -50, 3000, 2) == fv_sampler_row(&s, x, y, n, 0, H - 1, 2));
        }
    fv_sampler_free(&s);
}

static void test_full_and_bad(void **st)
{
    (void)st;
    fv_sampling_params p;
    fv_sampling_params_default(&p);
    p.kind = FV_SAMPLER_LIU;
    p.full = 1;
    fv_sampler s;
    assert_int_equal(fv_sampler_init(&s, W, H, focal_default(), &p), 0);
    assert_true(fv_sampler_row(&s, 64, 100, 64, 640, 720, 3) == ~0ull);
    assert_float_equal(fv_sampler_probability(&s, 900.0f, 0.0f), 1.0f, 0.0);
    fv_sampler_free(&s);
    p.full = 0;
    p.liu_density = -1.0f;
    assert_int_equal(fv_sampler_init(&s, W, H, focal_default(), &p), -1);
    p.liu_density = 0.5f; /* an undersampled fovea */
    assert_int_equal(fv_sampler_init(&s, W, H, focal_default(), &p), -1);
    p.liu_density = 0.0f;
    p.kind = FV_SAMPLER_KIND_COUNT;
    assert_int_equal(fv_sampler_init(&s, W, H, focal_default(), &p), -1);
    int k = -1;
    assert_int_equal(fv_sampler_kind_parse("liu", &k), 0);
    assert_int_equal(k, FV_SAMPLER_LIU);
    assert_int_equal(fv_sampler_kind_parse("weier", &k), 0);
    assert_int_equal(k, FV_SAMPLER_WEIER);
    assert_int_equal(fv_sampler_kind_parse("polar", &k), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_equations),           cmocka_unit_test(test_ring_density),
        cmocka_unit_test(test_matches_weier_count), cmocka_unit_test(test_rotation),
        cmocka_unit_test(test_rows_follow_gaze),    cmocka_unit_test(test_full_and_bad),
    };
    return cmocka_run_group_tests_name("sampling_liu", tests, NULL, NULL);
}
