/* Ray casting and the frame pipeline on hand-built scenes: hand-computed depths and colours,
 * misses, sample counts against the sampler, and identical bytes for any thread count. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "testscene.h"
#include "pipeline.h"
#include "eyetrack/gazefilter.h"
#include "raycast.h"
#include "scene.h"

#define AMBIENT 0.15f /* the scene's ambient term (see scene.c) */


static void add_quad(fv_scene *s, float x0, float y0, float x1, float y1, float z, const float rgb[3])
{
    fv_test_add_quad(s, x0, y0, x1, y1, z, rgb, -1);
}

static const float wall_rgb[3] = {0.5f, 0.25f, 1.0f}, card_rgb[3] = {0.2f, 0.8f, 0.4f};

/* A wall at 2 m filling the view's left and centre, a card at 1 m, nothing on the far right. */
static fv_scene *hand_scene(void)
{
    fv_scene *s = fv_scene_create();
    assert_non_null(s);
    add_quad(s, -10.0f, -10.0f, 1.0f, 10.0f, -2.0f, wall_rgb);
    add_quad(s, -0.6f, -0.3f, -0.2f, 0.3f, -1.0f, card_rgb);
    char err[256];
    assert_int_equal(fv_scene_commit(s, err, sizeof err), 0);
    return s;
}

static const fv_pose origin = {{0, 0, 0}, {0, 0, 0, 1}};

static void test_hand_scene_full(void **st)
{
    (void)st;
    fv_scene *s = hand_scene();
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    cfg.cam.width = 64;
    cfg.cam.height = 72;
    cfg.cam.fov_y_deg = 90.0f; /* tan(45) = 1: the image spans x in [-8/9, 8/9], y in [-1, 1] */
    cfg.samp.full = 1;
    cfg.threads = 2;
    char err[256];
    fv_pipeline *p = fv_pipeline_create(s, &cfg, err, sizeof err);
    assert_non_null(p);
    fv_frame_stats stats;
    assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, &origin, 0.5f, 0.5f, &stats), 0);
    assert_int_equal(stats.samples, 64 * 72);
    const fv_pyr_level *l0 = &fv_pipeline_pyramid(p, FV_EYE_CENTER)->lv[0];
    int checked_wall = 0, checked_card = 0, checked_miss = 0;
    for (int y = 0; y < 72; y++)
        for (int x = 0; x < 64; x++) {
            /* ray through the pixel centre: tan x, tan y */
            double tx = -64.0 / 72.0 + (x + 0.5) * 2.0 / 72.0, ty = 1.0 - (y + 0.5) * 2.0 / 72.0;
            const float *px = l0->rgbd + 4 * (y * l0->stride + x);
            assert_float_equal(l0->wgt[y * l0->stride + x], 1.0f, 0.0f);
            /* stay clear of the edges, where a ray could graze either side */
            int on_card = tx > -0.6 + 0.03 && tx < -0.2 - 0.03 && ty > -0.3 + 0.03 && ty < 0.3 - 0.03;
            int on_wall = !(tx > -0.6 - 0.03 && tx < -0.2 + 0.03 && ty > -0.3 - 0.03 && ty < 0.3 + 0.03) && 2.0 * tx < 1.0 - 0.06;
            int miss = 2.0 * tx > 1.0 + 0.06;
            /* head light at the eye, no falloff: lambert = cos(angle to the normal) = 1/|(tx,ty,-1)| */
            double lam = 1.0 / sqrt(1.0 + tx * tx + ty * ty);
            if (on_card || on_wall) {
                const float *c = on_card ? card_rgb : wall_rgb;
                assert_float_equal(px[3], on_card ? 1.0 : 2.0, 1e-4);
                for (int k = 0; k < 3; k++)
                    assert_float_equal(px[k], c[k] * (AMBIENT + lam), 2e-4);
                on_card ? checked_card++ : checked_wall++;
            } else if (miss) {
                assert_float_equal(px[3], FV_DEPTH_MISS_M, 0.0f);
                for (int k = 0; k < 3; k++)
                    assert_float_equal(px[k], fv_background_rgb[k], 0.0f);
                checked_miss++;
            }
        }
    assert_true(checked_wall > 500 && checked_card > 100 && checked_miss > 100);
    fv_pipeline_destroy(p);
    fv_scene_free(s);
}

/* Foveated: exactly the sampler's pixels are cast, carry weight 1 before reconstruction, and
 * the reconstruction keeps every cast sample exactly. */
static void test_foveated_samples(void **st)
{
    (void)st;
    fv_scene *s = hand_scene();
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    cfg.cam.width = 320;
    cfg.cam.height = 360;
    cfg.threads = 2;
    char err[256];
    fv_pipeline *p = fv_pipeline_create(s, &cfg, err, sizeof err);
    assert_non_null(p);
    const fv_sampler *smp = fv_pipeline_sampler(p);
    const fv_camera *cam = fv_pipeline_camera(p, FV_EYE_CENTER);
    float gx = 0.3f, gy = 0.6f;
    int px0 = (int)floorf(gx * 320), py0 = (int)floorf(gy * 360);
    long want = 0;
    for (int y = 0; y < 360; y++)
        for (int x = 0; x < 320; x += 64)
            want += __builtin_popcountll(fv_sampler_row(smp, x, y, 320 - x < 64 ? 320 - x : 64, px0, py0, 0));
    fv_frame_stats stats;
    assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, &origin, gx, gy, &stats), 0);
    assert_int_equal(stats.samples, want);
    assert_true(want < 320 * 360 / 2);
    assert_false(isnan(stats.stage_ms[FV_STAGE_TRACE]));
    assert_false(isnan(stats.stage_ms[FV_STAGE_RECONSTRUCT]));
    assert_true(isnan(stats.stage_ms[FV_STAGE_COC]));
    /* Sampled pixels keep their ray-cast values through pull-push: recast a few by hand */
    const fv_pyr_level *l0 = &fv_pipeline_pyramid(p, FV_EYE_CENTER)->lv[0];
    int checked = 0;
    for (int y = 0; y < 360; y += 7)
        for (int x = 0; x < 320; x += 5) {
            if (!(fv_sampler_row(smp, x, y, 1, px0, py0, 0) & 1))
                continue;
            float d[3];
            fv_camera_ray(cam, x + 0.5f, y + 0.5f, d);
            /* the wall plane z = -2 hit at view depth 2 where it is not covered by the card */
            double tx = d[0], ty = d[1];
            if (tx < 0.45 && !(tx > -0.65 && tx < -0.15 && ty > -0.35 && ty < 0.35)) {
                assert_float_equal(l0->rgbd[4 * (y * l0->stride + x) + 3], 2.0f, 1e-4);
                checked++;
            }
        }
    assert_true(checked > 100);
    fv_pipeline_destroy(p);
    fv_scene_free(s);
}

/* Samples the sampler in force casts for the gaze at pixel (px, py), phase 0. */
static long pattern_samples(const fv_sampler *smp, int w, int h, int px, int py)
{
    long n = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x += 64)
            n += __builtin_popcountll(fv_sampler_row(smp, x, y, w - x < 64 ? w - x : 64, px, py, 0));
    return n;
}

/* Pixels within radius rad (pixel centres) of (px + 0.5, py + 0.5) that the pattern leaves out. */
static int holes_in_disc(const fv_sampler *smp, int w, int h, int px, int py, float rad)
{
    int holes = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float dx = (float)(x - px), dy = (float)(y - py);
            if (dx * dx + dy * dy < rad * rad && !(fv_sampler_row(smp, x, y, 1, px, py, 0) & 1))
                holes++;
        }
    return holes;
}

/* A doubtful gaze widens the fovea: with the scale fv_fovea_radius_scale gives a low confidence,
 * r0 and r1 double, more rays are cast and the fully sampled disc is the wider one (the normal
 * pattern has holes in it); the scale is quantised, a step's pattern is the same on every visit
 * and going back to 1 restores the first pattern exactly. */
static void test_fovea_scale(void **st)
{
    (void)st;
    fv_scene *s = hand_scene();
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    cfg.cam.width = 320;
    cfg.cam.height = 360;
    cfg.threads = 2;
    cfg.samp.rotate = 0; /* one pattern: the expected counts hold for every frame */
    char err[256];
    fv_pipeline *p = fv_pipeline_create(s, &cfg, err, sizeof err);
    assert_non_null(p);
    const float gx = 0.45f, gy = 0.55f;
    const int px = (int)floorf(gx * 320), py = (int)floorf(gy * 360);
    fv_frame_stats a, b, c, d;
    assert_float_equal(fv_pipeline_fovea_scale(p), 1.0f, 0.0f);
    const fv_sampler *s1 = fv_pipeline_sampler(p);
    const float r0 = s1->r0_px, r1 = s1->r1_px;
    assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, &origin, gx, gy, &a), 0);
    assert_int_equal(a.samples, pattern_samples(s1, 320, 360, px, py));
    assert_int_equal(holes_in_disc(s1, 320, 360, px, py, r0), 0);
    assert_true(holes_in_disc(s1, 320, 360, px, py, 1.9f * r0) > 100);

    /* tracking confidence 0.1: scale 2 */
    const float scale = fv_fovea_radius_scale(0.1f);
    assert_float_equal(scale, 2.0f, 1e-6);
    assert_int_equal(fv_pipeline_set_fovea_scale(p, scale), 0);
    assert_float_equal(fv_pipeline_fovea_scale(p), 2.0f, 0.0f);
    const fv_sampler *s2 = fv_pipeline_sampler(p);
    assert_float_equal(s2->r0_px, 2.0f * r0, 1e-3f * r0);
    assert_float_equal(s2->r1_px, 2.0f * r1, 1e-3f * r1);
    assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, &origin, gx, gy, &b), 0);
    assert_int_equal(b.samples, pattern_samples(s2, 320, 360, px, py));
    assert_true(b.samples > a.samples * 13 / 10); /* 27248 -> 40288 rays here */
    assert_int_equal(holes_in_disc(s2, 320, 360, px, py, 1.99f * r0), 0);

    /* in between: 1.3 is the 1.25 step; back to 1 and to 2 again: the same patterns */
    assert_int_equal(fv_pipeline_set_fovea_scale(p, 1.3f), 0);
    assert_float_equal(fv_pipeline_fovea_scale(p), 1.25f, 0.0f);
    assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, &origin, gx, gy, &c), 0);
    assert_true(c.samples > a.samples && c.samples < b.samples);
    assert_int_equal(fv_pipeline_set_fovea_scale(p, 0.5f), 0);
    assert_ptr_equal(fv_pipeline_sampler(p), s1);
    assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, &origin, gx, gy, &d), 0);
    assert_int_equal(d.samples, a.samples);
    assert_int_equal(fv_pipeline_set_fovea_scale(p, NAN), 0); /* NaN confidence: widest */
    assert_ptr_equal(fv_pipeline_sampler(p), s2);
    assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, &origin, gx, gy, &d), 0);
    assert_int_equal(d.samples, b.samples);
    fv_pipeline_destroy(p);

    /* full sampling: nothing to widen */
    cfg.samp.full = 1;
    p = fv_pipeline_create(s, &cfg, err, sizeof err);
    assert_non_null(p);
    assert_int_equal(fv_pipeline_set_fovea_scale(p, 2.0f), 0);
    assert_float_equal(fv_pipeline_fovea_scale(p), 1.0f, 0.0f);
    fv_pipeline_destroy(p);
    fv_scene_free(s);
}

/* Many random triangles, foveated with an off-centre gaze: level 0 and the pyramid above are
 * identical bytes for 1, 2 and 5 threads, and on a repeated render. */
static void test_thread_determinism(void **st)
{
    (void)st;
    fv_scene *s = fv_scene_create();
    uint64_t rng = 42;
    enum { NT = 3000 };
    static float pos[NT * 9];
    for (int i = 0; i < NT; i++) {
        float cx = (fv_test_randf(&rng) - 0.5f) * 8.0f, cy = (fv_test_randf(&rng) - 0.5f) * 8.0f;
        float cz = -1.0f - fv_test_randf(&rng) * 8.0f;
        for (int v = 0; v < 3; v++) {
            pos[i * 9 + v * 3 + 0] = cx + (fv_test_randf(&rng) - 0.5f);
            pos[i * 9 + v * 3 + 1] = cy + (fv_test_randf(&rng) - 0.5f);
            pos[i * 9 + v * 3 + 2] = cz + (fv_test_randf(&rng) - 0.5f) * 0.3f;
        }
    }
    fv_mesh_desc m;
    memset(&m, 0, sizeof m);
    m.positions = pos;
    m.vertex_count = NT * 3;
    m.base_color[0] = 0.9f;
    m.base_color[1] = 0.6f;
    m.base_color[2] = 0.3f;
    m.base_color[3] = 1.0f;
    m.texture = -1;
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    assert_int_equal(fv_scene_commit(s, err, sizeof err), 0);

    const int threads[] = {1, 2, 5, 2};
    size_t n0 = 0, n3 = 0;
    float *ref0 = NULL, *ref3 = NULL;
    for (int k = 0; k < 4; k++) {
        fv_pipeline_config cfg;
        fv_pipeline_config_default(&cfg);
        cfg.cam.width = 200;
        cfg.cam.height = 230;
        cfg.threads = threads[k];
        fv_pipeline *p = fv_pipeline_create(s, &cfg, err, sizeof err);
        assert_non_null(p);
        fv_frame_stats stats;
        fv_pose head = {{0.1f, -0.2f, 0.5f}, {0.05f, 0.1f, 0.0f, 0.99f}};
        assert_int_equal(fv_pipeline_render(p, FV_EYE_LEFT, &head, 0.7f, 0.35f, &stats), 0);
        const fv_pyramid *pyr = fv_pipeline_pyramid(p, FV_EYE_LEFT);
        const fv_pyr_level *a = &pyr->lv[0], *b = &pyr->lv[3];
        if (!ref0) {
            n0 = (size_t)a->h * a->stride * 4;
            n3 = (size_t)b->h * b->stride * 4;
            ref0 = malloc(n0 * sizeof(float));
            ref3 = malloc(n3 * sizeof(float));
            for (int y = 0; y < a->h; y++) /* only valid pixels: padding is not part of the image */
                memcpy(ref0 + 4 * y * a->stride, a->rgbd + 4 * y * a->stride, 4 * sizeof(float) * a->w);
            for (int y = 0; y < b->h; y++)
                memcpy(ref3 + 4 * y * b->stride, b->rgbd + 4 * y * b->stride, 4 * sizeof(float) * b->w);
        } else {
            for (int y = 0; y < a->h; y++)
                assert_memory_equal(ref0 + 4 * y * a->stride, a->rgbd + 4 * y * a->stride, 4 * sizeof(float) * a->w);
            for (int y = 0; y < b->h; y++)
                assert_memory_equal(ref3 + 4 * y * b->stride, b->rgbd + 4 * y * b->stride, 4 * sizeof(float) * b->w);
        }
        fv_pipeline_destroy(p);
    }
    free(ref0);
    free(ref3);
    fv_scene_free(s);
}

/* The ray caster pulls level 0 into level 1 per tile (fused, while the tile is in cache); the
 * pyramid must be bit-identical to a plain fv_pullpush of the same samples. Odd sizes so the
 * right and bottom tiles are partial and odd. */
static void test_fused_pull_matches_pullpush(void **st)
{
    (void)st;
    fv_scene *s = hand_scene();
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    cfg.cam.width = 203;
    cfg.cam.height = 229;
    cfg.threads = 2;
    char err[256];
    fv_pipeline *p = fv_pipeline_create(s, &cfg, err, sizeof err);
    assert_non_null(p);
    fv_frame_stats stats;
    assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, &origin, 0.2f, 0.7f, &stats), 0);
    const fv_pyramid *got = fv_pipeline_pyramid(p, FV_EYE_CENTER);
    fv_pyramid ref;
    assert_int_equal(fv_pyramid_init(&ref, 203, 229), 0);
    assert_int_equal(ref.levels, got->levels);
    /* level 0 keeps its weights and every sampled pixel through push; holes are never read */
    for (int y = 0; y < 229; y++) {
        memcpy(ref.lv[0].rgbd + 4 * y * ref.lv[0].stride, got->lv[0].rgbd + 4 * y * got->lv[0].stride, 4 * sizeof(float) * 203);
        memcpy(ref.lv[0].wgt + y * ref.lv[0].stride, got->lv[0].wgt + y * got->lv[0].stride, sizeof(float) * 203);
    }
    fv_pullpush(&ref, &fv_pipeline_dsp(p)->pp, NULL);
    for (int l = 0; l < ref.levels; l++)
        for (int y = 0; y < ref.lv[l].h; y++) {
            assert_memory_equal(ref.lv[l].rgbd + 4 * y * ref.lv[l].stride, got->lv[l].rgbd + 4 * y * got->lv[l].stride,
                                4 * sizeof(float) * ref.lv[l].w);
            assert_memory_equal(ref.lv[l].wgt + y * ref.lv[l].stride, got->lv[l].wgt + y * got->lv[l].stride,
                                sizeof(float) * ref.lv[l].w);
        }
    fv_pyramid_free(&ref);
    fv_pipeline_destroy(p);
    fv_scene_free(s);
}

/* fv_pipeline_render_stereo (both eyes' tiles in one pool job) gives the bytes of rendering the
 * left then the right eye, frame after frame (history, reprojection, the DoF-driven sampling's
 * per-eye defocus maps, depth of field), for 1, 2 and 5 threads; the stats add up. */
static void test_stereo_pair_matches_sequential(void **st)
{
    (void)st;
    fv_scene *s = fv_scene_create();
    uint64_t rng = 7;
    enum { NT = 1500 };
    static float pos[NT * 9];
    for (int i = 0; i < NT; i++) {
        const float cx = (fv_test_randf(&rng) - 0.5f) * 6.0f, cy = (fv_test_randf(&rng) - 0.5f) * 6.0f;
        const float cz = -0.6f - fv_test_randf(&rng) * 6.0f;
        for (int v = 0; v < 3; v++) {
            pos[i * 9 + v * 3 + 0] = cx + (fv_test_randf(&rng) - 0.5f);
            pos[i * 9 + v * 3 + 1] = cy + (fv_test_randf(&rng) - 0.5f);
            pos[i * 9 + v * 3 + 2] = cz + (fv_test_randf(&rng) - 0.5f) * 0.3f;
        }
    }
    fv_mesh_desc m;
    memset(&m, 0, sizeof m);
    m.positions = pos;
    m.vertex_count = NT * 3;
    m.base_color[0] = 0.3f, m.base_color[1] = 0.7f, m.base_color[2] = 0.9f, m.base_color[3] = 1.0f;
    m.texture = -1;
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    assert_int_equal(fv_scene_commit(s, err, sizeof err), 0);
    enum { W = 176, H = 150, FRAMES = 4 };
    const size_t n = (size_t)W * H * 3;
    uint8_t *want = malloc(2 * n * FRAMES), *got = malloc(2 * n);
    assert_non_null(want);
    assert_non_null(got);
    const int threads[] = {1, 2, 5};
    for (int k = 0; k < 3; k++)
        for (int stereo = 0; stereo < 2; stereo++) {
            fv_pipeline_config cfg;
            fv_pipeline_config_default(&cfg);
            cfg.cam.width = W, cfg.cam.height = H;
            cfg.cam.fov_y_deg = 40.0f;
            cfg.samp.r0_deg = 3.0f, cfg.samp.r1_deg = 8.0f;
            cfg.dof.preset = FV_DOF_STRONG; /* with reprojection: DoF-driven sampling from frame 2 */
            cfg.dof.focus.fixed_m = 0.8f;   /* the far triangles blurred: thinned */
            cfg.dofsamp.kappa = 2.0f;
            cfg.threads = threads[k];
            fv_pipeline *p = fv_pipeline_create(s, &cfg, err, sizeof err);
            assert_non_null(p);
            for (int f = 0; f < FRAMES; f++) {
                const float a = 0.02f * (float)f;
                const fv_pose head = {{0.05f * (float)f, 0.0f, 0.3f}, {0.0f, sinf(a), 0.0f, cosf(a)}};
                const float gx = 0.4f + 0.05f * (float)f, gy = 0.55f;
                fv_pipeline_set_time_ns(p, (int64_t)f * 11111111);
                fv_frame_stats sts[2];
                if (stereo) {
                    assert_int_equal(fv_pipeline_render_stereo(p, &head, gx, gy, sts), 0);
                    for (int e = 0; e < 2; e++) {
                        assert_true(sts[e].samples > 0);
                        assert_true(sts[e].total_ms >= 0.0);
                        assert_true(sts[e].stage_ms[FV_STAGE_TRACE] >= 0.0);
                    }
                } else
                    for (int e = 0; e < 2; e++)
                        assert_int_equal(fv_pipeline_render(p, e ? FV_EYE_RIGHT : FV_EYE_LEFT, &head, gx, gy, &sts[e]), 0);
                for (int e = 0; e < 2; e++) {
                    const fv_eye eye = e ? FV_EYE_RIGHT : FV_EYE_LEFT;
                    /* from frame 2 on both eyes' tiles were thinned with their own maps */
                    assert_true(f > 0 ? fv_pipeline_last_rows(p, eye) != NULL : 1);
                    fv_pipeline_to_rgb8(p, eye, got + (size_t)e * n, W * 3);
                }
                uint8_t *w = want + 2 * n * (size_t)f;
                if (k == 0 && !stereo)
                    memcpy(w, got, 2 * n); /* the reference: one thread, one eye after the other */
                else
                    for (int e = 0; e < 2; e++)
                        if (memcmp(w + (size_t)e * n, got + (size_t)e * n, n))
                            fail_msg("%d threads, %s, frame %d: the %s eye differs from the sequential one-thread render",
                                     threads[k], stereo ? "stereo" : "sequential", f, e ? "right" : "left");
            }
            fv_pipeline_destroy(p);
        }
    /* the eyes differ (a check that the comparison sees two images) */
    assert_true(memcmp(want, want + n, n) != 0);
    free(want);
    free(got);
    fv_scene_free(s);
}

/* Stereo: the eyes sit IPD/2 either side of the head along its right axis. */
static void test_stereo_eyes(void **st)
{
    (void)st;
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.ipd_m = 0.064f;
    fv_pose head = {{1.0f, 2.0f, 3.0f}, {0.0f, 0.70710678f, 0.0f, 0.70710678f}}; /* 90 deg about +Y */
    fv_camera l, r;
    d.eye = FV_EYE_LEFT;
    assert_int_equal(fv_camera_setup(&l, &d, &head), 0);
    d.eye = FV_EYE_RIGHT;
    d.axis_shift = 0.1f;
    assert_int_equal(fv_camera_setup(&r, &d, &head), 0);
    /* +X of the head turned 90 deg about +Y points to -Z in the world */
    assert_float_equal(l.eye_pos[0], 1.0f, 1e-6);
    assert_float_equal(l.eye_pos[2], 3.0f + 0.032f, 1e-6);
    assert_float_equal(r.eye_pos[2], 3.0f - 0.032f, 1e-6);
    /* the view axis (-Z of the head) points to -X in the world; the right eye's frustum is shifted */
    float dir[3];
    fv_camera_ray(&l, 640.0f, 720.0f, dir);
    assert_float_equal(dir[0], -1.0f, 1e-5);
    assert_true(r.tan_right > -r.tan_left); /* the right eye sees further to the right */
    /* projecting the pixel's ray point back gives the pixel */
    float p[3] = {r.eye_pos[0], r.eye_pos[1], r.eye_pos[2]}, px, py;
    fv_camera_ray(&r, 100.5f, 1000.5f, dir);
    for (int i = 0; i < 3; i++)
        p[i] += 3.0f * dir[i];
    assert_float_equal(fv_camera_project(&r, p, &px, &py), 3.0f, 1e-4);
    assert_float_equal(px, 100.5f, 1e-2);
    assert_float_equal(py, 1000.5f, 1e-2);
}

/* Shading is timed only when the configuration asks (cfg.time_shading, the bench): otherwise
 * shade_ms is NAN; when timed it is positive and, being the workers' time inside the ray stage
 * over their count, no more than the stage's wall time; the image is the same bytes either way. */
static void test_shade_timing(void **st)
{
    (void)st;
    fv_scene *s = hand_scene();
    const fv_pyr_level *lv[2];
    fv_pipeline *p[2];
    for (int timed = 0; timed < 2; timed++) {
        fv_pipeline_config cfg;
        fv_pipeline_config_default(&cfg);
        cfg.cam.width = 64, cfg.cam.height = 72, cfg.samp.full = 1, cfg.threads = 2;
        cfg.time_shading = timed;
        char err[256];
        p[timed] = fv_pipeline_create(s, &cfg, err, sizeof err);
        assert_non_null(p[timed]);
        fv_frame_stats stats;
        stats.shade_ms = 123.0; /* overwritten either way */
        assert_int_equal(fv_pipeline_render(p[timed], FV_EYE_CENTER, &origin, 0.5f, 0.5f, &stats), 0);
        if (timed)
            assert_true(stats.shade_ms > 0.0 && stats.shade_ms <= stats.stage_ms[FV_STAGE_TRACE]);
        else
            assert_true(isnan(stats.shade_ms));
        lv[timed] = &fv_pipeline_pyramid(p[timed], FV_EYE_CENTER)->lv[0];
    }
    for (int y = 0; y < 72; y++) {
        assert_memory_equal(lv[0]->rgbd + 4 * y * lv[0]->stride, lv[1]->rgbd + 4 * y * lv[1]->stride, 4 * 64 * sizeof(float));
        assert_memory_equal(lv[0]->wgt + y * lv[0]->stride, lv[1]->wgt + y * lv[1]->stride, 64 * sizeof(float));
    }
    fv_pipeline_destroy(p[0]);
    fv_pipeline_destroy(p[1]);
    fv_scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hand_scene_full),
        cmocka_unit_test(test_shade_timing),
        cmocka_unit_test(test_foveated_samples),
        cmocka_unit_test(test_fovea_scale),
        cmocka_unit_test(test_thread_determinism),
        cmocka_unit_test(test_fused_pull_matches_pullpush),
        cmocka_unit_test(test_stereo_eyes),
        cmocka_unit_test(test_stereo_pair_matches_sequential),
    };
    return cmocka_run_group_tests_name("pipeline", tests, NULL, NULL);
}
