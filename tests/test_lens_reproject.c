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
#include "pullpush.h"
#include "sampling.h"
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
 * 2/3 deg) while moving 2 mm sideways a frame, depths 0.7 .. 50 m varying across each tile (the
 * depth the tile is linearised at: fv_taa_lens_tile_depth, as fv_taa_tile_run takes it); the fill's
 * reverse rows likewise. */
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
                /* depth of pixel (x, y): 0.7 .. 50 m, varying within the tile; every pixel a sample */
                float rgbd[FV_TILE * FV_TILE * 4], wgt[FV_TILE * FV_TILE];
                for (int y = 0; y < T; y++)
                    for (int x = 0; x < T; x++) {
                        rgbd[4 * (y * T + x) + 3] = 0.7f + 49.3f * (float)(((x * 7 + y * 3 + tx) % 16)) / 15.0f;
                        wgt[y * T + x] = 1.0f;
                    }
                const fv_pyr_level tile = {T, T, T, rgbd, wgt};
                const float d0 = fv_taa_lens_tile_depth(&tile, 0, 0, T, T);
                assert_true(d0 > 0.7f && d0 < 50.0f);
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
 * lens's (FV_TW_BLOCK_POS_PX + FV_TW_LENS_ERR_PX px: 0.4 px x ~6 levels a pixel) and rounding;
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

/* ---- the reprojection's tiles on an analytic frame ----
 * A plane 3 m ahead whose red channel is a ramp across it (10 per metre of world x: about 0.1 a
 * pixel here), green 1 everywhere, blue 0, seen through the lens from the previous pose: the
 * history (every texel a sample, coarse levels pulled). The current frame turns 2/3 deg and moves
 * 4 mm; two pixels in three are samples of black (the plane's depth from the current pose), the
 * rest holes. fv_taa_tile_run over every tile: a blended sample's history h = (out_r / out_g) (the
 * green history is 1), a filled hole's is its red; both must be the ramp at the pixel's own ray
 * (away from the previous image's edge), in units of the ramp's local slope: blended within 0.05 px
 * (bilinear taps of a ramp the lens curves), filled within the fill's own tolerance (half a pixel
 * per axis: 0.71 px along a diagonal gradient, + FV_TAA_LENS_ERR_PX), the mean as without a lens; with the lens ignored (the pinhole rows
 * on lensed images) the errors are pixels. */
typedef struct {
    double mean_px, worst_px, worst_fill_px;
    long blended, filled;
} tile_run_err;

static float plane_hit(const fv_camera *c, float px, float py, float *ramp)
{
    float d[3];
    fv_camera_ray(c, px, py, d);
    const float t = (-3.0f - c->eye_pos[2]) / d[2]; /* view depth: d has a view-axis component of 1 */
    *ramp = 10.0f * (c->eye_pos[0] + t * d[0]);
    return t;
}

static tile_run_err tile_run_analytic(const fv_camera *cur, const fv_camera *prev, const fv_lens_map *lm)
{
    const int W = cur->width, H = cur->height;
    fv_pyramid hist, pc;
    assert_int_equal(fv_pyramid_init(&hist, W, H), 0);
    assert_int_equal(fv_pyramid_init(&pc, W, H), 0);
    fv_pyr_level *h0 = &hist.lv[0], *c0 = &pc.lv[0];
    for (int y = -1; y <= H; y++)
        for (int x = -1; x <= W; x++) {
            float r;
            const float t = plane_hit(prev, (float)x + 0.5f, (float)y + 0.5f, &r);
            float *o = h0->rgbd + 4 * ((ptrdiff_t)y * h0->stride + x);
            o[0] = r, o[1] = 1.0f, o[2] = 0.0f, o[3] = t;
            h0->wgt[(ptrdiff_t)y * h0->stride + x] = 1.0f;
        }
    fv_pullpush_dsp ppd;
    fv_pullpush_dsp_init(&ppd, ~0u);
    fv_pullpush(&hist, &ppd, NULL);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float r;
            float *o = c0->rgbd + 4 * ((ptrdiff_t)y * c0->stride + x);
            const int smp = (x + y) % 3 != 0;
            o[0] = o[1] = o[2] = 0.0f, o[3] = smp ? plane_hit(cur, (float)x + 0.5f, (float)y + 0.5f, &r) : 0.0f;
            c0->wgt[(ptrdiff_t)y * c0->stride + x] = smp ? 1.0f : 0.0f;
        }
    fv_taa_frame f;
    fv_taa_frame_setup(&f, cur, prev, &hist, 0.03f);
    if (lm)
        fv_taa_frame_set_lens(&f, lm);
    fv_taa_params prm;
    fv_taa_params_default(&prm);
    fv_sampling_params sp;
    fv_sampling_params_default(&sp);
    sp.rotate = 1;
    fv_sampler smp;
    assert_int_equal(fv_sampler_init(&smp, W, H, cur->focal_px, &sp), 0);
    fv_reproject_dsp dsp;
    fv_reproject_dsp_init(&dsp, ~0u);
    for (int ty = 0; ty < H; ty += FV_TILE)
        for (int tx = 0; tx < W; tx += FV_TILE)
            fv_taa_tile_run(&f, &prm, &smp, W / 2, H / 2, c0, &dsp, tx, ty, FV_TILE, FV_TILE);
    tile_run_err e = {0.0, 0.0, 0.0, 0, 0};
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const float *o = c0->rgbd + 4 * ((ptrdiff_t)y * c0->stride + x);
            const float w = c0->wgt[(ptrdiff_t)y * c0->stride + x];
            float r, r1, r2;
            plane_hit(cur, (float)x + 0.5f, (float)y + 0.5f, &r);
            plane_hit(cur, (float)x + 1.5f, (float)y + 0.5f, &r1);
            plane_hit(cur, (float)x + 0.5f, (float)y + 1.5f, &r2);
            const double slope = hypot(r1 - r, r2 - r); /* ramp per pixel here */
            { /* history within a pixel of the previous image's edge reads its edge replicated into
               * the pyramid's border (pull-push's convention): not the mapping's error */
                float d[3], P[3], u, v;
                const float t = plane_hit(cur, (float)x + 0.5f, (float)y + 0.5f, &r);
                fv_camera_ray(cur, (float)x + 0.5f, (float)y + 0.5f, d);
                for (int k = 0; k < 3; k++)
                    P[k] = cur->eye_pos[k] + t * d[k];
                if (fv_camera_project(prev, P, &u, &v) > 0.0f && !(u >= 1.0f && v >= 1.0f && u <= W - 1.0f && v <= H - 1.0f))
                    continue;
            }
            double h;
            if ((x + y) % 3 != 0) {
                if (!(o[1] > 1e-3f)) /* no history (outside the previous image) */
                    continue;
                h = o[0] / o[1], e.blended++;
            } else {
                if (!(w > 0.0f))
                    continue;
                h = o[0], e.filled++;
            }
            const double px = fabs(h - r) / slope;
            e.mean_px += px;
            if ((x + y) % 3 != 0)
                e.worst_px = fmax(e.worst_px, px);
            else
                e.worst_fill_px = fmax(e.worst_fill_px, px);
        }
    e.mean_px /= (double)(e.blended + e.filled);
    fv_sampler_free(&smp);
    fv_pyramid_free(&hist);
    fv_pyramid_free(&pc);
    return e;
}

static void test_tile_run_analytic(void **st)
{
    (void)st;
    fv_lens l;
    example_lens(&l);
    const int W = 640, H = 720;
    fv_pose p0, p1;
    yaw_pose(&p0, 0.0f, 0.0f);
    yaw_pose(&p1, 2.0f / 3.0f, 0.004f);
    fv_camera c0, c1;
    eye_camera(&c0, &l, FV_EYE_LEFT, W, H, &p0);
    eye_camera(&c1, &l, FV_EYE_LEFT, W, H, &p1);
    fv_lens_map lm;
    fv_lens_map_init(&lm, &c1);
    const tile_run_err a = tile_run_analytic(&c1, &c0, &lm), b = tile_run_analytic(&c1, &c0, NULL);
    fv_camera q0, q1; /* the same without a lens: the reprojection's own error on this plane */
    eye_camera(&q0, NULL, FV_EYE_LEFT, W, H, &p0);
    eye_camera(&q1, NULL, FV_EYE_LEFT, W, H, &p1);
    const tile_run_err n = tile_run_analytic(&q1, &q0, NULL);
    const tile_run_err z = tile_run_analytic(&c0, &c0, &lm); /* still: the identity, lens or not */
    printf("still, with the lens: mean %.3f px, worst blended %.3f px, filled %.3f px\n", z.mean_px, z.worst_px, z.worst_fill_px);
    printf("without a lens: mean %.3f px, worst blended %.3f px, filled %.3f px (%ld blended, %ld filled)\n",
           n.mean_px, n.worst_px, n.worst_fill_px, n.blended, n.filled);
    printf("tiles on the analytic plane: with the lens mean %.3f px, worst blended %.3f px, filled %.3f px (%ld "
           "blended, %ld filled); the lens ignored: mean %.3f px, worst %.3f / %.3f px (%ld, %ld)\n", a.mean_px,
           a.worst_px, a.worst_fill_px, a.blended, a.filled, b.mean_px, b.worst_px, b.worst_fill_px, b.blended, b.filled);
    assert_true(a.blended > (long)W * H / 2 && a.filled > (long)W * H / 8);
    assert_true(a.mean_px < n.mean_px + 0.01);
    assert_true(a.worst_px < 0.05);
    assert_true(a.worst_fill_px < 0.7072 + FV_TAA_LENS_ERR_PX);
    assert_true(b.mean_px > 0.3 && b.worst_px > 1.0);
}

/* ---- rendered frames (the range scene) ---- */

static fv_scene *load_range(void)
{
    char err[512];
    fv_scene *s = fv_scene_load("assets/range.glb", err, sizeof err);
    if (!s)
        fail_msg("assets/range.glb: %s (built by make)", err);
    return s;
}

/* full: every pixel traced; taa: reprojection on; l: the lens or NULL */
static fv_pipeline *make_pipeline(const fv_scene *s, int w, int h, const fv_lens *l, int full, int taa, int threads)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    cfg.cam.width = w;
    cfg.cam.height = h;
    cfg.cam.fov_y_deg = 100.0f;
    cfg.cam.lens = l;
    cfg.samp.full = full;
    cfg.taa.enabled = taa;
    /* compared with the pixel-centre full render: the fovea's anti-aliasing converges to the box
     * filter instead (as in test_reproject.c) */
    cfg.taa.fovea_aa = 0;
    cfg.threads = threads;
    char err[256];
    fv_pipeline *p = fv_pipeline_create(s, &cfg, err, sizeof err);
    if (!p)
        fail_msg("pipeline: %s", err);
    return p;
}

static void render(fv_pipeline *p, const fv_pose *pose)
{
    fv_frame_stats st;
    assert_int_equal(fv_pipeline_render(p, FV_EYE_CENTER, pose, 0.5f, 0.5f, &st), 0);
}

/* the lensed view of a pinhole image: lensed pixel p shows the pinhole image at the pixel its ray
 * projects to (bilinear); mask[i] = 1 where that lies inside (1 px margin) */
static void resample_through_lens(const uint8_t *pin, const fv_camera *cp, const fv_camera *cl, uint8_t *out,
                                  uint8_t *mask)
{
    const int W = cl->width, H = cl->height;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float d[3], P[3], u, v;
            fv_camera_ray(cl, (float)x + 0.5f, (float)y + 0.5f, d);
            for (int k = 0; k < 3; k++)
                P[k] = cl->eye_pos[k] + 5.0f * d[k];
            const size_t i = (size_t)y * W + x;
            mask[i] = fv_camera_project(cp, P, &u, &v) > 0.0f && u >= 1.0f && v >= 1.0f && u <= W - 1.0f &&
                      v <= H - 1.0f;
            if (!mask[i]) {
                memset(out + 3 * i, 0, 3);
                continue;
            }
            const float bu = u - 0.5f, bv = v - 0.5f;
            const int x0 = (int)bu, y0 = (int)bv;
            const float fx = bu - (float)x0, fy = bv - (float)y0;
            for (int c = 0; c < 3; c++) {
                const uint8_t *r0 = pin + ((size_t)y0 * W + x0) * 3 + c, *r1 = r0 + (size_t)W * 3;
                const float t = (float)r0[0] + fx * (float)(r0[3] - r0[0]), b = (float)r1[0] + fx * (float)(r1[3] - r1[0]);
                out[3 * i + c] = (uint8_t)lrintf(t + fy * (b - t));
            }
        }
}

/* luma PSNR of b against a over the masked pixels */
static double psnr_mask(const uint8_t *a, const uint8_t *b, const uint8_t *mask, int n)
{
    double se = 0.0;
    long k = 0;
    for (int i = 0; i < n; i++) {
        if (!mask[i])
            continue;
        const double la = 0.2126 * a[3 * i] + 0.7152 * a[3 * i + 1] + 0.0722 * a[3 * i + 2];
        const double lb = 0.2126 * b[3 * i] + 0.7152 * b[3 * i + 1] + 0.0722 * b[3 * i + 2];
        se += (la - lb) * (la - lb), k++;
    }
    return se > 0.0 ? 10.0 * log10(255.0 * 255.0 * (double)k / se) : INFINITY;
}

/* no chromatic aberration (the pinhole path has none to compare with) */
static void plain_lens(fv_lens *l)
{
    static const char text[] = "k1 0.10\nk2 0.02\nleft_center 0.53 0.5\nright_center 0.47 0.5\n";
    char err[256];
    assert_int_equal(fv_lens_parse(l, text, strlen(text), "plain", 3.6f, err, sizeof err), 0);
}

/* A wall 3 m ahead and a card at 1.5 m, both with a smooth texture (sinusoids about 30 pixels a
 * period here: no aliasing for either sampling to disagree about, yet a pixel's misplacement
 * shows), lit by a directional light (the colour of a point does not depend on the eye). */
static fv_scene *smooth_scene(void)
{
    fv_scene *s = fv_scene_create();
    assert_non_null(s);
    enum { T = 1024 };
    uint8_t *t = malloc((size_t)T * T * 4);
    assert_non_null(t);
    for (int y = 0; y < T; y++)
        for (int x = 0; x < T; x++) {
            uint8_t *o = t + 4 * ((size_t)y * T + x);
            o[0] = (uint8_t)lrintf(128.0f + 100.0f * sinf(0.8f * (float)x));
            o[1] = (uint8_t)lrintf(128.0f + 100.0f * sinf(0.7f * (float)y + 0.3f * (float)x));
            o[2] = (uint8_t)lrintf(128.0f + 60.0f * cosf(0.5f * (float)(x + y)));
            o[3] = 255;
        }
    const int tex = fv_scene_add_texture(s, t, T, T);
    free(t);
    assert_true(tex >= 0);
    const float white[3] = {1, 1, 1};
    fv_test_add_quad(s, -40, -40, 40, 40, -3.0f, white, tex);
    fv_test_add_quad(s, -0.8f, -0.6f, 0.2f, 0.9f, -1.5f, white, tex);
    fv_light l;
    memset(&l, 0, sizeof l);
    l.type = FV_LIGHT_DIRECTIONAL;
    l.color[0] = l.color[1] = l.color[2] = 1.0f;
    l.intensity = 1.0f;
    l.dir[2] = -1.0f;
    fv_scene_add_light(s, &l);
    char err[256];
    assert_int_equal(fv_scene_commit(s, err, sizeof err), 0);
    return s;
}

/* The head turns 60 deg/s (2/3 deg a 90 Hz frame) and moves 2 mm a frame sideways for 16 frames,
 * gaze ahead, on the smooth scene. The lensed foveated image with reprojection against the lensless
 * one resampled through the lens: >= 25 dB (measured 27.3; the full renders agree to 41.5 dB, the
 * rest is the two paths' own reprojection errors, which do not coincide). Each against the full
 * render of its own camera (every pixel traced, no history): the lensed one >= 25 dB overall
 * (measured 28.0; the lensless 31.6) and within 1.5 dB of the lensless one at radii 0.3 .. 0.6 of
 * the half height (measured 29.7 and 30.7), where the lens changes the detail per pixel little;
 * farther out the lens packs up to twice the detail into a pixel and the history's resampling
 * loses more (27.0 against 32.8 dB beyond 0.9). The same run with the lens ignored in the mapping
 * (the pinhole rows on the lensed image) fails all three: 25.9 dB, 24.3 dB, 28.6 against 30.7. */
static void test_rendered_vs_resampled(void **st)
{
    (void)st;
    fv_scene *s = smooth_scene();
    fv_lens l;
    plain_lens(&l);
    const int W = 384, H = 432, N = W * H;
    enum { LT, LF, PT, PF, NP };
    fv_pipeline *p[NP] = {make_pipeline(s, W, H, &l, 0, 1, 2), make_pipeline(s, W, H, &l, 1, 0, 2),
                          make_pipeline(s, W, H, NULL, 0, 1, 2), make_pipeline(s, W, H, NULL, 1, 0, 2)};
    uint8_t *img[NP], *rs = malloc((size_t)N * 3), *rsf = malloc((size_t)N * 3), *mask = malloc((size_t)N);
    for (int k = 0; k < NP; k++)
        assert_non_null(img[k] = malloc((size_t)N * 3));
    for (int f = 0; f < 16; f++) {
        const float a = (float)f * (2.0f / 3.0f) * PI_F / 360.0f;
        const fv_pose pose = {{0.002f * (float)f, 0.0f, 0.0f}, {0.0f, sinf(a), 0.0f, cosf(a)}};
        for (int k = 0; k < NP; k++)
            render(p[k], &pose);
    }
    for (int k = 0; k < NP; k++)
        fv_pipeline_to_rgb8(p[k], FV_EYE_CENTER, img[k], (ptrdiff_t)W * 3);
    const fv_camera *cl = fv_pipeline_camera(p[LT], FV_EYE_CENTER), *cp = fv_pipeline_camera(p[PT], FV_EYE_CENTER);
    resample_through_lens(img[PT], cp, cl, rs, mask);
    resample_through_lens(img[PF], cp, cl, rsf, mask);
    long inside = 0;
    for (int i = 0; i < N; i++)
        inside += mask[i];
    const double taa = psnr_mask(rs, img[LT], mask, N), full = psnr_mask(rsf, img[LF], mask, N);
    uint8_t *all = malloc((size_t)N);
    memset(all, 1, (size_t)N);
    const double q_lens = psnr_mask(img[LF], img[LT], all, N), q_pin = psnr_mask(img[PF], img[PT], all, N);
    printf("turning 60 deg/s, frame 16, %.0f %% of the lensed image inside the lensless one:\n"
           "  lens + reprojection vs lensless + reprojection resampled through the lens %.2f dB (the full renders: %.2f dB)\n"
           "  against their own full render: with the lens %.2f dB, without %.2f dB\n",
           100.0 * inside / N, taa, full, q_lens, q_pin);
    /* by radius from the image centre (a fraction of the half height): the lens packs more of the
     * scene into a pixel the farther out (J_F ~1.2 at 0.6, ~1.5 at 0.9, ~2 in the corners), where
     * the history's resampling then loses more; near the centre the two must agree */
    static const float rr[5] = {0.0f, 0.3f, 0.6f, 0.9f, 2.0f};
    double ring[4][2];
    for (int b = 0; b < 4; b++) {
        for (int i = 0; i < N; i++) {
            const float dx = (float)(i % W) + 0.5f - 0.5f * W, dy = (float)(i / W) + 0.5f - 0.5f * H;
            const float r = sqrtf(dx * dx + dy * dy) / (0.5f * H);
            all[i] = r >= rr[b] && r < rr[b + 1];
        }
        ring[b][0] = psnr_mask(img[LF], img[LT], all, N), ring[b][1] = psnr_mask(img[PF], img[PT], all, N);
        printf("  r %.1f .. %.1f: with the lens %.2f dB, without %.2f dB\n", (double)rr[b], (double)rr[b + 1],
               ring[b][0], ring[b][1]);
    }
    assert_true(inside > N / 2);
    assert_true(ring[1][0] >= ring[1][1] - 1.5);
    assert_true(q_lens >= 25.0);
    assert_true(taa >= 25.0);
    for (int k = 0; k < NP; k++) {
        free(img[k]);
        fv_pipeline_destroy(p[k]);
    }
    free(rs);
    free(rsf);
    free(mask);
    free(all);
    fv_scene_free(s);
}

/* A still head and gaze: with the lens the foveated image converges to the lensed full render as
 * the lensless one converges to its full render (the identity frame: pixel to the same pixel). */
static void test_still_head_converges(void **st)
{
    (void)st;
    fv_scene *s = load_range();
    fv_lens l;
    example_lens(&l);
    const int W = 256, H = 288, N = W * H;
    fv_pose view;
    fv_scene_default_view(s, 100.0f, (float)W / H, view.pos, view.quat);
    double first[2], last[2];
    uint8_t *ref = malloc((size_t)N * 3), *img = malloc((size_t)N * 3), *all = malloc((size_t)N);
    memset(all, 1, (size_t)N);
    for (int k = 0; k < 2; k++) {
        fv_pipeline *full = make_pipeline(s, W, H, k ? &l : NULL, 1, 0, 2), *taa = make_pipeline(s, W, H, k ? &l : NULL, 0, 1, 2);
        render(full, &view);
        fv_pipeline_to_rgb8(full, FV_EYE_CENTER, ref, (ptrdiff_t)W * 3);
        double prev = 0.0;
        for (int f = 0; f < 30; f++) {
            render(taa, &view);
            fv_pipeline_to_rgb8(taa, FV_EYE_CENTER, img, (ptrdiff_t)W * 3);
            const double q = psnr_mask(ref, img, all, N);
            if (f == 0)
                first[k] = q;
            else
                assert_true(q >= prev - 0.05); /* never gets worse while it converges */
            prev = last[k] = q;
        }
        fv_pipeline_destroy(full);
        fv_pipeline_destroy(taa);
    }
    printf("still head against the full render: without the lens %.2f -> %.2f dB, with it %.2f -> %.2f dB\n", first[0],
           last[0], first[1], last[1]);
    assert_true(last[1] > first[1] + 12.0);
    assert_true(last[1] - first[1] >= last[0] - first[0] - 2.0);
    free(ref);
    free(img);
    free(all);
    fv_scene_free(s);
}

/* Lens + reprojection, stereo, the head turning and moving: the same bytes with 1, 2 and 5 threads. */
static void test_threads(void **st)
{
    (void)st;
    fv_scene *s = load_range();
    fv_lens l;
    example_lens(&l);
    const int W = 128, H = 144;
    uint8_t *img[3][2];
    static const int threads[3] = {1, 2, 5};
    fv_pose view;
    fv_scene_default_view(s, 100.0f, (float)W / H, view.pos, view.quat);
    for (int t = 0; t < 3; t++) {
        fv_pipeline *p = make_pipeline(s, W, H, &l, 0, 1, threads[t]);
        for (int f = 0; f < 6; f++) {
            fv_pose pose = view;
            const float a = (float)f * PI_F / 360.0f, q[4] = {0.0f, sinf(a), 0.0f, cosf(a)};
            fv_quat_mul(q, view.quat, pose.quat);
            pose.pos[0] += 0.003f * (float)f;
            fv_frame_stats fs[2];
            assert_int_equal(fv_pipeline_render_stereo(p, &pose, 0.4f, 0.6f, fs), 0);
        }
        for (int e = 0; e < 2; e++) {
            img[t][e] = malloc((size_t)W * H * 3);
            fv_pipeline_to_rgb8(p, e ? FV_EYE_RIGHT : FV_EYE_LEFT, img[t][e], (ptrdiff_t)W * 3);
        }
        fv_pipeline_destroy(p);
    }
    for (int t = 1; t < 3; t++)
        for (int e = 0; e < 2; e++)
            assert_memory_equal(img[0][e], img[t][e], (size_t)W * H * 3);
    for (int t = 0; t < 3; t++)
        for (int e = 0; e < 2; e++)
            free(img[t][e]);
    fv_scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_map_round_trip),
        cmocka_unit_test(test_tile_map),
        cmocka_unit_test(test_tile_run_analytic),
        cmocka_unit_test(test_timewarp_cell_map),
        cmocka_unit_test(test_timewarp_rotation),
        cmocka_unit_test(test_rendered_vs_resampled),
        cmocka_unit_test(test_still_head_converges),
        cmocka_unit_test(test_threads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
