/* Depth-of-field-driven sampling (core/sampling_dof.h): the expected CoC against Weier's eq. (3)
 * (coc.c, computed through image distances), the default density against the texel area of
 * the pyramid level the layered filter reads, the kept density against the equation
 * d(c) = min(p, 1 / ((min(c, c_cap) / kappa)^2 + 1/3)) with p per 4x4 block (the transition
 * ring), the roulette's weights 1/q unbiased, the in-focus region untouched, the fovea and the
 * periphery thinned as even dithers, a constant image reconstructed exactly from the thinned
 * samples, and in the pipeline: fewer rays, the reported bits are the traced ones, and the same
 * bytes for 1, 2 and 5 threads. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "testscene.h"
#include "camera.h"
#include "pipeline.h"
#include "pullpush.h"
#include "sampling_dof.h"
#include "tile.h"

#define W 256
#define H 256
#define KAPPA 2.0f
#define CAP 32.0f
#define PX_PER_DPT 20.0f
#define FOCUS_M 1.0f
#define TOL_M 0.2f

static const fv_pose origin = {{0, 0, 0}, {0, 0, 0, 1}};

/* depth of each 16-px column band of the synthetic history */
static const float band_m[W / 16] = {1.0f, 0.5f, 2.0f, 0.25f, 1.1f, 3.0f, 0.7f, 1000.0f,
                                     0.9f, 0.4f, 5.0f, 0.12f, 1.0f, 1.5f, 0.6f, 10.0f};

/* The test's own reading of the model: CoC = k_m focal_px scale * dioptres outside
 * [1 / (F + t), 1 / (F - t)]; density 1 / ((min(c, cap) / kappa)^2 + 1/3), at most 1. */
static double expect_coc(double depth_m)
{
    const double D = 1.0 / depth_m, lo = 1.0 / (FOCUS_M + TOL_M), hi = 1.0 / (FOCUS_M - TOL_M);
    return PX_PER_DPT * (D < lo ? lo - D : D > hi ? D - hi : 0.0);
}
static double expect_density(double c)
{
    const double cc = (c < CAP ? c : CAP) / KAPPA, a = cc * cc + 1.0 / 3.0;
    return a > 1.0 ? 1.0 / a : 1.0;
}

typedef struct {
    fv_camera cam;
    fv_pyramid hist;
    fv_taa_frame tf;
    fv_sampler smp;
    fv_dofsamp_params prm;
    float *map; /* the defocus map */
} fixture;

/* A history whose levels 1-4 hold band_m per column band, the same camera twice (identity map),
 * and an acuity sampler: full, or the periphery only (gaze far outside the image). */
static void fixture_init(fixture *fx, int full)
{
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.width = W;
    d.height = H;
    d.fov_y_deg = 90.0f;
    assert_int_equal(fv_camera_setup(&fx->cam, &d, &origin), 0);
    assert_int_equal(fv_pyramid_init(&fx->hist, W, H), 0);
    for (int l = 1; l <= 4; l++) { /* texels of 16 px and less lie in one band */
        const fv_pyr_level *L = &fx->hist.lv[l];
        for (int y = -1; y <= L->h; y++) /* with the border, as pull-push leaves it: the edge replicated */
            for (int x = -1; x <= L->w; x++)
                L->rgbd[4 * (y * L->stride + x) + 3] = band_m[((x < 0 ? 0 : x < L->w ? x : L->w - 1) << l) / 16];
    }
    fv_taa_frame_setup(&fx->tf, &fx->cam, &fx->cam, &fx->hist, 0.03f);
    assert_true(fx->tf.identity);
    fx->map = malloc(fv_dofsamp_map_len(&fx->hist) * sizeof(float));
    assert_non_null(fx->map);
    fv_sampling_params sp;
    fv_sampling_params_default(&sp);
    sp.full = full;
    assert_int_equal(fv_sampler_init(&fx->smp, W, H, fx->cam.focal_px, &sp), 0);
    fv_dofsamp_params_default(&fx->prm);
    fx->prm.kappa = KAPPA;
    fx->prm.coc_cap_px = CAP;
}

static void fixture_free(fixture *fx)
{
    fv_pyramid_free(&fx->hist);
    fv_sampler_free(&fx->smp);
    free(fx->map);
}

static const int far_gx = -100000, far_gy = -100000;

static void setup_frame(fixture *fx, fv_dofsamp_frame *f, uint32_t frame)
{
    const int gx = fx->smp.prm.full ? W / 2 : far_gx, gy = fx->smp.prm.full ? H / 2 : far_gy;
    fv_dofsamp_frame_setup(f, &fx->prm, &fx->tf, &fx->smp, gx, gy, FOCUS_M, FOCUS_M, TOL_M, PX_PER_DPT, frame, 0);
    fv_dofsamp_map_attach(f, fx->map);
    fv_dofsamp_map_rows(f, 0, f->map_h / 3); /* in two pieces, as bands would */
    fv_dofsamp_map_rows(f, f->map_h / 3, f->map_h);
}

/* Thinning blocks (and history texels) are B x B pixels; a block's 3x3 texel minimum reaches
 * B pixels past it. */
#define B (1 << FV_DOFSAMP_LEVEL)

/* One frame: every tile's acuity rows, thinned; kept[band] and acuity[band] count the interior
 * pixels of each band (B px clear of its sides: the 3x3 texel minimum reaches that far). */
static void run_frame(fixture *fx, uint32_t frame, double kept[W / 16], double acuity[W / 16], double *qsum)
{
    fv_dofsamp_frame f;
    setup_frame(fx, &f, frame);
    const int gx = f.gx, gy = f.gy;
    for (int ty = 0; ty < H / 16; ty++)
        for (int tx = 0; tx < W / 16; tx++) {
            uint32_t rows[16], before[16];
            for (int y = 0; y < 16; y++)
                rows[y] = before[y] = (uint32_t)fv_sampler_row(&fx->smp, tx * 16, ty * 16 + y, 16, gx, gy, 0);
            const float q = fv_dofsamp_tile(&f, tx * 16, ty * 16, 16, 16, rows);
            if (qsum)
                qsum[tx] += q;
            for (int y = 0; y < 16; y++) {
                assert_int_equal(rows[y] & ~before[y], 0); /* only ever drops acuity bits */
                for (int x = B; x < 16 - B; x++) {
                    acuity[tx] += before[y] >> x & 1u;
                    kept[tx] += rows[y] >> x & 1u;
                }
            }
        }
}

/* Weier's eq. (3) from coc.c (image distances, the preset's E) against the sampler's one-line
 * dioptre form, for a focus range collapsed to a point. */
static void test_coc_is_weier(void **st)
{
    (void)st;
    const float focal_px = 604.15f;
    const fv_dof_preset presets[] = {FV_DOF_WEAK, FV_DOF_MEDIUM, FV_DOF_STRONG};
    const float focus[] = {0.5f, 1.0f, 2.5f, 40.0f}, depth[] = {0.1f, 0.3f, 0.45f, 0.9f, 1.3f, 3.0f, 39.0f, 1000.0f};
    fv_dofsamp_params prm;
    fv_dofsamp_params_default(&prm);
    for (int p = 0; p < 3; p++) {
        fv_coc_weier w;
        fv_coc_weier_default(&w, focal_px);
        fv_coc_weier_apply_preset(&w, presets[p]);
        const float a = w.pupil_mm * 1e-3f * focal_px * fv_dof_presets[presets[p]].e_scale;
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 8; j++) {
                fv_dofsamp_frame f;
                fv_dofsamp_frame_setup(&f, &prm, NULL, NULL, 0, 0, focus[i], focus[i], w.tolerance_m, a, 0, 0);
                const float ref = fabsf(fv_coc_weier_px(&w, focus[i], depth[j]));
                assert_float_equal(fv_dofsamp_coc_px(&f, depth[j]), ref, 1e-3f * ref + 1e-4f);
            }
    }
    /* a focus range: the band's near end from the nearer focus, far end from the farther */
    fv_dofsamp_frame f;
    fv_dofsamp_frame_setup(&f, &prm, NULL, NULL, 0, 0, 2.0f, 0.5f, 0.2f, 10.0f, 0, 0);
    assert_float_equal(fv_dofsamp_coc_px(&f, 0.25f), 10.0f * (4.0f - 1.0f / 0.3f), 1e-4f);
    assert_float_equal(fv_dofsamp_coc_px(&f, 1.0f), 0.0f, 0.0f);
    assert_float_equal(fv_dofsamp_coc_px(&f, 10.0f), 10.0f * (1.0f / 2.2f - 0.1f), 1e-4f);
}

/* The default density is one sample per texel of the pyramid level the layered filter reads at
 * the CoC: core/dof/weier.c matches the level's variance (3 4^L - 1) / 12 (a level L up-sampled,
 * docs/dof.md) to the disc's c^2 / 16, so at c_L = sqrt(16 (3 4^L - 1) / 12) it reads level L
 * alone, whose texels hold 4^L pixels; below level 0's CoC every sample is kept; beyond the cap
 * (the filter's largest blur) the density stays at the cap's. */
static void test_density_is_filter_texel(void **st)
{
    (void)st;
    fv_dofsamp_params prm;
    fv_dofsamp_params_default(&prm);
    fv_dofsamp_frame f;
    fv_dofsamp_frame_setup(&f, &prm, NULL, NULL, 0, 0, 1.0f, 1.0f, 0.2f, 10.0f, 0, 0);
    for (int L = 1; L <= 5; L++) {
        const double cl = sqrt(16.0 * (3.0 * (double)(1 << (2 * L)) - 1.0) / 12.0);
        if (cl > prm.coc_cap_px)
            break;
        assert_float_equal(fv_dofsamp_density(&f, (float)cl), 1.0 / (double)(1 << (2 * L)), 1e-6);
    }
    const double c0 = sqrt(16.0 * 2.0 / 12.0); /* (3 - 1) / 12: level 0's variance, 1.63 px */
    assert_float_equal(fv_dofsamp_density(&f, 0.0f), 1.0f, 0.0f);
    assert_float_equal(fv_dofsamp_density(&f, (float)c0 - 1e-3f), 1.0f, 0.0f);
    assert_true(fv_dofsamp_density(&f, (float)c0 + 1e-2f) < 1.0f);
    for (float c = 1.75f; c < 40.0f; c += 0.25f) /* falls with the CoC's area, then stays */
        assert_true(c < prm.coc_cap_px ? fv_dofsamp_density(&f, c + 0.25f) < fv_dofsamp_density(&f, c)
                                       : fv_dofsamp_density(&f, c + 0.25f) == fv_dofsamp_density(&f, c));
    /* the periphery (p 0.2) is thinned from 4.32 px on, the fovea from 1.63 px */
    assert_float_equal(fv_dofsamp_keep(&f, 0.2f, 4.3f), 1.0f, 0.0f);
    assert_true(fv_dofsamp_keep(&f, 0.2f, 4.4f) < 1.0f);
    assert_float_equal(fv_dofsamp_keep(&f, 0.2f, 8.0f), 1.0 / ((16.0 + 1.0 / 3.0) * 0.2), 1e-6);
}

/* Measured kept density per depth band against d(c) / p, within 4.5 binomial sigmas, over 48
 * frames of the roulette; and the tiles' reported mean keep-probability against the same. */
static void density_case(int full)
{
    fixture fx;
    fixture_init(&fx, full);
    enum { FRAMES = 48 };
    double kept[W / 16] = {0}, acuity[W / 16] = {0}, qsum[W / 16] = {0};
    for (uint32_t fr = 0; fr < FRAMES; fr++)
        run_frame(&fx, fr, kept, acuity, qsum);
    const double p = full ? 1.0 : fx.smp.prm.p_min;
    for (int b = 0; b < W / 16; b++) {
        const double d = expect_density(expect_coc(band_m[b]));
        const double q = d < p ? d / p : 1.0;
        const double n = acuity[b], m = kept[b] / n;
        assert_true(n > 1000.0);
        const double sig = sqrt(q * (1.0 - q) / n) + 1e-12;
        if (fabs(m - q) > 4.5 * sig) {
            printf("band %d (%.2f m): kept %.5f, expected %.5f (sigma %.5f)\n", b, (double)band_m[b], m, q, sig);
            fail();
        }
        /* the tiles' mean keep-probability: the inner blocks see the band alone, the first (last)
         * also the last (first) texel of the band on its left (right): the smaller CoC of the two */
        double qb[2];
        for (int side = 0; side < 2; side++) {
            const int nb = side ? (b + 1 < W / 16 ? b + 1 : b) : (b > 0 ? b - 1 : b);
            const double c0 = expect_coc(band_m[b]), c1 = expect_coc(band_m[nb]);
            const double de = expect_density(c0 < c1 ? c0 : c1);
            qb[side] = de < p ? de / p : 1.0;
        }
        const double qr = qsum[b] / (FRAMES * (H / 16)), qe = (qb[0] + (16 / B - 2) * q + qb[1]) / (16 / B);
        assert_float_equal(qr, qe, 1e-5 + 1e-5 * qe);
    }
    fixture_free(&fx);
}
static void test_density_full(void **st)
{
    (void)st;
    density_case(1);
}
static void test_density_periphery(void **st)
{
    (void)st;
    density_case(0);
}

/* Russian roulette: a kept sample weighted 1/q makes every acuity sample's expected weight 1,
 * as without thinning. Summed over the image and 32 frames, sum(keep / q) / sum(1) = 1 within
 * 4.5 sigma, where sigma^2 = sum((1 - q) / q) / N^2. */
static void roulette_case(int full)
{
    fixture fx;
    fixture_init(&fx, full);
    const double p = full ? 1.0 : fx.smp.prm.p_min;
    double num = 0.0, var = 0.0, n = 0.0;
    for (uint32_t fr = 100; fr < 132; fr++) {
        fv_dofsamp_frame f;
        setup_frame(&fx, &f, fr);
        for (int ty = 0; ty < H / 16; ty++)
            for (int tx = 0; tx < W / 16; tx++) {
                uint32_t rows[16], acu[16];
                for (int y = 0; y < 16; y++)
                    rows[y] = acu[y] = (uint32_t)fv_sampler_row(&fx.smp, tx * 16, ty * 16 + y, 16, f.gx, f.gy, 0);
                fv_dofsamp_tile(&f, tx * 16, ty * 16, 16, 16, rows);
                const double de = expect_density(expect_coc(band_m[tx])), q = de < p ? de / p : 1.0;
                for (int y = 0; y < 16; y++)
                    for (int x = B; x < 16 - B; x++) {
                        if (!(acu[y] >> x & 1u))
                            continue;
                        num += (rows[y] >> x & 1u) / q;
                        var += (1.0 - q) / q;
                        n += 1.0;
                    }
            }
    }
    const double sig = sqrt(var) / n;
    if (fabs(num / n - 1.0) > 4.5 * sig) {
        printf("sum(keep / q) / N = %.5f, sigma %.5f\n", num / n, sig);
        fail();
    }
    fixture_free(&fx);
}
static void test_roulette_unbiased(void **st)
{
    (void)st;
    roulette_case(1); /* the R2 lattice */
    roulette_case(0); /* the periphery's lattice ranks */
}

/* In focus: every acuity bit survives, and so does every bit within the 3x3 texel reach of an
 * in-focus texel (a misregistered edge keeps the sharp side dense). */
static void test_in_focus_untouched(void **st)
{
    (void)st;
    fixture fx;
    fixture_init(&fx, 1);
    fv_dofsamp_frame f;
    setup_frame(&fx, &f, 7);
    for (int tx = 0; tx < W / 16; tx++) {
        const int sharp = expect_coc(band_m[tx]) == 0.0;
        const int left_sharp = tx > 0 && expect_coc(band_m[tx - 1]) == 0.0;
        const int right_sharp = tx + 1 < W / 16 && expect_coc(band_m[tx + 1]) == 0.0;
        for (int ty = 0; ty < H / 16; ty++) {
            uint32_t rows[16];
            for (int y = 0; y < 16; y++)
                rows[y] = 0xffffu;
            const float q = fv_dofsamp_tile(&f, tx * 16, ty * 16, 16, 16, rows);
            for (int y = 0; y < 16; y++) {
                if (sharp)
                    assert_int_equal(rows[y], 0xffffu);
                if (left_sharp) /* pixels 0 .. B-1 share a block whose neighbourhood reaches the band */
                    assert_int_equal(rows[y] & ((1u << B) - 1u), (1u << B) - 1u);
                if (right_sharp)
                    assert_int_equal(rows[y] >> (16 - B), (1u << B) - 1u);
            }
            if (sharp)
                assert_float_equal(q, 1.0f, 0.0f);
        }
    }
    /* a tile with no bits stays without bits */
    uint32_t rows[16] = {0};
    fv_dofsamp_tile(&f, 16, 16, 16, 16, rows);
    for (int y = 0; y < 16; y++)
        assert_int_equal(rows[y], 0u);
    fixture_free(&fx);
}

/* The periphery is thinned along S_out's own lattice dither: the kept samples are evenly spread
 * at density p q, no window of side ceil(2 / sqrt(p q)) is empty (white-noise thinning leaves
 * ~e^-4 of them empty, hundreds here); and fv_sampler_lattice is S_out's membership. */
/* the win x win windows of a W x H sample mask (16-bit rows per tile column) that hold no sample */
static int empty_windows(const uint32_t mask[H][W / 16], int win)
{
    int empty = 0;
    for (int y = 0; y + win <= H; y++)
        for (int x = 0; x + win <= W; x++) {
            int any = 0;
            for (int j = 0; j < win && !any; j++)
                for (int i = 0; i < win && !any; i++)
                    any = mask[y + j][(x + i) / 16] >> ((x + i) % 16) & 1u;
            empty += !any;
        }
    return empty;
}

static void test_periphery_thinned_evenly(void **st)
{
    (void)st;
    fixture fx;
    fixture_init(&fx, 0);
    for (int l = 1; l <= 4; l++) { /* one depth: 0.5 m, c = 15 px, d = (2 / 15)^2 */
        const fv_pyr_level *L = &fx.hist.lv[l];
        for (int y = -1; y <= L->h; y++)
            for (int x = -1; x <= L->w; x++)
                L->rgbd[4 * (y * L->stride + x) + 3] = 0.5f;
    }
    const double d = expect_density(expect_coc(0.5));
    const int win = (int)ceil(2.0 / sqrt(d));
    for (uint32_t fr = 0; fr < 3; fr++) {
        fv_dofsamp_frame f;
        setup_frame(&fx, &f, fr);
        static uint32_t mask[H][W / 16];
        long kept = 0;
        for (int ty = 0; ty < H / 16; ty++)
            for (int tx = 0; tx < W / 16; tx++) {
                uint32_t rows[16];
                for (int y = 0; y < 16; y++) {
                    rows[y] = (uint32_t)fv_sampler_row(&fx.smp, tx * 16, ty * 16 + y, 16, far_gx, far_gy, 0);
                    for (int x = 0; x < 16; x++)
                        assert_int_equal(rows[y] >> x & 1u,
                                         fv_sampler_lattice(&fx.smp, tx * 16 + x, ty * 16 + y, 0) < fx.smp.prm.p_min);
                }
                fv_dofsamp_tile(&f, tx * 16, ty * 16, 16, 16, rows);
                for (int y = 0; y < 16; y++) {
                    mask[ty * 16 + y][tx] = rows[y];
                    kept += __builtin_popcount(rows[y]);
                }
            }
        assert_float_equal((double)kept / (W * H), d, 0.1 * d);
        const int empty = empty_windows(mask, win);
        if (empty)
            printf("frame %u: %d empty %dx%d windows at density %.4f\n", fr, empty, win, win, d);
        assert_int_equal(empty, 0);
    }
    fixture_free(&fx);
}

/* Fills the history's levels 1-4 with one depth. */
static void history_depth(fixture *fx, float depth_m)
{
    for (int l = 1; l <= 4; l++) {
        const fv_pyr_level *L = &fx->hist.lv[l];
        for (int y = -1; y <= L->h; y++)
            for (int x = -1; x <= L->w; x++)
                L->rgbd[4 * (y * L->stride + x) + 3] = depth_m;
    }
}

/* The transition ring: every 4x4 block keeps its acuity samples with q = d / p, p the acuity
 * probability at the block's corner farthest from the gaze (not the tile's: a tile straddling
 * the ring has blocks much nearer the gaze). Over 48 frames: the kept count against sum(q) within
 * 4.5 binomial sigmas, the roulette's weights sum(keep / q) / N = 1, and the tiles' reported keep
 * share against the mean of q over their pixels. */
static void test_transition_per_block(void **st)
{
    (void)st;
    fixture fx;
    fixture_init(&fx, 0);
    history_depth(&fx, 0.5f); /* c = 15 px */
    const double d = expect_density(expect_coc(0.5));
    const int gx = W / 2, gy = H / 2;
    assert_true(fx.smp.r1_px < 60.0f); /* the ring lies well inside the image */
    double kept = 0.0, expect = 0.0, var = 0.0, wsum = 0.0, n = 0.0, qtile = 0.0, qtile_e = 0.0;
    for (uint32_t fr = 0; fr < 48; fr++) {
        fv_dofsamp_frame f;
        fv_dofsamp_frame_setup(&f, &fx.prm, &fx.tf, &fx.smp, gx, gy, FOCUS_M, FOCUS_M, TOL_M, PX_PER_DPT, fr, 0);
        fv_dofsamp_map_attach(&f, fx.map);
        fv_dofsamp_map_rows(&f, 0, f.map_h);
        for (int ty = 0; ty < H / 16; ty++)
            for (int tx = 0; tx < W / 16; tx++) {
                uint32_t rows[16], acu[16];
                for (int y = 0; y < 16; y++)
                    rows[y] = acu[y] = (uint32_t)fv_sampler_row(&fx.smp, tx * 16, ty * 16 + y, 16, gx, gy, 0);
                const float qt = fv_dofsamp_tile(&f, tx * 16, ty * 16, 16, 16, rows);
                double qpx = 0.0;
                int ring = 0;
                for (int by = 0; by < 16; by += B)
                    for (int bx = 0; bx < 16; bx += B) {
                        const float ax = (float)(tx * 16 + bx - gx), bx1 = ax + (float)B;
                        const float ay = (float)(ty * 16 + by - gy), by1 = ay + (float)B;
                        const float p = fv_sampler_probability(&fx.smp, fabsf(ax) > fabsf(bx1) ? ax : bx1,
                                                               fabsf(ay) > fabsf(by1) ? ay : by1);
                        const double q = d < p ? d / p : 1.0;
                        qpx += q * B * B;
                        ring |= p > fx.smp.prm.p_min && p < 1.0f;
                        for (int y = by; y < by + B; y++)
                            for (int x = bx; x < bx + B; x++) {
                                if (!(acu[y] >> x & 1u))
                                    continue;
                                const int k = rows[y] >> x & 1u;
                                kept += k;
                                expect += q;
                                var += q * (1.0 - q);
                                wsum += k / q;
                                n += 1.0;
                            }
                    }
                if (ring) {
                    qtile += qt;
                    qtile_e += qpx / 256.0;
                }
                for (int y = 0; y < 16; y++)
                    assert_int_equal(rows[y] & ~acu[y], 0u);
            }
    }
    printf("kept %.0f of %.0f acuity samples, expected %.1f\n", kept, n, expect);
    assert_true(n > 10000.0);
    assert_true(fabs(kept - expect) < 4.5 * sqrt(var) + 1.0);
    assert_true(fabs(wsum / n - 1.0) < 0.02);
    assert_float_equal(qtile, qtile_e, 1e-5 * qtile_e);
    fixture_free(&fx);
}

/* The fovea (every pixel an acuity sample) is thinned as an even dither too: at density d no
 * window of side ceil(2 / sqrt(d)) is empty (white-noise thinning leaves ~e^-4.5 of them empty,
 * hundreds here), and the kept share is d. */
static void test_fovea_thinned_evenly(void **st)
{
    (void)st;
    fixture fx;
    fixture_init(&fx, 1);
    history_depth(&fx, 0.5f);
    const double d = expect_density(expect_coc(0.5));
    const int win = (int)ceil(2.0 / sqrt(d));
    for (uint32_t fr = 0; fr < 3; fr++) {
        fv_dofsamp_frame f;
        setup_frame(&fx, &f, fr);
        static uint32_t mask[H][W / 16];
        long kept = 0;
        for (int ty = 0; ty < H / 16; ty++)
            for (int tx = 0; tx < W / 16; tx++) {
                uint32_t rows[16];
                for (int y = 0; y < 16; y++)
                    rows[y] = 0xffffu;
                fv_dofsamp_tile(&f, tx * 16, ty * 16, 16, 16, rows);
                for (int y = 0; y < 16; y++) {
                    mask[ty * 16 + y][tx] = rows[y];
                    kept += __builtin_popcount(rows[y]);
                }
            }
        assert_float_equal((double)kept / (W * H), d, 0.1 * d);
        const int empty = empty_windows(mask, win);
        if (empty)
            printf("frame %u: %d empty %dx%d windows at density %.4f\n", fr, empty, win, win, d);
        assert_int_equal(empty, 0);
    }
    fixture_free(&fx);
}

/* Over time in the periphery: an S_out pixel is in the pattern one frame in K (phase = frame mod
 * K); at q ~ 0.3 each pixel is re-traced within 6 of its visits (the golden-ratio shift per
 * visit; shifted per frame, the variate moved 5 g mod 1 = 0.09 between visits: runs of 9 visits
 * without a ray), and every pixel is traced. */
static void test_periphery_revisits(void **st)
{
    (void)st;
    fixture fx;
    fixture_init(&fx, 0);
    const float depth_m = 2.33f; /* c 8.1 px: d 0.06, q 0.3 at p_min 0.2 */
    history_depth(&fx, depth_m);
    const double q = expect_density(expect_coc(depth_m)) / fx.smp.prm.p_min;
    assert_true(q > 0.25 && q < 0.35);
    fv_sampler_free(&fx.smp); /* the rotating pattern, as with reprojection */
    fv_sampling_params sp;
    fv_sampling_params_default(&sp);
    sp.rotate = 1;
    assert_int_equal(fv_sampler_init(&fx.smp, W, H, fx.cam.focal_px, &sp), 0);
    const int K = fx.smp.phases;
    assert_int_equal(K, 5);
    enum { N = 64, X0 = 64, Y0 = 64 };
    static int last[N][N], visits[N][N], kept_n[N][N];
    int maxgap = 0;
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++)
            last[y][x] = -1, visits[y][x] = 0, kept_n[y][x] = 0;
    for (uint32_t fr = 0; fr < 40u * (uint32_t)K; fr++) {
        const int ph = (int)(fr % (uint32_t)K);
        fv_dofsamp_frame f;
        fv_dofsamp_frame_setup(&f, &fx.prm, &fx.tf, &fx.smp, far_gx, far_gy, FOCUS_M, FOCUS_M, TOL_M, PX_PER_DPT, fr,
                               ph);
        fv_dofsamp_map_attach(&f, fx.map);
        fv_dofsamp_map_rows(&f, 0, f.map_h);
        for (int ty = Y0 / 16; ty < (Y0 + N) / 16; ty++)
            for (int tx = X0 / 16; tx < (X0 + N) / 16; tx++) {
                uint32_t rows[16], acu[16];
                for (int y = 0; y < 16; y++)
                    rows[y] = acu[y] = (uint32_t)fv_sampler_row(&fx.smp, tx * 16, ty * 16 + y, 16, far_gx, far_gy, ph);
                fv_dofsamp_tile(&f, tx * 16, ty * 16, 16, 16, rows);
                for (int y = 0; y < 16; y++)
                    for (int x = 0; x < 16; x++) {
                        if (!(acu[y] >> x & 1u))
                            continue;
                        const int py = ty * 16 + y - Y0, px = tx * 16 + x - X0;
                        const int v = visits[py][px]++;
                        if (rows[y] >> x & 1u) {
                            if (last[py][px] >= 0 && v - last[py][px] > maxgap)
                                maxgap = v - last[py][px];
                            last[py][px] = v;
                            kept_n[py][px]++;
                        }
                    }
            }
    }
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++) {
            assert_int_equal(visits[y][x], 40); /* the K phases tile every pixel */
            assert_true(kept_n[y][x] > 0);
        }
    printf("q %.3f: longest run between two rays of a pixel %d visits\n", q, maxgap);
    assert_true(maxgap <= 6);
    fixture_free(&fx);
}

/* A constant image sampled through the roulette and reconstructed by pull-push is that
 * constant at every pixel: holes (their colours poisoned) are filled, nothing is lost. */
static void test_constant_image_reconstruction(void **st)
{
    (void)st;
    fixture fx;
    fixture_init(&fx, 0);
    fv_pyramid pyr;
    assert_int_equal(fv_pyramid_init(&pyr, W, H), 0);
    fv_pullpush_dsp dsp;
    fv_pullpush_dsp_init(&dsp, ~0u);
    fv_dofsamp_frame f;
    setup_frame(&fx, &f, 3);
    const float c[4] = {0.25f, 0.5f, 0.75f, 2.0f};
    const fv_pyr_level *l0 = &pyr.lv[0];
    long kept = 0, acuity = 0;
    for (int ty = 0; ty < H / 16; ty++)
        for (int tx = 0; tx < W / 16; tx++) {
            uint32_t rows[16];
            for (int y = 0; y < 16; y++) {
                rows[y] = (uint32_t)fv_sampler_row(&fx.smp, tx * 16, ty * 16 + y, 16, far_gx, far_gy, 0);
                acuity += __builtin_popcount(rows[y]);
            }
            fv_dofsamp_tile(&f, tx * 16, ty * 16, 16, 16, rows);
            for (int y = 0; y < 16; y++)
                for (int x = 0; x < 16; x++) {
                    const ptrdiff_t i = (ptrdiff_t)(ty * 16 + y) * l0->stride + tx * 16 + x;
                    const int on = rows[y] >> x & 1u;
                    l0->wgt[i] = (float)on;
                    kept += on;
                    for (int k = 0; k < 4; k++)
                        l0->rgbd[4 * i + k] = on ? c[k] : 1e30f;
                }
        }
    assert_true(kept < acuity * 3 / 4); /* the bands really were thinned */
    fv_pullpush(&pyr, &dsp, NULL);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            for (int k = 0; k < 4; k++)
                assert_float_equal(l0->rgbd[4 * ((ptrdiff_t)y * l0->stride + x) + k], c[k], 1e-6f * c[k]);
    fv_pyramid_free(&pyr);
    fixture_free(&fx);
}

/* ---- the pipeline ---- */

/* A far wall (10 m), an in-focus card at 1 m on the left, a near card at 0.3 m on the right;
 * the focus fixed at 1 m, strong DoF, a narrow field so the CoCs span many pixels. */
static fv_scene *dof_scene(void)
{
    fv_scene *s = fv_scene_create();
    assert_non_null(s);
    const float wall[3] = {0.6f, 0.5f, 0.4f}, card[3] = {0.2f, 0.8f, 0.4f}, near[3] = {0.9f, 0.2f, 0.2f};
    fv_test_add_quad(s, -20.0f, -20.0f, 20.0f, 20.0f, -10.0f, wall, -1);
    fv_test_add_quad(s, -0.15f, -0.1f, -0.02f, 0.1f, -1.0f, card, -1);
    fv_test_add_quad(s, 0.01f, -0.03f, 0.05f, 0.03f, -0.3f, near, -1);
    char err[256];
    assert_int_equal(fv_scene_commit(s, err, sizeof err), 0);
    return s;
}

static void dof_config(fv_pipeline_config *cfg, int dofsamp, int threads)
{
    fv_pipeline_config_default(cfg);
    cfg->cam.width = 192;
    cfg->cam.height = 160;
    cfg->cam.fov_y_deg = 20.0f;
    cfg->samp.r0_deg = 1.5f;
    cfg->samp.r1_deg = 3.0f;
    cfg->dof.preset = FV_DOF_STRONG;
    cfg->dof.focus.fixed_m = 1.0f;
    cfg->dofsamp.enabled = dofsamp;
    cfg->dofsamp.kappa = 2.0f; /* the wall (c 6 px) is thinned too, not only the near card */
    cfg->threads = threads;
    cfg->keep_image = 1; /* the float image is compared */
}

/* With history (frame 2 on) the strong blur of the wall and the near card removes rays; the
 * bits the pipeline reports are the ones it traced (their count is the frame's ray count), a
 * subset of the acuity sampler's, and every acuity bit on the in-focus card survives. */
static void test_pipeline_fewer_rays(void **st)
{
    (void)st;
    fv_scene *s = dof_scene();
    long rays[2] = {0, 0};
    for (int on = 0; on < 2; on++) {
        fv_pipeline_config cfg;
        dof_config(&cfg, on, 2);
        char err[256];
        fv_pipeline *p = fv_pipeline_create(s, &cfg, err, sizeof err);
        assert_non_null(p);
        for (int fr = 0; fr < 4; fr++) {
            fv_frame_stats stt;
            assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, &origin, 0.5f, 0.5f, &stt), 0);
            const uint32_t *rows = fv_pipeline_last_rows(p, FV_EYE_CENTER);
            assert_true(on && fr > 0 ? rows != NULL : rows == NULL); /* frame 0 has no history */
            if (fr == 3)
                rays[on] = stt.samples;
            if (!rows)
                continue;
            const fv_sampler *smp = fv_pipeline_sampler(p);
            const fv_camera *cam = fv_pipeline_camera(p, FV_EYE_CENTER);
            const int tiles_x = (cam->width + 15) / 16, tiles_y = (cam->height + 15) / 16;
            long n = 0;
            int card_px = 0;
            for (int ty = 0; ty < tiles_y; ty++)
                for (int tx = 0; tx < tiles_x; tx++)
                    for (int y = 0; y < 16 && ty * 16 + y < cam->height; y++) {
                        const int py = ty * 16 + y;
                        const uint32_t r = rows[(ty * tiles_x + tx) * 16 + y];
                        const uint32_t a = (uint32_t)fv_sampler_row(smp, tx * 16, py, 16, 96, 80,
                                                                   fv_pipeline_last_phase(p, FV_EYE_CENTER));
                        assert_int_equal(r & ~a, 0u);
                        n += __builtin_popcount(r);
                        for (int x = 0; x < 16; x++) { /* well inside the card at 1 m */
                            float d[3];
                            fv_camera_ray(cam, (float)(tx * 16 + x) + 0.5f, (float)py + 0.5f, d);
                            if (d[0] > -0.14f && d[0] < -0.03f && d[1] > -0.09f && d[1] < 0.09f) {
                                assert_int_equal(r >> x & 1u, a >> x & 1u);
                                card_px++;
                            }
                        }
                    }
            assert_int_equal(n, stt.samples);
            assert_true(card_px > 1000);
        }
        fv_pipeline_destroy(p);
    }
    printf("rays per frame: acuity %ld, with DoF sampling %ld\n", rays[0], rays[1]);
    assert_true(rays[1] < rays[0] * 3 / 4);
    fv_scene_free(s);
}

/* The roulette is a function of pixel and frame: the image (after DoF) and the pyramid are the same bytes
 * for 1, 2 and 5 threads, frame after frame, with the head moving (the tile flow). */
static void test_pipeline_thread_determinism(void **st)
{
    (void)st;
    fv_scene *s = dof_scene();
    const int threads[] = {1, 2, 5};
    float *ref = NULL;
    long ref_rays = 0;
    for (int k = 0; k < 3; k++) {
        fv_pipeline_config cfg;
        dof_config(&cfg, 1, threads[k]);
        char err[256];
        fv_pipeline *p = fv_pipeline_create(s, &cfg, err, sizeof err);
        assert_non_null(p);
        fv_frame_stats stt;
        long rays = 0;
        for (int fr = 0; fr < 4; fr++) {
            const fv_pose head = {{0.01f * (float)fr, 0.0f, 0.0f}, {0.0f, sinf(0.004f * (float)fr), 0.0f, cosf(0.004f * (float)fr)}};
            assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, &head, 0.45f, 0.5f, &stt), 0);
            rays += stt.samples;
        }
        ptrdiff_t stride;
        const float *img = fv_pipeline_image(p, FV_EYE_CENTER, &stride);
        const size_t n = (size_t)stride * 160 * 4;
        if (!ref) {
            ref = malloc(n * sizeof(float));
            for (int y = 0; y < 160; y++)
                memcpy(ref + 4 * y * stride, img + 4 * y * stride, 4 * sizeof(float) * 192);
            ref_rays = rays;
        } else {
            assert_int_equal(rays, ref_rays);
            for (int y = 0; y < 160; y++)
                assert_memory_equal(ref + 4 * y * stride, img + 4 * y * stride, 4 * sizeof(float) * 192);
        }
        fv_pipeline_destroy(p);
    }
    free(ref);
    fv_scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_coc_is_weier),
        cmocka_unit_test(test_density_is_filter_texel),
        cmocka_unit_test(test_density_full),
        cmocka_unit_test(test_density_periphery),
        cmocka_unit_test(test_roulette_unbiased),
        cmocka_unit_test(test_in_focus_untouched),
        cmocka_unit_test(test_periphery_thinned_evenly),
        cmocka_unit_test(test_transition_per_block),
        cmocka_unit_test(test_fovea_thinned_evenly),
        cmocka_unit_test(test_periphery_revisits),
        cmocka_unit_test(test_constant_image_reconstruction),
        cmocka_unit_test(test_pipeline_fewer_rays),
        cmocka_unit_test(test_pipeline_thread_determinism),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
