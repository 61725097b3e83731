/* The ray stage's yardstick (core/ceiling.c) casts exactly the rays of the real stage: the same
 * count and the same first-hit distances, for every pixel and for a sampler's set. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include <cmocka.h>

#include "ceiling.h"
#include "render_dsp.h"
#include "raycast.h"
#include "testscene.h"
#include "tile.h"

#define W 77 /* not a multiple of the tile: partial tiles on both edges */
#define H 50

static fv_scene *scene_make(void)
{
    fv_scene *s = fv_scene_create();
    assert_non_null(s);
    static const float a[3] = {0.5f, 0.5f, 0.5f}, b[3] = {0.2f, 0.6f, 0.3f};
    fv_test_add_quad(s, -3.0f, -3.0f, 0.5f, 3.0f, -4.0f, a, -1); /* a wall, part of the view misses */
    fv_test_add_quad(s, -0.5f, -0.5f, 0.8f, 0.4f, -1.5f, b, -1); /* a nearer card in front */
    char err[256];
    assert_int_equal(fv_scene_commit(s, err, sizeof err), 0);
    return s;
}

/* the default eye at W x H at the origin */
static void camera_make(fv_camera *cam)
{
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.width = W, d.height = H;
    static const fv_pose origin = {{0, 0, 0}, {0, 0, 0, 1}};
    assert_int_equal(fv_camera_setup(cam, &d, &origin), 0);
}

/* the real stage's level 0 for the same camera, sampler and gaze against the ceiling's depth */
static void check_same_rays(const fv_sampler *smp, int packet)
{
    fv_scene *s = scene_make();
    fv_camera cam;
    camera_make(&cam);
    fv_pool *pool = fv_pool_create(3);
    assert_non_null(pool);
    fv_render_dsp dsp;
    fv_render_dsp_init(&dsp, FV_ISA_C);
    fv_pyramid pyr;
    assert_int_equal(fv_pyramid_init(&pyr, W, H), 0);
    const int gx = 30, gy = 20;
    fv_sampler full; /* the real stage samples every pixel through a full sampler */
    fv_sampling_params fp;
    fv_sampling_params_default(&fp);
    fp.full = 1;
    assert_int_equal(fv_sampler_init(&full, W, H, cam.focal_px, &fp), 0);
    const long real = fv_tile_pass(s, &cam, smp ? smp : &full, gx, gy, &pyr, &dsp, pool, NULL, NULL);
    fv_sampler_free(&full);
    float *depth = malloc(sizeof(float) * W * H);
    assert_non_null(depth);
    for (int i = 0; i < W * H; i++)
        depth[i] = -1.0f; /* untouched marker */
    const fv_ceiling_opts o = {.packet = packet, .smp = smp, .gx = gx, .gy = gy, .phase = 0};
    const long bare = fv_ceiling_trace(s, &cam, pool, &o, depth);
    assert_int_equal(bare, real);
    long hits = 0, misses = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const fv_pyr_level *l0 = &pyr.lv[0];
            const float w = l0->wgt[y * l0->stride + x], z = l0->rgbd[4 * (y * l0->stride + x) + 3];
            const float c = depth[y * W + x];
            if (w == 0.0f) { /* not sampled: the ceiling traced no ray there either */
                assert_float_equal(c, -1.0f, 0.0f);
                continue;
            }
            if (isinf(c)) {
                assert_float_equal(z, FV_DEPTH_MISS_M, 0.0f);
                misses++;
            } else {
                assert_float_equal(c, z, 0.0f); /* the same ray: the same bits */
                hits++;
            }
        }
    assert_true(hits > 0 && misses > 0);
    if (!smp)
        assert_int_equal(real, W * H);
    free(depth);
    fv_pyramid_free(&pyr);
    fv_pool_destroy(pool);
    fv_scene_free(s);
}

static void test_full_frame_16(void **state)
{
    (void)state;
    check_same_rays(NULL, 16);
}

static void test_full_frame_8(void **state)
{
    (void)state;
    check_same_rays(NULL, 8);
}

static void test_sampled(void **state)
{
    (void)state;
    fv_sampling_params p;
    fv_sampling_params_default(&p);
    p.r0_deg = 5.0f, p.r1_deg = 12.0f, p.p_min = 0.3f;
    fv_camera cam;
    camera_make(&cam);
    fv_sampler smp;
    assert_int_equal(fv_sampler_init(&smp, W, H, cam.focal_px, &p), 0);
    check_same_rays(&smp, 16);
    check_same_rays(&smp, 8);
    fv_sampler_free(&smp);
}

/* One tile cast on this thread from two eye positions in turn (the packets' fixed lanes, the
 * origin among them, are kept per thread between tiles): each time the depths are the bare
 * rays' from that eye; a tile without rays shades nothing, a tile with hits adds shading time. */
static void test_tile_moves_eye(void **state)
{
    (void)state;
    fv_scene *s = scene_make();
    fv_pool *pool = fv_pool_create(1);
    assert_non_null(pool);
    fv_render_dsp dsp;
    fv_render_dsp_init(&dsp, FV_ISA_C);
    fv_pyramid pyr;
    assert_int_equal(fv_pyramid_init(&pyr, W, H), 0);
    float *depth = malloc(sizeof(float) * W * H);
    assert_non_null(depth);
    uint32_t rows[FV_TILE], none[FV_TILE] = {0};
    for (int y = 0; y < FV_TILE; y++)
        rows[y] = ~0u;
    fv_camera cam0;
    camera_make(&cam0);
    int64_t idle_ns = 0;
    assert_int_equal(fv_raycast_tile(s, &cam0, &dsp, &pyr.lv[0], 16, 16, 16, 16, none, &idle_ns), 0);
    assert_true(idle_ns == 0);
    for (int it = 0; it < 4; it++) {
        fv_camera_desc d;
        fv_camera_desc_default(&d);
        d.width = W, d.height = H;
        const fv_pose eye = {{it & 1 ? 0.7f : -0.2f, it & 1 ? 0.3f : 0.0f, it & 1 ? 0.5f : 0.0f}, {0, 0, 0, 1}};
        fv_camera cam;
        assert_int_equal(fv_camera_setup(&cam, &d, &eye), 0);
        int64_t shade_ns = 0; /* untimed on odd turns: the same image without a clock */
        assert_int_equal(fv_raycast_tile(s, &cam, &dsp, &pyr.lv[0], 16, 16, 16, 16, rows, it & 1 ? NULL : &shade_ns),
                         256);
        assert_true(it & 1 ? shade_ns == 0 : shade_ns > 0);
        const fv_ceiling_opts o = {.packet = 16};
        assert_int_equal(fv_ceiling_trace(s, &cam, pool, &o, depth), W * H);
        int hits = 0;
        for (int y = 16; y < 32; y++)
            for (int x = 16; x < 32; x++) {
                const fv_pyr_level *l0 = &pyr.lv[0];
                const float z = l0->rgbd[4 * (y * l0->stride + x) + 3], c = depth[y * W + x];
                assert_float_equal(z, isinf(c) ? FV_DEPTH_MISS_M : c, 0.0f);
                hits += !isinf(c);
            }
        assert_true(hits > 0);
    }
    free(depth);
    fv_pyramid_free(&pyr);
    fv_pool_destroy(pool);
    fv_scene_free(s);
}

/* A sparse tile's samples land on their own pixels and nowhere else: each sampled pixel holds
 * what the full tile gave it, the others (and the next tile's) keep a sentinel. The rows put
 * (1, 13..15) right before (2, 0) in the packets' pixel order, consecutive offsets across a row
 * end (a write of 4 pixels from one address must not take them for one run), and full rows of 4
 * with hits and misses (the wall ends inside the tile at this eye). */
static void test_sparse_tile_writes(void **state)
{
    (void)state;
    fv_scene *s = scene_make();
    fv_render_dsp dsp;
    fv_render_dsp_init(&dsp, FV_ISA_C);
    fv_pyramid pyr;
    assert_int_equal(fv_pyramid_init(&pyr, W, H), 0);
    fv_camera cam;
    camera_make(&cam);
    const fv_pyr_level *l0 = &pyr.lv[0];
    uint32_t all[FV_TILE], rows[FV_TILE] = {0};
    for (int y = 0; y < FV_TILE; y++)
        all[y] = ~0u;
    rows[1] = 0xe000u | 0x00f0u | 0x0001u; /* x 13-15, 4-7, 0 */
    rows[2] = 0x0001u | 0x0f00u;           /* x 0, 8-11 */
    rows[3] = 0x8000u;
    rows[6] = 0xffffu, rows[7] = 0x5555u, rows[12] = 0x1248u, rows[15] = 0xf00fu;
    for (int x0 = 0; x0 <= 48; x0 += 48) { /* a tile with misses (0) and one on the card and wall */
        const int y0 = 16;
        assert_int_equal(fv_raycast_tile(s, &cam, &dsp, &pyr.lv[0], x0, y0, 16, 16, all, NULL), 256);
        float want[16][16][4];
        for (int y = 0; y < 16; y++)
            for (int x = 0; x < 16; x++)
                for (int c = 0; c < 4; c++)
                    want[y][x][c] = l0->rgbd[4 * ((y0 + y) * l0->stride + x0 + x) + c];
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++)
                for (int c = 0; c < 4; c++)
                    l0->rgbd[4 * (y * l0->stride + x) + c] = -7.0f;
        int n = 0;
        for (int y = 0; y < 16; y++)
            n += __builtin_popcount(rows[y]);
        assert_int_equal(fv_raycast_tile(s, &cam, &dsp, &pyr.lv[0], x0, y0, 16, 16, rows, NULL), n);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const int in = x >= x0 && x < x0 + 16 && y >= y0 && y < y0 + 16 && (rows[y - y0] >> (x - x0) & 1u);
                for (int c = 0; c < 4; c++)
                    assert_float_equal(l0->rgbd[4 * (y * l0->stride + x) + c], in ? want[y - y0][x - x0][c] : -7.0f,
                                       0.0f);
            }
    }
    fv_pyramid_free(&pyr);
    fv_scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_full_frame_16),
        cmocka_unit_test(test_full_frame_8),
        cmocka_unit_test(test_sampled),
        cmocka_unit_test(test_tile_moves_eye),
        cmocka_unit_test(test_sparse_tile_writes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
