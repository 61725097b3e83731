/* The alternative DoF models (core/dof/hussain.c, mantiuk.c, konrad.c, liu.c) on synthetic
 * pyramids: in-focus planes come out bit for bit, far blur stays off an in-focus nearer object,
 * a blurred near object's blur spreads past its silhouette, 1 and 3 threads give the same bits,
 * plus hand-computed impulse responses (Hussain's sigma per foveation region and the min rule,
 * Liu's per-channel discs with chromatic aberration). Expected numbers were computed outside the
 * code from the definitions (formulas in the comments). */
#include <math.h>
#include <string.h>

#include "testutil.h"

#include "dof/dof.h"
#include "pool.h"
#include "pullpush.h"
#include "render_dsp.h"

#define W 90 /* not a multiple of the 16 px tiles or the 8 px blocks */
#define H 70
#define FOCAL_PX 600.0f

typedef struct model {
    const char *name;
    fv_dof_model_fn fn;
} model;
static const model models[] = {
    {"hussain", fv_dof_hussain},
    {"mantiuk", fv_dof_mantiuk},
    {"konrad", fv_dof_konrad},
    {"liu", fv_dof_liu},
};
#define NMODELS (int)(sizeof models / sizeof models[0])

/* Square in the middle of the image: [SQ_X0, SQ_X1) x [SQ_Y0, SQ_Y1). */
#define SQ_X0 35
#define SQ_X1 55
#define SQ_Y0 25
#define SQ_Y1 45

typedef struct fixture {
    fv_pyramid pyr;
    fv_dof_work wk;
    fv_dof_params prm;
    fv_dof_view view;
    fv_render_dsp dsp;
    float *out, *out2;
} fixture;

/* rgb, depth of a pixel of a test scene */
typedef void (*scene_fn)(int x, int y, float px[4], const void *arg);

static float texture(int x, int y, int salt)
{
    uint64_t s = (uint64_t)(y * 1000 + x) * 0x9e3779b97f4a7c15ull + (uint64_t)salt;
    return 0.1f + 0.3f * fv_test_randf(&s) + 0.2f * (float)(((x >> 2) + (y >> 2)) & 1);
}

static int in_square(int x, int y) { return x >= SQ_X0 && x < SQ_X1 && y >= SQ_Y0 && y < SQ_Y1; }

static void fx_init(fixture *f)
{
    memset(f, 0, sizeof *f);
    assert_int_equal(fv_pyramid_init(&f->pyr, W, H), 0);
    assert_int_equal(fv_dof_work_init(&f->wk, W, H, f->pyr.lv[0].stride), 0);
    fv_render_dsp_init(&f->dsp, ~0u);
    fv_dof_params_default(&f->prm);
    f->prm.preset = FV_DOF_MEDIUM;
    const float scale = fv_dof_presets[FV_DOF_MEDIUM].e_scale; /* 2 */
    f->view = (fv_dof_view){.pyr = &f->pyr, .focus_m = 2.0f, .focal_px = FOCAL_PX,
                            .e_px_per_mm = FOCAL_PX / FV_EYE_IMAGE_DIST_MM * scale, .blur_scale = scale,
                            /* gaze far off the image: everything is periphery for hussain */
                            .gaze_x = -1000.0f, .gaze_y = -1000.0f, .r0_px = 40.0f, .r1_px = 80.0f, .prm = &f->prm};
    f->out = calloc((size_t)W * H * 4, sizeof(float));
    f->out2 = calloc((size_t)W * H * 4, sizeof(float));
    assert_non_null(f->out);
    assert_non_null(f->out2);
}

static void fx_free(fixture *f)
{
    fv_pyramid_free(&f->pyr);
    fv_dof_work_free(&f->wk);
    free(f->out);
    free(f->out2);
}

static void fx_scene(fixture *f, scene_fn fn, const void *arg)
{
    const fv_pyr_level *L = &f->pyr.lv[0];
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            fn(x, y, L->rgbd + 4 * ((ptrdiff_t)y * L->stride + x), arg);
            L->wgt[(ptrdiff_t)y * L->stride + x] = 1.0f;
        }
    fv_pullpush(&f->pyr, &f->dsp.pp, NULL);
}

static const float *in_px(const fixture *f, int x, int y)
{
    return f->pyr.lv[0].rgbd + 4 * ((ptrdiff_t)y * f->pyr.lv[0].stride + x);
}
static float *out_px(float *out, int x, int y) { return out + 4 * ((size_t)y * W + x); }

static void run(fixture *f, int m, fv_pool *pool, float *out)
{
    fv_dof_times t = {0};
    models[m].fn(&f->view, &f->wk, out, W, pool, &f->dsp.dof, &t);
    assert_true(t.coc_ms >= 0.0 && t.filter_ms >= 0.0);
    assert_true(isnan(t.combine_ms) || t.combine_ms >= 0.0);
}

/* max |out - in| over rgb of the pixels where sel(x, y) holds */
static float max_change(const fixture *f, const float *out, int (*sel)(int, int))
{
    float m = 0.0f;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            if (sel(x, y))
                for (int c = 0; c < 3; c++) {
                    float d = fabsf(out[4 * ((size_t)y * W + x) + c] - in_px(f, x, y)[c]);
                    m = d > m ? d : m;
                }
    return m;
}

/* ------------------------------------------------------------------ scenes */

static void plane_scene(int x, int y, float px[4], const void *arg)
{
    const float depth = *(const float *)arg;
    px[0] = texture(x, y, 1), px[1] = texture(x, y, 2), px[2] = texture(x, y, 3), px[3] = depth;
}

typedef struct sq_scene_arg {
    float square_m, background_m;
} sq_scene_arg;

/* a bright flat square at square_m before a dark textured background at background_m */
static void square_scene(int x, int y, float px[4], const void *arg)
{
    const sq_scene_arg *a = arg;
    if (in_square(x, y)) {
        px[0] = 0.9f + 0.1f * texture(x, y, 7), px[1] = 0.8f, px[2] = 0.95f, px[3] = a->square_m;
    } else {
        px[0] = 0.2f * texture(x, y, 4), px[1] = 0.2f * texture(x, y, 5), px[2] = 0.2f * texture(x, y, 6);
        px[3] = a->background_m;
    }
}

/* (1) a textured plane at the focus depth: every model returns the input bit for bit (rgb and
 * depth), also with Liu's chromatic aberration (the focus plane stays sharp in every channel). */
static void test_in_focus_plane_exact(void **st)
{
    (void)st;
    fixture f;
    fx_init(&f);
    const float depth = 2.0f;
    fx_scene(&f, plane_scene, &depth);
    f.view.focus_m = 2.0f;
    for (int chroma = 0; chroma < 2; chroma++)
        for (int m = 0; m < NMODELS; m++) {
            f.prm.chroma = chroma;
            memset(f.out, 0xff, (size_t)W * H * 4 * sizeof(float)); /* NaNs: every pixel must be written */
            run(&f, m, NULL, f.out);
            for (int y = 0; y < H; y++)
                if (memcmp(out_px(f.out, 0, y), in_px(&f, 0, y), (size_t)W * 4 * sizeof(float))) {
                    print_error("%s (chroma %d): row %d changed\n", models[m].name, chroma, y);
                    fail();
                }
        }
    fx_free(&f);
}

static int sel_square(int x, int y) { return in_square(x, y); }
/* background pixels 3 or more px away from the square (inside the blurred background) */
static int sel_bg_far3(int x, int y)
{
    return x < SQ_X0 - 3 || x >= SQ_X1 + 3 || y < SQ_Y0 - 3 || y >= SQ_Y1 + 3;
}

/* (2) focus on an in-focus near square (0.5 m) before a far textured background (5 m, a CoC of
 * ~9.7 px at medium; hussain's sigma 2.4 px): the far blur must not reach into the square. The
 * bound: no square pixel changes by more than 1e-6 (every model keeps far colour out of an
 * in-focus pixel entirely), while the background does change (the blur is there). */
static void test_far_blur_stays_off_in_focus_near(void **st)
{
    (void)st;
    fixture f;
    fx_init(&f);
    const sq_scene_arg a = {0.5f, 5.0f};
    fx_scene(&f, square_scene, &a);
    f.view.focus_m = 0.5f;
    for (int m = 0; m < NMODELS; m++) {
        run(&f, m, NULL, f.out);
        const float sq = max_change(&f, f.out, sel_square), bg = max_change(&f, f.out, sel_bg_far3);
        print_message("%-8s square max change %.3g, background max change %.3g\n", models[m].name, sq, bg);
        assert_true(sq <= 1e-6f);
        assert_true(bg > 0.02f);
    }
    fx_free(&f);
}

/* ring of background pixels 1..2 px outside the square */
static int sel_ring2(int x, int y)
{
    return !in_square(x, y) && x >= SQ_X0 - 2 && x < SQ_X1 + 2 && y >= SQ_Y0 - 2 && y < SQ_Y1 + 2;
}
/* background 24 px or more from the square: beyond every model's reach */
static int sel_bg_far24(int x, int y)
{
    return x < SQ_X0 - 24 || x >= SQ_X1 + 24 || y < SQ_Y0 - 24 || y >= SQ_Y1 + 24;
}

/* (3) a blurred near square (0.5 m; CoC ~9 px, hussain sigma 2.2 px) before an in-focus background
 * (3 m): the blur spreads past the silhouette: the mean change of the background ring 1-2 px
 * outside is at least 0.05 (the square is ~0.85 brighter), and the background far away is
 * untouched. */
static void test_near_blur_spreads_past_silhouette(void **st)
{
    (void)st;
    fixture f;
    fx_init(&f);
    const sq_scene_arg a = {0.5f, 3.0f};
    fx_scene(&f, square_scene, &a);
    f.view.focus_m = 3.0f;
    for (int m = 0; m < NMODELS; m++) {
        run(&f, m, NULL, f.out);
        double sum = 0.0;
        int n = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++)
                if (sel_ring2(x, y)) {
                    sum += out_px(f.out, x, y)[1] - in_px(&f, x, y)[1];
                    n++;
                }
        print_message("%-8s mean green change 1-2 px outside the square %.4f\n", models[m].name, sum / n);
        assert_true(sum / n > 0.05);
        assert_true(max_change(&f, f.out, sel_bg_far24) == 0.0f);
    }
    fx_free(&f);
}

/* a slanted textured plane with a near square and a far strip: every kind of neighbourhood */
static void mixed_scene(int x, int y, float px[4], const void *arg)
{
    (void)arg;
    plane_scene(x, y, px, &(float){0.0f});
    px[3] = 0.6f + 0.05f * (float)x;
    if (in_square(x, y))
        px[3] = 0.3f;
    if (y < 10)
        px[3] = 1000.0f; /* a miss */
}

/* (4) 1 thread and 3 threads give the same bits (gaze inside the image, Liu with chroma), and so
 * does an output with a wider row stride. */
static void test_thread_count_invariant(void **st)
{
    (void)st;
    fixture f;
    fx_init(&f);
    fx_scene(&f, mixed_scene, NULL);
    f.view.focus_m = 1.5f;
    f.view.gaze_x = 40.3f, f.view.gaze_y = 31.7f, f.view.r0_px = 8.0f, f.view.r1_px = 20.0f;
    f.prm.chroma = 1;
    fv_pool *p1 = fv_pool_create(1), *p3 = fv_pool_create(3);
    assert_non_null(p1);
    assert_non_null(p3);
    for (int m = 0; m < NMODELS; m++) {
        memset(f.out, 0, (size_t)W * H * 4 * sizeof(float));
        memset(f.out2, 0xff, (size_t)W * H * 4 * sizeof(float));
        run(&f, m, p1, f.out);
        run(&f, m, p3, f.out2);
        if (memcmp(f.out, f.out2, (size_t)W * H * 4 * sizeof(float))) {
            print_error("%s: 1 and 3 threads differ\n", models[m].name);
            fail();
        }
        assert_true(max_change(&f, f.out, sel_square) > 0.01f); /* not trivially equal */
        /* rows of the output further apart than the image is wide: the same pixels */
        const ptrdiff_t os = W + 3;
        float *wide = malloc((size_t)os * H * 4 * sizeof(float));
        assert_non_null(wide);
        fv_dof_times t;
        models[m].fn(&f.view, &f.wk, wide, os, p3, &f.dsp.dof, &t);
        for (int y = 0; y < H; y++)
            assert_memory_equal(wide + 4 * y * os, out_px(f.out, 0, y), (size_t)W * 4 * sizeof(float));
        free(wide);
    }
    fv_pool_destroy(p1);
    fv_pool_destroy(p3);
    fx_free(&f);
}

/* ------------------------------------------------------------------ hussain */

#define IMP_X 45
#define IMP_Y 35

typedef struct impulse_arg {
    float depth_m;
} impulse_arg;

/* black plane with one white pixel at (IMP_X, IMP_Y) */
static void impulse_scene(int x, int y, float px[4], const void *arg)
{
    const float v = x == IMP_X && y == IMP_Y ? 1.0f : 0.0f;
    px[0] = px[1] = px[2] = v, px[3] = ((const impulse_arg *)arg)->depth_m;
}

/* place the gaze so that the impulse pixel's centre is R px from it */
static void gaze_at_distance(fixture *f, float R)
{
    f->view.gaze_x = (float)IMP_X + 0.5f - R, f->view.gaze_y = (float)IMP_Y + 0.5f;
}

/* Hussain's regions: r0 10 px, r1 20 px, so the blend rings are [10, 15] and [20, 25] px.
 * Normalised 15-tap Gaussians g_s(k) = exp(-k^2 / 2 s^2) / sum_{|j|<=7} exp(-j^2 / 2 s^2):
 *   s 3.5:  g(0) 0.1176958, g(1) 0.1129886 -> g0^2 0.0138523, g0 g1 0.0132983
 *   s 1.7:  g(0) 0.2346737, g(1) 0.1973909 -> g0^2 0.0550718, g0 g1 0.0463224
 *   s 1.01025 (K = 4.49e-3 * 600 / 4 * 2 = 1.347 px m; focus 1 m, plane 4 m: 1.347 * 0.75):
 *           g0^2 0.1559418, g0 g1 0.0955431
 * The impulse response of the two passes at (dx, dy) is g(dx) g(dy). */
static void test_hussain_regions_and_min_rule(void **st)
{
    (void)st;
    fixture f;
    fx_init(&f);
    f.view.r0_px = 10.0f, f.view.r1_px = 20.0f;
    /* a far plane: focus 0.2 m, plane 10 m -> sigma_d = 1.347 * (5 - 0.1) = 6.6 px, above both caps */
    impulse_arg a = {10.0f};
    fx_scene(&f, impulse_scene, &a);
    f.view.focus_m = 0.2f;

    /* mid periphery (R 60): min(6.6, 3.5) = 3.5 */
    gaze_at_distance(&f, 60.0f);
    run(&f, 0, NULL, f.out);
    assert_float_equal(out_px(f.out, IMP_X, IMP_Y)[0], 0.0138523f, 2e-6f);
    assert_float_equal(out_px(f.out, IMP_X + 1, IMP_Y)[1], 0.0132983f, 2e-6f);
    assert_float_equal(out_px(f.out, IMP_X, IMP_Y - 1)[2], 0.0132983f, 2e-6f);
    assert_float_equal(out_px(f.out, IMP_X + 7, IMP_Y + 7)[0], 0.135335f * 0.135335f * 0.0138523f, 1e-7f);
    assert_true(out_px(f.out, IMP_X + 8, IMP_Y)[0] == 0.0f); /* 15 taps: nothing beyond 7 px */

    /* near periphery (R 17, neighbours 16..18): min(6.6, 1.7) = 1.7 (table step 1/256 px: 1e-4) */
    gaze_at_distance(&f, 17.0f);
    run(&f, 0, NULL, f.out);
    assert_float_equal(out_px(f.out, IMP_X, IMP_Y)[0], 0.0550718f, 1e-4f);
    assert_float_equal(out_px(f.out, IMP_X - 1, IMP_Y)[0], 0.0463224f, 1e-4f);

    /* first blend ring, R 11.25: B = (11.25 - 10) / 5 = 0.25; O = B I_near + (1 - B) input
     * = 0.25 * 0.0550718 + 0.75 = 0.7637680 (eq. (3) as printed would give 0.2913039) */
    gaze_at_distance(&f, 11.25f);
    run(&f, 0, NULL, f.out);
    assert_float_equal(out_px(f.out, IMP_X, IMP_Y)[0], 0.7637680f, 1e-4f);

    /* fovea (R 3, the neighbours within 10 px too): the input */
    gaze_at_distance(&f, 3.0f);
    run(&f, 0, NULL, f.out);
    assert_true(out_px(f.out, IMP_X, IMP_Y)[0] == 1.0f);
    assert_true(out_px(f.out, IMP_X + 1, IMP_Y)[0] == 0.0f);

    /* the min rule the other way: sigma_d 1.01 px in the mid periphery stays 1.01, not 3.5 */
    a.depth_m = 4.0f;
    fx_scene(&f, impulse_scene, &a);
    f.view.focus_m = 1.0f;
    gaze_at_distance(&f, 60.0f);
    run(&f, 0, NULL, f.out);
    assert_float_equal(out_px(f.out, IMP_X, IMP_Y)[0], 0.1559418f, 1e-3f);
    assert_float_equal(out_px(f.out, IMP_X, IMP_Y + 1)[0], 0.0955431f, 1e-3f);
    fx_free(&f);
}

/* ------------------------------------------------------------------ mantiuk */

/* colour linear in x (red) and y (green) on a far plane */
static void ramp_scene(int x, int y, float px[4], const void *arg)
{
    (void)arg;
    px[0] = 0.01f * (float)x, px[1] = 0.01f * (float)y, px[2] = 0.5f, px[3] = 5.0f;
}

/* Mantiuk eq. (1): focus 0.5 m, plane 5 m, a 4.49 mm, f 22.3 mm:
 * CoC = 4.49 * 22.3 / 477.7 * |1 - 0.1| = 0.1886453 mm; * E (53.571429 px/mm) = 10.105823 px, a
 * disc of radius 5.052912 px. Bilinear taps of a linear ramp are exact, so the mean of the 15
 * samples is the ramp at the mean offset: the table's mean is (0.0125667, -0.0049533), so
 * red = 0.01 (45 + 5.052912 * 0.0125667) = 0.4506350 and green = 0.01 (35 - 5.052912 * 0.0049533)
 * = 0.3497497 at pixel (45, 35). (A diameter-sized disc would give 0.4512700.) */
static void test_mantiuk_disc_size(void **st)
{
    (void)st;
    fixture f;
    fx_init(&f);
    fx_scene(&f, ramp_scene, NULL);
    f.view.focus_m = 0.5f;
    run(&f, 1, NULL, f.out);
    assert_float_equal(out_px(f.out, 45, 35)[0], 0.4506350f, 2e-6f);
    assert_float_equal(out_px(f.out, 45, 35)[1], 0.3497497f, 2e-6f);
    assert_true(out_px(f.out, 45, 35)[2] == 0.5f);
    fx_free(&f);
}

/* ------------------------------------------------------------------ konrad */

/* a white square at square_m before a black background at background_m */
static void bw_square_scene(int x, int y, float px[4], const void *arg)
{
    const sq_scene_arg *a = arg;
    const float v = in_square(x, y) ? 1.0f : 0.0f;
    px[0] = px[1] = px[2] = v, px[3] = in_square(x, y) ? a->square_m : a->background_m;
}

/* Zhou's factors by hand, thin-lens CoC 4.49e-3 |1/F - 1/D| * 600 * 2 px.
 * - Far impulse (focus 0.5 m, plane 5 m): CoC 9.69840 px, r 4.84920 (r^2 23.5147); every pixel has
 *   the same radius, so the weights are 1 for each of the N pixels with dx^2 + dy^2 <= r^2:
 *   columns dx 0, +-1, +-2, +-3, +-4 hold 9, 9, 9, 7, 5 -> N = 69, the impulse keeps 1/69.
 * - Near square (0.5 m) before an in-focus background (3 m): r 4.49 (r^2 20.1601). The background
 *   pixel C left of the square's edge (x = 34) has area factor 1 (a sharp pixel), the square's
 *   pixels 1 / (pi 20.1601) = 1 / 63.33482; those within reach: dx = 1..4 hold 9, 9, 7, 5 -> 30.
 *   out = (30 / 63.33482) / (1 + 30 / 63.33482) = 0.3214234. Background pixels never reach C. */
static void test_konrad_factors(void **st)
{
    (void)st;
    fixture f;
    fx_init(&f);
    const impulse_arg a = {5.0f};
    fx_scene(&f, impulse_scene, &a);
    f.view.focus_m = 0.5f;
    run(&f, 2, NULL, f.out);
    assert_float_equal(out_px(f.out, IMP_X, IMP_Y)[0], 1.0f / 69.0f, 1e-6f);
    assert_float_equal(out_px(f.out, IMP_X + 4, IMP_Y + 2)[0], 1.0f / 69.0f, 1e-6f);
    assert_true(out_px(f.out, IMP_X + 4, IMP_Y + 3)[0] == 0.0f);

    const sq_scene_arg s = {0.5f, 3.0f};
    fx_scene(&f, bw_square_scene, &s);
    f.view.focus_m = 3.0f;
    run(&f, 2, NULL, f.out);
    assert_float_equal(out_px(f.out, SQ_X0 - 1, 35)[0], 0.3214234f, 2e-6f);
    assert_true(out_px(f.out, SQ_X0 - 5, 35)[0] == 0.0f); /* beyond 4.49 px */
    fx_free(&f);
}

/* ------------------------------------------------------------------ liu */

/* Liu eq. (12) on a far plane: focus 0.5 m, plane 5 m; C = tau_e f_e (1/F - 1/D)
 * = 4.49 * 22.3 * 1.8e-3 = 0.1802286 mm; E = 600 / 22.4 * 2 = 53.571429 px/mm.
 * Chroma shifts tau_e f_e dP: red -0.445 D -> -0.0445577 mm, blue +0.571 D -> +0.0571738 mm.
 * Disc radii (C / 2 * E): red 3.63407, green 4.82755, blue 6.35896 px. With every pixel at the
 * same depth and radius, an impulse's own pixel keeps 1 / (1 + sum_{P != C} cov(P)), cov =
 * clamp(r - |P - C| + 0.5, 0, 1): red 0.0240231, green 0.0135865, blue 0.0078264; a 4-neighbour
 * (fully covered) gets the same value. */
static void test_liu_chroma_discs(void **st)
{
    (void)st;
    fixture f;
    fx_init(&f);
    const impulse_arg a = {5.0f};
    fx_scene(&f, impulse_scene, &a);
    f.view.focus_m = 0.5f;

    f.prm.chroma = 0;
    run(&f, 3, NULL, f.out);
    for (int c = 0; c < 3; c++) {
        assert_float_equal(out_px(f.out, IMP_X, IMP_Y)[c], 0.0135865f, 2e-6f);
        assert_float_equal(out_px(f.out, IMP_X + 1, IMP_Y)[c], 0.0135865f, 2e-6f);
    }

    f.prm.chroma = 1;
    run(&f, 3, NULL, f.out);
    const float *o = out_px(f.out, IMP_X, IMP_Y);
    assert_float_equal(o[0], 0.0240231f, 2e-6f);
    assert_float_equal(o[1], 0.0135865f, 2e-6f);
    assert_float_equal(o[2], 0.0078264f, 2e-6f);
    /* 5 px away: inside blue's disc (6.36), outside red's (3.63) */
    assert_true(out_px(f.out, IMP_X + 5, IMP_Y)[0] == 0.0f);
    assert_float_equal(out_px(f.out, IMP_X + 5, IMP_Y)[2], 0.0078264f, 2e-6f);

    /* near field: red is the more blurred one (its focus lies farther) */
    const impulse_arg n = {0.3f};
    fx_scene(&f, impulse_scene, &n);
    f.view.focus_m = 2.0f;
    run(&f, 3, NULL, f.out);
    o = out_px(f.out, IMP_X, IMP_Y);
    assert_true(o[0] < o[1] && o[1] < o[2]);
    fx_free(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_in_focus_plane_exact),
        cmocka_unit_test(test_far_blur_stays_off_in_focus_near),
        cmocka_unit_test(test_near_blur_spreads_past_silhouette),
        cmocka_unit_test(test_thread_count_invariant),
        cmocka_unit_test(test_hussain_regions_and_min_rule),
        cmocka_unit_test(test_mantiuk_disc_size),
        cmocka_unit_test(test_konrad_factors),
        cmocka_unit_test(test_liu_chroma_discs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
