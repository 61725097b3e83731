/* Thin-lens reference (core/reference.c): in focus it is the pinhole image, with a zero pupil
 * it is the pinhole image bit for bit, out of focus a step edge becomes the ramp the thin lens
 * predicts, and the bytes do not depend on the thread count. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "dof/coc.h"
#include "pipeline.h"
#include "raycast.h"
#include "reference.h"
#include "scene.h"
#include "testscene.h"


/* A grey quad (tests/testscene.h). */
static void add_quad(fv_scene *s, float x0, float y0, float x1, float y1, float z, float grey)
{
    const float rgb[3] = {grey, grey, grey};
    fv_test_add_quad(s, x0, y0, x1, y1, z, rgb, -1);
}

static fv_scene *commit(fv_scene *s)
{
    char err[256];
    assert_int_equal(fv_scene_commit(s, err, sizeof err), 0);
    return s;
}

/* Depth variety: a wall at 3 m (left two thirds), a card at 1 m, background on the right. */
static fv_scene *mixed_scene(void)
{
    fv_scene *s = fv_scene_create();
    add_quad(s, -10.0f, -10.0f, 0.5f, 10.0f, -3.0f, 0.6f);
    add_quad(s, -0.3f, -0.2f, 0.1f, 0.25f, -1.0f, 0.3f);
    return commit(s);
}

static const fv_pose origin = {{0, 0, 0}, {0, 0, 0, 1}};

/* mixed_scene with a half-transparent alpha BLEND pane at 0.8 m over the card's left half */
static fv_scene *blend_scene(void)
{
    fv_scene *s = fv_scene_create();
    add_quad(s, -10.0f, -10.0f, 0.5f, 10.0f, -3.0f, 0.6f);
    add_quad(s, -0.3f, -0.2f, 0.1f, 0.25f, -1.0f, 0.3f);
    float pos[] = {-0.35f, -0.25f, -0.8f, -0.1f, -0.25f, -0.8f, -0.1f, 0.3f, -0.8f, -0.35f, 0.3f, -0.8f};
    float nrm[] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    uint32_t idx[] = {0, 1, 2, 0, 2, 3};
    fv_mesh_desc m;
    memset(&m, 0, sizeof m);
    m.positions = pos, m.normals = nrm, m.indices = idx, m.vertex_count = 4, m.index_count = 6;
    m.base_color[0] = 0.9f, m.base_color[1] = 0.2f, m.base_color[2] = 0.1f, m.base_color[3] = 0.5f;
    m.texture = -1;
    m.alpha_blend = 1;
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    return commit(s);
}


static fv_camera make_cam(int w, int h, float fov_deg)
{
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.width = w;
    d.height = h;
    d.fov_y_deg = fov_deg;
    fv_camera c;
    assert_int_equal(fv_camera_setup(&c, &d, &origin), 0);
    return c;
}

/* The pinhole pipeline's image (full sampling) of the same view: level 0, rgb + depth. */
static float *pinhole(const fv_scene *s, int w, int h, float fov_deg, uint8_t *rgb8)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    cfg.cam.width = w;
    cfg.cam.height = h;
    cfg.cam.fov_y_deg = fov_deg;
    cfg.samp.full = 1;
    cfg.threads = 1;
    char err[256];
    fv_pipeline *p = fv_pipeline_create(s, &cfg, err, sizeof err);
    assert_non_null(p);
    fv_frame_stats st;
    assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, &origin, 0.5f, 0.5f, &st), 0);
    const fv_pyr_level *l0 = &fv_pipeline_pyramid(p, FV_EYE_CENTER)->lv[0];
    float *out = malloc(sizeof(float) * 4 * w * h);
    for (int y = 0; y < h; y++)
        memcpy(out + 4 * y * w, l0->rgbd + 4 * y * l0->stride, sizeof(float) * 4 * w);
    if (rgb8)
        fv_pipeline_to_rgb8(p, FV_EYE_CENTER, rgb8, 3 * w);
    fv_pipeline_destroy(p);
    return out;
}

/* SPP 1, pupil 0: every ray is the pinhole ray, so colour and depth equal the pipeline's
 * exactly, and so do the sRGB bytes. */
static void test_zero_pupil_is_pinhole(void **st)
{
    (void)st;
    const int W = 48, H = 40;
    for (int with_blend = 0; with_blend < 2; with_blend++) {
    /* with a blended pane: the reference composites it as the ray stage does */
    fv_scene *s = with_blend ? blend_scene() : mixed_scene();
    fv_camera cam = make_cam(W, H, 60.0f);
    uint8_t a8[W * H * 3], b8[W * H * 3];
    float *pin = pinhole(s, W, H, 60.0f, a8);
    float *ref = malloc(sizeof(float) * 4 * W * H);
    fv_reference_params prm = {.spp = 1, .pupil_mm = 0.0f, .focus_m = 0.7f};
    assert_int_equal(fv_reference_render(s, &cam, &prm, NULL, ref, NULL, NULL), 2L * W * H);
    assert_memory_equal(ref, pin, sizeof(float) * 4 * W * H);
    fv_reference_to_rgb8(ref, W, H, b8, 3 * W, ~0u); /* the pipeline's default kernels */
    assert_memory_equal(a8, b8, sizeof a8);
    /* the scene really has three depths: 3 m, 1 m and misses */
    assert_float_equal(ref[4 * (20 * W + 2) + 3], 3.0f, 1e-4f);
    assert_float_equal(ref[4 * (20 * W + W - 2) + 3], FV_DEPTH_MISS_M, 0.0f);
    free(pin);
    free(ref);
    fv_scene_free(s);
    }
}

/* A plane at the focus distance: every lens ray of a pixel meets the plane at the pixel's
 * focus point, so any SPP and pupil give the pinhole image (to float noise). */
static void test_plane_in_focus_is_sharp(void **st)
{
    (void)st;
    const int W = 40, H = 32;
    fv_scene *s = fv_scene_create();
    add_quad(s, -5.0f, -5.0f, 0.0f, 5.0f, -2.0f, 0.9f); /* an edge in the middle: any blur shows */
    add_quad(s, 0.0f, -5.0f, 5.0f, 5.0f, -2.0f, 0.1f);
    commit(s);
    fv_camera cam = make_cam(W, H, 50.0f);
    float *pin = pinhole(s, W, H, 50.0f, NULL);
    float *ref = malloc(sizeof(float) * 4 * W * H);
    const int spps[] = {1, 7, 64};
    for (int i = 0; i < 3; i++) {
        fv_reference_params prm = {.spp = spps[i], .pupil_mm = 6.0f, .focus_m = 2.0f};
        assert_true(fv_reference_render(s, &cam, &prm, NULL, ref, NULL, NULL) > 0);
        float maxd = 0.0f;
        for (int k = 0; k < 4 * W * H; k++)
            maxd = fmaxf(maxd, fabsf(ref[k] - pin[k]));
        assert_true(maxd < 1e-5f);
    }
    free(pin);
    free(ref);
    fv_scene_free(s);
}

/* 10-90 % width of the edge-spread function of a uniform disc of diameter c: the fraction of
 * the disc beyond a chord at distance u R from the centre is 1/2 + (u sqrt(1-u^2) + asin u)/pi;
 * it reaches 0.9 at u = 0.687049 (bisection), so the width is 2 * 0.687049 R = 0.687049 c. */
#define DISC_ESF_10_90 0.687049

/* Crossing of level v in a profile rising from 0 to 1 (linear between pixel centres). */
static double crossing(const double *e, int n, double v)
{
    for (int x = 1; x < n; x++)
        if (e[x - 1] < v && e[x] >= v)
            return (x - 1) + (v - e[x - 1]) / (e[x] - e[x - 1]) + 0.5;
    return NAN;
}

/* Measures the 10-90 % width of a vertical step edge on a plane at depth g, focus at focus_m. */
static double edge_width_px(float g, float focus_m, float pupil_mm, const fv_camera *cam, int spp)
{
    const int W = cam->width, H = cam->height;
    fv_scene *s = fv_scene_create();
    add_quad(s, -50.0f, -50.0f, 0.0f, 50.0f, -g, 0.0f); /* black left, white right: edge at x = W/2 */
    add_quad(s, 0.0f, -50.0f, 50.0f, 50.0f, -g, 1.0f);
    commit(s);
    float *ref = malloc(sizeof(float) * 4 * W * H);
    fv_reference_params prm = {.spp = spp, .pupil_mm = pupil_mm, .focus_m = focus_m};
    assert_true(fv_reference_render(s, cam, &prm, NULL, ref, NULL, NULL) > 0);
    double prof[256];
    assert_true(W <= 256);
    for (int x = 0; x < W; x++) {
        prof[x] = 0.0;
        for (int y = 0; y < H; y++)
            prof[x] += ref[4 * (y * W + x)];
    }
    double lo = 0.0, hi = 0.0;
    for (int x = 0; x < 8; x++) {
        lo += prof[x] / 8.0;
        hi += prof[W - 1 - x] / 8.0;
    }
    for (int x = 0; x < W; x++)
        prof[x] = (prof[x] - lo) / (hi - lo);
    const double w = crossing(prof, W, 0.9) - crossing(prof, W, 0.1);
    free(ref);
    fv_scene_free(s);
    return w;
}

/* A plane far behind the focus plane: the edge's ramp is as wide as the thin lens predicts,
 * CoC = pupil_m |1/g - 1/focus| focal_px (Weier eq. 3 with t = 0, times E = focal_px / d_i).
 * 96x32 pixels at a 4 deg vertical FOV: focal_px = 16 / tan(2 deg) = 458.19.
 * Focus 0.25 m, plane 4 m, pupil 8 mm: CoC = 0.008 * 3.75 * 458.19 = 13.75 px, 10-90 % width
 * 0.687049 * 13.75 = 9.44 px. Pupil 4 mm halves both. Tolerance 2 % (sampling noise of 32 rows
 * x 64 lens samples and the linear interpolation between pixel centres). */
static void test_defocused_edge_width(void **st)
{
    (void)st;
    fv_camera cam = make_cam(96, 32, 4.0f);
    assert_float_equal(cam.focal_px, 458.19f, 0.01f);
    const float pupils[] = {8.0f, 4.0f};
    for (int i = 0; i < 2; i++) {
        fv_coc_weier p;
        fv_coc_weier_default(&p, cam.focal_px);
        p.tolerance_m = 0.0f;
        p.pupil_mm = pupils[i];
        const double coc_px = fv_coc_weier_px(&p, 0.25f, 4.0f);
        assert_float_equal(coc_px, pupils[i] * 1e-3 * 3.75 * 458.19, 0.01);
        const double want = DISC_ESF_10_90 * coc_px;
        const double got = edge_width_px(4.0f, 0.25f, pupils[i], &cam, 64);
        printf("    edge 10-90%% width, pupil %.0f mm: measured %.3f px, thin lens %.3f px (CoC %.3f px)\n",
               (double)pupils[i], got, want, coc_px);
        assert_true(fabs(got - want) < 0.02 * want);
    }
    /* the near side: focus 4 m, the plane at 0.25 m has the same |1/g - 1/focus| = 3.75 D and
     * so the same 9.44 px width (8 mm pupil) */
    const double near = edge_width_px(0.25f, 4.0f, 8.0f, &cam, 64);
    printf("    near field (plane 0.25 m, focus 4 m): measured %.3f px, thin lens %.3f px\n", near,
           DISC_ESF_10_90 * 0.008 * 3.75 * cam.focal_px);
    assert_true(fabs(near - DISC_ESF_10_90 * 0.008 * 3.75 * cam.focal_px) < 0.02 * near);
    /* in focus the edge is a one-pixel step (the crossings lie between two pixel centres) */
    assert_true(edge_width_px(4.0f, 4.0f, 8.0f, &cam, 16) < 1.0);
}

typedef struct {
    long calls, last, total;
    int monotonic;
} prog_rec;
static void on_progress(void *ctx, long done, long total)
{
    prog_rec *r = ctx;
    r->monotonic &= done >= r->last;
    r->calls++;
    r->last = done;
    r->total = total;
}

/* Same bytes for 1 and 2 threads; progress reaches total. */
static void test_threads_and_progress(void **st)
{
    (void)st;
    const int W = 70, H = 50; /* partial tiles on both edges */
    fv_scene *s = mixed_scene();
    fv_camera cam = make_cam(W, H, 60.0f);
    float *a = malloc(sizeof(float) * 4 * W * H), *b = malloc(sizeof(float) * 4 * W * H);
    fv_reference_params prm = {.spp = 8, .pupil_mm = 4.49f, .focus_m = 1.0f, .seed = 3};
    fv_pool *p1 = fv_pool_create(1), *p2 = fv_pool_create(2);
    prog_rec r = {0, 0, 0, 1};
    const long rays = fv_reference_render(s, &cam, &prm, p1, a, on_progress, &r);
    assert_int_equal(rays, 9L * W * H);
    assert_int_equal(fv_reference_render(s, &cam, &prm, p2, b, NULL, NULL), rays);
    assert_memory_equal(a, b, sizeof(float) * 4 * W * H);
    assert_true(r.monotonic);
    assert_int_equal(r.last, 5 * 4); /* 5 x 4 tiles of 16 */
    assert_int_equal(r.total, 20);
    /* the lens does blur: the card's edge differs from the pinhole image */
    float *pin = pinhole(s, W, H, 60.0f, NULL);
    assert_memory_not_equal(a, pin, sizeof(float) * 4 * W * H);
    free(pin);
    fv_pool_destroy(p1);
    fv_pool_destroy(p2);
    free(a);
    free(b);
    fv_scene_free(s);
}

static void test_bad_params(void **st)
{
    (void)st;
    fv_scene *s = mixed_scene();
    fv_camera cam = make_cam(16, 16, 60.0f);
    float buf[4 * 16 * 16];
    fv_reference_params bad[] = {{0, 4.0f, 1.0f, 0, 0}, {4, -1.0f, 1.0f, 0, 0}, {4, 4.0f, 0.0f, 0, 0}, {4, 4.0f, INFINITY, 0, 0}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        assert_int_equal(fv_reference_render(s, &cam, &bad[i], NULL, buf, NULL, NULL), -1);
    /* the focus at the point of regard: one pinhole ray */
    assert_float_equal(fv_reference_depth_at(s, &cam, 2.5f, 8.5f), 3.0f, 1e-4f);
    fv_scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_zero_pupil_is_pinhole),
        cmocka_unit_test(test_plane_in_focus_is_sharp),
        cmocka_unit_test(test_defocused_edge_width),
        cmocka_unit_test(test_threads_and_progress),
        cmocka_unit_test(test_bad_params),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
