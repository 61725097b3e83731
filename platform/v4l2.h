/* fovea platform: V4L2 capture of the infrared eye camera.
 *
 *   fv_v4l2_config cfg;
 *   fv_v4l2_config_default(&cfg, "/dev/v4l/by-id/usb-...-video-index0");
 *   fv_v4l2 cam;
 *   if (fv_v4l2_open(&cam, &cfg, err, sizeof err)) ...                  // one-line reason in err
 *   for (;;) {
 *       fv_v4l2_frame f;
 *       switch (fv_v4l2_next(&cam, 5, &f, err, sizeof err)) {           // waits at most 5 ms
 *       case FV_V4L2_FRAME:   track(f.luma, f.width, f.height, f.stride, f.t_ns); break;
 *       case FV_V4L2_TIMEOUT: break;                                    // no new frame yet
 *       case FV_V4L2_GONE:    break;   // unplugged: keep the last good gaze; next() reopens it
 *       case FV_V4L2_ERROR:   ...      // err says which call failed on which device and why
 *       }
 *   }
 *   fv_v4l2_close(&cam);
 *
 * Memory-mapped streaming I/O, single-planar capture devices. One camera is used by one thread at
 * a time (no locks inside); there is no global state. See docs/v4l2.md. */
#ifndef FOVEA_V4L2_H
#define FOVEA_V4L2_H

#include <stddef.h>
#include <stdint.h>

#include "mjpeg.h"
#include "base/clock.h"
#include "pixfmt.h"

struct pollfd;

/* The system calls a camera makes. NULL in the config means the real ones; tests substitute a
 * fake device. Each returns like the call it stands for (errno set on failure), except mmap,
 * which returns NULL on failure. */
typedef struct fv_v4l2_sys {
    void *user;
    int (*open)(void *user, const char *path, int flags);
    int (*close)(void *user, int fd);
    int (*ioctl)(void *user, int fd, unsigned long req, void *arg);
    int (*poll)(void *user, struct pollfd *pfd, int timeout_ms); /* one descriptor */
    void *(*mmap)(void *user, int fd, size_t length, int64_t offset);
    int (*munmap)(void *user, void *start, size_t length);
} fv_v4l2_sys;

#define FV_V4L2_MAX_FORMATS 8
#define FV_V4L2_MAX_CTRLS 16
#define FV_V4L2_MAX_BUFFERS 32
#define FV_V4L2_MIN_BUFFERS 4

typedef struct fv_v4l2_config {
    const char *path;              /* device node; copied by fv_v4l2_open */
    int width, height;             /* requested size; the driver may pick the nearest it has */
    int fps;                       /* requested frame rate; 0 = leave the driver's */
    uint32_t formats[FV_V4L2_MAX_FORMATS]; /* preferred pixel formats, best first (FV_PIX_*) */
    int n_formats;                 /* 0 = GREY, Y16, Y12, Y10, YUYV, UYVY, MJPG */
    int buffers;                   /* mmap buffers to request, FV_V4L2_MIN_BUFFERS..MAX_BUFFERS */
    const char *ctrls[FV_V4L2_MAX_CTRLS]; /* "name=value", applied in order; copied by open */
    int n_ctrls;
    int wait_for_device;           /* 1: a missing device at open is not an error: the camera
                                    * starts FV_V4L2_GONE and next() keeps trying to open it */
    int latest_only;               /* 1: when several frames are waiting, return the newest and
                                    * hand the older back (lowest gaze latency; cam.stale counts) */
    int copy_frames;               /* 1: copy GREY frames too instead of lending the driver's
                                    * buffer (for drivers whose buffers are uncached: slow reads) */
    const fv_v4l2_sys *sys;        /* NULL = the real system calls (copied by open) */
} fv_v4l2_config;

/* 640x480, driver's frame rate, the default formats, 4 buffers, no controls. */
void fv_v4l2_config_default(fv_v4l2_config *cfg, const char *path);
/* 0, or -1 naming the bad field (no path, size <= 0, fps < 0, buffers out of range, unsupported
 * or repeated format, malformed control). fv_v4l2_open calls it too. */
int fv_v4l2_config_validate(const fv_v4l2_config *cfg, char *err, size_t err_len);
/* Command-line helpers: "GREY,YUYV" replaces the format list; "name=value" is appended to the
 * controls (the string is kept by pointer, as argv strings are). 0, or -1 with a reason. */
int fv_v4l2_config_formats(fv_v4l2_config *cfg, const char *list, char *err, size_t err_len);
int fv_v4l2_config_ctrl(fv_v4l2_config *cfg, const char *name_eq_value, char *err, size_t err_len);

/* One camera frame reduced to 8-bit luma. */
typedef struct fv_v4l2_frame {
    const uint8_t *luma;   /* width x height, rows stride bytes apart; valid until the next
                            * fv_v4l2_next or fv_v4l2_close on the same camera */
    int width, height;
    size_t stride;
    uint32_t sequence;     /* the driver's frame counter (gaps = frames the driver dropped) */
    int64_t t_ns;          /* capture time on CLOCK_MONOTONIC (fv_time_ns's clock) */
    int t_from_driver;     /* 1: the driver's buffer timestamp; 0: taken at dequeue (the driver's
                            * timestamps are not monotonic, or it gave none) */
    uint32_t fourcc;       /* the pixel format the luma was reduced from */
} fv_v4l2_frame;

typedef enum {
    FV_V4L2_ERROR = -1,    /* err says what failed; the camera stays open (call close) */
    FV_V4L2_FRAME = 0,     /* *out filled */
    FV_V4L2_TIMEOUT = 1,   /* no frame within timeout_ms */
    FV_V4L2_GONE = 2,      /* device vanished (ENODEV/EIO) or not back yet; being reopened */
} fv_v4l2_status;

typedef struct fv_v4l2_buf {
    void *start;
    size_t length;
} fv_v4l2_buf;

/* A camera. All fields are read-only for callers; those above "private" describe the stream that
 * is open (they change when a reopened device negotiates differently). */
typedef struct fv_v4l2 {
    char path[4096];
    char driver[16], card[32], bus_info[32];
    uint32_t fourcc;            /* negotiated pixel format */
    int width, height;
    size_t bytesperline, sizeimage;
    uint32_t fps_num, fps_den;  /* frame interval's inverse; 0/0 if the driver doesn't say */
    int n_buffers;              /* granted by the driver */
    int timestamps_monotonic;   /* 1: frames carry the driver's CLOCK_MONOTONIC timestamps */
    int gone;                   /* 1 between a vanished device and its successful reopen */
    int reopen_attempts;        /* failed reopen attempts since it went away */
    long reopens;               /* successful reopens since fv_v4l2_open */
    long stale;                 /* frames passed over for a newer one (latest_only) */
    long skipped;               /* frames dropped as corrupt: flagged by the driver, short, or
                                 * (MJPEG) undecodable; the reason of the last is in last_err */
    /* private */
    fv_v4l2_sys sys;
    int fd;
    int streaming;
    int held;                   /* buffer lent to the caller as a zero-copy frame, or -1 */
    int64_t next_try_ns;
    char last_err[512];         /* why it went away, then the last reopen failure */
    fv_v4l2_config cfg;         /* with path and ctrls pointing into the strings below */
    char ctrl_text[FV_V4L2_MAX_CTRLS][128];
    fv_v4l2_buf bufs[FV_V4L2_MAX_BUFFERS];
    uint8_t *luma;              /* conversion target for formats other than GREY */
    size_t luma_size;
} fv_v4l2;

/* Opens cfg->path (cam: fresh or closed), checks it is a streaming capture device, negotiates
 * format, size and frame rate, applies the controls, maps the buffers and starts streaming. On
 * failure the camera is left closed (fv_v4l2_close is harmless) and err names the call, the
 * device and the reason, e.g. "VIDIOC_QUERYCAP on /dev/null: Inappropriate ioctl for device (not a V4L2 device)". */
int fv_v4l2_open(fv_v4l2 *cam, const fv_v4l2_config *cfg, char *err, size_t err_len);

/* Waits at most timeout_ms (0 = just look; negative counts as 0) for the next frame. While the
 * device is gone it tries to reopen it on the fv_v4l2_backoff_ns schedule, sleeping only within
 * timeout_ms, and returns FV_V4L2_GONE with the last reopen failure in err. */
fv_v4l2_status fv_v4l2_next(fv_v4l2 *cam, int timeout_ms, fv_v4l2_frame *out, char *err, size_t err_len);

/* Stops streaming, unmaps and closes. Safe after a failed fv_v4l2_open and when called twice (not
 * on a camera never passed to fv_v4l2_open). The struct must not be copied while open. */
void fv_v4l2_close(fv_v4l2 *cam);

/* The descriptor to poll (POLLIN) beside others, e.g. a vsync GPIO line; -1 while gone. It
 * changes on a reopen: fetch it again after every fv_v4l2_next. */
int fv_v4l2_fd(const fv_v4l2 *cam);

/* The capture devices (streaming, single-planar) among DIR/videoN (dir NULL = "/dev"), by number,
 * as "/dev/video0 (card), /dev/video2 (card)" into buf (truncated to len), for messages such as
 * "no camera at X; capture devices here: ...". Nodes that cannot be opened are passed over.
 * sys as in the config (NULL = the real calls). Returns how many were found. */
int fv_v4l2_list(const char *dir, const fv_v4l2_sys *sys, char *buf, size_t len);

/* One line about the open stream: device, driver, format, size, rate, buffers, timestamp source. */
void fv_v4l2_describe(const fv_v4l2 *cam, char *buf, size_t len);

/* Reopen back-off: the delay before reopen attempt `attempt` (0 = first) after the device went
 * away: 50 ms doubling to at most 2 s. Pure. */
int64_t fv_v4l2_backoff_ns(int attempt);

/* Control names are compared after fv_v4l2_ctrl_norm: ASCII letters lower-cased, digits kept,
 * everything else (spaces, '_', ',', '-', '(', ')') dropped, so "exposure_time_absolute",
 * "Exposure Time, Absolute" and "exposure-time (absolute)" all read "exposuretimeabsolute".
 * Writes at most out_len - 1 characters plus the terminator; returns out. */
char *fv_v4l2_ctrl_norm(const char *name, char *out, size_t out_len);

/* Splits "name=value" (value a decimal or 0x integer, or true/false/on/off). 0, or -1 with a
 * reason. name_out gets the name part (truncated to name_len - 1). */
int fv_v4l2_ctrl_parse(const char *s, char *name_out, size_t name_len, int64_t *value, char *err, size_t err_len);

#endif
