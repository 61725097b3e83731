/* Lens distortion with reprojection and the timewarp (issue 16 item 3): the lens in pixel units
 * (fv_lens_map) against the camera's rays and its Newton inverse, the reprojection's per-tile
 * linearisation against the exact per-pixel map, and rendered frames: lens + reprojection
 * against the lensless path resampled through the lens, a still head converging as without a
 * lens, the same bytes for 1, 2 and 5 threads. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "testscene.h"
#include "camera.h"
#include "lens.h"
#include "metrics.h"
#include "pipeline.h"
#include "reproject.h"
#include "scene.h"
#include "tile.h"

#define PI_F 3.14159265358979f

/* the example profile (assets/hmd_example.lens) */
static void example_lens(fv_lens *l)
{
    static const char text[] = "k1 0.10\nk2 0.02\nchroma 0.994 1.0 1.008\nleft_center 0.53 0.5\nright_center 0.47 0.5\n";
    char err[256];
    assert_int_equal(fv_lens_parse(l, text, strlen(text), "example", 3.6f, err, sizeof err), 0);
}

static void eye_camera(fv_camera *c, const fv_lens *l, fv_eye eye, int w, int h, const fv_pose *head)
{
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.width = w, d.height = h, d.eye = eye, d.lens = l;
    assert_int_equal(fv_camera_setup(c, &d, head), 0);
}

/* yaw by deg about +Y */
static void yaw_pose(fv_pose *p, float deg, float x)
{
    const float a = deg * PI_F / 360.0f;
    *p = (fv_pose){{x, 1.6f, 0.0f}, {0.0f, sinf(a), 0.0f, cosf(a)}};
}

/* F is fv_camera_ray's mapping in pixel units; F^-1(F(p)) = p over every pixel centre of both
 * eyes of a 1280 x 1440 panel within FV_LENS_MAP_ERR_PX; F^-1 agrees with the camera's projection
 * (its double-precision Newton inverse) on points seen off the panel too. */
static void test_map_round_trip(void **st)
{
    (void)st;
    fv_lens l;
    example_lens(&l);
    const fv_pose head = {{0, 0, 0}, {0, 0, 0, 1}};
    for (int e = 0; e < 2; e++) {
        fv_camera c;
        eye_camera(&c, &l, e ? FV_EYE_RIGHT : FV_EYE_LEFT, 1280, 1440, &head);
        fv_lens_map m;
        assert_int_equal(fv_lens_map_init(&m, &c), 0);
        double worst_rt = 0.0, worst_fwd = 0.0, worst_proj = 0.0;
        for (int y = 0; y < c.height; y++)
            for (int x = 0; x < c.width; x++) {
                const float px = (float)x + 0.5f, py = (float)y + 0.5f;
                float qx, qy, bx, by;
                fv_lens_map_fwd(&m, px, py, &qx, &qy);
                if ((x % 7) == 0 && (y % 7) == 0) { /* the ray through p is the pinhole ray of q */
                    float dir[3];
                    fv_camera_ray(&c, px, py, dir); /* head at identity: right = x, up = y, back = z */
                    const double ex = (dir[0] - c.tan_left) / c.px_tan, ey = (c.tan_top - dir[1]) / c.px_tan;
                    worst_fwd = fmax(worst_fwd, fmax(fabs(ex - qx), fabs(ey - qy)));
                    const float P[3] = {c.eye_pos[0] + 3.0f * dir[0], c.eye_pos[1] + 3.0f * dir[1], c.eye_pos[2] + 3.0f * dir[2]};
                    float u, v;
                    assert_true(fv_camera_project(&c, P, &u, &v) > 0.0f);
                    assert_int_equal(fv_lens_map_inv(&m, qx, qy, &bx, &by), 0);
                    worst_proj = fmax(worst_proj, fmax(fabs(bx - u), fabs(by - v)));
                }
                assert_int_equal(fv_lens_map_inv(&m, qx, qy, &bx, &by), 0);
                worst_rt = fmax(worst_rt, fmax(fabs(bx - px), fabs(by - py)));
            }
        printf("eye %d: F vs the camera's rays %.2e px, F^-1(F(p)) - p %.2e px, F^-1 vs the camera's projection "
               "%.2e px\n", e, worst_fwd, worst_rt, worst_proj);
        assert_true(worst_fwd < 0.01);
        assert_true(worst_rt <= FV_LENS_MAP_ERR_PX);
        assert_true(worst_proj < 0.01);
        /* beyond the table: flagged, and pushed outside the image */
        float bx, by;
        assert_int_equal(fv_lens_map_inv(&m, m.cx + 20000.0f, m.cy, &bx, &by), 1);
        assert_true(bx > (float)c.width);
    }
}

/* The kernels' form of a frame's map, (U, V, Z) = T + d (M0 + px MX + py MY), in the kernels'
 * operation order (reproject_tmpl.h) */
static float rows_project(const float T[3], const float M0[3], const float MX[3], const float MY[3], float px,
                          float py, float d, float *u, float *v)
{
    const float b0 = M0[0] + py * MY[0], b1 = M0[1] + py * MY[1], b2 = M0[2] + py * MY[2];
    const float U = T[0] + d * (b0 + px * MX[0]), V = T[1] + d * (b1 + px * MX[1]);
    const float Z = T[2] + d * (b2 + px * MX[2]);
    const float rz = 1.0f / Z;
    *u = U * rz, *v = V * rz;
    return Z;
}

/* The per-tile linearisation (what the kernels get) against the exact map through F and F^-1, at
 * every pixel of a 1280 x 1440 eye, for a head turning 30 deg/s (one and two 90 Hz frames: 1/3 and
 * 2/3 deg) while moving 2 mm sideways a frame, depths 0.7 .. 50 m varying across each tile (the tile's linearisation
 * depth: their harmonic mean, as fv_taa_tile_run takes it); the fill's reverse rows likewise. */
static void test_tile_map(void **st)
{
    (void)st;
    fv_lens l;
    example_lens(&l);
    const int W = 1280, H = 1440, T = FV_TILE;
    fv_pyramid none;
    memset(&none, 0, sizeof none);
    none.levels = 1;
    static const float turn[][2] = {{1.0f / 3.0f, 0.002f}, {2.0f / 3.0f, 0.004f}, {-1.0f / 3.0f, 0.0f}};
    for (int k = 0; k < 3; k++) {
        fv_pose ph, ch;
        yaw_pose(&ph, 10.0f, 0.0f);
        yaw_pose(&ch, 10.0f + turn[k][0], turn[k][1]);
        fv_camera cur, prev;
        eye_camera(&cur, &l, FV_EYE_LEFT, W, H, &ch);
        eye_camera(&prev, &l, FV_EYE_LEFT, W, H, &ph);
        fv_lens_map m;
        fv_lens_map_init(&m, &cur);
        fv_taa_frame f;
        fv_taa_frame_setup(&f, &cur, &prev, &none, 0.03f);
        fv_taa_frame_set_lens(&f, &m);
        assert_ptr_equal(f.lens, &m);
        double worst = 0.0, worst_fill = 0.0, mean_move = 0.0;
        long n = 0;
        for (int ty = 0; ty < H; ty += T)
            for (int tx = 0; tx < W; tx += T) {
                const float cx = (float)tx + 0.5f * T, cy = (float)ty + 0.5f * T;
                /* depth of pixel (x, y): 0.7 .. 50 m, varying within the tile */
                float si = 0.0f;
                for (int y = 0; y < T; y++)
                    for (int x = 0; x < T; x++)
                        si += 1.0f / (0.7f + 49.3f * (float)(((x * 7 + y * 3 + tx) % 16)) / 15.0f);
                const float d0 = (float)(T * T) / si;
                fv_taa_frame t;
                fv_taa_lens_tile_blend(&f, &t, cx, cy, d0);
                float u0, v0;
                const float z0 = fv_taa_project(&f, cx, cy, d0, &u0, &v0);
                const int fx = (int)floorf(u0 - cx + 0.5f), fy = (int)floorf(v0 - cy + 0.5f);
                fv_taa_lens_tile_fill(&f, &t, cx + (float)fx, cy + (float)fy, z0);
                for (int y = 0; y < T; y++)
                    for (int x = 0; x < T; x++) {
                        const float px = (float)(tx + x) + 0.5f, py = (float)(ty + y) + 0.5f;
                        const float d = 0.7f + 49.3f * (float)(((x * 7 + y * 3 + tx) % 16)) / 15.0f;
                        float ue, ve, ut, vt;
                        const float ze = fv_taa_project(&f, px, py, d, &ue, &ve);
                        const float zt = rows_project(t.T, t.M0, t.MX, t.MY, px, py, d, &ut, &vt);
                        assert_true(ze > 0.0f);
                        assert_float_equal(zt, ze, 1e-4f * ze);
                        if (!(ue >= 0.0f && ue < (float)W && ve >= 0.0f && ve < (float)H))
                            continue; /* outside the previous image: the kernels drop it either way */
                        worst = fmax(worst, fmax(fabs(ut - ue), fabs(vt - ve)));
                        mean_move += hypot(ue - px, ve - py), n++;
                        /* the fill: a history texel at (px, py) + flow maps back to this frame */
                        const float hx = px + (float)fx, hy = py + (float)fy;
                        if (!(hx > 0.0f && hx < (float)W && hy > 0.0f && hy < (float)H))
                            continue;
                        fv_taa_frame back; /* the exact reverse map: the frame from prev to cur */
                        fv_taa_frame_setup(&back, &prev, &cur, &none, 0.03f);
                        fv_taa_frame_set_lens(&back, &m);
                        float ub, vb, uf, vf;
                        const float zb = fv_taa_project(&back, hx, hy, ze, &ub, &vb);
                        const float zf = rows_project(t.T2, t.N0, t.NX, t.NY, hx, hy, ze, &uf, &vf);
                        assert_float_equal(zf, zb, 1e-4f * zb);
                        worst_fill = fmax(worst_fill, fmax(fabs(uf - ub), fabs(vf - vb)));
                    }
            }
        printf("turn %.3f deg, move %.0f mm: mean motion %.2f px; tile map vs exact: blend %.4f px, fill %.4f px\n",
               (double)turn[k][0], 1000.0 * turn[k][1], mean_move / (double)n, worst, worst_fill);
        assert_true(worst <= FV_TAA_LENS_ERR_PX);
        assert_true(worst_fill <= FV_TAA_LENS_ERR_PX);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_map_round_trip),
        cmocka_unit_test(test_tile_map),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
