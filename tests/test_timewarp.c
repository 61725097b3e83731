/* The timewarp against hand-computed cases: a pure rotation equals the image rendered at the
 * rotated camera (an analytic, smooth pattern of world directions), a fronto-parallel plane seen
 * from a camera stepped sideways moves by focal * step / depth pixels (two planes, two depths),
 * and a disocclusion behind a near square is counted to the expected width and filled with the
 * background. The kernels' agreement with this reference is checkasm's (tests/checkasm/timewarp.c). */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "camera.h"
#include "metrics.h"
#include "pipeline.h"
#include "posepred.h"
#include "scene.h"
#include "timewarp.h"

#define PI_D 3.14159265358979323846
#define W 160
#define H 144

typedef struct {
    uint8_t rgb[W * H * 3 + FV_TW_RGB_PAD];
    uint16_t invd[W * H + FV_TW_INVD_PAD];
    uint8_t out[W * H * 3];
} planes;

static void cam(fv_camera *c, const fv_pose *p)
{
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.width = W, d.height = H, d.eye = FV_EYE_CENTER;
    assert_int_equal(fv_camera_setup(c, &d, p), 0);
}

/* a smooth colour of a world direction (no seam in the field of view) */
static void dir_colour(const float d[3], float rgb[3])
{
    const float n = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const float az = atan2f(d[0], -d[2]), el = asinf(d[1] / n);
    rgb[0] = 128.0f + 100.0f * sinf(4.0f * az);
    rgb[1] = 128.0f + 100.0f * cosf(5.0f * el);
    rgb[2] = 128.0f + 80.0f * sinf(3.0f * az + 2.0f * el);
}

static void render_dirs(uint8_t *rgb, const fv_camera *c)
{
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float d[3], col[3];
            fv_camera_ray(c, (float)x + 0.5f, (float)y + 0.5f, d);
            dir_colour(d, col);
            for (int k = 0; k < 3; k++)
                rgb[(y * W + x) * 3 + k] = (uint8_t)lrintf(col[k]);
        }
}

static long warp(planes *p, const fv_camera *display, const fv_camera *source)
{
    fv_timewarp_dsp d;
    fv_timewarp_dsp_init(&d, FV_ISA_C);
    fv_tw_map m;
    fv_tw_setup(&m, display, source, 0.05f);
    const fv_tw_src s = {p->rgb, W * 3, p->invd, W, W, H};
    return fv_tw_warp_rows(&d, p->out, W * 3, 0, H, &m, &s, NULL);
}

static long warp_bounded(planes *p, const fv_camera *display, const fv_camera *source, long budget,
                         fv_tw_warp_stats *st)
{
    fv_timewarp_dsp d;
    fv_timewarp_dsp_init(&d, FV_ISA_C);
    fv_tw_map m;
    fv_tw_setup(&m, display, source, 0.05f);
    const fv_tw_src s = {p->rgb, W * 3, p->invd, W, W, H};
    fv_tw_tiles t;
    static uint16_t lohi[2 * ((W + 7) / 8) * ((H + 7) / 8)], lohi4[2 * ((W + 31) / 32) * ((H + 31) / 32)];
    t.lohi = lohi, t.lohi4 = lohi4;
    fv_tw_tiles_build(&d, &t, &s);
    return fv_tw_warp_rows_bounded(&d, p->out, W * 3, 0, H, &m, &s, &t, budget, st);
}

/* The warped image p->out against want (the image rendered at c1) where c1's display ray falls
 * inside the source c0 (away from the clamped edge): pixels checked, the largest channel error,
 * and the channels of the unwarped p->rgb more than 8 levels from want (it must have moved). */
static void rotation_error(const planes *p, const uint8_t *want, const fv_camera *c0, const fv_camera *c1,
                           int *checked, int *maxd, int *moved)
{
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float d[3], px[3], u, v;
            fv_camera_ray(c1, (float)x + 0.5f, (float)y + 0.5f, d);
            for (int k = 0; k < 3; k++)
                px[k] = c1->eye_pos[k] + d[k];
            fv_camera_project(c0, px, &u, &v);
            if (u < 2 || v < 2 || u > W - 2 || v > H - 2)
                continue;
            (*checked)++;
            for (int k = 0; k < 3; k++) {
                const int i = (y * W + x) * 3 + k, e = abs((int)p->out[i] - (int)want[i]);
                *maxd = e > *maxd ? e : *maxd;
                *moved += abs((int)p->rgb[i] - (int)want[i]) > 8;
            }
        }
}

/* The rotation cases: c1 turned 6 degrees from c0 about a tilted axis, the pattern rendered at c0
 * into p->rgb, depths varying per pixel (a pure rotation's warp must not depend on them). */
static void rotation_case(planes *p, fv_camera *c0, fv_camera *c1)
{
    const float a = 6.0f * 3.14159265f / 360.0f;
    const float ax[3] = {0.3f, 0.9f, 0.1f}, an = sqrtf(0.91f);
    fv_pose p0 = {{0.1f, 1.6f, 2.0f}, {0, 0, 0, 1}};
    fv_pose p1 = {{0.1f, 1.6f, 2.0f}, {ax[0] / an * sinf(a), ax[1] / an * sinf(a), ax[2] / an * sinf(a), cosf(a)}};
    cam(c0, &p0);
    cam(c1, &p1);
    render_dirs(p->rgb, c0);
    for (int i = 0; i < W * H; i++)
        p->invd[i] = (uint16_t)(FV_TW_INVD_PER_M / (0.5f + (float)(i % 7)));
}

static void test_pure_rotation(void **state)
{
    (void)state;
    planes *p = calloc(1, sizeof *p);
    assert_non_null(p);
    fv_camera c0, c1;
    rotation_case(p, &c0, &c1);
    assert_int_equal(warp(p, &c1, &c0), 0);
    static uint8_t want[W * H * 3];
    render_dirs(want, &c1);
    int checked = 0, maxd = 0, moved = 0;
    rotation_error(p, want, &c0, &c1, &checked, &maxd, &moved);
    assert_true(checked > W * H / 2);
    assert_true(moved > checked / 4); /* the unwarped image is far from the answer */
    /* bilinear interpolation of the 8-bit pattern (curvature ~ 100 * 5^2 * pixel_angle^2 / 8) */
    if (maxd > 3)
        fail_msg("rotation: max error %d levels over %d pixels", maxd, checked);
    free(p);
}

/* The bounded warp with no per-pixel budget on a turn of 6 degrees about a tilted axis (the block
 * proof fails: a 64-pixel row's offsets spread by more than 0.25 px): nothing runs per pixel, the
 * failed parts are grid cells, and the image is the rotated one within the cells' position error
 * (the homography's change over half a cell, under 0.5 px here) times the pattern's slope (at
 * most ~7 levels a pixel) plus the bilinear tap's 3 levels: 8 (measured 7). */
static void test_bounded_rotation(void **state)
{
    (void)state;
    planes *p = calloc(1, sizeof *p);
    assert_non_null(p);
    fv_camera c0, c1;
    rotation_case(p, &c0, &c1);
    fv_tw_warp_stats st = {0, 0};
    assert_int_equal(warp_bounded(p, &c1, &c0, 0, &st), 0);
    assert_int_equal(st.pixel_px, 0);
    if (st.grid_px < W * H / 4)
        fail_msg("grid cells: %ld of %d pixels (the case should fail the block proof)", st.grid_px, W * H);
    static uint8_t want[W * H * 3];
    render_dirs(want, &c1);
    int checked = 0, maxd = 0, moved = 0;
    rotation_error(p, want, &c0, &c1, &checked, &maxd, &moved);
    assert_true(checked > W * H / 2);
    if (maxd > 8) /* measured 7; the per-pixel warp 3 */
        fail_msg("bounded rotation: max error %d levels over %d pixels", maxd, checked);
    /* an unbounded budget is the block warp (the per-pixel kernel where the proof fails) */
    static uint8_t blockw[W * H * 3];
    warp(p, &c1, &c0);
    memcpy(blockw, p->out, sizeof blockw);
    fv_tw_warp_stats su = {0, 0};
    warp_bounded(p, &c1, &c0, LONG_MAX, &su);
    assert_memory_equal(blockw, p->out, sizeof blockw);
    assert_int_equal(su.grid_px, 0);
    assert_true(su.pixel_px > 0);
    free(p);
}

/* two fronto-parallel planes (left half 2 m, right half 4 m); the camera steps right by s: a
 * point at depth z moves left by focal * s / z pixels, so display pixel x shows source x + shift */
static void test_translated_planes(void **state)
{
    (void)state;
    planes *p = calloc(1, sizeof *p);
    assert_non_null(p);
    fv_pose p0 = {{0, 0, 0}, {0, 0, 0, 1}};
    fv_camera c0;
    cam(&c0, &p0);
    const float step = 8.0f * 2.0f / c0.focal_px; /* 8 px at 2 m, 4 px at 4 m */
    fv_pose p1 = {{step, 0, 0}, {0, 0, 0, 1}};
    fv_camera c1;
    cam(&c1, &p1);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            uint8_t *q = p->rgb + (y * W + x) * 3;
            q[0] = (uint8_t)x, q[1] = (uint8_t)y, q[2] = (uint8_t)(x < W / 2 ? 50 : 200);
            p->invd[y * W + x] = (uint16_t)(FV_TW_INVD_PER_M / (x < W / 2 ? 2.0f : 4.0f) + 0.5f);
        }
    warp(p, &c1, &c0);
    int checked = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const int shift = x + 8 < W / 2 - 2 ? 8 : (x + 4 > W / 2 + 2 && x + 4 < W - 1) ? 4 : 0;
            if (!shift)
                continue; /* near the step or the right edge */
            const uint8_t *o = p->out + (y * W + x) * 3;
            if (abs((int)o[0] - (x + shift)) > 1 || abs((int)o[1] - y) > 1)
                fail_msg("plane at %s: pixel (%d, %d) shows source (%d, %d), want (%d, %d)", shift == 8 ? "2 m" : "4 m",
                         x, y, o[0], o[1], x + shift, y);
            checked++;
        }
    assert_true(checked > W * H / 2);
    free(p);
}

/* The bounded warp on the two planes stepped farther (24 px at 2 m, 12 px at 4 m: every block that
 * sees both planes fails the proof) with no per-pixel budget: each grid cell takes the depth at
 * its vertices, so a cell on one plane moves by that plane's shift exactly. */
static void test_bounded_planes(void **state)
{
    (void)state;
    planes *p = calloc(1, sizeof *p);
    assert_non_null(p);
    fv_pose p0 = {{0, 0, 0}, {0, 0, 0, 1}};
    fv_camera c0;
    cam(&c0, &p0);
    const float step = 24.0f * 2.0f / c0.focal_px;
    fv_pose p1 = {{step, 0, 0}, {0, 0, 0, 1}};
    fv_camera c1;
    cam(&c1, &p1);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            uint8_t *q = p->rgb + (y * W + x) * 3;
            q[0] = (uint8_t)x, q[1] = (uint8_t)y, q[2] = (uint8_t)(x < W / 2 ? 50 : 200);
            p->invd[y * W + x] = (uint16_t)(FV_TW_INVD_PER_M / (x < W / 2 ? 2.0f : 4.0f) + 0.5f);
        }
    fv_tw_warp_stats st = {0, 0};
    warp_bounded(p, &c1, &c0, 0, &st);
    assert_int_equal(st.pixel_px, 0);
    assert_true(st.grid_px > 0);
    int checked = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            /* whole cells on one plane: a cell (16 columns) clear of the step on both sides */
            const int cx0 = x / FV_TW_GRID_W * FV_TW_GRID_W, cx1 = cx0 + FV_TW_GRID_W;
            const int shift = cx1 + 24 <= W / 2 ? 24 : (cx0 + 12 >= W / 2 && cx1 + 12 < W) ? 12 : 0;
            if (!shift)
                continue;
            const uint8_t *o = p->out + (y * W + x) * 3;
            if (abs((int)o[0] - (x + shift)) > 1 || abs((int)o[1] - y) > 1)
                fail_msg("plane at %s: pixel (%d, %d) shows source (%d, %d), want (%d, %d)", shift == 24 ? "2 m" : "4 m",
                         x, y, o[0], o[1], x + shift, y);
            checked++;
        }
    assert_true(checked > W * H / 3);
    free(p);
}

/* a square at 0.5 m before a wall at 5 m, camera stepped left: the wall beside the square's left
 * edge comes out from behind it, a strip focal * s * (1/0.5 - 1/5) px wide; it must be counted
 * and shown as wall, not as square */
static void test_disocclusion(void **state)
{
    (void)state;
    planes *p = calloc(1, sizeof *p);
    assert_non_null(p);
    fv_pose p0 = {{0, 0, 0}, {0, 0, 0, 1}};
    fv_camera c0;
    cam(&c0, &p0);
    const float strip_px = 6.0f, step = strip_px / (c0.focal_px * (1.0f / 0.5f - 1.0f / 5.0f));
    fv_pose p1 = {{-step, 0, 0}, {0, 0, 0, 1}};
    fv_camera c1;
    cam(&c1, &p1);
    const int sx0 = 60, sx1 = 100, sy0 = 40, sy1 = 100; /* the square in the source */
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const int in = x >= sx0 && x < sx1 && y >= sy0 && y < sy1;
            uint8_t *q = p->rgb + (y * W + x) * 3;
            q[0] = q[1] = q[2] = in ? 240 : 20;
            p->invd[y * W + x] = (uint16_t)(FV_TW_INVD_PER_M / (in ? 0.5f : 5.0f) + 0.5f);
        }
    const long holes = warp(p, &c1, &c0);
    /* the square moves right by focal * s / 0.5, the wall by focal * s / 5 */
    const float fg = c0.focal_px * step / 0.5f, bg = c0.focal_px * step / 5.0f;
    const long want = lrintf(strip_px) * (sy1 - sy0);
    if (labs(holes - want) > 2 * (sy1 - sy0))
        fail_msg("disocclusion: %ld pixels, want %ld (+- 2 columns)", holes, want);
    /* the strip itself: columns left of the moved square's left edge, right of where the wall was hidden */
    int wall = 0, n = 0;
    for (int y = sy0 + 2; y < sy1 - 2; y++)
        for (int x = (int)ceilf(sx0 + bg) + 1; x < (int)floorf(sx0 + fg) - 1; x++) {
            n++;
            wall += p->out[(y * W + x) * 3] < 60;
        }
    assert_true(n > 0);
    if (wall < n * 95 / 100)
        fail_msg("disocclusion fill: %d of %d strip pixels show the wall", wall, n);
    free(p);
}

/* The block warp's footprint proof (timewarp.h): a wall at 1 m with a pole at 0.3 m in source
 * column 65, just right of the first block's columns [0, 64); the camera steps so the wall
 * moves 2 px (the pole 6.7 px). At w = 0 the block sees only wall, but the reference's
 * iteration for its last column fetches the pole (63.5 + 2 = 65.5), then samples beside it
 * (63.5 + 6.7): the block must not be translated as wall (it would sample column 65.5). The
 * source's red is its column, so the output shows where each pixel sampled. */
static void test_block_footprint(void **state)
{
    (void)state;
    planes *p = calloc(1, sizeof *p);
    planes *q = calloc(1, sizeof *q);
    assert_non_null(p);
    assert_non_null(q);
    fv_pose p0 = {{0, 0, 0}, {0, 0, 0, 1}};
    fv_camera c0;
    cam(&c0, &p0);
    fv_pose p1 = {{2.0f / c0.focal_px, 0, 0}, {0, 0, 0, 1}}; /* 2 px at 1 m */
    fv_camera c1;
    cam(&c1, &p1);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            uint8_t *r = p->rgb + (y * W + x) * 3;
            r[0] = (uint8_t)x, r[1] = (uint8_t)y, r[2] = 0;
            p->invd[y * W + x] = (uint16_t)(FV_TW_INVD_PER_M / (x == 65 ? 0.3f : 1.0f) + 0.5f);
        }
    memcpy(q, p, sizeof *p);
    warp(p, &c1, &c0); /* the block warp */
    fv_timewarp_dsp d;
    fv_timewarp_dsp_init(&d, FV_ISA_C);
    fv_tw_map m;
    fv_tw_setup(&m, &c1, &c0, 0.05f);
    const fv_tw_src s = {q->rgb, W * 3, q->invd, W, W, H};
    fv_tw_warp_rows_pixel(&d, q->out, W * 3, 0, H, &m, &s);
    for (int y = 0; y < FV_TW_BLOCK_H; y++) {
        const int want = q->out[(y * W + 63) * 3], got = p->out[(y * W + 63) * 3];
        assert_true(want >= 69); /* the reference samples beside the pole (the case is as described) */
        if (abs(got - want) > 1)
            fail_msg("row %d column 63: sampled column %d, the reference %d", y, got, want);
    }
    /* elsewhere on the wall the block warp translates: 2 px */
    assert_int_equal(p->out[(40 * W + 20) * 3], 22);
    free(p);
    free(q);
}

/* The quality target on the range scene at the headset's size: a frame warped to a head
 * turned at 30 deg/s for one and two refreshes (90 Hz) against the frame rendered directly there
 * (full sampling, no reprojection, no DoF: the warp is the only difference) scores >= 30 dB luma
 * PSNR outside the disocclusions, far above showing the old frame as it is. The figures:
 * tools/tw_quality. */
static void test_quality_range(void **state)
{
    (void)state;
    char err[512];
    fv_scene *scene = fv_scene_load("assets/range.glb", err, sizeof err);
    if (!scene)
        fail_msg("assets/range.glb: %s (built by make)", err);
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    cfg.samp.full = 1;
    cfg.taa.enabled = 0;
    cfg.threads = 2;
    const int w = cfg.cam.width, h = cfg.cam.height;
    fv_pipeline *pl = fv_pipeline_create(scene, &cfg, err, sizeof err);
    assert_non_null(pl);
    fv_pose p0;
    fv_scene_default_view(scene, cfg.cam.fov_y_deg, (float)w / (float)h, p0.pos, p0.quat);
    fv_tw_frame f0, f1;
    uint8_t *out = malloc((size_t)w * h * 3);
    assert_non_null(out);
    assert_int_equal(fv_tw_frame_alloc(&f0, w, h), 0);
    assert_int_equal(fv_tw_frame_alloc(&f1, w, h), 0);
    fv_frame_stats st;
    assert_int_equal(fv_pipeline_render(pl, FV_EYE_LEFT, &p0, 0.5f, 0.5f, &st), 0);
    fv_tw_frame_capture(&f0, pl, 0);
    fv_timewarp_dsp d;
    fv_timewarp_dsp_init(&d, ~0u);
    for (int k = 1; k <= 2; k++) {
        const double a = 30.0 * k / 90.0 * PI_D / 180.0;
        const float q[4] = {0, (float)sin(a / 2), 0, (float)cos(a / 2)};
        fv_pose p1 = p0;
        fv_quat_mul(q, p0.quat, p1.quat);
        assert_int_equal(fv_pipeline_render(pl, FV_EYE_LEFT, &p1, 0.5f, 0.5f, &st), 0);
        fv_tw_frame_capture(&f1, pl, 0);
        fv_tw_map m;
        fv_tw_setup(&m, &f1.cam[0], &f0.cam[0], 0.05f);
        const fv_tw_src s = {f0.rgb[0], (ptrdiff_t)w * 3, f0.invd[0], w, w, h};
        fv_tw_warp_rows(&d, out, (ptrdiff_t)w * 3, 0, h, &m, &s, &f0.tiles[0]);
        double holes;
        const double psnr = fv_tw_psnr_outside_holes(out, f1.rgb[0], &m, &s, &holes);
        const double stale = fv_luma_psnr(f0.rgb[0], f1.rgb[0], w, h, (ptrdiff_t)w * 3, NULL);
        printf("    %d refresh(es) old: warped %.2f dB, unwarped %.2f dB, disoccluded %.4f %%\n", k, psnr, stale,
               100.0 * holes);
        if (!(psnr >= 30.0) || !(psnr > stale + 8.0) || !(holes < 0.01))
            fail_msg("%d refreshes: warped %.2f dB (unwarped %.2f dB), disoccluded %.4f %%", k, psnr, stale, 100.0 * holes);
    }
    fv_tw_frame_free(&f0);
    fv_tw_frame_free(&f1);
    free(out);
    fv_pipeline_destroy(pl);
    fv_scene_free(scene);
}

/* ---- pose prediction ---- */
static void yaw_pose(fv_pose *p, double yaw_rad, double x_m)
{
    memset(p, 0, sizeof *p);
    p->pos[0] = (float)x_m;
    p->quat[1] = (float)sin(yaw_rad / 2), p->quat[3] = (float)cos(yaw_rad / 2);
}

static void test_posepred_constant_velocity(void **state)
{
    (void)state;
    fv_posepred pp;
    fv_posepred_init(&pp, 8000000, 50000000);
    fv_pose out, truth;
    assert_int_equal(fv_posepred_predict(&pp, 0, &out, NULL), 0);
    const double w = 30.0 * PI_D / 180.0, v = 0.5; /* 30 deg/s, 0.5 m/s */
    for (int ms = 0; ms <= 100; ms++) {
        fv_pose s;
        yaw_pose(&s, w * ms * 1e-3, v * ms * 1e-3);
        fv_posepred_push(&pp, (int64_t)ms * 1000000, &s);
    }
    int64_t ts;
    assert_int_equal(fv_posepred_predict(&pp, 120000000, &out, &ts), 1);
    assert_true(ts == 100000000);
    yaw_pose(&truth, w * 0.120, v * 0.120);
    fv_pose held;
    yaw_pose(&held, w * 0.100, v * 0.100);
    assert_true(fv_pose_angle_deg(&out, &truth) < 2e-3);
    assert_true(fv_pose_dist_m(&out, &truth) < 1e-5);
    assert_true(fabs(fv_pose_angle_deg(&held, &truth) - 0.6) < 2e-3); /* the helper: 30 deg/s x 20 ms */
    /* the horizon is capped: 1 s ahead predicts 50 ms ahead */
    fv_posepred_predict(&pp, 1100000000, &out, NULL);
    yaw_pose(&truth, w * 0.150, v * 0.150);
    assert_true(fv_pose_angle_deg(&out, &truth) < 2e-3);
}

static void test_posepred_sinusoid(void **state)
{
    (void)state;
    /* a head shaking +-20 deg at 1 Hz, sampled at 1 kHz, predicted 20 ms ahead: much closer than
     * holding the last sample */
    fv_posepred pp;
    fv_posepred_init(&pp, 8000000, 50000000);
    double err_pred = 0, err_hold = 0;
    int n = 0;
    for (int ms = 0; ms < 2000; ms++) {
        fv_pose s, out, truth;
        yaw_pose(&s, 20.0 * PI_D / 180.0 * sin(2 * PI_D * ms * 1e-3), 0);
        fv_posepred_push(&pp, (int64_t)ms * 1000000, &s);
        if (ms < 20 || ms % 10)
            continue;
        fv_posepred_predict(&pp, (int64_t)(ms + 20) * 1000000, &out, NULL);
        yaw_pose(&truth, 20.0 * PI_D / 180.0 * sin(2 * PI_D * (ms + 20) * 1e-3), 0);
        err_pred += fv_pose_angle_deg(&out, &truth);
        err_hold += fv_pose_angle_deg(&s, &truth);
        n++;
    }
    err_pred /= n, err_hold /= n;
    /* hold: mean |d yaw| over 20 ms = 20 deg * 2 pi * 0.02 * 2/pi = 1.6 deg; the prediction's
     * error is the curvature's, ~ (1/2) yaw'' (20 ms)(20 ms + span) */
    assert_true(fabs(err_hold - 1.6) < 0.1);
    if (err_pred > 0.25 * err_hold)
        fail_msg("prediction error %.3f deg vs %.3f deg holding the last sample", err_pred, err_hold);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pure_rotation),
        cmocka_unit_test(test_bounded_rotation),
        cmocka_unit_test(test_bounded_planes),
        cmocka_unit_test(test_translated_planes),
        cmocka_unit_test(test_disocclusion),
        cmocka_unit_test(test_block_footprint),
        cmocka_unit_test(test_quality_range),
        cmocka_unit_test(test_posepred_constant_velocity),
        cmocka_unit_test(test_posepred_sinusoid),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
