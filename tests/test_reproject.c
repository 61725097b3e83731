/* Temporal reprojection (Weier et al. 2018 §3.1) end to end: the mapping against hand-computed
 * pose changes, exact reprojection of a textured plane under a known translation, convergence of
 * a static view towards full sampling, and no ghost of a near object on the far surface it
 * uncovers. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "testscene.h"
#include "metrics.h"
#include "pipeline.h"
#include "raycast.h"
#include "reproject.h"
#include "scene.h"


/* Directional light along -Z: shading does not depend on where the eye is, so a surface point
 * has the same colour from both poses and reprojected history can be compared exactly. */
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

/* A noise texture: neighbouring texels differ, so an error of one pixel shows. */
static int noise_texture(fv_scene *s, int n)
{
    uint8_t *t = malloc((size_t)n * n * 4);
    assert_non_null(t);
    uint64_t r = 99;
    for (int i = 0; i < n * n; i++) {
        uint64_t v = fv_test_rand(&r);
        t[4 * i] = (uint8_t)v;
        t[4 * i + 1] = (uint8_t)(v >> 8);
        t[4 * i + 2] = (uint8_t)(v >> 16);
        t[4 * i + 3] = 255;
    }
    int id = fv_scene_add_texture(s, t, n, n);
    free(t);
    assert_true(id >= 0);
    return id;
}

static fv_pipeline *make_pipeline_taa(const fv_scene *s, int w, int h, float fov, int full, int taa, float tol,
                                      float alpha)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    cfg.taa.depth_tol = tol;
    cfg.taa.alpha_min = alpha;
    cfg.cam.width = w;
    cfg.cam.height = h;
    cfg.cam.fov_y_deg = fov;
    cfg.samp.full = full;
    cfg.taa.enabled = taa;
    /* these tests compare with the pixel-centre full render: the fovea's anti-aliasing (its own
     * tests: test_fovea_aa.c) converges to the box filter instead */
    cfg.taa.fovea_aa = 0;
    cfg.threads = 2;
    char err[256];
    fv_pipeline *p = fv_pipeline_create(s, &cfg, err, sizeof err);
    assert_non_null(p);
    return p;
}

static fv_pipeline *make_pipeline(const fv_scene *s, int w, int h, float fov, int full, int taa)
{
    fv_taa_params d;
    fv_taa_params_default(&d);
    return make_pipeline_taa(s, w, h, fov, full, taa, d.depth_tol, d.alpha_min);
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

/* Quaternion product: composing rotations equals rotating twice; the identity is neutral. */
static void test_quat_mul(void **st)
{
    (void)st;
    const float a[4] = {0.1f, 0.7f, -0.2f, 0.5f}, b[4] = {-0.4f, 0.1f, 0.3f, 0.8f}, id[4] = {0, 0, 0, 1};
    float qa[4], qb[4], ab[4], t[4];
    memcpy(qa, a, sizeof qa);
    memcpy(qb, b, sizeof qb);
    fv_quat_normalize(qa);
    fv_quat_normalize(qb);
    fv_quat_mul(qa, qb, ab);
    const float v[3] = {0.3f, -1.2f, 2.0f};
    float r1[3], r2[3], r3[3];
    fv_quat_rotate(ab, v, r1);
    fv_quat_rotate(qb, v, r2);
    fv_quat_rotate(qa, r2, r3);
    for (int i = 0; i < 3; i++)
        assert_float_equal(r1[i], r3[i], 1e-5);
    fv_quat_mul(id, qa, t);
    for (int i = 0; i < 4; i++)
        assert_float_equal(t[i], qa[i], 0.0);
    fv_quat_mul(qa, id, t);
    for (int i = 0; i < 4; i++)
        assert_float_equal(t[i], qa[i], 0.0);
}

/* The mapping against hand-computed pose changes: a sideways translation t shifts a point at
 * depth D by -t f / D pixels; a rotation moves points independently of their depth, to where
 * an independent projection (fv_camera_project) puts them. */
static void test_mapping(void **st)
{
    (void)st;
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.width = 200;
    d.height = 240;
    fv_pose a = {{0.3f, 1.5f, -0.2f}, {0, 0, 0, 1}}, b = a;
    b.pos[0] += 0.05f; /* the previous frame's eye was 5 cm to the right */
    fv_camera cur, prev;
    assert_int_equal(fv_camera_setup(&cur, &d, &a), 0);
    assert_int_equal(fv_camera_setup(&prev, &d, &b), 0);
    fv_pyramid hist;
    assert_int_equal(fv_pyramid_init(&hist, 200, 240), 0);
    fv_taa_frame f;
    fv_taa_frame_setup(&f, &cur, &prev, &hist, 0.03f);
    assert_false(f.identity);
    const float depths[] = {0.5f, 2.0f, 9.0f};
    for (int k = 0; k < 3; k++)
        for (int y = 0; y < 240; y += 37)
            for (int x = 0; x < 200; x += 29) {
                float u, v;
                const float z = fv_taa_project(&f, x + 0.5f, y + 0.5f, depths[k], &u, &v);
                assert_float_equal(z, depths[k], 1e-5 * depths[k]);
                assert_float_equal(u, x + 0.5 - 0.05 * cur.focal_px / depths[k], 2e-3);
                assert_float_equal(v, y + 0.5, 2e-3);
            }
    /* yaw 3 deg and pitch 1 deg: compare with projecting the world point into the old camera */
    const double deg = 3.14159265358979323846 / 180.0, yaw = 3.0 * deg, pitch = 1.0 * deg;
    b = a;
    b.quat[0] = (float)(cos(yaw / 2) * sin(pitch / 2));
    b.quat[1] = (float)(sin(yaw / 2) * cos(pitch / 2));
    b.quat[2] = (float)(-sin(yaw / 2) * sin(pitch / 2));
    b.quat[3] = (float)(cos(yaw / 2) * cos(pitch / 2));
    assert_int_equal(fv_camera_setup(&prev, &d, &b), 0);
    fv_taa_frame_setup(&f, &cur, &prev, &hist, 0.03f);
    for (int k = 0; k < 3; k++)
        for (int y = 0; y < 240; y += 41)
            for (int x = 0; x < 200; x += 23) {
                float dir[3], P[3], u, v, eu, ev;
                fv_camera_ray(&cur, x + 0.5f, y + 0.5f, dir);
                for (int i = 0; i < 3; i++)
                    P[i] = cur.eye_pos[i] + depths[k] * dir[i];
                const float ez = fv_camera_project(&prev, P, &eu, &ev);
                const float z = fv_taa_project(&f, x + 0.5f, y + 0.5f, depths[k], &u, &v);
                assert_float_equal(z, ez, 1e-4 * depths[k]);
                assert_float_equal(u, eu, 2e-3);
                assert_float_equal(v, ev, 2e-3);
            }
    /* equal cameras are flagged: the kernels then use the identity exactly */
    fv_taa_frame_setup(&f, &cur, &cur, &hist, 0.03f);
    assert_true(f.identity);
    fv_pyramid_free(&hist);
}

/* Where the tile's alpha is 1 (the fovea: every pixel traced every frame), the blend gives the
 * history no weight: the samples must come back bit for bit, for every ISA, while the flow sums
 * the fill needs are still taken. This is the fovea's path with --fovea-aa off, and with it on for
 * the tiles that are not wholly fully sampled (the fovea's rim, the saturated transition); the
 * whole tiles of the fovea then accumulate jittered samples instead (core/reproject_aa.c,
 * tests/test_fovea_aa.c, which also checks that with it off the pipeline's fovea is exactly the
 * pixel-centre full render). The history here is far brighter than the samples on the same surface,
 * so blending with a weight of 1 and rounding (h + 1 (px - h)) would show: 1000.3 + (0.1 - 1000.3)
 * is 0.1000366 in float, not 0.1. */
static void test_fovea_samples_untouched(void **st)
{
    (void)st;
    enum { W = 40, H = 24 };
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.width = W;
    d.height = H;
    static const fv_pose o = {{0, 0, 0}, {0, 0, 0, 1}};
    fv_camera cam;
    assert_int_equal(fv_camera_setup(&cam, &d, &o), 0);
    fv_pyramid hist, cur;
    assert_int_equal(fv_pyramid_init(&hist, W, H), 0);
    assert_int_equal(fv_pyramid_init(&cur, W, H), 0);
    for (int l = 0; l < hist.levels; l++) {
        fv_pyr_level *L = &hist.lv[l];
        for (int y = -1; y <= L->h; y++)
            for (int x = -1; x <= L->w; x++) {
                float *c = L->rgbd + 4 * ((ptrdiff_t)y * L->stride + x);
                c[0] = 1000.3f, c[1] = 700.7f, c[2] = 333.3f, c[3] = 2.0f;
                L->wgt[(ptrdiff_t)y * L->stride + x] = 1.0f;
            }
    }
    fv_taa_frame f;
    fv_taa_frame_setup(&f, &cam, &cam, &hist, 0.03f);
    fv_pyr_level *c0 = &cur.lv[0];
    for (int motion = 0; motion < 2; motion++) {
        if (motion) { /* a small turn: the samples land between history texels */
            fv_pose p = o;
            p.quat[1] = 0.0087f, p.quat[3] = 0.99996f;
            fv_camera prev;
            assert_int_equal(fv_camera_setup(&prev, &d, &p), 0);
            fv_taa_frame_setup(&f, &cam, &prev, &hist, 0.03f);
            assert_false(f.identity);
        }
        for (unsigned isa = 0; isa <= FV_ISA_NEON; isa = isa ? isa << 1 : 1) {
            if (isa && !(fv_cpu_isas() & isa))
                continue;
            fv_reproject_dsp dsp;
            fv_reproject_dsp_init(&dsp, isa);
            int n = 0;
            for (int y = 0; y < H; y++)
                for (int x = 0; x < W; x++) {
                    float *c = c0->rgbd + 4 * ((ptrdiff_t)y * c0->stride + x);
                    c[0] = 0.1f, c[1] = 0.2f + 0.001f * (float)x, c[2] = 0.3f, c[3] = 2.0f;
                    c0->wgt[(ptrdiff_t)y * c0->stride + x] = (x + y) % 3 ? 1.0f : 0.0f;
                    float u, v; /* the flow counts the samples that land in the previous image */
                    const float z = fv_taa_project(&f, (float)x + 0.5f, (float)y + 0.5f, 2.0f, &u, &v);
                    n += (x + y) % 3 != 0 && z > 0.0f && u >= 0.0f && u < (float)W && v >= 0.0f && v < (float)H;
                }
            assert_true(n > W * H / 2);
            fv_taa_tile t = {1.0f, 1.0f, 0, 0};
            fv_taa_flow fl = {0.0f, 0.0f, 0.0f};
            dsp.taa_blend(&f, &t, c0->rgbd, c0->wgt, c0->stride, 0, 0, W, H, &fl);
            assert_float_equal(fl.n, (float)n, 0.0);
            for (int y = 0; y < H; y++)
                for (int x = 0; x < W; x++) {
                    const float *c = c0->rgbd + 4 * ((ptrdiff_t)y * c0->stride + x);
                    const float want[4] = {0.1f, 0.2f + 0.001f * (float)x, 0.3f, 2.0f};
                    if (memcmp(c, want, sizeof want))
                        fail_msg("%s motion %d: sample (%d, %d) changed to %.9g %.9g %.9g", fv_isa_name(isa),
                                 motion, x, y, (double)c[0], (double)c[1], (double)c[2]);
                }
            /* the same samples at alpha 0.5 do take history: the case is not vacuous */
            t.alpha = 0.5f;
            dsp.taa_blend(&f, &t, c0->rgbd, c0->wgt, c0->stride, 0, 0, W, H, &fl);
            assert_true(c0->rgbd[4 * (5 * c0->stride + 5)] > 100.0f);
        }
    }
    fv_pyramid_free(&hist);
    fv_pyramid_free(&cur);
}

/* A textured plane at 2 m and a sideways head translation of exactly 3 pixels at that depth:
 * after the static view has converged, every pixel whose history is in view must come out as the
 * full render of the new pose (samples fresh, holes from history at the exact shift), although
 * only about a fifth of the periphery is ray traced in the new frame. */
static void test_exact_plane_shift(void **st)
{
    (void)st;
    fv_scene *s = fv_scene_create();
    assert_non_null(s);
    const float white[3] = {1, 1, 1};
    fv_test_add_quad(s, -20, -20, 20, 20, -2.0f, white, noise_texture(s, 1024));
    add_sun(s);
    char err[256];
    assert_int_equal(fv_scene_commit(s, err, sizeof err), 0);
    const int W = 192, H = 216;
    fv_pipeline *p = make_pipeline(s, W, H, 60.0f, 0, 1), *full = make_pipeline(s, W, H, 60.0f, 1, 0);
    fv_pose a = {{0, 0, 0}, {0, 0, 0, 1}};
    for (int i = 0; i < 6; i++) /* one full pattern cycle (K = 5) plus one: converged */
        render(p, &a, 0.1f, 0.1f);
    const float focal = fv_pipeline_camera(p, FV_EYE_CENTER)->focal_px;
    const int shift = 3;
    /* history texels that hold a real sample (the transition ring's Halton points do not reach
     * every pixel with a static gaze; those are pull-push values with weight 0) */
    const fv_pyr_level *h0 = &fv_pipeline_pyramid(p, FV_EYE_CENTER)->lv[0];
    float *hw = malloc((size_t)W * H * sizeof(float));
    assert_non_null(hw);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            hw[(size_t)y * W + x] = h0->wgt[(ptrdiff_t)y * h0->stride + x];
    fv_pose b = a;
    b.pos[0] = (float)shift * 2.0f / focal; /* the plane moves 3 px to the left in the image */
    render(p, &b, 0.1f, 0.1f);
    render(full, &b, 0.1f, 0.1f);
    long checked = 0, holes = 0, no_hist = 0;
    double worst = 0.0;
    const fv_sampler *smp = fv_pipeline_sampler(p);
    const int gpx = (int)floorf(0.1f * W), gpy = (int)floorf(0.1f * H);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W - shift - 1; x++) {
            const float *q = px_at(p, x, y), *r = px_at(full, x, y);
            if (hw[(size_t)y * W + x + shift] < 1.0f) {
                no_hist++;
                continue;
            }
            for (int k = 0; k < 4; k++) {
                const double e = fabs((double)q[k] - r[k]);
                worst = e > worst ? e : worst;
            }
            checked++;
            /* the 7th frame used pattern phase 6: was this pixel ray traced in it? */
            holes += !(fv_sampler_row(smp, x, y, 1, gpx, gpy, 6) & 1);
        }
    printf("exact shift: %ld pixels checked (%ld not ray traced in the new frame; %ld without history skipped), "
           "worst |foveated - full| = %.2e\n", checked, holes, no_hist, worst);
    assert_true(no_hist < checked / 10);
    free(hw);
    assert_true(holes > checked / 2);
    assert_true(worst < 2e-4);
    /* and it was not just sampling: without history the same frame is far off */
    fv_pipeline *nh = make_pipeline(s, W, H, 60.0f, 0, 0);
    render(nh, &b, 0.1f, 0.1f);
    double worst_nh = 0.0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W - shift - 1; x++) {
            const double e = fabs((double)px_at(nh, x, y)[0] - px_at(full, x, y)[0]);
            worst_nh = e > worst_nh ? e : worst_nh;
        }
    printf("exact shift: without reprojection the worst error is %.3f\n", worst_nh);
    assert_true(worst_nh > 0.1);
    fv_pipeline_destroy(nh);
    fv_pipeline_destroy(p);
    fv_pipeline_destroy(full);
    fv_scene_free(s);
}

static fv_scene *load_range(void)
{
    char err[512];
    fv_scene *s = fv_scene_load("assets/range.glb", err, sizeof err);
    if (!s)
        fail_msg("assets/range.glb: %s (built by make)", err);
    return s;
}

static void to_rgb8(const fv_pipeline *p, uint8_t *rgb, int w) { fv_pipeline_to_rgb8(p, FV_EYE_CENTER, rgb, (ptrdiff_t)w * 3); }

/* Static head and gaze on the range scene: the foveated image converges to the full render once
 * the rotating pattern has visited every peripheral pixel; without reprojection it stays put. */
static void test_static_convergence(void **st)
{
    (void)st;
    fv_scene *s = load_range();
    const int W = 256, H = 288;
    fv_pose view;
    fv_scene_default_view(s, 100.0f, (float)W / H, view.pos, view.quat);
    fv_pipeline *taa = make_pipeline(s, W, H, 100.0f, 0, 1), *off = make_pipeline(s, W, H, 100.0f, 0, 0);
    fv_pipeline *full = make_pipeline(s, W, H, 100.0f, 1, 0);
    uint8_t *ref = malloc((size_t)W * H * 3), *img = malloc((size_t)W * H * 3);
    assert_non_null(ref);
    assert_non_null(img);
    render(full, &view, 0.5f, 0.5f);
    to_rgb8(full, ref, W);
    double p_taa[30], p_off[30];
    for (int f = 0; f < 30; f++) {
        render(taa, &view, 0.5f, 0.5f);
        to_rgb8(taa, img, W);
        p_taa[f] = fv_luma_psnr(ref, img, W, H, (ptrdiff_t)W * 3, NULL);
        render(off, &view, 0.5f, 0.5f);
        to_rgb8(off, img, W);
        p_off[f] = fv_luma_psnr(ref, img, W, H, (ptrdiff_t)W * 3, NULL);
    }
    printf("static view, luma PSNR against full sampling: frame 1 %.2f dB, frame 30 %.2f dB with reprojection; "
           "%.2f / %.2f dB without\n", p_taa[0], p_taa[29], p_off[0], p_off[29]);
    assert_true(p_taa[0] < 40.0);              /* one sparse frame really is lossy */
    assert_true(p_taa[29] > p_taa[0] + 12.0);  /* ... and the history makes up for it */
    assert_float_equal(p_off[29], p_off[0], 1e-9); /* nothing accumulates without it */
    for (int f = 1; f < 30; f++)               /* never gets worse while it converges */
        assert_true(p_taa[f] >= p_taa[f - 1] - 0.05);
    free(ref);
    free(img);
    fv_pipeline_destroy(taa);
    fv_pipeline_destroy(off);
    fv_pipeline_destroy(full);
    fv_scene_free(s);
}

/* The still head in place (reproject.h, fv_taa_still_*): against the path it replaces (the
 * history's level 0 copied into the other pyramid by the fill, every sample blended by the
 * taa_blend kernel), on a still view of the range scene. Asserted: the in-place path really
 * runs (level 0 of the history stays in the same memory from frame to frame, as it alternates
 * with the copy), and level 0 after pull-push (colour, depth and weight of every pixel, the
 * history of the next frame) and the display image are bit-identical to the copy's with the
 * rotating pattern, with and without the fovea's anti-aliasing and DoF-driven thinning. With
 * the static pattern the periphery's footprints are wider than a texel (level-0 quincunx:
 * the one case the in-place blend does differently, a single tap): bound, luma PSNR of the
 * display image against the copy's >= 45 dB over 12 frames (measured 62.1 dB). */
static double still_run(const fv_scene *s, const fv_pose *view, int aa, int dof, int rotate, int frames)
{
    const int W = 256, H = 288;
    fv_pipeline *pl[2];
    for (int k = 0; k < 2; k++) {
        fv_pipeline_config cfg;
        fv_pipeline_config_default(&cfg);
        cfg.cam.width = W;
        cfg.cam.height = H;
        cfg.cam.fov_y_deg = 100.0f;
        cfg.taa.fovea_aa = aa;
        cfg.taa.in_place = k;
        cfg.samp.rotate = rotate;
        cfg.dof.preset = dof ? FV_DOF_MEDIUM : FV_DOF_NONE;
        cfg.threads = 2;
        char err[256];
        assert_non_null(pl[k] = fv_pipeline_create(s, &cfg, err, sizeof err));
    }
    uint8_t *img[2];
    for (int k = 0; k < 2; k++)
        assert_non_null(img[k] = malloc((size_t)W * H * 3));
    const float *last[2] = {NULL, NULL};
    double worst = INFINITY;
    for (int f = 0; f < frames; f++) {
        for (int k = 0; k < 2; k++) {
            render(pl[k], view, 0.45f, 0.55f);
            to_rgb8(pl[k], img[k], W);
            const float *now = fv_pipeline_pyramid(pl[k], FV_EYE_CENTER)->lv[0].rgbd;
            if (f >= 2) /* frame 0 has no history, frame 1 renders into the second pyramid */
                assert_true(k ? now == last[k] : now != last[k]);
            last[k] = now;
        }
        const fv_pyr_level *a = &fv_pipeline_pyramid(pl[0], FV_EYE_CENTER)->lv[0];
        const fv_pyr_level *b = &fv_pipeline_pyramid(pl[1], FV_EYE_CENTER)->lv[0];
        long diff = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const ptrdiff_t o = (ptrdiff_t)y * a->stride + x;
                for (int c = 0; c < 4; c++)
                    diff += a->rgbd[4 * o + c] != b->rgbd[4 * o + c];
                diff += a->wgt[o] != b->wgt[o];
            }
        const double q = memcmp(img[0], img[1], (size_t)W * H * 3)
                             ? fv_luma_psnr(img[0], img[1], W, H, (ptrdiff_t)W * 3, NULL)
                             : INFINITY;
        worst = q < worst ? q : worst;
        if (rotate) {
            assert_int_equal(diff, 0);
            assert_true(isinf(q));
        }
    }
    for (int k = 0; k < 2; k++) {
        free(img[k]);
        fv_pipeline_destroy(pl[k]);
    }
    return worst;
}

static void test_still_in_place(void **st)
{
    (void)st;
    fv_scene *s = load_range();
    fv_pose view;
    fv_scene_default_view(s, 100.0f, 256.0f / 288.0f, view.pos, view.quat);
    still_run(s, &view, 0, 0, 1, 8);
    still_run(s, &view, 1, 0, 1, 8);
    still_run(s, &view, 1, 1, 1, 12);
    const double q = still_run(s, &view, 1, 0, 0, 12);
    printf("still head in place, static pattern: display luma PSNR against the copying path >= %.2f dB\n", q);
    assert_true(q >= 45.0);
    fv_scene_free(s);
}

/* A red card at 1 m in front of a plain wall at 5 m; the head rests for a pattern cycle (so the
 * history is dense and confident), then steps sideways, so the card uncovers wall that the
 * history saw as card. Every uncovered pixel the reprojection wrote (a sample blended with
 * history, or a hole filled from it: weight > 0) must show the wall of the full render of the
 * same frame, with no red carried over. Holes it leaves to pull-push get some card colour bled
 * across the edge by the interpolation, as without reprojection; that is reported. The same
 * run with a heavy history and no depth rejection shows what a ghost looks like here, so the
 * test can tell. */
static void test_no_ghost_on_disocclusion(void **st)
{
    (void)st;
    fv_scene *s = fv_scene_create();
    assert_non_null(s);
    const float wall[3] = {0.1f, 0.6f, 0.3f}, card[3] = {1.0f, 0.05f, 0.05f};
    fv_test_add_quad(s, -30, -30, 30, 30, -5.0f, wall, -1);
    fv_test_add_quad(s, -0.25f, -0.6f, 0.25f, 0.6f, -1.0f, card, -1);
    add_sun(s);
    char err[256];
    assert_int_equal(fv_scene_commit(s, err, sizeof err), 0);
    const int W = 240, H = 270;
    enum { TAA, HEAVY, GHOST, OFF, FULL, N };
    fv_pipeline *p[N] = {make_pipeline(s, W, H, 70.0f, 0, 1), make_pipeline_taa(s, W, H, 70.0f, 0, 1, 0.03f, 0.02f),
                         make_pipeline_taa(s, W, H, 70.0f, 0, 1, 10.0f, 0.02f), make_pipeline(s, W, H, 70.0f, 0, 0),
                         make_pipeline(s, W, H, 70.0f, 1, 0)};
    /* gaze off to the corner: the card is in the sparsely sampled periphery */
    const float gx = 0.05f, gy = 0.05f;
    float *was_card = calloc((size_t)W * H, sizeof(float));
    assert_non_null(was_card);
    long uncovered = 0, written[OFF + 1] = {0}, ghost_px[OFF + 1] = {0};
    double red_written[OFF + 1] = {0}, red_all[OFF + 1] = {0};
    for (int f = 0; f < 30; f++) {
        fv_pose pose = {{0.02f * (float)(f / 6), 0, 0}, {0, 0, 0, 1}}; /* 2 cm to the right every 6 frames */
        for (int k = 0; k < N; k++)
            render(p[k], &pose, gx, gy);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const float *r = px_at(p[FULL], x, y);
                const int is_card = r[3] < 2.0f;
                if (f % 6 == 0 && f > 0 && !is_card && was_card[(size_t)y * W + x] > 0.0f) {
                    for (int k = 0; k <= OFF; k++) { /* red excess over the true wall colour */
                        const fv_pyr_level *l0 = &fv_pipeline_pyramid(p[k], FV_EYE_CENTER)->lv[0];
                        double e = px_at(p[k], x, y)[0] - r[0];
                        e = e > 0 ? e : 0;
                        red_all[k] += e;
                        if (l0->wgt[(ptrdiff_t)y * l0->stride + x] > 0.0f) {
                            red_written[k] += e;
                            written[k]++;
                            ghost_px[k] += e > 0.05;
                        }
                    }
                    uncovered++;
                }
                was_card[(size_t)y * W + x] = (float)is_card;
            }
    }
    static const char *name[] = {"reprojection", "heavy history", "heavy, no depth rejection", "none"};
    printf("uncovered wall: %ld pixel-frames\n", uncovered);
    for (int k = 0; k <= OFF; k++)
        printf("  %-26s: %5ld written by samples/history, mean red excess there %.4f (%ld above 0.05); "
               "all uncovered pixels %.4f\n", name[k], written[k], written[k] ? red_written[k] / written[k] : 0.0,
               ghost_px[k], red_all[k] / uncovered);
    assert_true(uncovered > 1000);
    for (int k = TAA; k <= HEAVY; k++) {
        assert_true(written[k] > written[OFF]);        /* history filled some of them */
        assert_true(red_written[k] / written[k] < 1e-3); /* and none with card colour */
        assert_true(ghost_px[k] == 0);
    }
    /* a history without depth rejection leaves the card's red there */
    assert_true(red_written[GHOST] / written[GHOST] > 0.1);
    free(was_card);
    for (int k = 0; k < N; k++)
        fv_pipeline_destroy(p[k]);
    fv_scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quat_mul),
        cmocka_unit_test(test_mapping),
        cmocka_unit_test(test_fovea_samples_untouched),
        cmocka_unit_test(test_exact_plane_shift),
        cmocka_unit_test(test_static_convergence),
        cmocka_unit_test(test_no_ghost_on_disocclusion),
        cmocka_unit_test(test_still_in_place),
    };
    return cmocka_run_group_tests_name("reproject", tests, NULL, NULL);
}
