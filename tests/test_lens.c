/* Lens profiles: parsing from memory (core/lens.c) and its errors, the file loader
 * (platform/lensfile.c); the distortion against its formula, its inverse, and the camera's rays
 * and projection with and without a lens. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "camera.h"
#include "lens.h"
#include "lensfile.h"
#include "testutil.h"

static int parse(fv_lens *l, const char *text, const char *name, char *err, size_t err_len)
{
    return fv_lens_parse(l, text, strlen(text), name, 2.0f, err, err_len);
}

static void test_parse(void **st)
{
    (void)st;
    fv_lens l;
    char err[256];
    assert_int_equal(parse(&l,
                           "# test HMD\n\nk1 0.12\nk2 0.03 # comment\r\nchroma 0.99 1.0 1.01\n"
                           "left_center 0.53 0.48\n  right_center\t0.47 0.52\n",
                           "p.txt", err, sizeof err),
                     0);
    assert_float_equal(l.k1, 0.12f, 0);
    assert_float_equal(l.k2, 0.03f, 0);
    assert_float_equal(l.scale[0], 0.99f, 0);
    assert_float_equal(l.scale[2], 1.01f, 0);
    assert_float_equal(l.center[0][0], 0.53f, 0);
    assert_float_equal(l.center[1][1], 0.52f, 0);
    /* empty: no distortion */
    assert_int_equal(parse(&l, "# nothing\n", "e.txt", err, sizeof err), 0);
    assert_float_equal(l.k1, 0.0f, 0);
    assert_float_equal(l.scale[1], 1.0f, 0);
    assert_float_equal(l.center[1][0], 0.5f, 0);

    static const struct {
        const char *text, *why;
    } bad[] = {
        {"k3 0.1\n", "b.txt:1: unknown key 'k3'"},
        {"k1\n", "b.txt:1: k1 wants 1 number"},
        {"\nk1 0.1 0.2\n", "b.txt:2: k1 wants 1 number"},
        {"chroma 1 1\n", "b.txt:1: chroma wants 3 numbers"},
        {"left_center 0.5 abc\n", "b.txt:1: left_center wants 2 numbers"},
        {"left_center 1.5 0.5\n", "b.txt: lens: centres"},
        {"chroma 1 3 1\n", "b.txt: lens: channel scales"},
        {"k1 -0.5\n", "not invertible"}, /* 1 - 1.5 r^2 < 0 before r = 2 */
        {"k2 nan\n", "k2 wants 1 number"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        err[0] = 0;
        assert_int_equal(parse(&l, bad[i].text, "b.txt", err, sizeof err), -1);
        if (!strstr(err, bad[i].why))
            fail_msg("'%s': got '%s', want '%s'", bad[i].text, err, bad[i].why);
    }
    assert_int_equal(fv_lens_load(&l, "/nonexistent/hmd.lens", 2.0f, err, sizeof err), -1);
    assert_non_null(strstr(err, "/nonexistent/hmd.lens: No such file"));
}

/* The in-memory parser: text_len bounds the text, exact messages, NUL bytes and long lines. */
static void test_parse_memory(void **st)
{
    (void)st;
    fv_lens l;
    char err[256];
    /* only the first line counts: the cut falls before "k2 oops" */
    const char *text = "k1 0.25\nk2 oops\n";
    assert_int_equal(fv_lens_parse(&l, text, 8, "cut.lens", 2.0f, err, sizeof err), 0);
    assert_float_equal(l.k1, 0.25f, 0);
    assert_float_equal(l.k2, 0.0f, 0);
    /* no final newline */
    assert_int_equal(fv_lens_parse(&l, "k2 0.01", 7, "nonl.lens", 2.0f, err, sizeof err), 0);
    assert_float_equal(l.k2, 0.01f, 0);
    assert_int_equal(fv_lens_parse(&l, "", 0, "empty.lens", 2.0f, err, sizeof err), 0);
    assert_float_equal(l.scale[0], 1.0f, 0);

    assert_int_equal(parse(&l, "# x\nk1 0.1\nk9 1\n", "m.lens", err, sizeof err), -1);
    assert_string_equal(err, "m.lens:3: unknown key 'k9' (k1, k2, chroma, left_center, right_center)");
    assert_int_equal(parse(&l, "right_center 0.5\n", "m.lens", err, sizeof err), -1);
    assert_string_equal(err, "m.lens:1: right_center wants 2 numbers");
    assert_int_equal(fv_lens_parse(&l, "k1 0.1\0\n", 8, "nul.lens", 2.0f, err, sizeof err), -1);
    assert_string_equal(err, "nul.lens: not a text file (NUL byte)");
    char longline[600];
    memset(longline, ' ', sizeof longline);
    memcpy(longline, "k1 0.1", 6);
    assert_int_equal(fv_lens_parse(&l, longline, sizeof longline, "long.lens", 2.0f, err, sizeof err), -1);
    assert_string_equal(err, "long.lens:1: line too long");
}

/* platform/lensfile.c: reads the file and names it in the parser's messages. */
static void test_load_file(void **st)
{
    (void)st;
    char path[] = "/tmp/fovea_lens_XXXXXX";
    fv_test_temp_file(path, "k1 0.1\nk2 0.02\nchroma 0.99 1 1.01\n");
    fv_lens l;
    char err[512];
    assert_int_equal(fv_lens_load(&l, path, 2.0f, err, sizeof err), 0);
    assert_float_equal(l.k2, 0.02f, 0);
    assert_float_equal(l.scale[2], 1.01f, 0);
    fv_test_write_file(path, "k1 0.1\nchroma 1\n");
    char want[256];
    snprintf(want, sizeof want, "%s:2: chroma wants 3 numbers", path);
    assert_int_equal(fv_lens_load(&l, path, 2.0f, err, sizeof err), -1);
    unlink(path);
    assert_string_equal(err, want);
}

static void test_formula_and_round_trip(void **st)
{
    (void)st;
    const float k1 = 0.22f, k2 = 0.05f, cx = 0.07f, cy = -0.03f;
    uint64_t rng = 11;
    double worst = 0.0;
    for (int i = 0; i < 2000; i++) {
        const float tx = 2.4f * fv_test_randf(&rng) - 1.2f, ty = 2.4f * fv_test_randf(&rng) - 1.2f;
        for (int c = 0; c < 3; c++) {
            const float s = c == 0 ? 0.994f : c == 1 ? 1.0f : 1.008f;
            float dx, dy;
            fv_lens_distort(k1, k2, s, cx, cy, tx, ty, &dx, &dy);
            /* the formula, in double */
            const double ux = (double)tx - cx, uy = (double)ty - cy, r2 = ux * ux + uy * uy;
            const double f = s * (1.0 + k1 * r2 + k2 * r2 * r2);
            assert_true(fabs(dx - (cx + ux * f)) < 2e-6 && fabs(dy - (cy + uy * f)) < 2e-6);
            /* barrel-correcting: farther out than the panel point (k > 0) */
            if (c == 1 && r2 > 1e-4)
                assert_true((dx - cx) * (dx - cx) + (dy - cy) * (dy - cy) > r2);
            float bx, by;
            assert_int_equal(fv_lens_undistort(k1, k2, s, cx, cy, dx, dy, &bx, &by), 0);
            const double e = fmax(fabs(bx - tx), fabs(by - ty));
            if (e > worst)
                worst = e;
        }
    }
    assert_true(worst < 2e-6);
}

static void test_camera(void **st)
{
    (void)st;
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.width = 320;
    d.height = 360;
    d.eye = FV_EYE_RIGHT;
    const fv_pose head = {{0.1f, 1.6f, 2.0f}, {0, 0.258819f, 0, 0.9659258f}};
    fv_camera plain, lensed, again;
    /* every field is set whatever the memory held (reprojection memcmp()s whole cameras) */
    memset(&plain, 0xaa, sizeof plain);
    memset(&again, 0x55, sizeof again);
    assert_int_equal(fv_camera_setup(&plain, &d, &head), 0);
    assert_int_equal(fv_camera_setup(&again, &d, &head), 0);
    assert_memory_equal(&plain, &again, sizeof plain);
    fv_lens lens;
    fv_lens_default(&lens);
    lens.k1 = 0.2f;
    lens.k2 = 0.04f;
    lens.center[1][0] = 0.45f; /* right eye: centre toward the nose */
    lens.center[1][1] = 0.55f;
    d.lens = &lens;
    assert_int_equal(fv_camera_setup(&lensed, &d, &head), 0);
    assert_false(plain.lens_on);
    assert_true(lensed.lens_on);

    /* without a lens the ray is the plain pinhole formula, bit for bit */
    float dir[3];
    fv_camera_ray(&plain, 17.5f, 200.5f, dir);
    const float tx = plain.tan_left + 17.5f * plain.px_tan, ty = plain.tan_top - 200.5f * plain.px_tan;
    for (int i = 0; i < 3; i++)
        assert_true(dir[i] == tx * plain.right[i] + ty * plain.up[i] - plain.back[i]);

    /* the frustum is the asymmetric one of the lens centre: the centre pixel (0.45, 0.55 of the
     * panel) looks straight ahead, along -back; the extents are the plain ones shifted by
     * (2 c - 1) tan (hand formula), the total field unchanged */
    float b[3];
    const float px0 = 0.45f * 320, py0 = 0.55f * 360;
    fv_camera_ray(&lensed, px0, py0, b);
    for (int i = 0; i < 3; i++)
        assert_float_equal(b[i], -lensed.back[i], 2e-6);
    assert_float_equal(lensed.tan_left, plain.tan_left - (2 * 0.45f - 1) * plain.tan_right, 1e-6);
    assert_float_equal(lensed.tan_right, plain.tan_right - (2 * 0.45f - 1) * plain.tan_right, 1e-6);
    assert_float_equal(lensed.tan_top, plain.tan_top + (2 * 0.55f - 1) * plain.tan_top, 1e-6);
    assert_float_equal(lensed.tan_bottom, plain.tan_bottom + (2 * 0.55f - 1) * plain.tan_top, 1e-6);
    assert_float_equal(lensed.lens_cx, 0.0f, 1e-6);
    assert_float_equal(lensed.lens_cy, 0.0f, 1e-6);
    /* the left eye takes its own centre (the default 0.5, 0.5: symmetric) */
    d.eye = FV_EYE_LEFT;
    fv_camera left;
    assert_int_equal(fv_camera_setup(&left, &d, &head), 0);
    assert_float_equal(left.tan_left, -left.tan_right, 1e-6);

    /* elsewhere: along the distorted tangent; projecting the point seen returns the pixel */
    for (int y = 10; y < 360; y += 50)
        for (int x = 5; x < 320; x += 45) {
            const float px = (float)x + 0.5f, py = (float)y + 0.5f;
            fv_camera_ray(&lensed, px, py, b);
            float ux = lensed.tan_left + px * lensed.px_tan, uy = lensed.tan_top - py * lensed.px_tan, ex, ey;
            fv_lens_distort(0.2f, 0.04f, 1.0f, lensed.lens_cx, lensed.lens_cy, ux, uy, &ex, &ey);
            for (int i = 0; i < 3; i++)
                assert_float_equal(b[i], ex * lensed.right[i] + ey * lensed.up[i] - lensed.back[i], 1e-5);
            const float p[3] = {lensed.eye_pos[0] + 3 * b[0], lensed.eye_pos[1] + 3 * b[1], lensed.eye_pos[2] + 3 * b[2]};
            float qx, qy;
            assert_float_equal(fv_camera_project(&lensed, p, &qx, &qy), 3.0f, 1e-4);
            assert_float_equal(qx, px, 2e-3);
            assert_float_equal(qy, py, 2e-3);
        }
}

/* Lateral chromatic aberration: the table's source point for red / blue at panel point P is the
 * point Q whose green ray goes where P's red / blue ray goes, checked against the direct
 * construction (distort with the channel's scale, undistort with green's, in double). */
static void test_lca_source(void **st)
{
    (void)st;
    const float k1 = 0.22f, k2 = 0.04f, scale[3] = {1.012f, 1.0f, 0.985f};
    fv_lens_lca t;
    fv_lens_lca_init(&t, k1, k2, scale, 1.6f);
    assert_true(t.on);
    uint64_t rng = 7;
    for (int i = 0; i < 2000; i++) {
        const float cx = 0.05f, cy = -0.02f;
        const float tx = cx + 2.2f * (fv_test_randf(&rng) - 0.5f), ty = cy + 2.2f * (fv_test_randf(&rng) - 0.5f);
        for (int ch = 0; ch < 2; ch++) {
            float dx, dy, ex, ey, qx, qy;
            fv_lens_distort(k1, k2, scale[ch ? 2 : 0], cx, cy, tx, ty, &dx, &dy);
            assert_int_equal(fv_lens_undistort(k1, k2, scale[1], cx, cy, dx, dy, &ex, &ey), 0);
            fv_lens_lca_source(&t, ch, cx, cy, tx, ty, &qx, &qy);
            assert_float_equal(qx, ex, 2e-5f);
            assert_float_equal(qy, ey, 2e-5f);
        }
    }
    /* red spreads outwards of green, blue inwards, by about the scale ratio near the centre */
    float qx, qy;
    fv_lens_lca_source(&t, 0, 0.0f, 0.0f, 0.01f, 0.0f, &qx, &qy);
    assert_float_equal(qx, 0.01f * 1.012f, 2e-6f);
    fv_lens_lca_source(&t, 1, 0.0f, 0.0f, 0.01f, 0.0f, &qx, &qy);
    assert_float_equal(qx, 0.01f * 0.985f, 2e-6f);
    /* equal scales: nothing to do */
    const float same[3] = {1.0f, 1.0f, 1.0f};
    fv_lens_lca_init(&t, k1, k2, same, 1.6f);
    assert_false(t.on);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse),
        cmocka_unit_test(test_parse_memory),
        cmocka_unit_test(test_load_file),
        cmocka_unit_test(test_formula_and_round_trip),
        cmocka_unit_test(test_camera),
        cmocka_unit_test(test_lca_source),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
