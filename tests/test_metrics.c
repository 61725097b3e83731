/* Image metrics (core/metrics.c): luma PSNR and SSIM against hand-computed values and against a
 * direct, unoptimised evaluation of the SSIM definition; region handling (fovea / periphery). */
#include <math.h>
#include <string.h>

#include "testutil.h"
#include "metrics.h"

/* cmocka's assert_float_equal compares floats; these are doubles */
#define assert_near(a, b, eps) assert_true(fabs((double)(a) - (double)(b)) <= (eps))

static void fill_grey(uint8_t *img, int n, uint8_t v) { memset(img, v, (size_t)n * 3); }

static double lum(const uint8_t *p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

/* The definition, evaluated directly per window with two-pass moments (the code under test
 * uses separable sums of E[x], E[x^2], E[xy] over a ring of rows): mean over region pixels
 * whose 11x11 window is inside the image. */
static double ssim_direct(const uint8_t *a, const uint8_t *b, int w, int h, const fv_region *reg)
{
    double wt[11][11], ws = 0.0;
    for (int j = 0; j < 11; j++)
        for (int i = 0; i < 11; i++)
            ws += wt[j][i] = exp(-((i - 5) * (i - 5) + (j - 5) * (j - 5)) / (2.0 * 1.5 * 1.5));
    const double C1 = 2.55 * 2.55, C2 = 7.65 * 7.65;
    double sum = 0.0;
    long n = 0;
    for (int y = 5; y < h - 5; y++)
        for (int x = 5; x < w - 5; x++) {
            if (reg) {
                const double dx = x + 0.5 - reg->cx, dy = y + 0.5 - reg->cy;
                const int in = dx * dx + dy * dy < (double)reg->r_px * reg->r_px;
                if (in == reg->outside)
                    continue;
            }
            double ma = 0, mb = 0, va = 0, vb = 0, cab = 0;
            for (int j = 0; j < 11; j++)
                for (int i = 0; i < 11; i++) {
                    const size_t o = 3 * ((size_t)(y + j - 5) * w + x + i - 5);
                    ma += wt[j][i] / ws * lum(a + o);
                    mb += wt[j][i] / ws * lum(b + o);
                }
            for (int j = 0; j < 11; j++)
                for (int i = 0; i < 11; i++) {
                    const size_t o = 3 * ((size_t)(y + j - 5) * w + x + i - 5);
                    const double da = lum(a + o) - ma, db = lum(b + o) - mb;
                    va += wt[j][i] / ws * da * da;
                    vb += wt[j][i] / ws * db * db;
                    cab += wt[j][i] / ws * da * db;
                }
            sum += (2 * ma * mb + C1) * (2 * cab + C2) / ((ma * ma + mb * mb + C1) * (va + vb + C2));
            n++;
        }
    return sum / (double)n;
}

/* Constant images: the variances and covariance are 0, so SSIM is the luminance term alone,
 * (2 a b + C1) / (a^2 + b^2 + C1). Grey 100 vs 150 (luma = the grey level, the Rec. 709 weights
 * sum to 1), C1 = 6.5025: 30006.5025 / 32506.5025 = 0.9230923. */
static void test_ssim_constant_offset(void **st)
{
    (void)st;
    enum { W = 24, H = 20 };
    uint8_t a[W * H * 3], b[W * H * 3];
    fill_grey(a, W * H, 100);
    fill_grey(b, W * H, 150);
    assert_near(fv_luma_ssim(a, b, W, H, 3 * W, NULL), 0.9230923, 1e-6);
    /* PSNR: every luma differs by 50, MSE 2500: 10 log10(65025 / 2500) = 14.1514 dB */
    assert_near(fv_luma_psnr(a, b, W, H, 3 * W, NULL), 14.1514, 1e-4);
    assert_near(fv_luma_ssim(a, a, W, H, 3 * W, NULL), 1.0, 1e-12);
    /* smaller than one window: undefined */
    assert_true(isnan(fv_luma_ssim(a, b, 10, 10, 3 * W, NULL)));
}

static void test_ssim_matches_definition(void **st)
{
    (void)st;
    enum { W = 40, H = 33 };
    static uint8_t a[W * H * 3], b[W * H * 3];
    uint64_t seed = 7;
    for (int i = 0; i < W * H; i++) { /* smooth-ish structure plus noise, B a distorted A */
        const int x = i % W, y = i / W;
        for (int c = 0; c < 3; c++) {
            a[3 * i + c] = (uint8_t)(128 + 60 * sin(x * 0.4 + c) * cos(y * 0.3) + 20 * fv_test_randf(&seed));
            b[3 * i + c] = (uint8_t)(0.8 * a[3 * i + c] + 30 * fv_test_randf(&seed));
        }
    }
    const double s = fv_luma_ssim(a, b, W, H, 3 * W, NULL);
    assert_near(s, ssim_direct(a, b, W, H, NULL), 1e-9);
    assert_true(s > 0.2 && s < 0.95); /* a real distortion, not a degenerate case */
    assert_near(fv_luma_ssim(a, a, W, H, 3 * W, NULL), 1.0, 1e-12);
    fv_region per = fv_region_disc(20.0f, 16.0f, 8.0f, 1), fov = fv_region_disc(20.0f, 16.0f, 8.0f, 0);
    assert_near(fv_luma_ssim(a, b, W, H, 3 * W, &per), ssim_direct(a, b, W, H, &per), 1e-9);
    assert_near(fv_luma_ssim(a, b, W, H, 3 * W, &fov), ssim_direct(a, b, W, H, &fov), 1e-9);
    /* a disc whose centres all lie within 5 px of the border has no valid window */
    fv_region corner = fv_region_disc(0.0f, 0.0f, 3.0f, 0);
    assert_true(isnan(fv_luma_ssim(a, b, W, H, 3 * W, &corner)));
}

/* Images equal within 18 px of (32, 32) and different beyond: the fovea (r 10: every 11x11
 * window within 10 + 5 sqrt(2) < 18 px) scores exactly 1 and PSNR inf; the periphery does not. */
static void test_regions(void **st)
{
    (void)st;
    enum { W = 64, H = 64 };
    static uint8_t a[W * H * 3], b[W * H * 3];
    uint64_t seed = 11;
    for (int i = 0; i < W * H * 3; i++)
        a[i] = b[i] = (uint8_t)(fv_test_rand(&seed) & 0xff);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const double dx = x + 0.5 - 32, dy = y + 0.5 - 32;
            if (dx * dx + dy * dy >= 18 * 18)
                for (int c = 0; c < 3; c++)
                    b[3 * (y * W + x) + c] = (uint8_t)(a[3 * (y * W + x) + c] / 2 + 10);
        }
    fv_region fov = fv_region_disc(32.0f, 32.0f, 10.0f, 0), per = fv_region_disc(32.0f, 32.0f, 10.0f, 1);
    assert_near(fv_luma_ssim(a, b, W, H, 3 * W, &fov), 1.0, 1e-12);
    assert_true(isinf(fv_luma_psnr(a, b, W, H, 3 * W, &fov)));
    assert_true(fv_luma_ssim(a, b, W, H, 3 * W, &per) < 0.9);
    assert_true(isfinite(fv_luma_psnr(a, b, W, H, 3 * W, &per)));
    /* row stride larger than the row: padding bytes must not be read as pixels */
    static uint8_t pa[(3 * W + 5) * H], pb[(3 * W + 5) * H];
    memset(pa, 0, sizeof pa);
    memset(pb, 255, sizeof pb);
    for (int y = 0; y < H; y++) {
        memcpy(pa + y * (3 * W + 5), a + y * 3 * W, 3 * W);
        memcpy(pb + y * (3 * W + 5), b + y * 3 * W, 3 * W);
    }
    assert_near(fv_luma_ssim(pa, pb, W, H, 3 * W + 5, &per), fv_luma_ssim(a, b, W, H, 3 * W, &per), 1e-12);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ssim_constant_offset),
        cmocka_unit_test(test_ssim_matches_definition),
        cmocka_unit_test(test_regions),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
