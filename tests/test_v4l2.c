/* V4L2 capture: pixel-format reduction against hand-made buffers, the open path's errors against
 * things that are not video devices, the reopen back-off, control names and config checks. Runs
 * without a camera (and under qemu-user, whose ioctl errno may differ: messages are checked for
 * the call and the path, not the errno text). */
#define _DEFAULT_SOURCE
#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "testutil.h"
#include "pixfmt.h"
#include "v4l2.h"

static int64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

#define assert_contains(hay, needle)                                                       \
    do {                                                                                   \
        if (!strstr((hay), (needle)))                                                      \
            fail_msg("'%s' does not contain '%s'", (hay), (needle));                       \
    } while (0)

/* ---- pixel formats ----------------------------------------------------------------------- */

static void test_grey_stride(void **st)
{
    (void)st;
    /* 3x2, bytesperline 5: the two padding bytes per row must not leak into the image. */
    const uint8_t src[] = {1, 2, 3, 0xEE, 0xEE, 4, 5, 6, 0xEE, 0xEE};
    uint8_t dst[8];
    memset(dst, 0x55, sizeof dst);
    assert_int_equal(fv_pix_to_luma8(FV_PIX_GREY, src, sizeof src, 5, 3, 2, dst, 4), 0);
    const uint8_t want[] = {1, 2, 3, 0x55, 4, 5, 6, 0x55}; /* dst padding untouched */
    assert_memory_equal(dst, want, sizeof want);
    /* The last row need not be padded. */
    assert_int_equal(fv_pix_min_size(FV_PIX_GREY, 3, 2, 5), 8);
    assert_int_equal(fv_pix_to_luma8(FV_PIX_GREY, src, 8, 5, 3, 2, dst, 4), 0);
    assert_int_equal(fv_pix_to_luma8(FV_PIX_GREY, src, 7, 5, 3, 2, dst, 4), -1);
}

/* 16-bit little-endian words into bytes. */
static void le16(uint8_t *p, const unsigned *v, int n)
{
    for (int i = 0; i < n; i++) {
        p[2 * i] = (uint8_t)(v[i] & 0xff);
        p[2 * i + 1] = (uint8_t)(v[i] >> 8);
    }
}

static void test_y10_y12_y16(void **st)
{
    (void)st;
    uint8_t src[16], dst[8];
    /* Y10: >> 2; 1024 and 0xffff are out of range (a broken driver) and saturate. */
    const unsigned y10[8] = {0, 3, 4, 7, 512, 1023, 1024, 0xffff};
    const uint8_t y10_want[8] = {0, 0, 1, 1, 128, 255, 255, 255};
    le16(src, y10, 8);
    assert_int_equal(fv_pix_to_luma8(FV_PIX_Y10, src, sizeof src, 16, 8, 1, dst, 8), 0);
    assert_memory_equal(dst, y10_want, 8);

    const unsigned y12[8] = {0, 15, 16, 0x800, 4095, 4096, 0x1234, 0x0ff0};
    const uint8_t y12_want[8] = {0, 0, 1, 128, 255, 255, 255, 255};
    le16(src, y12, 8);
    assert_int_equal(fv_pix_to_luma8(FV_PIX_Y12, src, sizeof src, 16, 8, 1, dst, 8), 0);
    assert_memory_equal(dst, y12_want, 8);

    const unsigned y16[8] = {0, 0xff, 0x100, 0xabcd, 0x7fff, 0x8000, 0xffff, 0x01fe};
    const uint8_t y16_want[8] = {0, 0, 1, 0xab, 0x7f, 0x80, 0xff, 0x01};
    le16(src, y16, 8);
    assert_int_equal(fv_pix_to_luma8(FV_PIX_Y16, src, sizeof src, 16, 8, 1, dst, 8), 0);
    assert_memory_equal(dst, y16_want, 8);

    /* 3x2 Y10 with bytesperline 8 (2 padding bytes of 0xff that must not be read as a pixel). */
    const uint8_t pad[16] = {0x00, 0x01, 0x04, 0x00, 0xff, 0x03, 0xff, 0xff,
                             0x08, 0x00, 0x0c, 0x00, 0x10, 0x00, 0xff, 0xff};
    uint8_t d6[6];
    assert_int_equal(fv_pix_to_luma8(FV_PIX_Y10, pad, sizeof pad, 8, 3, 2, d6, 3), 0);
    const uint8_t pad_want[6] = {64, 1, 255, 2, 3, 4};
    assert_memory_equal(d6, pad_want, 6);
    /* An odd stride for a 16-bit format is allowed (the driver says where rows start). */
    assert_int_equal(fv_pix_min_size(FV_PIX_Y16, 3, 2, 7), 13);
}

static void test_yuyv_uyvy_odd_width(void **st)
{
    (void)st;
    /* 3 pixels wide: two 2-pixel groups (the last luma slot is padding), bytesperline 10. */
    const uint8_t yuyv[20] = {10, 128, 20, 129, 30, 130, 99, 131, 0xEE, 0xEE,
                              40, 128, 50, 129, 60, 130, 99, 131, 0xEE, 0xEE};
    const uint8_t uyvy[20] = {128, 10, 129, 20, 130, 30, 131, 99, 0xEE, 0xEE,
                              128, 40, 129, 50, 130, 60, 131, 99, 0xEE, 0xEE};
    const uint8_t want[6] = {10, 20, 30, 40, 50, 60};
    uint8_t dst[6];
    assert_int_equal(fv_pix_min_stride(FV_PIX_YUYV, 3), 8);
    assert_int_equal(fv_pix_min_stride(FV_PIX_UYVY, 4), 8);
    memset(dst, 0, sizeof dst);
    assert_int_equal(fv_pix_to_luma8(FV_PIX_YUYV, yuyv, sizeof yuyv, 10, 3, 2, dst, 3), 0);
    assert_memory_equal(dst, want, 6);
    memset(dst, 0, sizeof dst);
    assert_int_equal(fv_pix_to_luma8(FV_PIX_UYVY, uyvy, sizeof uyvy, 10, 3, 2, dst, 3), 0);
    assert_memory_equal(dst, want, 6);
    /* bytesperline 6 cannot hold two 4-byte groups */
    assert_int_equal(fv_pix_to_luma8(FV_PIX_YUYV, yuyv, sizeof yuyv, 6, 3, 2, dst, 3), -1);
}

static void test_pix_rejects(void **st)
{
    (void)st;
    uint8_t src[64] = {0}, dst[64];
    memset(dst, 0x77, sizeof dst);
    const uint32_t mjpg = FV_FOURCC('M', 'J', 'P', 'G');
    assert_int_equal(fv_pix_to_luma8(mjpg, src, sizeof src, 8, 4, 2, dst, 4), -1);
    assert_int_equal(fv_pix_to_luma8(FV_PIX_GREY, src, sizeof src, 3, 4, 2, dst, 4), -1); /* stride < width */
    assert_int_equal(fv_pix_to_luma8(FV_PIX_Y16, src, 15, 8, 4, 2, dst, 4), -1);        /* short buffer */
    assert_int_equal(fv_pix_to_luma8(FV_PIX_GREY, src, sizeof src, 4, 4, 2, dst, 3), -1); /* dst stride < width */
    assert_int_equal(fv_pix_to_luma8(FV_PIX_GREY, src, sizeof src, 4, 0, 2, dst, 4), -1);
    assert_int_equal(fv_pix_to_luma8(FV_PIX_GREY, src, sizeof src, 4, 4, 0, dst, 4), -1);
    for (size_t i = 0; i < sizeof dst; i++)
        assert_int_equal(dst[i], 0x77); /* failures write nothing */
    assert_int_equal(fv_pix_min_stride(mjpg, 4), 0);
    assert_int_equal(fv_pix_min_stride(FV_PIX_GREY, 0), 0);
    assert_int_equal(fv_pix_min_size(FV_PIX_GREY, 4, 2, SIZE_MAX), 0); /* overflow */
}

static void test_pix_names(void **st)
{
    (void)st;
    char nm[5];
    assert_string_equal(fv_pix_name(FV_PIX_Y10, nm), "Y10");
    assert_string_equal(fv_pix_name(FV_PIX_YUYV, nm), "YUYV");
    assert_string_equal(fv_pix_name(0x01020304u, nm), "????");
    assert_int_equal(fv_pix_parse("GREY"), FV_PIX_GREY);
    assert_int_equal(fv_pix_parse("y10"), FV_PIX_Y10);
    assert_int_equal(fv_pix_parse("Y16 "), FV_PIX_Y16);
    assert_int_equal(fv_pix_parse("uyvy"), FV_PIX_UYVY);
    assert_int_equal(fv_pix_parse("MJPG"), 0);
    assert_int_equal(fv_pix_parse(""), 0);
    assert_int_equal(fv_pix_parse("GREYY"), 0);
}

/* ---- opening things that are not cameras ------------------------------------------------- */

static void expect_open_fails(const char *path, const char *call)
{
    fv_v4l2_config cfg;
    fv_v4l2_config_default(&cfg, path);
    fv_v4l2 cam;
    char err[512] = "";
    assert_int_equal(fv_v4l2_open(&cam, &cfg, err, sizeof err), -1);
    char want[600];
    snprintf(want, sizeof want, "%s on %s: ", call, path);
    assert_contains(err, want);
    assert_int_equal(cam.fd, -1);
    assert_false(cam.gone);
    /* A failed camera answers next() with an error, and closes twice without harm. */
    fv_eye_frame f;
    char err2[256] = "";
    assert_int_equal(fv_v4l2_next(&cam, 0, &f, err2, sizeof err2), FV_V4L2_ERROR);
    assert_contains(err2, "not open");
    fv_v4l2_close(&cam);
    fv_v4l2_close(&cam);
}

static void test_open_dev_null(void **st)
{
    (void)st;
    expect_open_fails("/dev/null", "VIDIOC_QUERYCAP");
}

static void test_open_regular_file(void **st)
{
    (void)st;
    char path[] = "/tmp/fovea-v4l2-XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, "not a camera\n", 13), 13);
    close(fd);
    expect_open_fails(path, "VIDIOC_QUERYCAP");
    unlink(path);
}

static void test_open_directory(void **st)
{
    (void)st;
    char path[] = "/tmp/fovea-v4l2-dir-XXXXXX";
    assert_non_null(mkdtemp(path));
    expect_open_fails(path, "open"); /* EISDIR */
    rmdir(path);
}

static void test_open_missing(void **st)
{
    (void)st;
    expect_open_fails("/nonexistent-fovea/video9", "open");
}

static void test_open_bad_config(void **st)
{
    (void)st;
    fv_v4l2_config cfg;
    fv_v4l2_config_default(&cfg, "/dev/null");
    cfg.buffers = 2;
    fv_v4l2 cam;
    char err[256] = "";
    assert_int_equal(fv_v4l2_open(&cam, &cfg, err, sizeof err), -1);
    assert_contains(err, "buffers");
    fv_v4l2_close(&cam);
}

/* A device that is not there yet (wait_for_device): next() keeps trying on the back-off schedule
 * without blocking longer than its timeout. */
static void test_wait_for_device(void **st)
{
    (void)st;
    const char *path = "/nonexistent-fovea/video7";
    fv_v4l2_config cfg;
    fv_v4l2_config_default(&cfg, path);
    cfg.wait_for_device = 1;
    fv_v4l2 cam;
    char err[512] = "";
    assert_int_equal(fv_v4l2_open(&cam, &cfg, err, sizeof err), 0);
    assert_true(cam.gone);
    fv_eye_frame f;
    int64_t t0 = now_ns();
    assert_int_equal(fv_v4l2_next(&cam, 0, &f, err, sizeof err), FV_V4L2_GONE);
    assert_true(now_ns() - t0 < 40000000); /* the first attempt is 50 ms away: no sleep */
    assert_contains(err, path);
    assert_int_equal(cam.reopen_attempts, 0);

    t0 = now_ns();
    assert_int_equal(fv_v4l2_next(&cam, 250, &f, err, sizeof err), FV_V4L2_GONE);
    int64_t dt = now_ns() - t0;
    /* attempts at ~50 and ~150 ms; the third (~350 ms) is past the deadline, which it sleeps to
     * (a loop calling next() must not spin) but not beyond */
    assert_true(cam.reopen_attempts >= 1 && cam.reopen_attempts <= 3);
    assert_true(dt >= 240000000 && dt < 1500000000);
    assert_contains(err, "open on /nonexistent-fovea/video7");
    assert_contains(err, "reopen attempt");
    char d[256];
    fv_v4l2_describe(&cam, d, sizeof d);
    assert_contains(d, "gone");
    fv_v4l2_close(&cam);

    /* Present but not a camera: a hard error even when waiting. */
    fv_v4l2_config_default(&cfg, "/dev/null");
    cfg.wait_for_device = 1;
    assert_int_equal(fv_v4l2_open(&cam, &cfg, err, sizeof err), -1);
    assert_contains(err, "VIDIOC_QUERYCAP on /dev/null");
    fv_v4l2_close(&cam);
}

/* ---- pure helpers ------------------------------------------------------------------------ */

static void test_backoff(void **st)
{
    (void)st;
    const int64_t ms = 1000000;
    assert_int_equal(fv_v4l2_backoff_ns(0), 50 * ms);
    assert_int_equal(fv_v4l2_backoff_ns(1), 100 * ms);
    assert_int_equal(fv_v4l2_backoff_ns(2), 200 * ms);
    assert_int_equal(fv_v4l2_backoff_ns(3), 400 * ms);
    assert_int_equal(fv_v4l2_backoff_ns(4), 800 * ms);
    assert_int_equal(fv_v4l2_backoff_ns(5), 1600 * ms);
    assert_int_equal(fv_v4l2_backoff_ns(6), 2000 * ms);
    assert_int_equal(fv_v4l2_backoff_ns(63), 2000 * ms);
    assert_int_equal(fv_v4l2_backoff_ns(INT_MAX), 2000 * ms);
    assert_int_equal(fv_v4l2_backoff_ns(-3), 50 * ms);
    for (int i = 0; i < 100; i++)
        assert_true(fv_v4l2_backoff_ns(i + 1) >= fv_v4l2_backoff_ns(i));
}

static void test_ctrl_names(void **st)
{
    (void)st;
    char a[64], b[64];
    assert_string_equal(fv_v4l2_ctrl_norm("Exposure, Absolute", a, sizeof a), "exposureabsolute");
    assert_string_equal(fv_v4l2_ctrl_norm("exposure_absolute", b, sizeof b), "exposureabsolute");
    assert_string_equal(fv_v4l2_ctrl_norm("Exposure Time, Absolute", a, sizeof a),
                        fv_v4l2_ctrl_norm("exposure-time (absolute)", b, sizeof b));
    assert_string_equal(fv_v4l2_ctrl_norm("GAIN", a, sizeof a), "gain");
    assert_string_equal(fv_v4l2_ctrl_norm("Gain 2", a, sizeof a), "gain2");
    assert_string_equal(fv_v4l2_ctrl_norm("Brightness", a, 5), "brig"); /* truncated */
    assert_string_not_equal(fv_v4l2_ctrl_norm("Exposure", a, sizeof a), fv_v4l2_ctrl_norm("Exposure, Auto", b, sizeof b));

    char name[32];
    int64_t v = -99;
    char err[256];
    assert_int_equal(fv_v4l2_ctrl_parse("gain=10", name, sizeof name, &v, err, sizeof err), 0);
    assert_string_equal(name, "gain");
    assert_int_equal(v, 10);
    assert_int_equal(fv_v4l2_ctrl_parse("Exposure, Absolute=0x1f", name, sizeof name, &v, err, sizeof err), 0);
    assert_string_equal(name, "Exposure, Absolute");
    assert_int_equal(v, 31);
    assert_int_equal(fv_v4l2_ctrl_parse("brightness=-5", name, sizeof name, &v, err, sizeof err), 0);
    assert_int_equal(v, -5);
    assert_int_equal(fv_v4l2_ctrl_parse("gain=010", name, sizeof name, &v, err, sizeof err), 0);
    assert_int_equal(v, 10); /* not octal */
    assert_int_equal(fv_v4l2_ctrl_parse("exposure_auto_priority=on", name, sizeof name, &v, err, sizeof err), 0);
    assert_int_equal(v, 1);
    assert_int_equal(fv_v4l2_ctrl_parse("x=False", name, sizeof name, &v, err, sizeof err), 0);
    assert_int_equal(v, 0);
    const char *bad[] = {"gain", "=5", "gain=", "gain=abc", "gain=12x", "__=3", "gain=99999999999999999999"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        err[0] = 0;
        assert_int_equal(fv_v4l2_ctrl_parse(bad[i], name, sizeof name, &v, err, sizeof err), -1);
        assert_contains(err, "control '");
    }
}

static void test_config(void **st)
{
    (void)st;
    fv_v4l2_config cfg;
    char err[256];
    fv_v4l2_config_default(&cfg, "/dev/video0");
    assert_int_equal(fv_v4l2_config_validate(&cfg, err, sizeof err), 0);
    assert_true(cfg.buffers >= 4);

#define BAD(stmt, needle)                                                                   \
    do {                                                                                    \
        fv_v4l2_config_default(&cfg, "/dev/video0");                                        \
        stmt;                                                                               \
        err[0] = 0;                                                                         \
        assert_int_equal(fv_v4l2_config_validate(&cfg, err, sizeof err), -1);              \
        assert_contains(err, needle);                                                       \
    } while (0)
    BAD(cfg.buffers = 3, "buffers");
    BAD(cfg.buffers = FV_V4L2_MAX_BUFFERS + 1, "buffers");
    BAD(cfg.width = 0, "size");
    BAD(cfg.height = -480, "size");
    BAD(cfg.fps = -1, "frame rate");
    BAD(cfg.path = NULL, "path");
    BAD(cfg.path = "", "path");
    BAD((cfg.formats[0] = FV_FOURCC('M', 'J', 'P', 'G'), cfg.n_formats = 1), "MJPG");
    BAD((cfg.formats[0] = FV_PIX_GREY, cfg.formats[1] = FV_PIX_GREY, cfg.n_formats = 2), "twice");
    BAD((cfg.ctrls[0] = "gain", cfg.n_ctrls = 1), "name=value");
    BAD((cfg.ctrls[0] = NULL, cfg.n_ctrls = 1), "missing");
#undef BAD

    fv_v4l2_config_default(&cfg, "/dev/video0");
    assert_int_equal(fv_v4l2_config_formats(&cfg, "GREY,yuyv,Y10", err, sizeof err), 0);
    assert_int_equal(cfg.n_formats, 3);
    assert_int_equal(cfg.formats[0], FV_PIX_GREY);
    assert_int_equal(cfg.formats[1], FV_PIX_YUYV);
    assert_int_equal(cfg.formats[2], FV_PIX_Y10);
    const char *bad_lists[] = {"", "GREY,", ",GREY", "GREY,,YUYV", "MJPG", "GREY,GREY", "GREYS"};
    for (size_t i = 0; i < sizeof bad_lists / sizeof *bad_lists; i++) {
        err[0] = 0;
        assert_int_equal(fv_v4l2_config_formats(&cfg, bad_lists[i], err, sizeof err), -1);
        assert_true(strlen(err) > 10);
        assert_int_equal(cfg.n_formats, 3); /* unchanged on failure */
    }

    for (int i = 0; i < FV_V4L2_MAX_CTRLS; i++)
        assert_int_equal(fv_v4l2_config_ctrl(&cfg, "gain=1", err, sizeof err), 0);
    assert_int_equal(fv_v4l2_config_ctrl(&cfg, "gain=1", err, sizeof err), -1);
    assert_contains(err, "too many");
    assert_int_equal(cfg.n_ctrls, FV_V4L2_MAX_CTRLS);
    assert_int_equal(fv_v4l2_config_validate(&cfg, err, sizeof err), 0);
    fv_v4l2_config_default(&cfg, "/dev/video0");
    assert_int_equal(fv_v4l2_config_ctrl(&cfg, "gain", err, sizeof err), -1);
    assert_int_equal(cfg.n_ctrls, 0);
}

/* ---- a real camera, when the machine has one --------------------------------------------- */

static void test_real_device(void **st)
{
    (void)st;
    DIR *d = opendir("/dev");
    char path[300] = "";
    if (d) {
        struct dirent *e;
        while ((e = readdir(d)))
            if (!strncmp(e->d_name, "video", 5)) {
                snprintf(path, sizeof path, "/dev/%s", e->d_name);
                break;
            }
        closedir(d);
    }
    if (!*path || getenv("FV_TEST_NO_CAMERA")) {
        skip();
        return;
    }
    fv_v4l2_config cfg;
    fv_v4l2_config_default(&cfg, path);
    fv_v4l2 cam;
    char err[512];
    if (fv_v4l2_open(&cam, &cfg, err, sizeof err)) {
        /* Not every video node captures (metadata nodes, codecs); the message must still name it. */
        print_message("note: %s\n", err);
        assert_contains(err, path);
        skip();
        return;
    }
    int got = 0;
    for (int i = 0; i < 3; i++) {
        fv_eye_frame f;
        fv_v4l2_status s = fv_v4l2_next(&cam, 2000, &f, err, sizeof err);
        if (s != FV_V4L2_FRAME)
            break;
        assert_non_null(f.luma);
        assert_int_equal(f.width, cam.width);
        assert_true(f.stride >= (size_t)f.width);
        assert_true(f.t_ns > 0);
        got++;
    }
    fv_v4l2_close(&cam);
    if (!got)
        skip();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grey_stride),
        cmocka_unit_test(test_y10_y12_y16),
        cmocka_unit_test(test_yuyv_uyvy_odd_width),
        cmocka_unit_test(test_pix_rejects),
        cmocka_unit_test(test_pix_names),
        cmocka_unit_test(test_open_dev_null),
        cmocka_unit_test(test_open_regular_file),
        cmocka_unit_test(test_open_directory),
        cmocka_unit_test(test_open_missing),
        cmocka_unit_test(test_open_bad_config),
        cmocka_unit_test(test_wait_for_device),
        cmocka_unit_test(test_backoff),
        cmocka_unit_test(test_ctrl_names),
        cmocka_unit_test(test_config),
        cmocka_unit_test(test_real_device),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
