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
#include "timewarp.h"

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

/* The timewarp's per-cell maps (what the block planner and the kernels get) against the exact
 * lens map at every display pixel: the source pixel F^-1(H(F(p), w)) from the cameras themselves
 * (the display pixel's lensed ray, the point at its depth, projected into the source camera through
 * its double-precision inverse), for the head turning 30 deg/s one and two 90 Hz refreshes and
 * moving 2 mm a refresh, depths 0.7 .. 50 m varying pixel to pixel (the source's depth plane is
 * that depth field seen from the source, so a cell's linearisation depth comes from it). */
static void test_timewarp_cell_map(void **st)
{
    (void)st;
    fv_lens l;
    example_lens(&l);
    const int W = 1280, H = 1440;
    uint16_t *invd = calloc((size_t)W * H + FV_TW_INVD_PAD, sizeof *invd);
    uint8_t *rgb = calloc((size_t)W * H * 3 + FV_TW_RGB_PAD, 1);
    assert_non_null(invd);
    assert_non_null(rgb);
    static const float turn[][2] = {{1.0f / 3.0f, 0.002f}, {2.0f / 3.0f, 0.004f}, {-2.0f / 3.0f, 0.0f}};
    for (int k = 0; k < 3; k++) {
        fv_pose p0, p1;
        yaw_pose(&p0, 10.0f, 0.0f);
        yaw_pose(&p1, 10.0f + turn[k][0], turn[k][1]);
        fv_camera c0, c1;
        eye_camera(&c0, &l, FV_EYE_RIGHT, W, H, &p0);
        eye_camera(&c1, &l, FV_EYE_RIGHT, W, H, &p1);
        fv_lens_map lm;
        fv_lens_map_init(&lm, &c0);
        /* a smooth depth field over the source: 0.7 .. 50 m */
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const float dm = 0.7f + 49.3f * 0.5f * (1.0f + sinf(0.01f * (float)x + 0.013f * (float)y));
                invd[(size_t)y * W + x] = (uint16_t)lrintf(FV_TW_INVD_PER_M / dm);
            }
        const fv_tw_src src = {rgb, (ptrdiff_t)W * 3, invd, W, W, H};
        fv_tw_map m;
        fv_tw_setup(&m, &c1, &c0, 0.05f);
        fv_tw_map_set_lens(&m, &lm);
        double worst = 0.0;
        long n = 0;
        const int C = FV_TW_LENS_CELL;
        for (int cy = 0; cy < H; cy += C)
            for (int cx = 0; cx < W; cx += C) {
                fv_tw_map cm;
                fv_tw_cell_map(&m, &src, cx, cx + C < W ? cx + C : W, cy, cy + C < H ? cy + C : H, &cm);
                assert_null(cm.lens);
                for (int y = cy; y < cy + C && y < H; y++)
                    for (int x = cx; x < cx + C && x < W; x++) {
                        const float px = (float)x + 0.5f, py = (float)y + 0.5f;
                        /* depth of this display pixel: the field at the pixel (any depth will do) */
                        const float dm = 0.7f + 49.3f * 0.5f * (1.0f + sinf(0.01f * (float)x + 0.013f * (float)y));
                        float d[3], P[3], ue, ve;
                        fv_camera_ray(&c1, px, py, d);
                        for (int i = 0; i < 3; i++)
                            P[i] = c1.eye_pos[i] + dm * d[i];
                        if (!(fv_camera_project(&c0, P, &ue, &ve) > 0.0f) || !(ue >= 0.0f && ue < W && ve >= 0.0f && ve < H))
                            continue;
                        const float A[3] = {(cm.a0[0] + py * cm.ay[0]) + px * cm.ax[0],
                                            (cm.a0[1] + py * cm.ay[1]) + px * cm.ax[1],
                                            (cm.a0[2] + py * cm.ay[2]) + px * cm.ax[2]};
                        float u, v;
                        fv_tw_proj(A, cm.t, 1.0f / dm, &u, &v);
                        worst = fmax(worst, fmax(fabs(u - ue), fabs(v - ve)));
                        n++;
                    }
            }
        printf("timewarp, turn %.3f deg, move %.0f mm: cell map vs exact over %ld pixels: %.4f px\n",
               (double)turn[k][0], 1000.0 * turn[k][1], n, worst);
        assert_true(n > (long)W * H / 2);
        assert_true(worst <= FV_TW_LENS_ERR_PX);
    }
    free(invd);
    free(rgb);
}

/* a smooth but steep colour of a world direction (about 6 levels a pixel at 1280 x 1440 and
 * 100 deg), so a tap a third of a pixel off shows */
static void dir_colour(const float d[3], uint8_t rgb[3])
{
    const float n = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const float az = atan2f(d[0], -d[2]), el = asinf(d[1] / n);
    rgb[0] = (uint8_t)lrintf(128.0f + 100.0f * sinf(40.0f * az));
    rgb[1] = (uint8_t)lrintf(128.0f + 100.0f * cosf(37.0f * el));
    rgb[2] = (uint8_t)lrintf(128.0f + 80.0f * sinf(3.0f * az + 2.0f * el));
}

static void render_dirs(uint8_t *rgb, const fv_camera *c)
{
    for (int y = 0; y < c->height; y++)
        for (int x = 0; x < c->width; x++) {
            float d[3];
            fv_camera_ray(c, (float)x + 0.5f, (float)y + 0.5f, d);
            dir_colour(d, rgb + ((size_t)y * c->width + x) * 3);
        }
}

/* Pure rotation through the lens: the warped image equals the image rendered at the rotated
 * camera (each display pixel's own lensed ray), within the block warp's position bound plus the
 * lens's (FV_TW_BLOCK_POS_PX + FV_TW_LENS_ERR_PX px: 0.35 px x ~6 levels a pixel) and rounding;
 * the same warp ignoring the lens (a pinhole warp of the lensed image) is far off. Both eyes,
 * every ISA's kernels give the same bytes. */
static void test_timewarp_rotation(void **st)
{
    (void)st;
    fv_lens l;
    example_lens(&l);
    const int W = 1280, H = 1440;
    uint8_t *src = calloc((size_t)W * H * 3 + FV_TW_RGB_PAD, 1), *want = malloc((size_t)W * H * 3);
    uint8_t *out = malloc((size_t)W * H * 3), *out_c = malloc((size_t)W * H * 3);
    uint16_t *invd = calloc((size_t)W * H + FV_TW_INVD_PAD, sizeof *invd);
    assert_true(src && want && out && out_c && invd);
    for (int i = 0; i < W * H; i++)
        invd[i] = (uint16_t)(FV_TW_INVD_PER_M / (0.5f + (float)(i % 7))); /* depth must not matter */
    fv_timewarp_dsp dc, db;
    fv_timewarp_dsp_init(&dc, FV_ISA_C);
    fv_timewarp_dsp_init(&db, ~0u);
    for (int e = 0; e < 2; e++) {
        /* 2/3 deg about a tilted axis (two refreshes at 30 deg/s... and some pitch and roll) */
        const float a = (2.0f / 3.0f) * PI_F / 360.0f, ax[3] = {0.3f, 0.9f, 0.1f}, an = sqrtf(0.91f);
        fv_pose p0 = {{0.0f, 1.6f, 0.0f}, {0, 0, 0, 1}};
        fv_pose p1 = {{0.0f, 1.6f, 0.0f}, {ax[0] / an * sinf(a), ax[1] / an * sinf(a), ax[2] / an * sinf(a), cosf(a)}};
        /* a pure rotation of the head moves the eyes (IPD / 2 from its centre): rotate each eye
         * about itself instead, so the warp is a rotation of the image */
        fv_camera c0, c1;
        eye_camera(&c0, &l, e ? FV_EYE_RIGHT : FV_EYE_LEFT, W, H, &p0);
        eye_camera(&c1, &l, e ? FV_EYE_RIGHT : FV_EYE_LEFT, W, H, &p1);
        memcpy(c1.eye_pos, c0.eye_pos, sizeof c0.eye_pos);
        render_dirs(src, &c0);
        render_dirs(want, &c1);
        fv_lens_map lm;
        fv_lens_map_init(&lm, &c0);
        const fv_tw_src s = {src, (ptrdiff_t)W * 3, invd, W, W, H};
        fv_tw_map m;
        fv_tw_setup(&m, &c1, &c0, 0.05f);
        fv_tw_map_set_lens(&m, &lm);
        assert_int_equal(fv_tw_warp_rows(&dc, out_c, (ptrdiff_t)W * 3, 0, H, &m, &s, NULL), 0);
        fv_tw_tiles tl;
        const int tw = (W + FV_TW_TILE - 1) / FV_TW_TILE, th = (H + FV_TW_TILE - 1) / FV_TW_TILE;
        tl.lohi = malloc(2 * (size_t)tw * th * sizeof(uint16_t));
        tl.lohi4 = malloc(2 * (size_t)((tw + 3) / 4) * ((th + 3) / 4) * sizeof(uint16_t));
        fv_tw_tiles_build(&db, &tl, &s);
        fv_tw_warp_rows(&db, out, (ptrdiff_t)W * 3, 0, H, &m, &s, &tl);
        assert_memory_equal(out, out_c, (size_t)W * H * 3); /* the kernels' bytes on any ISA */
        int maxd = 0, maxd_pinhole = 0;
        long checked = 0;
        uint8_t *pin = malloc((size_t)W * H * 3);
        assert_non_null(pin);
        fv_tw_map mp;
        fv_tw_setup(&mp, &c1, &c0, 0.05f); /* the lens ignored */
        fv_tw_warp_rows(&dc, pin, (ptrdiff_t)W * 3, 0, H, &mp, &s, NULL);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                float d[3], P[3], u, v;
                fv_camera_ray(&c1, (float)x + 0.5f, (float)y + 0.5f, d);
                for (int k = 0; k < 3; k++)
                    P[k] = c1.eye_pos[k] + d[k];
                if (!(fv_camera_project(&c0, P, &u, &v) > 0.0f) || u < 2 || v < 2 || u > W - 2 || v > H - 2)
                    continue;
                checked++;
                for (int k = 0; k < 3; k++) {
                    const size_t i = ((size_t)y * W + x) * 3 + k;
                    const int ed = abs((int)out[i] - (int)want[i]), ep = abs((int)pin[i] - (int)want[i]);
                    maxd = ed > maxd ? ed : maxd;
                    maxd_pinhole = ep > maxd_pinhole ? ep : maxd_pinhole;
                }
            }
        printf("eye %d: rotation through the lens, max error %d levels over %ld pixels (ignoring the lens: %d)\n", e,
               maxd, checked, maxd_pinhole);
        assert_true(checked > (long)W * H * 3 / 4);
        assert_true(maxd <= 4);
        assert_true(maxd_pinhole > 12);
        free(pin);
        free(tl.lohi);
        free(tl.lohi4);
    }
    free(src);
    free(want);
    free(out);
    free(out_c);
    free(invd);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_map_round_trip),
        cmocka_unit_test(test_tile_map),
        cmocka_unit_test(test_timewarp_cell_map),
        cmocka_unit_test(test_timewarp_rotation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
