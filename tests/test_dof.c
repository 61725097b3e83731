/* The layered depth-of-field filter (core/dof/weier.c) on synthetic reconstructions: exactness in
 * focus, no far-to-near leakage, near blur spreading past silhouettes, the far Gaussian against
 * its formula, the CoC row against eq. (3), and thread-count invariance. */
#include <math.h>
#include <string.h>

#include "testutil.h"
#include "dof/dof.h"
#include "dof/weier_impl.h"
#include "render_dsp.h"
#include "base/util.h"

#define W 200
#define H 160
#define FOCAL 600.0f

typedef struct {
    fv_pyramid pyr;
    fv_render_dsp dsp;
    fv_dof_params prm;
    fv_dof_view v;
    fv_dof_work wk;
    float *out;
} rig;

/* Pixel colour/depth setter type: fills (r, g, b, depth_m) of pixel (x, y). */
typedef void (*scene_fn)(int x, int y, float px[4]);

static void rig_init(rig *r, scene_fn scene, fv_dof_preset preset, float focus_m, float gx, float gy)
{
    assert_int_equal(fv_pyramid_init(&r->pyr, W, H), 0);
    fv_pyr_level *l0 = &r->pyr.lv[0];
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            scene(x, y, l0->rgbd + 4 * ((ptrdiff_t)y * l0->stride + x));
            l0->wgt[(ptrdiff_t)y * l0->stride + x] = 1.0f;
        }
    fv_render_dsp_init(&r->dsp, FV_ISA_C);
    fv_pullpush(&r->pyr, &r->dsp.pp, NULL);
    fv_dof_params_default(&r->prm);
    r->prm.preset = preset;
    r->prm.contrast_gain = 0.0f;
    memset(&r->v, 0, sizeof r->v);
    r->v.pyr = &r->pyr;
    r->v.focus_m = focus_m;
    r->v.focal_px = FOCAL;
    r->v.blur_scale = fv_dof_presets[preset].e_scale;
    r->v.e_px_per_mm = FOCAL / 22.4f * r->v.blur_scale;
    r->v.gaze_x = gx, r->v.gaze_y = gy;
    r->v.r0_px = 30.0f, r->v.r1_px = 60.0f;
    r->v.prm = &r->prm;
    assert_int_equal(fv_dof_work_init(&r->wk, W, H, l0->stride), 0);
    r->out = malloc((size_t)l0->stride * H * 4 * sizeof(float));
    assert_non_null(r->out);
}

static void rig_run(rig *r, fv_pool *pool, unsigned isa)
{
    fv_render_dsp_init(&r->dsp, isa);
    fv_dof_times t;
    fv_dof_weier(&r->v, &r->wk, r->out, r->pyr.lv[0].stride, pool, &r->dsp.dof, &t);
    assert_true(t.coc_ms >= 0.0 && t.filter_ms >= 0.0 && t.combine_ms >= 0.0);
}

static void rig_free(rig *r)
{
    fv_pyramid_free(&r->pyr);
    fv_dof_work_free(&r->wk);
    free(r->out);
}

static const float *in_px(const rig *r, int x, int y) { return r->pyr.lv[0].rgbd + 4 * ((ptrdiff_t)y * r->pyr.lv[0].stride + x); }
static const float *out_px(const rig *r, int x, int y) { return r->out + 4 * ((ptrdiff_t)y * r->pyr.lv[0].stride + x); }

/* a high-frequency texture in [0.1, 0.9] */
static float tex(int x, int y, int c) { return 0.1f + 0.8f * (float)(((x * 7 + y * 13 + c * 5) % 17)) / 16.0f; }

static void plane_at_2m(int x, int y, float px[4])
{
    for (int c = 0; c < 3; c++)
        px[c] = tex(x, y, c);
    px[3] = 2.0f;
}

/* In focus everywhere: every pixel comes out exactly as it went in, with contrast enhancement
 * off, and in the fovea also with it on. */
static void test_in_focus_unchanged(void **st)
{
    (void)st;
    rig r;
    rig_init(&r, plane_at_2m, FV_DOF_STRONG, 2.0f, 100.0f, 80.0f);
    rig_run(&r, NULL, ~0u);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            assert_memory_equal(out_px(&r, x, y), in_px(&r, x, y), 4 * sizeof(float));
    /* a plane within the tolerance (2.15 m, t 0.2 m) is in focus too */
    r.v.focus_m = 2.15f;
    r.prm.contrast_gain = 0.5f;
    static const float fp[4] = {1.0f, 1.0f, 2.0f, 3.0f};
    r.v.enh_fp = fp, r.v.enh_n = 4, r.v.enh_step = 20.0f;
    rig_run(&r, NULL, ~0u);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const float dx = (float)x + 0.5f - 100.0f, dy = (float)y + 0.5f - 80.0f;
            if (dx * dx + dy * dy < 30.0f * 30.0f) /* the fovea: no enhancement */
                assert_memory_equal(out_px(&r, x, y), in_px(&r, x, y), 4 * sizeof(float));
        }
    rig_free(&r);
}

/* A near object (1 m, in focus) in front of a far textured background (10 m). */
#define SQ_X0 60
#define SQ_X1 120
#define SQ_Y0 50
#define SQ_Y1 110
static void near_square_far_bg(int x, int y, float px[4])
{
    const int in = x >= SQ_X0 && x < SQ_X1 && y >= SQ_Y0 && y < SQ_Y1;
    for (int c = 0; c < 3; c++)
        px[c] = in ? 0.5f : tex(x, y, c);
    px[3] = in ? 1.0f : 10.0f;
}

static void check_no_leak(float gx, float gy)
{
    rig r;
    rig_init(&r, near_square_far_bg, FV_DOF_STRONG, 1.0f, gx, gy);
    rig_run(&r, NULL, ~0u);
    /* the background is blurred (far CoC = 0.00449 * (1/1.2 - 1/10) * 600 * 4 = 7.9 px) ... */
    double bg_change = 0.0;
    for (int y = 0; y < 40; y++)
        for (int x = 0; x < W; x++)
            bg_change += fabsf(out_px(&r, x, y)[0] - in_px(&r, x, y)[0]);
    assert_true(bg_change / (40.0 * W) > 0.05);
    /* ... but not one pixel of the in-focus square moves */
    for (int y = SQ_Y0; y < SQ_Y1; y++)
        for (int x = SQ_X0; x < SQ_X1; x++)
            for (int c = 0; c < 3; c++)
                assert_float_equal(out_px(&r, x, y)[c], 0.5f, 1e-6f);
    rig_free(&r);
}

static void bright_square_dark_far_bg(int x, int y, float px[4])
{
    const int in = x >= SQ_X0 && x < SQ_X1 && y >= SQ_Y0 && y < SQ_Y1;
    px[0] = px[1] = px[2] = in ? 1.0f : 0.0f;
    px[3] = in ? 1.0f : 10.0f;
}

static void test_far_does_not_leak_fovea(void **st)
{
    (void)st;
    check_no_leak(90.0f, 80.0f); /* the square is in the Gaussian (centre) region */
    /* and in the centre the far layer holds only far samples: the blurred background next to
     * the sharp square does not take the square's colour (it is in front of it) */
    rig r;
    rig_init(&r, bright_square_dark_far_bg, FV_DOF_STRONG, 1.0f, 90.0f, 80.0f);
    r.v.r0_px = 80.0f, r.v.r1_px = 120.0f; /* all of it in the fovea (the transition blends in pyramid taps) */
    rig_run(&r, NULL, ~0u);
    for (int d = 1; d <= 6; d++) {
        assert_float_equal(out_px(&r, SQ_X1 - 1 + d, 80)[0], 0.0f, 1e-6f);
        assert_float_equal(out_px(&r, 90, SQ_Y0 - d)[1], 0.0f, 1e-6f);
    }
    rig_free(&r);
}

static void test_far_does_not_leak_periphery(void **st)
{
    (void)st;
    check_no_leak(-500.0f, -500.0f); /* everything in the periphery: pyramid taps */
}

/* A near object (0.3 m, out of focus) in front of an in-focus background (2 m). */
static void near_blurred_square(int x, int y, float px[4])
{
    const int in = x >= SQ_X0 && x < SQ_X1 && y >= SQ_Y0 && y < SQ_Y1;
    for (int c = 0; c < 3; c++)
        px[c] = in ? 1.0f : 0.0f;
    px[3] = in ? 0.3f : 2.0f;
}

/* In the fovea the near layer is the full-resolution box: the exact coverage profile. */
static void test_near_spreads_fovea(void **st)
{
    (void)st;
    rig r;
    rig_init(&r, near_blurred_square, FV_DOF_MEDIUM, 2.0f, 90.0f, 80.0f);
    r.v.r0_px = 90.0f, r.v.r1_px = 130.0f; /* the square and its surround in the fovea */
    rig_run(&r, NULL, ~0u);
    /* near CoC = 0.00449 * 600 * 2 * (1/0.3 - 1/1.8) = 14.97 px: radius floor(7.48) = 7 */
    const int R = 7, ym = (SQ_Y0 + SQ_Y1) / 2;
    for (int d = 1; d <= R; d++) {
        /* outside the silhouette on the focused background, within reach: the object's colour
         * spreads over it, less with distance (coverage of a box of 2R+1 = 15: (R + 1 - d) / 15) */
        const float expect = (float)(R + 1 - d) / 15.0f;
        assert_float_equal(out_px(&r, SQ_X1 - 1 + d, ym)[0], expect, 1e-4f);
        assert_float_equal(out_px(&r, SQ_X0 - d, ym)[1], expect, 1e-4f);
    }
    /* beyond reach the background is untouched */
    assert_memory_equal(out_px(&r, SQ_X1 + R, ym), in_px(&r, SQ_X1 + R, ym), 4 * sizeof(float));
    assert_memory_equal(out_px(&r, 5, 5), in_px(&r, 5, 5), 4 * sizeof(float));
    /* the object's inside, far from its edges, keeps its colour */
    assert_float_equal(out_px(&r, 90, ym)[0], 1.0f, 1e-5f);
    rig_free(&r);
}

/* In the periphery the near layer is the same filter on 4x4 blocks, up-sampled: the spread
 * falls off monotonically over about the same reach and leaves the rest alone. */
static void test_near_spreads_periphery(void **st)
{
    (void)st;
    rig r;
    rig_init(&r, near_blurred_square, FV_DOF_MEDIUM, 2.0f, -500.0f, -500.0f);
    rig_run(&r, NULL, ~0u);
    const int ym = (SQ_Y0 + SQ_Y1) / 2;
    float prev = 1.0f;
    for (int d = 1; d <= 12; d++) {
        const float v = out_px(&r, SQ_X1 - 1 + d, ym)[0];
        assert_true(v <= prev + 1e-6f);
        prev = v;
    }
    assert_true(out_px(&r, SQ_X1, ym)[0] > 0.3f);   /* spreads past the silhouette */
    assert_true(out_px(&r, SQ_X1 + 4, ym)[0] > 0.1f);
    assert_true(out_px(&r, SQ_X1 + 6, ym)[0] < out_px(&r, SQ_X1, ym)[0]);
    /* two blocks of reach plus the up-sampling's texel: nothing beyond 16 px */
    assert_memory_equal(out_px(&r, SQ_X1 + 16, ym), in_px(&r, SQ_X1 + 16, ym), 4 * sizeof(float));
    assert_memory_equal(out_px(&r, 5, 5), in_px(&r, 5, 5), 4 * sizeof(float));
    assert_float_equal(out_px(&r, 90, ym)[0], 1.0f, 1e-5f);
    rig_free(&r);
}

/* A far vertical step edge at one depth, in the centre: the far layer is a Gaussian of sigma
 * c / 4; the blurred edge follows 0.5 (1 + erf(d / (sigma sqrt 2))) (sampled at pixel centres). */
static void far_step(int x, int y, float px[4])
{
    (void)y;
    px[0] = px[1] = px[2] = x >= 100 ? 1.0f : 0.0f;
    px[3] = 5.0f;
}

static void test_far_gaussian_profile(void **st)
{
    (void)st;
    rig r;
    rig_init(&r, far_step, FV_DOF_STRONG, 0.6f, 100.0f, 80.0f);
    r.prm.tolerance_m = 0.0f;
    rig_run(&r, NULL, ~0u);
    const float c = 0.00449f * (1.0f / 0.6f - 1.0f / 5.0f) * FOCAL * 4.0f; /* 15.8 px */
    const float sigma = c / 4.0f;
    const int q = (int)(sigma * FV_DOF_SIG_STEPS + 0.5f); /* the table's quantised sigma */
    const double sq = (double)q / FV_DOF_SIG_STEPS;
    for (int x = 85; x < 115; x++) {
        /* discrete Gaussian: sum of weights over samples >= 100, normalised */
        double num = 0.0, den = 0.0;
        for (int j = -(int)ceil(3 * sq); j <= (int)ceil(3 * sq); j++) {
            const double g = exp(-0.5 * j * j / (sq * sq));
            den += g;
            num += x + j >= 100 ? g : 0.0;
        }
        assert_float_equal(out_px(&r, x, 80)[0], (float)(num / den), 2e-5f);
        /* and close to the continuous formula */
        const double d = (double)x + 0.5 - 100.0;
        assert_float_equal(out_px(&r, x, 80)[0], (float)(0.5 * (1.0 + erf(d / (sigma * sqrt(2.0))))), 0.03f);
    }
    rig_free(&r);
}

/* Patney's contrast enhancement, in focus (only it acts): a flat area is left exactly as it is
 * (the blur of a constant is that constant); across a step edge in the periphery the bright
 * side overshoots and the dark side clamps at 0; far from the edge nothing changes. */
static void step_in_focus(int x, int y, float px[4])
{
    (void)y;
    px[0] = px[1] = px[2] = x >= 100 ? 0.8f : 0.2f;
    px[3] = 2.0f;
}

static void test_contrast_enhancement(void **st)
{
    (void)st;
    rig r;
    rig_init(&r, step_in_focus, FV_DOF_WEAK, 2.0f, -300.0f, 80.0f); /* all in the periphery */
    r.prm.contrast_gain = 0.5f;
    static const float fp[4] = {3.0f, 3.0f, 3.0f, 3.0f};
    r.v.enh_fp = fp, r.v.enh_n = 4, r.v.enh_step = 1000.0f;
    rig_run(&r, NULL, ~0u);
    for (int y = 0; y < H; y++) {
        assert_memory_equal(out_px(&r, 10, y), in_px(&r, 10, y), 4 * sizeof(float));
        assert_memory_equal(out_px(&r, 190, y), in_px(&r, 190, y), 4 * sizeof(float));
    }
    assert_true(out_px(&r, 100, 80)[0] > 0.85f);                 /* overshoot on the bright side */
    assert_true(out_px(&r, 99, 80)[0] < 0.15f);                  /* undershoot on the dark side */
    assert_true(out_px(&r, 99, 80)[0] >= 0.0f);
    assert_true(out_px(&r, 100, 80)[0] > out_px(&r, 103, 80)[0]); /* fading away from the edge */
    rig_free(&r);
}

/* The periphery's pyramid blur at half resolution against the full-resolution path it replaced:
 * a textured floor receding from 0.4 to 40 m (every level 0..5), focus 1.5 m, strong, the gaze
 * at the centre. The fovea and transition region are bit for bit the same; beyond them the
 * half-resolution blur of levels >= 1 up-sampled differs from the per-pixel levels by the
 * extra bilinear step and the 2x2-mean CoC: mean |difference| <= 0.005, max <= 0.06 (colours in
 * [0.1, 0.9]; measured 0.0025 / 0.037). */
static void receding_floor(int x, int y, float px[4])
{
    for (int c = 0; c < 3; c++)
        px[c] = tex(x / 2, y / 3, c);
    px[3] = 0.4f * powf(100.0f, (float)y / (H - 1));
}

static void test_half_res_periphery(void **st)
{
    (void)st;
    rig a, b;
    rig_init(&a, receding_floor, FV_DOF_STRONG, 1.5f, 100.0f, 80.0f);
    rig_init(&b, receding_floor, FV_DOF_STRONG, 1.5f, 100.0f, 80.0f);
    b.prm.full_res_periphery = 1;
    rig_run(&a, NULL, ~0u);
    rig_run(&b, NULL, ~0u);
    double sum = 0.0, mx = 0.0;
    int n = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const float dx = (float)x + 0.5f - 100.0f, dy = (float)y + 0.5f - 80.0f;
            if (dx * dx + dy * dy < 60.0f * 60.0f) {
                assert_memory_equal(out_px(&a, x, y), out_px(&b, x, y), 4 * sizeof(float));
                continue;
            }
            for (int c = 0; c < 3; c++) {
                const double d = fabs((double)out_px(&a, x, y)[c] - out_px(&b, x, y)[c]);
                sum += d, mx = d > mx ? d : mx, n++;
            }
        }
    print_message("half-res periphery: mean |diff| %.4f, max %.4f over %d values\n", sum / n, mx, n);
    assert_true(sum / n <= 0.005);
    assert_true(mx <= 0.06);
    rig_free(&a);
    rig_free(&b);
}

/* Beyond the transition disc one kernel (dof_periph_row) blends the sharp row towards the
 * half-resolution blur up-sampled by 2, with the own-blur weight in closed form: w = min(|c|, 1)
 * min(|c|^2 3 / 44, 1) (the level-0..1 interpolation of the disc's variance, which the level table
 * held in steps of 1/8 px). A far plane with c = 2.06 px (off the table's grid; its 2x2-mean CoC
 * selects level 1 itself on the half grid): every peripheral pixel is s + w (U - s), U level 1
 * up-sampled bilinearly (computed here in double), within 2e-6. The table's w (c taken as 2.0)
 * is 0.0166 lower: the chain of kernels fails this (max 6.3e-3). */
static void busy(int x, int y, float px[4]);
#define C206_FOCUS 1.0f
static float c206_depth(void)
{
    const double K = 4.49e-3 * FOCAL * fv_dof_presets[FV_DOF_MEDIUM].e_scale, df = C206_FOCUS + 0.2;
    return (float)(1.0 / (1.0 / df - 2.06 / K));
}
static void plane_c206(int x, int y, float px[4])
{
    for (int c = 0; c < 3; c++)
        px[c] = tex(x, y, c);
    px[3] = c206_depth();
}

static void test_periph_closed_form(void **st)
{
    (void)st;
    rig r;
    rig_init(&r, plane_c206, FV_DOF_MEDIUM, C206_FOCUS, 40.0f, 40.0f);
    assert_float_equal(r.prm.pupil_mm, 4.49f, 0.0f);
    rig_run(&r, NULL, ~0u);
    const double K = 4.49e-3 * FOCAL * r.v.blur_scale;
    const double c = K * (1.0 / (C206_FOCUS + 0.2) - 1.0 / (double)c206_depth());
    const double w = fmin(c, 1.0) * fmin(c * c * 3.0 / 44.0, 1.0);
    const fv_pyr_level *l1 = &r.pyr.lv[1];
    double mx = 0.0, dmax = 0.0;
    int n = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const float dx = (float)x + 0.5f - 40.0f, dy = (float)y + 0.5f - 40.0f;
            if (dx * dx + dy * dy < 62.0f * 62.0f)
                continue;
            const double u = ((double)x + 0.5) * 0.5 - 0.5, v = ((double)y + 0.5) * 0.5 - 0.5;
            const int u0 = (int)floor(u), v0 = (int)floor(v);
            const double au = u - u0, av = v - v0;
            for (int k = 0; k < 3; k++) {
                double t[2];
                for (int j = 0; j < 2; j++) {
                    const int yy = fv_clampi(v0 + j, 0, l1->h - 1);
                    const float *row = l1->rgbd + 4 * (ptrdiff_t)yy * l1->stride;
                    const double a = row[4 * fv_clampi(u0, 0, l1->w - 1) + k], b = row[4 * fv_clampi(u0 + 1, 0, l1->w - 1) + k];
                    t[j] = a + au * (b - a);
                }
                const double U = t[0] + av * (t[1] - t[0]), s = in_px(&r, x, y)[k];
                const double e = s + w * (U - s), d = fabs((double)out_px(&r, x, y)[k] - e);
                mx = d > mx ? d : mx, n++;
                dmax = fabs(U - s) > dmax ? fabs(U - s) : dmax;
            }
            assert_memory_equal(&out_px(&r, x, y)[3], &in_px(&r, x, y)[3], sizeof(float));
        }
    print_message("periphery closed form: c %.4f px, w %.5f, max |out - expected| %.2e over %d values (max |U - s| %.3f)\n",
                  c, w, mx, n, dmax);
    assert_true(n > 10000 && dmax > 0.3);
    assert_true(mx <= 2e-6);
    rig_free(&r);
}

/* The fused periphery against the chain of kernels it replaced (up-sampling, pyramid blend,
 * combine; prm.chain_periphery) on the receding floor (every CoC 0..~60 px, strong): the fovea
 * and transition ring bit for bit; beyond them they differ only by the level table's steps of
 * 1/8 px: |w - w_table| <= 3/44 (c^2 - (c - 1/8)^2) < 3/44 * 2 * 3.83 / 8 = 0.066 below the
 * knee (|c| = 3.83, where both reach 1) times |U - s| <= 0.8: max <= 0.053, and on average far
 * less (measured: see the message). */
static void test_fused_periphery_vs_chain(void **st)
{
    (void)st;
    rig a, b;
    rig_init(&a, receding_floor, FV_DOF_STRONG, 1.5f, 100.0f, 80.0f);
    rig_init(&b, receding_floor, FV_DOF_STRONG, 1.5f, 100.0f, 80.0f);
    b.prm.chain_periphery = 1;
    rig_run(&a, NULL, ~0u);
    rig_run(&b, NULL, ~0u);
    double sum = 0.0, mx = 0.0;
    int n = 0, diff = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const float dx = (float)x + 0.5f - 100.0f, dy = (float)y + 0.5f - 80.0f;
            if (dx * dx + dy * dy < 59.0f * 59.0f) {
                assert_memory_equal(out_px(&a, x, y), out_px(&b, x, y), 4 * sizeof(float));
                continue;
            }
            assert_memory_equal(&out_px(&a, x, y)[3], &out_px(&b, x, y)[3], sizeof(float));
            for (int c = 0; c < 3; c++) {
                const double d = fabs((double)out_px(&a, x, y)[c] - out_px(&b, x, y)[c]);
                sum += d, mx = d > mx ? d : mx, n++, diff += d > 0.0;
            }
        }
    print_message("fused periphery vs chain: mean |diff| %.5f, max %.4f, %d of %d values differ\n", sum / n, mx, diff, n);
    assert_true(mx <= 0.053);
    assert_true(sum / n <= 0.005);
    rig_free(&a);
    rig_free(&b);
}

/* Runs r on 1, 2 and 5 threads with the C kernels and the best ISA's, each time from a zeroed
 * output, and asserts every run's rows equal ref's (row stride ref_stride pixels) bit for bit. */
static void assert_same_any_threads_isa(rig *r, const float *ref, ptrdiff_t ref_stride)
{
    const int threads[] = {1, 2, 5};
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < 2; i++) {
            fv_pool *pool = fv_pool_create(threads[k]);
            assert_non_null(pool);
            memset(r->out, 0, (size_t)r->pyr.lv[0].stride * H * 4 * sizeof(float));
            rig_run(r, pool, i ? ~0u : FV_ISA_C);
            for (int y = 0; y < H; y++)
                assert_memory_equal(r->out + 4 * (size_t)y * r->pyr.lv[0].stride, ref + 4 * (ptrdiff_t)y * ref_stride,
                                    W * 4 * sizeof(float));
            fv_pool_destroy(pool);
        }
}

/* The fused periphery path (contrast enhancement off) gives the same bits for 1, 2 and 5 threads
 * and for the C kernels and the best ISA's. */
static void test_fused_threads_and_isas_identical(void **st)
{
    (void)st;
    rig r;
    rig_init(&r, busy, FV_DOF_MEDIUM, 1.0f, 70.0f, 60.0f);
    const size_t n = (size_t)r.pyr.lv[0].stride * H * 4;
    float *ref = malloc(n * sizeof(float));
    assert_non_null(ref);
    rig_run(&r, NULL, FV_ISA_C);
    memcpy(ref, r.out, n * sizeof(float));
    assert_same_any_threads_isa(&r, ref, r.pyr.lv[0].stride);
    free(ref);
    rig_free(&r);
}

/* The fused pass makes the half-resolution periphery blur's rows per band (with a half row of
 * halo each side, recomputed by both bands that read it) instead of one pass writing the whole
 * image: bound 0, the same bits as that pass (prm.hblur_pass), on the receding floor (every CoC,
 * so every level the half grid reads) with the gaze at the centre and near a corner (bands whose
 * halo rows clamp at the image's edge, rows with no disc), for 1, 2 and 5 threads and C / best ISA. */
static void test_band_hblur_vs_pass(void **st)
{
    (void)st;
    const float gaze[2][2] = {{100.0f, 80.0f}, {23.0f, 151.0f}};
    for (int g = 0; g < 2; g++) {
        rig a, b;
        rig_init(&a, receding_floor, FV_DOF_STRONG, 1.5f, gaze[g][0], gaze[g][1]);
        rig_init(&b, receding_floor, FV_DOF_STRONG, 1.5f, gaze[g][0], gaze[g][1]);
        b.prm.hblur_pass = 1;
        rig_run(&b, NULL, FV_ISA_C);
        assert_same_any_threads_isa(&a, b.out, b.pyr.lv[0].stride);
        rig_free(&a);
        rig_free(&b);
    }
}

/* The CoC plane (the first 1-float scratch plane) is written only for the centre rectangle's rows
 * (the transition disc plus twice the largest blur radius, FV_DOF_RMAX: with r1 = 60 and the gaze
 * at y = 151 the rows from floor(151 - 60 - 48) = 43 on); the fused pass recomputes the other rows'
 * CoC from level 0. Poisoned with NaN, rows 0..42 stay NaN and the output keeps its bits
 * (recomputed rows: the same kernel on the same inputs). Without the change every row is written. */
static void test_coc_plane_centre_only(void **st)
{
    (void)st;
    rig r;
    rig_init(&r, busy, FV_DOF_MEDIUM, 1.0f, 23.0f, 151.0f);
    const size_t n = (size_t)r.pyr.lv[0].stride * H * 4;
    float *ref = malloc(n * sizeof(float));
    assert_non_null(ref);
    rig_run(&r, NULL, FV_ISA_C);
    memcpy(ref, r.out, n * sizeof(float));
    fv_pool *pool = fv_pool_create(2);
    assert_non_null(pool);
    const unsigned isas[] = {FV_ISA_C, ~0u};
    for (int k = 0; k < 2; k++) {
        for (size_t i = 0; i < (size_t)r.wk.stride * H; i++)
            r.wk.p1[0][i] = NAN;
        memset(r.out, 0, n * sizeof(float));
        rig_run(&r, pool, isas[k]);
        for (int y = 0; y < H; y++) {
            assert_memory_equal(r.out + 4 * (size_t)y * r.pyr.lv[0].stride, ref + 4 * (size_t)y * r.pyr.lv[0].stride,
                                W * 4 * sizeof(float));
            for (int x = 0; x < W; x++)
                assert_int_equal(isnan(r.wk.p1[0][(size_t)y * r.wk.stride + x]) != 0, y < 43);
        }
    }
    fv_pool_destroy(pool);
    free(ref);
    rig_free(&r);
}

/* The CoC row kernel against eq. (3) in double (core/dof/coc.c), every ISA. */
static void test_coc_row_matches_eq3(void **st)
{
    (void)st;
    fv_coc_weier p;
    fv_coc_weier_default(&p, FOCAL);
    float rgbd[4 * 64], coc[64];
    for (int i = 0; i < 64; i++) {
        rgbd[4 * i + 3] = 0.04f * (float)(i + 1) * (float)(i + 1) / 8.0f; /* 5 mm .. 20 m */
        rgbd[4 * i] = rgbd[4 * i + 1] = rgbd[4 * i + 2] = 0.0f;
    }
    const float focus = 1.0f, K = 0.00449f * FOCAL;
    const unsigned isas[] = {FV_ISA_C, FV_ISA_SSE41, FV_ISA_SSE41 | FV_ISA_AVX2, FV_ISA_NEON};
    for (size_t k = 0; k < sizeof isas / sizeof isas[0]; k++) {
        fv_dof_dsp d;
        fv_dof_dsp_init(&d, isas[k]);
        d.dof_coc_row(coc, rgbd, 64, K, focus - 0.2f, focus + 0.2f);
        for (int i = 0; i < 64; i++) {
            const float e = fv_coc_weier_px(&p, focus, rgbd[4 * i + 3]);
            assert_float_equal(coc[i], e, 1e-3f + 1e-3f * fabsf(e));
            if (rgbd[4 * i + 3] >= 0.8f && rgbd[4 * i + 3] <= 1.2f)
                assert_true(coc[i] == 0.0f);
        }
    }
}

/* A busy scene: near, in-focus and far parts, the gaze so that all three regions appear. */
static void busy(int x, int y, float px[4])
{
    for (int c = 0; c < 3; c++)
        px[c] = tex(x, y, c);
    px[3] = 0.3f + 0.02f * (float)((x * 3 + y * 5) % 97) + ((x / 20 + y / 20) & 1 ? 5.0f : 0.0f);
}

static void test_threads_and_isas_identical(void **st)
{
    (void)st;
    rig r;
    rig_init(&r, busy, FV_DOF_MEDIUM, 1.0f, 70.0f, 60.0f);
    r.prm.contrast_gain = 0.5f;
    float fp[40];
    for (int i = 0; i < 40; i++)
        fp[i] = 1.0f + 0.2f * (float)i;
    r.v.enh_fp = fp, r.v.enh_n = 40, r.v.enh_step = 8.0f;
    const size_t n = (size_t)r.pyr.lv[0].stride * H * 4;
    float *ref = malloc(n * sizeof(float));
    assert_non_null(ref);
    rig_run(&r, NULL, FV_ISA_C);
    memcpy(ref, r.out, n * sizeof(float));
    fv_pool *pool = fv_pool_create(3);
    assert_non_null(pool);
    const unsigned isas[] = {FV_ISA_C, ~0u};
    for (size_t k = 0; k < 2; k++) {
        memset(r.out, 0, n * sizeof(float));
        rig_run(&r, pool, isas[k]);
        for (int y = 0; y < H; y++)
            assert_memory_equal(r.out + 4 * (size_t)y * r.pyr.lv[0].stride, ref + 4 * (size_t)y * r.pyr.lv[0].stride,
                                W * 4 * sizeof(float));
    }
    fv_pool_destroy(pool);
    free(ref);
    rig_free(&r);
}

/* A scene without any near field (everything behind the focus range): the frame's quarter-
 * resolution layer is empty and the combine gets no near layer at all. */
static void far_only(int x, int y, float px[4])
{
    for (int c = 0; c < 3; c++)
        px[c] = tex(x, y, c);
    px[3] = 2.0f + 0.05f * (float)((x * 3 + y * 5) % 37);
}

/* Near field only in a strip of rows 100..107 (block rows 25, 26), far behind it: block rows have
 * different largest radii, so the band pipeline's per-row reach differs from the frame's. */
static void near_strip(int x, int y, float px[4])
{
    for (int c = 0; c < 3; c++)
        px[c] = tex(x, y, c);
    px[3] = y >= 100 && y < 108 && x >= 30 && x < 170 ? 0.25f + 0.01f * (float)(x % 7) : 4.0f;
}

/* Near field at 0.15 m over the top 20 rows (a radius of 24 px with the strong preset: the
 * dilation's reach is 2 tiles from the first band on), the busy scene below. */
static void near_top(int x, int y, float px[4])
{
    busy(x, y, px);
    if (y < 20)
        px[3] = 0.15f;
}

/* near_strip plus a patch of near pixels of radius 1 (1 m, focus 1.5 m, strong) in rows 56..63:
 * band 3 has near work, but the frame's reach (2 tiles) is known only from the strip's tile row
 * 6, so its horizontal pass is made after the pipeline, and with the gaze at y = 78 (r1 = 15) the
 * disc's rows from 64 on read it through the near box. */
static void near_strip_patch(int x, int y, float px[4])
{
    near_strip(x, y, px);
    if (y >= 56 && y < 64 && x >= 90 && x < 110)
        px[3] = 1.0f;
}

/* near_top's near rows over a far background (4 m) with near pixels of radius 0 (c = -0.9 px at
 * 0.75 m, focus 1 m, strong) on a third of the rows 40..70: with the gaze at y = 56 and r1 = 15 they
 * lie in the transition ring, where a tile the dilation marks (2 tiles from the top rows' 24 px
 * radius) blends them in as their own near layer and an unmarked one does not. */
static void near_top_ring(int x, int y, float px[4])
{
    for (int c = 0; c < 3; c++)
        px[c] = tex(x, y, c);
    px[3] = y < 20 ? 0.15f : y >= 40 && y <= 70 && (x + y) % 3 == 0 ? 0.75f : 4.0f;
}

/* near_top_ring's radius-0 ring pixels (rows 40..70) with a near row of radius 2 px (0.6 m) in
 * tile row 1 and a radius of 24 px (0.15 m) only in the bottom rows 140..159: with the gaze at
 * y = 56 the ring's tile row 3 is 2 tiles from the radius-2 row, the frame's dilation spans 2 tiles
 * (marking it) but the pipeline learns that only at band 6, so bands 0..5 guess 1 tile and are
 * made again after the job. */
static void ring_late(int x, int y, float px[4])
{
    near_top_ring(x, y, px);
    if (y < 20)
        px[3] = 4.0f;
    if (y >= 16 && y < 32)
        px[3] = 0.6f;
    if (y >= 140)
        px[3] = 0.15f;
}

/* ring_late without the bottom rows' near field: the frame's dilation spans 1 tile (largest radius
 * 2 px), which the pipeline's guess gets right; the ring's tile row 3 stays unmarked. */
static void ring_small(int x, int y, float px[4])
{
    ring_late(x, y, px);
    if (y >= 140)
        px[3] = 4.0f;
}

/* The band pipeline (the CoC pass, the centre's horizontal pass and the fused pass in one job,
 * weier_pipe.c) against the passes one after another (prm.band_passes): bound 0, for 1, 2 and 5
 * threads and C / best ISA, on scenes with near field everywhere (busy), a near field whose
 * radius grows towards the top (receding floor, strong), none (far only: the combine gets no near
 * layer), a narrow strip (per-row reach below the frame's; a radius of 17 px from tile row 6 on,
 * so with the gaze at y = 120 the centre bands 6..9 run in the pipeline and 3..5 after it; with a
 * patch of radius-1 near pixels in band 3 and the gaze at y = 78, band 4 after it, because band
 * 3's horizontal pass, which it reads, is made after it), a near top
 * (the centre's bands all in the pipeline), the near top with radius-0 near pixels in the
 * transition ring (the pipeline's tile dilation must span exactly the frame's 2 tiles), and those
 * ring pixels 2 tiles from a radius-2 near row, with a radius of 24 px only at the bottom (the
 * guessed reach of 1 tile is wrong: bands 0..5 are made again after the job) or nowhere (the
 * guess is right and kept); the gaze
 * and r1 so that the free bands are above the centre, below it, on both sides, all of them (the
 * gaze off the image) or none. */
static void test_pipeline_vs_band_passes(void **st)
{
    (void)st;
    const struct {
        scene_fn scene;
        fv_dof_preset preset;
        float focus_m, gx, gy, r1;
    } cases[] = {
        {busy, FV_DOF_MEDIUM, 1.0f, 70.0f, 60.0f, 15.0f},           {busy, FV_DOF_MEDIUM, 1.0f, 23.0f, 151.0f, 60.0f},
        {receding_floor, FV_DOF_STRONG, 1.5f, 100.0f, 80.0f, 15.0f}, {receding_floor, FV_DOF_STRONG, 1.5f, 100.0f, 20.0f, 15.0f},
        {far_only, FV_DOF_STRONG, 1.0f, 100.0f, 80.0f, 15.0f},       {near_strip, FV_DOF_STRONG, 1.5f, 100.0f, 30.0f, 15.0f},
        {near_strip, FV_DOF_STRONG, 1.5f, 100.0f, -200.0f, 15.0f},   {near_strip, FV_DOF_STRONG, 1.5f, 100.0f, 120.0f, 15.0f},
        {near_top, FV_DOF_STRONG, 1.0f, 100.0f, 80.0f, 15.0f},       {near_top, FV_DOF_STRONG, 1.0f, 100.0f, 80.0f, 60.0f},
        {near_strip_patch, FV_DOF_STRONG, 1.5f, 100.0f, 78.0f, 15.0f}, {near_top_ring, FV_DOF_STRONG, 1.0f, 100.0f, 56.0f, 15.0f},
        {ring_late, FV_DOF_STRONG, 1.0f, 100.0f, 56.0f, 15.0f},      {ring_small, FV_DOF_STRONG, 1.0f, 100.0f, 56.0f, 15.0f},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        rig a, b;
        rig_init(&a, cases[k].scene, cases[k].preset, cases[k].focus_m, cases[k].gx, cases[k].gy);
        rig_init(&b, cases[k].scene, cases[k].preset, cases[k].focus_m, cases[k].gx, cases[k].gy);
        a.v.r0_px = b.v.r0_px = cases[k].r1 * 0.5f;
        a.v.r1_px = b.v.r1_px = cases[k].r1;
        b.prm.band_passes = 1;
        rig_run(&b, NULL, FV_ISA_C);
        assert_same_any_threads_isa(&a, b.out, b.pyr.lv[0].stride);
        rig_free(&a);
        rig_free(&b);
    }
}

/* The pipeline's order, from its per-band spans on the workers' tracks ("dof coc band", "dof
 * fused band", arg = the band): every band's CoC work once; the fused pass, with the gaze at
 * y = 80 and r1 = 15 (centre rows [17, 143): bands 1..8 hold centre rows), of the free bands 0 and
 * 9 three bands after their CoC work, and of the centre bands four bands after it when the frame's
 * near reach is known early (near_top, strong: a radius of 24 px in band 0) or not at all in the
 * job when it is not (busy, medium: radii up to 5 px, so the reach is known only after the whole
 * frame). Each fused band after the CoC work of the bands up to b + 3 (b + 4 in the centre) that it
 * reads and, on one thread, in the order below, so that its level 0 rows are at most four or five
 * bands (64-80 rows) old. On 2 and 5 threads the same dependency by the spans' times. Fails
 * without the pipeline (no such spans: the CoC pass ran first). */
static void test_pipeline_order(void **st)
{
    (void)st;
    const int th = (H + 15) / 16, threads[] = {1, 2, 5};
    /* slot 0's events on one thread: CoC work of band b as b, its fused pass as 100 + b */
    const int want[] = {0, 1, 2, 3, 100, 4, 5, 101, 6, 102, 7, 103, 8, 104, 9, 105, 106, 107, 109, 108};
    for (int sc = 0; sc < 2; sc++)
        for (int n = 0; n < 3; n++) {
            rig r;
            rig_init(&r, sc ? near_top : busy, sc ? FV_DOF_STRONG : FV_DOF_MEDIUM, 1.0f, 100.0f, 80.0f);
            r.v.r0_px = 8.0f, r.v.r1_px = 15.0f;
            fv_prof *prof = fv_prof_create(threads[n], 4096);
            fv_pool *pool = fv_pool_create(threads[n]);
            assert_non_null(prof);
            assert_non_null(pool);
            r.v.prof = prof;
            rig_run(&r, pool, ~0u);
            int64_t coc_end[16], fused_start[16];
            int coc_n[16] = {0}, fused_n[16] = {0}, seq[64], nseq = 0;
            for (int s = 0; s < threads[n]; s++)
                for (size_t i = 0; i < fv_prof_count(prof, s); i++) {
                    const fv_prof_event *e = fv_prof_event_at(prof, s, i);
                    const int coc = !strcmp(e->name, "dof coc band"), fused = !strcmp(e->name, "dof fused band");
                    if (!coc && !fused)
                        continue;
                    assert_true(e->arg >= 0 && e->arg < th);
                    if (coc)
                        coc_n[e->arg]++, coc_end[e->arg] = e->t1_ns;
                    else
                        fused_n[e->arg]++, fused_start[e->arg] = e->t0_ns;
                    if (threads[n] == 1 && nseq < 64)
                        seq[nseq++] = coc ? e->arg : 100 + e->arg; /* slot 0's events in order */
                }
            for (int b = 0; b < th; b++) {
                const int free_band = b == 0 || b == th - 1;
                assert_int_equal(coc_n[b], 1);
                assert_int_equal(fused_n[b], 1);
                if (fused_n[b])
                    assert_true(fused_start[b] >= coc_end[fv_mini(b + (free_band ? 3 : 4), th - 1)]);
            }
            if (threads[n] == 1) {
                const int nw = (int)(sizeof want / sizeof *want);
                assert_int_equal(nseq, nw);
                assert_memory_equal(seq, want, (size_t)nw * sizeof *want);
            }
            fv_pool_destroy(pool);
            fv_prof_destroy(prof);
            rig_free(&r);
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_in_focus_unchanged),
        cmocka_unit_test(test_far_does_not_leak_fovea),
        cmocka_unit_test(test_far_does_not_leak_periphery),
        cmocka_unit_test(test_near_spreads_fovea),
        cmocka_unit_test(test_near_spreads_periphery),
        cmocka_unit_test(test_half_res_periphery),
        cmocka_unit_test(test_far_gaussian_profile),
        cmocka_unit_test(test_contrast_enhancement),
        cmocka_unit_test(test_coc_row_matches_eq3),
        cmocka_unit_test(test_threads_and_isas_identical),
        cmocka_unit_test(test_periph_closed_form),
        cmocka_unit_test(test_fused_periphery_vs_chain),
        cmocka_unit_test(test_fused_threads_and_isas_identical),
        cmocka_unit_test(test_band_hblur_vs_pass),
        cmocka_unit_test(test_coc_plane_centre_only),
        cmocka_unit_test(test_pipeline_vs_band_passes),
        cmocka_unit_test(test_pipeline_order),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
