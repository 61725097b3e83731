/* Anti-aliasing in the fovea (issue 17 item 5): the jitter sequence (low discrepancy, covers the
 * pixel), a still view converging to the box-filtered value of a hand-made edge (coverage
 * computed here from the edge's line, not by the renderer), a moving view not ghosting, the
 * supersampled reference's pixel box filter, and with --fovea-aa off the fovea's samples exactly
 * as traced at the pixel centres. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "testscene.h"
#include "pipeline.h"
#include "raycast.h"
#include "reference.h"
#include "reproject.h"
#include "sampling.h"
#include "scene.h"

/* ---------------------------------------------------------------- the jitter sequence */

/* Star discrepancy of n points in [0, 1)^2, exactly (every box corner at point coordinates). */
static double star_discrepancy(const float (*p)[2], int n)
{
    double d = 0.0;
    for (int a = 0; a <= n; a++)
        for (int b = 0; b <= n; b++) {
            const double x = a < n ? p[a][0] : 1.0, y = b < n ? p[b][1] : 1.0;
            int open = 0, closed = 0;
            for (int i = 0; i < n; i++) {
                open += p[i][0] < x && p[i][1] < y;
                closed += p[i][0] <= x && p[i][1] <= y;
            }
            d = fmax(d, fmax(fabs((double)open / n - x * y), fabs((double)closed / n - x * y)));
        }
    return d;
}

static void test_jitter_sequence(void **st)
{
    (void)st;
    float ox, oy;
    fv_sampling_jitter(0, &ox, &oy); /* frame 0: the pixel centre (a first frame is today's image) */
    assert_true(ox == 0.5f && oy == 0.5f);
    /* runs of consecutive frames starting anywhere (a pixel joins the fovea at any frame) */
    static const uint32_t starts[] = {0, 1, 5, 16, 1000, 123457, 4000000000u, 2147483000u};
    for (size_t s = 0; s < sizeof starts / sizeof starts[0]; s++) {
        float p[32][2];
        for (int i = 0; i < 32; i++) {
            fv_sampling_jitter(starts[s] + (uint32_t)i, &p[i][0], &p[i][1]);
            assert_true(p[i][0] >= 0.0f && p[i][0] < 1.0f && p[i][1] >= 0.0f && p[i][1] < 1.0f);
        }
        /* low discrepancy: 16 random points have a star discrepancy of 0.28 on average (0.18 at
         * best in 200 draws); a (0,2)-sequence is O(log^2 n / n) */
        const double d16 = star_discrepancy((const float(*)[2])p, 16), d32 = star_discrepancy((const float(*)[2])p, 32);
        /* covers the pixel: every cell of a 4x4 grid holds one of the 32 points, and the points'
         * mean is the pixel centre (the box filter's centroid) within 1/32 */
        int cells = 0;
        unsigned seen = 0;
        double mx = 0.0, my = 0.0;
        for (int i = 0; i < 32; i++) {
            seen |= 1u << ((int)(4.0f * p[i][1]) * 4 + (int)(4.0f * p[i][0]));
            mx += p[i][0] / 32.0;
            my += p[i][1] / 32.0;
        }
        for (int c = 0; c < 16; c++)
            cells += seen >> c & 1u;
        printf("jitter from frame %u: star discrepancy 16 frames %.3f, 32 frames %.3f; 4x4 cells hit %d; "
               "mean (%.3f, %.3f)\n", starts[s], d16, d32, cells, mx, my);
        assert_true(d16 < 0.2);
        assert_true(d32 < 0.13);
        assert_int_equal(cells, 16);
        assert_true(fabs(mx - 0.5) < 1.0 / 32 && fabs(my - 0.5) < 1.0 / 32);
    }
}

/* ---------------------------------------------------------------- scenes */

/* Directional light along -Z: a quad facing the eye has one colour everywhere. */
static void add_sun(fv_scene *s)
{
    fv_light l;
    memset(&l, 0, sizeof l);
    l.type = FV_LIGHT_DIRECTIONAL;
    l.color[0] = l.color[1] = l.color[2] = 1.0f;
    l.intensity = 1.0f;
    l.dir[2] = -1.0f;
    fv_scene_add_light(s, &l);
}

/* A triangle facing +Z at depth z covering the half-plane right of the line through (cx, cy) with
 * direction (dx, dy) (world x right, y up), as far as the view reaches. */
static void add_half_plane(fv_scene *s, float cx, float cy, float dx, float dy, float z, const float rgb[3])
{
    const float L = 50.0f, nx = dy, ny = -dx; /* (nx, ny): to the right of the direction */
    float pos[] = {cx - L * dx, cy - L * dy, z, cx + L * dx, cy + L * dy, z, cx + L * nx, cy + L * ny, z};
    /* counter-clockwise seen from +Z */
    if ((pos[3] - pos[0]) * (pos[7] - pos[1]) - (pos[4] - pos[1]) * (pos[6] - pos[0]) < 0.0f)
        for (int k = 0; k < 3; k++) {
            const float t = pos[3 + k];
            pos[3 + k] = pos[6 + k], pos[6 + k] = t;
        }
    float nrm[] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    float uv[] = {0, 0, 1, 0, 0, 1};
    uint32_t idx[] = {0, 1, 2};
    fv_mesh_desc m;
    memset(&m, 0, sizeof m);
    m.positions = pos;
    m.normals = nrm;
    m.uvs = uv;
    m.indices = idx;
    m.vertex_count = 3;
    m.index_count = 3;
    for (int k = 0; k < 3; k++)
        m.base_color[k] = rgb[k];
    m.base_color[3] = 1.0f;
    m.texture = -1;
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
}

static fv_pipeline *make(const fv_scene *s, int w, int h, int full, int aa, float r0_deg)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    cfg.cam.width = w;
    cfg.cam.height = h;
    cfg.cam.fov_y_deg = 60.0f;
    cfg.samp.full = full;
    cfg.samp.r0_deg = r0_deg;
    cfg.samp.r1_deg = r0_deg + 5.0f;
    cfg.taa.fovea_aa = aa;
    cfg.threads = 2;
    char err[256];
    fv_pipeline *p = fv_pipeline_create(s, &cfg, err, sizeof err);
    if (!p)
        fail_msg("pipeline: %s", err);
    return p;
}

static void render(fv_pipeline *p, const fv_pose *pose, float gx, float gy)
{
    fv_frame_stats st;
    assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, pose, gx, gy, &st), 0);
}

static const float *px_at(const fv_pipeline *p, int x, int y)
{
    const fv_pyr_level *l0 = &fv_pipeline_pyramid(p, FV_EYE_CENTER)->lv[0];
    return l0->rgbd + 4 * ((ptrdiff_t)y * l0->stride + x);
}

/* The edge's image is a straight line (a pinhole camera, a plane edge): the share of pixel (x, y)
 * right of the line through image points a, b, on a 64 x 64 grid of the pixel's area. */
static double coverage(const float a[2], const float b[2], int x, int y)
{
    int in = 0;
    for (int j = 0; j < 64; j++)
        for (int i = 0; i < 64; i++) {
            const double px = x + (i + 0.5) / 64.0, py = y + (j + 0.5) / 64.0;
            /* image y points down: right of a->b in the world is this sign of the cross product */
            in += (b[0] - a[0]) * (py - a[1]) - (b[1] - a[1]) * (px - a[0]) > 0.0;
        }
    return in / 4096.0;
}

enum { EW = 160, EH = 160 };

/* A bright half-plane at 2 m with an edge at 14 deg from vertical through the view's centre, the
 * background beyond; the whole view is the fovea (r0 40 deg). */
static fv_scene *edge_scene(float a_px[2], float b_px[2])
{
    fv_scene *s = fv_scene_create();
    assert_non_null(s);
    const float white[3] = {0.9f, 0.85f, 0.8f};
    const float dx = sinf(0.245f), dy = cosf(0.245f);
    add_half_plane(s, 0.013f, -0.007f, dx, dy, -2.0f, white);
    add_sun(s);
    char err[256];
    assert_int_equal(fv_scene_commit(s, err, sizeof err), 0);
    /* the edge's two points in the image */
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.width = EW;
    d.height = EH;
    d.fov_y_deg = 60.0f;
    static const fv_pose o = {{0, 0, 0}, {0, 0, 0, 1}};
    fv_camera cam;
    assert_int_equal(fv_camera_setup(&cam, &d, &o), 0);
    const float p0[3] = {0.013f - dx, -0.007f - dy, -2.0f}, p1[3] = {0.013f + dx, -0.007f + dy, -2.0f};
    assert_true(fv_camera_project(&cam, p0, &a_px[0], &a_px[1]) > 0.0f);
    assert_true(fv_camera_project(&cam, p1, &b_px[0], &b_px[1]) > 0.0f);
    return s;
}

/* ---------------------------------------------------------------- still view: convergence */

static void test_still_edge_converges(void **st)
{
    (void)st;
    float a[2], b[2];
    fv_scene *s = edge_scene(a, b);
    fv_pipeline *aa = make(s, EW, EH, 0, 1, 40.0f), *off = make(s, EW, EH, 0, 0, 40.0f), *full = make(s, EW, EH, 1, 0, 40.0f);
    static const fv_pose o = {{0, 0, 0}, {0, 0, 0, 1}};
    render(full, &o, 0.5f, 0.5f);
    /* the two colours: a pixel well inside the plane and one well outside (one colour each: a
     * directional light on a plane facing the eye, a constant background) */
    float in[3], out[3];
    int found_in = 0, found_out = 0;
    for (int y = 40; y < 120 && !(found_in && found_out); y++)
        for (int x = 40; x < 120; x++) {
            const double c = coverage(a, b, x, y);
            const double c2 = fmin(coverage(a, b, x - 2, y), coverage(a, b, x + 2, y));
            const double c3 = fmax(coverage(a, b, x - 2, y), coverage(a, b, x + 2, y));
            if (!found_in && c == 1.0 && c2 == 1.0)
                memcpy(in, px_at(full, x, y), sizeof in), found_in = 1;
            if (!found_out && c == 0.0 && c3 == 0.0)
                memcpy(out, px_at(full, x, y), sizeof out), found_out = 1;
        }
    assert_true(found_in && found_out);
    assert_true(in[1] - out[1] > 0.3f);
    /* the edge pixels of the middle (whole tiles of the fovea): error against the box filter */
    double err_aa[17] = {0}, err_off = 0.0, worst_aa = 0.0;
    int n = 0;
    for (int f = 1; f <= 16; f++) {
        render(aa, &o, 0.5f, 0.5f);
        render(off, &o, 0.5f, 0.5f);
        for (int y = 48; y < 112; y++)
            for (int x = 48; x < 112; x++) {
                const double c = coverage(a, b, x, y);
                if (c == 0.0 || c == 1.0)
                    continue;
                const double want = out[1] + c * (in[1] - out[1]);
                const double e = fabs(px_at(aa, x, y)[1] - want) / (in[1] - out[1]);
                err_aa[f] += e;
                if (f == 16) {
                    err_off += fabs(px_at(off, x, y)[1] - want) / (in[1] - out[1]);
                    worst_aa = fmax(worst_aa, e);
                    n++;
                }
            }
    }
    for (int f = 1; f <= 16; f++)
        err_aa[f] /= n;
    err_off /= n;
    printf("edge, %d pixels: mean |error| against the box filter (of the contrast) frame 1 %.4f, 2 %.4f, 4 %.4f, "
           "8 %.4f, 16 %.4f (worst %.4f); --fovea-aa off %.4f\n",
           n, err_aa[1], err_aa[2], err_aa[4], err_aa[8], err_aa[16], worst_aa, err_off);
    assert_true(n > 50);
    /* frame 1 is the pixel-centre image: the off error; a point sample of a random edge
     * position errs by 1/4 of the contrast on average */
    assert_true(fabs(err_aa[1] - err_off) < 1e-9);
    assert_true(err_off > 0.15);
    /* 16 low-discrepancy samples: a few percent, falling as the samples come */
    assert_true(err_aa[16] < 0.05);
    assert_true(err_aa[16] < err_aa[8] && err_aa[8] < err_aa[4] && err_aa[4] < err_aa[1]);
    assert_true(worst_aa < 0.2);
    fv_pipeline_destroy(aa);
    fv_pipeline_destroy(off);
    fv_pipeline_destroy(full);
    fv_scene_free(s);
}

/* With --fovea-aa off the fovea's samples are exactly as traced at the pixel centres (the
 * reprojection does not touch them: test_fovea_samples_untouched in test_reproject.c checks the
 * kernels); with it on, frame 0 is the same image and later frames are not. */
static void test_off_is_pixel_centres(void **st)
{
    (void)st;
    float a[2], b[2];
    fv_scene *s = edge_scene(a, b);
    fv_pipeline *aa = make(s, EW, EH, 0, 1, 40.0f), *off = make(s, EW, EH, 0, 0, 40.0f), *full = make(s, EW, EH, 1, 0, 40.0f);
    static const fv_pose o = {{0, 0, 0}, {0, 0, 0, 1}};
    for (int f = 0; f < 3; f++) {
        render(aa, &o, 0.5f, 0.5f);
        render(off, &o, 0.5f, 0.5f);
        render(full, &o, 0.5f, 0.5f);
        int same_off = 1, same_aa = 1;
        for (int y = 48; y < 112; y++)
            for (int x = 48; x < 112; x++) {
                same_off &= !memcmp(px_at(off, x, y), px_at(full, x, y), 4 * sizeof(float));
                same_aa &= !memcmp(px_at(aa, x, y), px_at(full, x, y), 4 * sizeof(float));
            }
        assert_true(same_off);
        assert_true(f == 0 ? same_aa : !same_aa);
    }
    fv_pipeline_destroy(aa);
    fv_pipeline_destroy(off);
    fv_pipeline_destroy(full);
    fv_scene_free(s);
}

/* ---------------------------------------------------------------- moving view: no ghost */

/* A red card at 1 m before a green wall at 5 m, the gaze on the card (the fovea), the head at
 * rest for 8 frames then stepping 2 cm sideways every 4 frames. On the wall the card uncovers,
 * pixels 2 or more pixels from the card (their box filter is pure wall), the anti-aliased fovea
 * shows no red: the history there is the card's, rejected (another surface) or clamped to the
 * neighbourhood (all wall). */
static void test_moving_no_ghost(void **st)
{
    (void)st;
    fv_scene *s = fv_scene_create();
    assert_non_null(s);
    const float wall[3] = {0.1f, 0.6f, 0.3f}, card[3] = {1.0f, 0.05f, 0.05f};
    fv_test_add_quad(s, -30, -30, 30, 30, -5.0f, wall, -1);
    fv_test_add_quad(s, -0.2f, -0.3f, 0.2f, 0.3f, -1.0f, card, -1);
    add_sun(s);
    char err[256];
    assert_int_equal(fv_scene_commit(s, err, sizeof err), 0);
    enum { W = 192, H = 192 };
    fv_pipeline *aa = make(s, W, H, 0, 1, 25.0f), *full = make(s, W, H, 1, 0, 25.0f);
    float *was_card = calloc((size_t)W * H, sizeof(float)), *is_card = calloc((size_t)W * H, sizeof(float));
    assert_non_null(was_card);
    assert_non_null(is_card);
    long checked = 0, ghost = 0;
    double red = 0.0, edge_seen = 0.0;
    for (int f = 0; f < 40; f++) {
        const float step = f < 8 ? 0.0f : 0.02f * (float)((f - 4) / 4);
        fv_pose pose = {{step, 0, 0}, {0, 0, 0, 1}};
        render(aa, &pose, 0.5f, 0.5f);
        render(full, &pose, 0.5f, 0.5f);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++)
                is_card[(size_t)y * W + x] = px_at(full, x, y)[3] < 2.0f;
        for (int y = 2; y < H - 2; y++)
            for (int x = 2; x < W - 2; x++) {
                /* 48 px around the gaze: whole tiles of the fovea (r0 25 deg = 83 px) */
                if (abs(x - W / 2) > 48 || abs(y - H / 2) > 48 || !was_card[(size_t)y * W + x])
                    continue;
                int near_card = 0;
                for (int j = -2; j <= 2; j++)
                    for (int i = -2; i <= 2; i++)
                        near_card |= is_card[(size_t)(y + j) * W + x + i] > 0.0f;
                if (near_card)
                    continue;
                const double e = fmax(0.0, px_at(aa, x, y)[0] - px_at(full, x, y)[0]);
                red += e;
                ghost += e > 0.02;
                checked++;
            }
        /* the card's edges are anti-aliased (not the pixel-centre image) while the head moves */
        if (f >= 8)
            for (int y = H / 2 - 48; y < H / 2 + 48; y++)
                for (int x = W / 2 - 48; x < W / 2 + 48; x++)
                    edge_seen += fabs(px_at(aa, x, y)[0] - px_at(full, x, y)[0]) > 0.05;
        memcpy(was_card, is_card, (size_t)W * H * sizeof(float));
    }
    printf("moving head: %ld uncovered wall pixel-frames in the fovea, mean red excess %.5f, %ld above 0.02; "
           "pixels anti-aliased (|aa - centre| > 0.05) %.0f\n", checked, checked ? red / checked : 0.0, ghost, edge_seen);
    assert_true(checked > 300);
    assert_true(red / checked < 1e-3);
    assert_int_equal(ghost, 0);
    assert_true(edge_seen > 100);
    free(was_card);
    free(is_card);
    fv_pipeline_destroy(aa);
    fv_pipeline_destroy(full);
    fv_scene_free(s);
}

/* ---------------------------------------------------------------- the supersampled reference */

/* fv_reference_render with pixel_aa (the --reference SPP --dof none image): each pixel the box
 * filter of the scene over its area, the edge's coverage mix within the point set's error. */
static void test_reference_box_filter(void **st)
{
    (void)st;
    float a[2], b[2];
    fv_scene *s = edge_scene(a, b);
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.width = EW;
    d.height = EH;
    d.fov_y_deg = 60.0f;
    static const fv_pose o = {{0, 0, 0}, {0, 0, 0, 1}};
    fv_camera cam;
    assert_int_equal(fv_camera_setup(&cam, &d, &o), 0);
    float *img = malloc(sizeof(float) * 4 * EW * EH), *pin = malloc(sizeof(float) * 4 * EW * EH);
    assert_non_null(img);
    assert_non_null(pin);
    fv_reference_params prm = {.spp = 64, .pupil_mm = 0.0f, .focus_m = 1.0f, .seed = 0, .pixel_aa = 1};
    assert_true(fv_reference_render(s, &cam, &prm, NULL, img, NULL, NULL) > 0);
    prm.pixel_aa = 0;
    assert_true(fv_reference_render(s, &cam, &prm, NULL, pin, NULL, NULL) > 0);
    double e_aa = 0.0, e_pin = 0.0, worst = 0.0;
    int n = 0;
    float in = 0.0f, out = 0.0f;
    for (int y = 40; y < 120; y++)
        for (int x = 40; x < 120; x++) {
            const double c = coverage(a, b, x, y);
            if (c == 1.0)
                in = pin[4 * (y * EW + x) + 1];
            if (c == 0.0)
                out = pin[4 * (y * EW + x) + 1];
        }
    for (int y = 40; y < 120; y++)
        for (int x = 40; x < 120; x++) {
            const double c = coverage(a, b, x, y);
            if (c == 0.0 || c == 1.0)
                continue;
            const double want = out + c * (in - out);
            const double e = fabs(img[4 * (y * EW + x) + 1] - want) / (in - out);
            e_aa += e;
            e_pin += fabs(pin[4 * (y * EW + x) + 1] - want) / (in - out);
            worst = fmax(worst, e);
            n++;
        }
    printf("reference, %d edge pixels: mean |error| against the coverage mix %.4f (worst %.4f), pixel centres %.4f\n",
           n, e_aa / n, worst, e_pin / n);
    assert_true(n > 50);
    assert_true(e_aa / n < 0.02 && worst < 0.08); /* 64 stratified points */
    assert_true(e_pin / n > 0.15);
    free(img);
    free(pin);
    fv_scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_jitter_sequence),
        cmocka_unit_test(test_still_edge_converges),
        cmocka_unit_test(test_off_is_pixel_centres),
        cmocka_unit_test(test_moving_no_ghost),
        cmocka_unit_test(test_reference_box_filter),
    };
    return cmocka_run_group_tests_name("fovea_aa", tests, NULL, NULL);
}
