/* V4L2 capture: pixel-format reduction against hand-made buffers, the open path's errors against
 * things that are not video devices, the reopen back-off, control names and config checks. Runs
 * without a camera (and under qemu-user, whose ioctl errno may differ: messages are checked for
 * the call and the path, not the errno text). */
#define _DEFAULT_SOURCE
#include <dirent.h>
#include <poll.h>
#include <linux/videodev2.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <jpeglib.h>

#include "base/clock.h"
#include "testutil.h"
#include "mjpeg.h"
#include "pixfmt.h"
#include "v4l2.h"


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
    fv_v4l2_frame f;
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
    fv_v4l2_frame f;
    /* timeout 0 never sleeps, though the next attempt is 50+ ms away (best of 3: a loaded
     * machine may deschedule us once) */
    int64_t best = INT64_MAX;
    for (int i = 0; i < 3; i++) {
        int64_t t0 = fv_time_ns();
        assert_int_equal(fv_v4l2_next(&cam, 0, &f, err, sizeof err), FV_V4L2_GONE);
        int64_t dt = fv_time_ns() - t0;
        best = dt < best ? dt : best;
        assert_contains(err, path);
    }
    assert_true(best < 40000000);
    assert_true(cam.reopen_attempts <= 1);
    int64_t t0;

    t0 = fv_time_ns();
    assert_int_equal(fv_v4l2_next(&cam, 250, &f, err, sizeof err), FV_V4L2_GONE);
    int64_t dt = fv_time_ns() - t0;
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
    BAD((cfg.formats[0] = FV_FOURCC('H', '2', '6', '4'), cfg.n_formats = 1), "H264");
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
    assert_int_equal(fv_v4l2_config_formats(&cfg, "mjpg", err, sizeof err), 0);
    assert_int_equal(cfg.formats[0], FV_PIX_MJPEG);
    assert_int_equal(fv_v4l2_config_formats(&cfg, "GREY,yuyv,Y10", err, sizeof err), 0);
    const char *bad_lists[] = {"", "GREY,", ",GREY", "GREY,,YUYV", "H264", "GREY,GREY", "GREYS", "mjpg,MJPG"};
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

/* ---- a fake device behind fv_v4l2_sys: the streaming, control and reopen paths ------------ */

#define FAKE_FD 42
#define FAKE_MAX_BUFS 8
typedef struct fake {
    int absent, vanish;          /* open fails ENOENT / everything fails ENODEV (unplugged) */
    const char *deny;            /* open of a path ending so fails EACCES */
    int fd_open, opens, mapped;
    uint32_t caps;
    uint32_t formats[4];
    int n_formats;
    uint32_t pad;                /* bytes of padding per line */
    uint32_t ts_flags;           /* V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC or _COPY */
    int fail_sfmt, eintr_dqbuf, error_next, pollerr;
    uint32_t fourcc, bpl;
    int w, h, streaming, n_bufs, next_buf, ready;
    size_t len;
    uint8_t *mem[FAKE_MAX_BUFS];
    int queued[FAKE_MAX_BUFS];
    uint32_t seq;
    int64_t stamp_ns;
    int32_t brightness, gain, exposure;
    const uint8_t *jpeg;         /* the frame an MJPEG fake sends */
    size_t jpeg_len, sizeimage;
    uint32_t fps_den;
} fake;

static uint8_t fake_luma(uint32_t seq, int x, int y) { return (uint8_t)(seq * 7 + (uint32_t)y * 16 + (uint32_t)x); }

static const struct {
    uint32_t id, type;
    const char *name;
    int32_t min, max;
} fake_ctrls[] = {
    {V4L2_CID_USER_CLASS, V4L2_CTRL_TYPE_CTRL_CLASS, "User Controls", 0, 0},
    {V4L2_CID_BRIGHTNESS, V4L2_CTRL_TYPE_INTEGER, "Brightness", 0, 255},
    {V4L2_CID_GAIN, V4L2_CTRL_TYPE_INTEGER, "Gain", 0, 100},
    {V4L2_CID_CAMERA_CLASS, V4L2_CTRL_TYPE_CTRL_CLASS, "Camera Controls", 0, 0},
    {V4L2_CID_EXPOSURE_ABSOLUTE, V4L2_CTRL_TYPE_INTEGER, "Exposure Time, Absolute", 1, 5000},
};

static int fake_open(void *u, const char *path, int flags)
{
    fake *f = u;
    (void)flags;
    size_t n = strlen(path), d = f->deny ? strlen(f->deny) : 0;
    if (d && n >= d && !strcmp(path + n - d, f->deny)) {
        errno = EACCES;
        return -1;
    }
    if (f->absent) {
        errno = ENOENT;
        return -1;
    }
    assert_false(f->fd_open); /* the camera never leaks a descriptor */
    f->fd_open = 1;
    f->opens++;
    return FAKE_FD;
}

static int fake_close(void *u, int fd)
{
    fake *f = u;
    assert_int_equal(fd, FAKE_FD);
    assert_true(f->fd_open);
    f->fd_open = 0;
    f->streaming = 0;
    for (int i = 0; i < f->n_bufs; i++)
        free(f->mem[i]);
    f->n_bufs = 0;
    return 0;
}

static int fake_fail(int e)
{
    errno = e;
    return -1;
}

static void fake_fill(fake *f, int i)
{
    uint8_t *m = f->mem[i];
    memset(m, 0xEE, f->len);
    if (f->fourcc == V4L2_PIX_FMT_MJPEG) {
        memcpy(m, f->jpeg, f->jpeg_len);
        return;
    }
    for (int y = 0; y < f->h; y++)
        for (int x = 0; x < f->w; x++) {
            uint8_t l = fake_luma(f->seq, x, y);
            uint8_t *row = m + (size_t)y * f->bpl;
            if (f->fourcc == V4L2_PIX_FMT_GREY)
                row[x] = l;
            else if (f->fourcc == V4L2_PIX_FMT_Y10) { /* 10 bits: luma in the top 8, junk in the low 2 */
                row[2 * x] = (uint8_t)((l << 2) | 3);
                row[2 * x + 1] = (uint8_t)(l >> 6);
            } else if (f->fourcc == V4L2_PIX_FMT_YUYV) {
                row[2 * x] = l;
                row[2 * x + 1] = 128;
            }
        }
}

static int fake_ioctl(void *u, int fd, unsigned long req, void *arg)
{
    fake *f = u;
    assert_int_equal(fd, FAKE_FD);
    if (f->vanish)
        return fake_fail(ENODEV);
    switch (req) {
    case VIDIOC_QUERYCAP: {
        struct v4l2_capability *c = arg;
        memset(c, 0, sizeof *c);
        strcpy((char *)c->driver, "fake");
        strcpy((char *)c->card, "Fake IR eye camera");
        strcpy((char *)c->bus_info, "platform:fake");
        c->capabilities = f->caps | V4L2_CAP_DEVICE_CAPS;
        c->device_caps = f->caps;
        return 0;
    }
    case VIDIOC_ENUM_FMT: {
        struct v4l2_fmtdesc *d = arg;
        if (d->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || d->index >= (uint32_t)f->n_formats)
            return fake_fail(EINVAL);
        d->pixelformat = f->formats[d->index];
        return 0;
    }
    case VIDIOC_S_FMT: {
        struct v4l2_format *fm = arg;
        if (f->fail_sfmt)
            return fake_fail(f->fail_sfmt);
        f->fourcc = fm->fmt.pix.pixelformat;
        f->w = (int)fm->fmt.pix.width;
        f->h = (int)fm->fmt.pix.height;
        f->bpl = (uint32_t)fv_pix_min_stride(f->fourcc, f->w) + f->pad;
        fm->fmt.pix.bytesperline = f->bpl;
        fm->fmt.pix.sizeimage = f->bpl * (uint32_t)f->h;
        if (f->fourcc == V4L2_PIX_FMT_MJPEG)
            fm->fmt.pix.sizeimage = (uint32_t)(f->w * f->h * 2);
        f->sizeimage = fm->fmt.pix.sizeimage;
        return 0;
    }
    case VIDIOC_G_PARM: case VIDIOC_S_PARM: {
        struct v4l2_streamparm *p = arg;
        if (req == VIDIOC_S_PARM)
            f->fps_den = p->parm.capture.timeperframe.denominator;
        p->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
        p->parm.capture.timeperframe.numerator = 1;
        p->parm.capture.timeperframe.denominator = f->fps_den;
        return 0;
    }
    case VIDIOC_QUERYCTRL: {
        struct v4l2_queryctrl *q = arg;
        int next = !!(q->id & V4L2_CTRL_FLAG_NEXT_CTRL);
        uint32_t id = q->id & ~(V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND);
        for (size_t i = 0; i < sizeof fake_ctrls / sizeof *fake_ctrls; i++)
            if (next ? fake_ctrls[i].id > id : fake_ctrls[i].id == id) {
                memset(q, 0, sizeof *q);
                q->id = fake_ctrls[i].id;
                q->type = fake_ctrls[i].type;
                snprintf((char *)q->name, sizeof q->name, "%s", fake_ctrls[i].name);
                q->minimum = fake_ctrls[i].min;
                q->maximum = fake_ctrls[i].max;
                q->step = 1;
                return 0;
            }
        return fake_fail(EINVAL);
    }
    case VIDIOC_S_EXT_CTRLS: {
        struct v4l2_ext_controls *cs = arg;
        assert_int_equal(cs->count, 1);
        int32_t v = cs->controls[0].value;
        switch (cs->controls[0].id) {
        case V4L2_CID_BRIGHTNESS: f->brightness = v; break;
        case V4L2_CID_GAIN: f->gain = v; break;
        case V4L2_CID_EXPOSURE_ABSOLUTE: f->exposure = v; break;
        default: return fake_fail(EINVAL);
        }
        return 0;
    }
    case VIDIOC_REQBUFS: {
        struct v4l2_requestbuffers *rb = arg;
        assert_int_equal(rb->memory, V4L2_MEMORY_MMAP);
        if (rb->count > FAKE_MAX_BUFS)
            rb->count = FAKE_MAX_BUFS;
        f->n_bufs = (int)rb->count;
        f->len = f->sizeimage;
        for (int i = 0; i < f->n_bufs; i++) {
            f->mem[i] = malloc(f->len);
            f->queued[i] = 0;
        }
        f->next_buf = 0;
        return 0;
    }
    case VIDIOC_QUERYBUF: case VIDIOC_QBUF: {
        struct v4l2_buffer *b = arg;
        if (b->index >= (uint32_t)f->n_bufs)
            return fake_fail(EINVAL);
        if (req == VIDIOC_QBUF) {
            if (f->queued[b->index])
                return fake_fail(EINVAL);
            f->queued[b->index] = 1;
            return 0;
        }
        b->length = (uint32_t)f->len;
        b->m.offset = b->index * 0x10000u;
        b->flags = f->ts_flags;
        return 0;
    }
    case VIDIOC_STREAMON: f->streaming = 1; return 0;
    case VIDIOC_STREAMOFF: f->streaming = 0; return 0;
    case VIDIOC_DQBUF: {
        if (f->eintr_dqbuf > 0) {
            f->eintr_dqbuf--;
            return fake_fail(EINTR);
        }
        int i = f->next_buf;
        if (!f->streaming || !f->ready || !f->queued[i])
            return fake_fail(EAGAIN);
        struct v4l2_buffer *b = arg;
        fake_fill(f, i);
        f->queued[i] = 0;
        f->next_buf = (i + 1) % f->n_bufs;
        f->ready--;
        b->index = (uint32_t)i;
        b->bytesused = (uint32_t)(f->fourcc == V4L2_PIX_FMT_MJPEG ? f->jpeg_len : f->len);
        b->flags = f->ts_flags | (f->error_next ? V4L2_BUF_FLAG_ERROR : 0);
        f->error_next = 0;
        b->sequence = f->seq++;
        b->timestamp.tv_sec = (time_t)(f->stamp_ns / 1000000000);
        b->timestamp.tv_usec = (suseconds_t)(f->stamp_ns % 1000000000 / 1000);
        return 0;
    }
    default:
        return fake_fail(ENOTTY);
    }
}

static int fake_poll(void *u, struct pollfd *pfd, int timeout_ms)
{
    fake *f = u;
    (void)timeout_ms; /* no real time passes in the fake */
    pfd->revents = 0;
    if (f->vanish || f->pollerr)
        pfd->revents = POLLERR | POLLHUP;
    else if (f->streaming && f->ready && f->queued[f->next_buf])
        pfd->revents = POLLIN;
    return pfd->revents ? 1 : 0;
}

static void *fake_mmap(void *u, int fd, size_t length, int64_t offset)
{
    fake *f = u;
    assert_int_equal(fd, FAKE_FD);
    int i = (int)(offset / 0x10000);
    assert_true(i < f->n_bufs && length == f->len);
    f->mapped++;
    return f->mem[i];
}

static int fake_munmap(void *u, void *start, size_t length)
{
    fake *f = u;
    (void)start, (void)length;
    f->mapped--;
    return 0;
}

static fv_v4l2_sys fake_sys(fake *f)
{
    fv_v4l2_sys s = {f, fake_open, fake_close, fake_ioctl, fake_poll, fake_mmap, fake_munmap};
    return s;
}

static void fake_init(fake *f, uint32_t fourcc)
{
    memset(f, 0, sizeof *f);
    f->caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
    f->formats[0] = V4L2_PIX_FMT_MJPEG;
    f->formats[1] = fourcc;
    f->n_formats = 2;
    f->ts_flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
    f->fps_den = 30;
}

static int fake_queued(const fake *f)
{
    int n = 0;
    for (int i = 0; i < f->n_bufs; i++)
        n += f->queued[i];
    return n;
}

static void assert_frame(const fv_v4l2_frame *fr, uint32_t seq, int w, int h)
{
    assert_int_equal(fr->width, w);
    assert_int_equal(fr->height, h);
    assert_int_equal(fr->sequence, seq);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            if (fr->luma[(size_t)y * fr->stride + (size_t)x] != fake_luma(seq, x, y))
                fail_msg("frame %u pixel (%d,%d) = %u, want %u", seq, x, y, fr->luma[(size_t)y * fr->stride + (size_t)x],
                         fake_luma(seq, x, y));
}

static void test_fake_yuyv_stream(void **st)
{
    (void)st;
    fake f;
    fake_init(&f, V4L2_PIX_FMT_YUYV);
    f.pad = 4;
    fv_v4l2_sys sys = fake_sys(&f);
    fv_v4l2_config cfg;
    fv_v4l2_config_default(&cfg, "/fake/video0");
    cfg.sys = &sys;
    cfg.width = 5; /* odd: 3 YUYV groups per row */
    cfg.height = 3;
    cfg.fps = 120;
    cfg.buffers = 6;
    char err[512] = "";
    assert_int_equal(fv_v4l2_config_ctrl(&cfg, "exposure_time_absolute=100", err, sizeof err), 0);
    assert_int_equal(fv_v4l2_config_ctrl(&cfg, "GAIN=7", err, sizeof err), 0);
    fv_v4l2 cam;
    if (fv_v4l2_open(&cam, &cfg, err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(cam.fourcc, FV_PIX_YUYV); /* MJPG offered first, skipped */
    assert_int_equal(cam.bytesperline, 16);
    assert_int_equal(cam.n_buffers, 6);
    assert_int_equal(f.mapped, 6);
    assert_int_equal(fake_queued(&f), 6);
    assert_int_equal(f.fps_den, 120);
    assert_int_equal(f.exposure, 100);
    assert_int_equal(f.gain, 7);
    char d[512];
    fv_v4l2_describe(&cam, d, sizeof d);
    assert_contains(d, "YUYV 5x3");
    assert_contains(d, "120.00 fps");
    assert_contains(d, "driver monotonic");

    fv_v4l2_frame fr;
    for (uint32_t seq = 0; seq < 3; seq++) {
        f.ready = 1;
        f.stamp_ns = fv_time_ns() - 2000000;
        assert_int_equal(fv_v4l2_next(&cam, 100, &fr, err, sizeof err), FV_V4L2_FRAME);
        assert_frame(&fr, seq, 5, 3);
        assert_int_equal(fr.stride, 5);
        assert_int_equal(fr.fourcc, FV_PIX_YUYV);
        assert_true(fr.t_from_driver);
        assert_true(fr.t_ns == f.stamp_ns / 1000 * 1000);
        assert_int_equal(fake_queued(&f), 6); /* converted frames go straight back */
    }
    assert_int_equal(fv_v4l2_next(&cam, 0, &fr, err, sizeof err), FV_V4L2_TIMEOUT);

    /* EINTR is retried; a buffer the driver flags as bad is skipped */
    f.ready = 2;
    f.eintr_dqbuf = 2;
    f.error_next = 1;
    f.stamp_ns = fv_time_ns() - 1000000;
    assert_int_equal(fv_v4l2_next(&cam, 100, &fr, err, sizeof err), FV_V4L2_FRAME);
    assert_frame(&fr, 4, 5, 3);

    /* A frame that waited in the queue keeps the driver's (old) stamp. */
    f.ready = 1;
    f.stamp_ns = fv_time_ns() - 3000000000;
    assert_int_equal(fv_v4l2_next(&cam, 100, &fr, err, sizeof err), FV_V4L2_FRAME);
    assert_true(fr.t_from_driver);
    assert_true(fr.t_ns == f.stamp_ns / 1000 * 1000);

    /* POLLERR with nothing to dequeue: a dead queue, treated as a lost device */
    f.pollerr = 1;
    assert_int_equal(fv_v4l2_next(&cam, 100, &fr, err, sizeof err), FV_V4L2_GONE);
    assert_contains(err, "poll on /fake/video0: error condition");
    assert_false(f.fd_open);
    fv_v4l2_close(&cam);
    assert_false(f.fd_open);
    assert_int_equal(f.mapped, 0);
}

static void test_fake_grey_zero_copy(void **st)
{
    (void)st;
    fake f;
    fake_init(&f, V4L2_PIX_FMT_GREY);
    f.pad = 3;
    f.ts_flags = V4L2_BUF_FLAG_TIMESTAMP_COPY; /* not monotonic: stamped at dequeue */
    fv_v4l2_sys sys = fake_sys(&f);
    fv_v4l2_config cfg;
    fv_v4l2_config_default(&cfg, "/fake/video0");
    cfg.sys = &sys;
    cfg.width = 4;
    cfg.height = 2;
    char err[512] = "";
    fv_v4l2 cam;
    if (fv_v4l2_open(&cam, &cfg, err, sizeof err))
        fail_msg("%s", err);
    assert_false(cam.timestamps_monotonic);
    fv_v4l2_frame fr;
    f.ready = 1;
    f.stamp_ns = 12345; /* garbage: must not be used */
    int64_t t0 = fv_time_ns();
    assert_int_equal(fv_v4l2_next(&cam, 100, &fr, err, sizeof err), FV_V4L2_FRAME);
    assert_frame(&fr, 0, 4, 2);
    assert_int_equal(fr.stride, 7);
    assert_ptr_equal(fr.luma, f.mem[0]); /* lent, not copied */
    assert_int_equal(fake_queued(&f), 3);
    assert_false(fr.t_from_driver);
    assert_true(fr.t_ns >= t0 && fr.t_ns <= fv_time_ns());
    assert_int_equal(fv_v4l2_next(&cam, 0, &fr, err, sizeof err), FV_V4L2_TIMEOUT);
    assert_int_equal(fake_queued(&f), 4); /* given back on the next call */
    fv_v4l2_close(&cam);
    assert_int_equal(f.mapped, 0);
}

static void test_fake_unplug_reopen(void **st)
{
    (void)st;
    fake f;
    fake_init(&f, V4L2_PIX_FMT_Y10);
    fv_v4l2_sys sys = fake_sys(&f);
    fv_v4l2_config cfg;
    fv_v4l2_config_default(&cfg, "/fake/video0");
    cfg.sys = &sys;
    cfg.width = 6;
    cfg.height = 2;
    cfg.ctrls[0] = "gain=9";
    cfg.n_ctrls = 1;
    char err[512] = "";
    fv_v4l2 cam;
    if (fv_v4l2_open(&cam, &cfg, err, sizeof err))
        fail_msg("%s", err);
    fv_v4l2_frame fr;
    f.ready = 1;
    f.stamp_ns = fv_time_ns() - 1000000;
    assert_int_equal(fv_v4l2_next(&cam, 100, &fr, err, sizeof err), FV_V4L2_FRAME);
    assert_frame(&fr, 0, 6, 2);

    assert_int_equal(fv_v4l2_fd(&cam), FAKE_FD);
    f.vanish = 1; /* unplugged mid-stream */
    assert_int_equal(fv_v4l2_next(&cam, 100, &fr, err, sizeof err), FV_V4L2_GONE);
    assert_contains(err, "VIDIOC_DQBUF on /fake/video0: ");
    assert_contains(err, "device gone");
    assert_true(cam.gone);
    assert_false(f.fd_open); /* the dead descriptor and mappings are let go at once */
    assert_int_equal(fv_v4l2_fd(&cam), -1);
    assert_int_equal(f.mapped, 0);

    /* The node is gone: tries on the back-off schedule, never beyond the caller's timeout. */
    f.vanish = 0;
    f.absent = 1;
    f.gain = 0;
    int64_t t0 = fv_time_ns();
    assert_int_equal(fv_v4l2_next(&cam, 0, &fr, err, sizeof err), FV_V4L2_GONE);
    assert_true(cam.reopen_attempts <= 1); /* 0 unless 50 ms passed since the loss */
    assert_int_equal(fv_v4l2_next(&cam, 120, &fr, err, sizeof err), FV_V4L2_GONE);
    assert_true(fv_time_ns() - t0 < 1000000000);
    assert_true(cam.reopen_attempts >= 1);
    assert_contains(err, "open on /fake/video0");

    /* Plugged back in: reopened, renegotiated, controls applied again, frames flow. */
    f.absent = 0;
    f.ready = 1;
    f.seq = 0;
    f.stamp_ns = fv_time_ns() + 500000000; /* from the future (a driver bug): not trusted */
    fv_v4l2_status s = FV_V4L2_GONE;
    for (int i = 0; i < 40 && s == FV_V4L2_GONE; i++)
        s = fv_v4l2_next(&cam, 100, &fr, err, sizeof err);
    if (s != FV_V4L2_FRAME)
        fail_msg("no frame after replug: %d %s", s, err);
    assert_false(cam.gone);
    assert_int_equal(cam.reopens, 1);
    assert_int_equal(f.opens, 2);
    assert_int_equal(f.gain, 9);
    assert_frame(&fr, 0, 6, 2);
    assert_false(fr.t_from_driver);
    fv_v4l2_close(&cam);
    assert_false(f.fd_open);
}

static void test_fake_latest_and_copy(void **st)
{
    (void)st;
    fake f;
    fake_init(&f, V4L2_PIX_FMT_GREY);
    fv_v4l2_sys sys = fake_sys(&f);
    fv_v4l2_config cfg;
    fv_v4l2_config_default(&cfg, "/fake/video0");
    cfg.sys = &sys;
    cfg.width = 8;
    cfg.height = 4;
    cfg.latest_only = 1;
    cfg.copy_frames = 1;
    char err[512] = "";
    fv_v4l2 cam;
    if (fv_v4l2_open(&cam, &cfg, err, sizeof err))
        fail_msg("%s", err);
    fv_v4l2_frame fr;
    /* three frames waiting: the newest is returned, the two older handed back */
    f.ready = 3;
    f.stamp_ns = fv_time_ns() - 1000000;
    assert_int_equal(fv_v4l2_next(&cam, 100, &fr, err, sizeof err), FV_V4L2_FRAME);
    assert_frame(&fr, 2, 8, 4);
    assert_int_equal(cam.stale, 2);
    assert_int_equal(fr.stride, 8);
    for (int i = 0; i < f.n_bufs; i++) /* copied, not lent */
        assert_true(fr.luma != f.mem[i]);
    assert_int_equal(fake_queued(&f), cam.n_buffers);
    /* a flagged frame first: skipped; of the two good ones the newer wins */
    f.ready = 3;
    f.error_next = 1;
    assert_int_equal(fv_v4l2_next(&cam, 100, &fr, err, sizeof err), FV_V4L2_FRAME);
    assert_frame(&fr, 5, 8, 4);
    assert_int_equal(cam.skipped, 1);
    assert_int_equal(cam.stale, 3);
    assert_int_equal(fake_queued(&f), cam.n_buffers);
    fv_v4l2_close(&cam);
}

static void expect_fake_fails(fake *f, const char *ctrl, const char *needle)
{
    fv_v4l2_sys sys = fake_sys(f);
    fv_v4l2_config cfg;
    fv_v4l2_config_default(&cfg, "/fake/video0");
    cfg.sys = &sys;
    if (ctrl) {
        cfg.ctrls[0] = ctrl;
        cfg.n_ctrls = 1;
    }
    char err[512] = "";
    fv_v4l2 cam;
    assert_int_equal(fv_v4l2_open(&cam, &cfg, err, sizeof err), -1);
    assert_contains(err, needle);
    assert_false(f->fd_open);
    assert_int_equal(f->mapped, 0);
    fv_v4l2_close(&cam);
}

static void test_fake_errors(void **st)
{
    (void)st;
    fake f;
    fake_init(&f, V4L2_PIX_FMT_GREY);
    f.fail_sfmt = EBUSY;
    expect_fake_fails(&f, NULL, "VIDIOC_S_FMT on /fake/video0: Device or resource busy");
    fake_init(&f, V4L2_PIX_FMT_H264);
    f.formats[0] = V4L2_PIX_FMT_RGB24;
    expect_fake_fails(&f, NULL, "/fake/video0: no usable pixel format (device offers RGB3, H264; fovea wants GREY, Y16");
    fake_init(&f, V4L2_PIX_FMT_GREY);
    expect_fake_fails(&f, "focus_absolute=3",
                      "/fake/video0: no control 'focus_absolute' (it has: brightness, gain, exposure_time_absolute)");
    fake_init(&f, V4L2_PIX_FMT_GREY);
    expect_fake_fails(&f, "gain=1000", "'Gain' = 1000 is outside 0..100");
    fake_init(&f, V4L2_PIX_FMT_GREY);
    f.caps = V4L2_CAP_VIDEO_OUTPUT | V4L2_CAP_STREAMING;
    expect_fake_fails(&f, NULL, "/fake/video0 (fake): not a video capture device");
    fake_init(&f, V4L2_PIX_FMT_GREY);
    f.caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_READWRITE;
    expect_fake_fails(&f, NULL, "no streaming I/O");
    /* Device errors other than a vanished device are reported, not retried. */
    fake_init(&f, V4L2_PIX_FMT_GREY);
    fv_v4l2_sys sys = fake_sys(&f);
    fv_v4l2_config cfg;
    fv_v4l2_config_default(&cfg, "/fake/video0");
    cfg.sys = &sys;
    cfg.wait_for_device = 1;
    f.fail_sfmt = EINVAL;
    char err[512];
    fv_v4l2 cam;
    assert_int_equal(fv_v4l2_open(&cam, &cfg, err, sizeof err), -1);
    assert_contains(err, "VIDIOC_S_FMT on /fake/video0: ");
    fv_v4l2_close(&cam);
}

static void test_list_devices(void **st)
{
    (void)st;
    char dir[] = "/tmp/fovea-v4l2-dev-XXXXXX";
    assert_non_null(mkdtemp(dir));
    const char *names[] = {"video10", "video0", "video2", "videoX", "video1a", "media0", "video"};
    char p[128];
    for (size_t i = 0; i < sizeof names / sizeof *names; i++) {
        snprintf(p, sizeof p, "%s/%s", dir, names[i]);
        FILE *fp = fopen(p, "w");
        assert_non_null(fp);
        fclose(fp);
    }
    fake f;
    fake_init(&f, V4L2_PIX_FMT_GREY);
    f.deny = "/video2";
    fv_v4l2_sys sys = fake_sys(&f);
    char buf[512], want[512];
    assert_int_equal(fv_v4l2_list(dir, &sys, buf, sizeof buf), 2);
    snprintf(want, sizeof want, "%s/video0 (Fake IR eye camera), %s/video10 (Fake IR eye camera)", dir, dir);
    assert_string_equal(buf, want);
    assert_false(f.fd_open);
    f.deny = NULL;
    f.caps = V4L2_CAP_META_CAPTURE | V4L2_CAP_STREAMING; /* metadata nodes are not cameras */
    assert_int_equal(fv_v4l2_list(dir, &sys, buf, sizeof buf), 0);
    assert_string_equal(buf, "");
    for (size_t i = 0; i < sizeof names / sizeof *names; i++) {
        snprintf(p, sizeof p, "%s/%s", dir, names[i]);
        unlink(p);
    }
    rmdir(dir);
    /* The real /dev: whatever is there, the count and the text agree. */
    int n = fv_v4l2_list(NULL, NULL, buf, sizeof buf);
    assert_true(n >= 0);
    assert_int_equal(n == 0, buf[0] == 0);
    assert_int_equal(fv_v4l2_list("/nonexistent-fovea", NULL, buf, sizeof buf), 0);
}

/* ---- MJPEG ------------------------------------------------------------------------------- */

/* A smooth grey gradient (JPEG keeps it within a few levels). */
static uint8_t grad(int x, int y) { return (uint8_t)(40 + 3 * x + 5 * y); }

/* JPEG of the gradient: 1 component, or YCbCr 4:2:2 as UVC cameras send it. Caller frees. */
static unsigned char *make_jpeg(int w, int h, int ycc, unsigned long *len)
{
    struct jpeg_compress_struct c;
    struct jpeg_error_mgr e;
    c.err = jpeg_std_error(&e);
    jpeg_create_compress(&c);
    unsigned char *out = NULL;
    *len = 0;
    jpeg_mem_dest(&c, &out, len);
    c.image_width = (JDIMENSION)w;
    c.image_height = (JDIMENSION)h;
    c.input_components = ycc ? 3 : 1;
    c.in_color_space = ycc ? JCS_RGB : JCS_GRAYSCALE;
    jpeg_set_defaults(&c);
    jpeg_set_quality(&c, 95, TRUE);
    if (ycc) {
        c.comp_info[0].h_samp_factor = 2; /* 4:2:2 */
        c.comp_info[0].v_samp_factor = 1;
    }
    jpeg_start_compress(&c, TRUE);
    uint8_t row[3 * 64];
    while (c.next_scanline < c.image_height) {
        int y = (int)c.next_scanline;
        for (int x = 0; x < w; x++)
            for (int k = 0; k < c.input_components; k++)
                row[x * c.input_components + k] = grad(x, y);
        JSAMPROW r = row;
        jpeg_write_scanlines(&c, &r, 1);
    }
    jpeg_finish_compress(&c);
    jpeg_destroy_compress(&c);
    return out;
}

/* Drops every DHT segment before the scan, as UVC cameras do to save bandwidth. */
static size_t strip_dht(unsigned char *j, size_t n)
{
    size_t i = 2; /* after SOI */
    while (i + 4 <= n && j[i] == 0xFF && j[i + 1] != 0xDA) {
        size_t seg = 2 + ((size_t)j[i + 2] << 8 | j[i + 3]);
        if (j[i + 1] == 0xC4) {
            memmove(j + i, j + i + seg, n - i - seg);
            n -= seg;
        } else {
            i += seg;
        }
    }
    return n;
}

static void assert_near_grad(const uint8_t *l, size_t stride, int w, int h)
{
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            int d = (int)l[(size_t)y * stride + (size_t)x] - grad(x, y);
            if (d < -3 || d > 3)
                fail_msg("pixel (%d,%d) = %u, want %u +- 3", x, y, l[(size_t)y * stride + (size_t)x], grad(x, y));
        }
}

static void test_mjpeg_decode(void **st)
{
    (void)st;
    const int w = 24, h = 16;
    uint8_t dst[24 * 16 + 64];
    char err[256];
    for (int ycc = 0; ycc < 2; ycc++) {
        unsigned long n;
        unsigned char *j = make_jpeg(w, h, ycc, &n);
        memset(dst, 0, sizeof dst);
        if (fv_mjpeg_to_luma8(j, n, w, h, dst, w + 2, err, sizeof err))
            fail_msg("%s", err);
        assert_near_grad(dst, (size_t)w + 2, w, h);

        /* Without Huffman tables (UVC): the standard ones are assumed. */
        size_t m = strip_dht(j, n);
        assert_true(m < n);
        memset(dst, 0, sizeof dst);
        if (fv_mjpeg_to_luma8(j, m, w, h, dst, w, err, sizeof err))
            fail_msg("no DHT: %s", err);
        assert_near_grad(dst, (size_t)w, w, h);

        err[0] = 0; /* truncated: libjpeg only warns; the frame is refused */
        assert_int_equal(fv_mjpeg_to_luma8(j, m / 2, w, h, dst, w, err, sizeof err), -1);
        assert_contains(err, "MJPEG: ");
        err[0] = 0;
        assert_int_equal(fv_mjpeg_to_luma8(j, m, w + 8, h, dst, w + 8, err, sizeof err), -1);
        assert_contains(err, "24x16");
        free(j);
    }
    const uint8_t junk[] = "this is not a jpeg";
    err[0] = 0;
    assert_int_equal(fv_mjpeg_to_luma8(junk, sizeof junk, 4, 4, dst, 4, err, sizeof err), -1);
    assert_contains(err, "MJPEG: ");
    assert_int_equal(fv_mjpeg_to_luma8(junk, 0, 4, 4, dst, 4, err, sizeof err), -1);
}

static void test_fake_mjpeg_stream(void **st)
{
    (void)st;
    fake f;
    fake_init(&f, V4L2_PIX_FMT_H264); /* offers MJPG and H264: MJPG is taken */
    unsigned long n;
    unsigned char *j = make_jpeg(32, 8, 1, &n);
    size_t m = strip_dht(j, n);
    f.jpeg = j;
    f.jpeg_len = m;
    fv_v4l2_sys sys = fake_sys(&f);
    fv_v4l2_config cfg;
    fv_v4l2_config_default(&cfg, "/fake/video0");
    cfg.sys = &sys;
    cfg.width = 32;
    cfg.height = 8;
    char err[512] = "";
    fv_v4l2 cam;
    if (fv_v4l2_open(&cam, &cfg, err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(cam.fourcc, FV_PIX_MJPEG);
    fv_v4l2_frame fr;
    f.ready = 1;
    f.stamp_ns = fv_time_ns() - 1000000;
    assert_int_equal(fv_v4l2_next(&cam, 100, &fr, err, sizeof err), FV_V4L2_FRAME);
    assert_int_equal(fr.fourcc, FV_PIX_MJPEG);
    assert_int_equal(fr.stride, 32);
    assert_near_grad(fr.luma, fr.stride, 32, 8);
    /* a truncated JPEG is dropped (counted), the next good one delivered */
    f.jpeg_len = m / 2;
    f.ready = 1;
    assert_int_equal(fv_v4l2_next(&cam, 0, &fr, err, sizeof err), FV_V4L2_TIMEOUT);
    assert_int_equal(cam.skipped, 1);
    f.jpeg_len = m;
    f.ready = 1;
    assert_int_equal(fv_v4l2_next(&cam, 100, &fr, err, sizeof err), FV_V4L2_FRAME);
    assert_int_equal(fr.sequence, 2);
    assert_int_equal(fake_queued(&f), cam.n_buffers);
    fv_v4l2_close(&cam);
    free(j);
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
        fv_v4l2_frame f;
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
        cmocka_unit_test(test_fake_yuyv_stream),
        cmocka_unit_test(test_fake_grey_zero_copy),
        cmocka_unit_test(test_fake_unplug_reopen),
        cmocka_unit_test(test_fake_latest_and_copy),
        cmocka_unit_test(test_fake_errors),
        cmocka_unit_test(test_list_devices),
        cmocka_unit_test(test_mjpeg_decode),
        cmocka_unit_test(test_fake_mjpeg_stream),
        cmocka_unit_test(test_real_device),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
