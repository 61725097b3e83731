/* V4L2 capture: see v4l2.h and docs/v4l2.md. Error paths follow v4l-utils: every failing call is
 * named with the device and strerror, ioctls are retried on EINTR. */
#define _DEFAULT_SOURCE
#include "v4l2.h"
#include "base/clock.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>
#include <linux/videodev2.h>

#include "base/err.h"
#include "mjpeg.h"

_Static_assert(FV_PIX_GREY == V4L2_PIX_FMT_GREY, "GREY fourcc");
_Static_assert(FV_PIX_Y10 == V4L2_PIX_FMT_Y10, "Y10 fourcc");
_Static_assert(FV_PIX_Y12 == V4L2_PIX_FMT_Y12, "Y12 fourcc");
_Static_assert(FV_PIX_Y16 == V4L2_PIX_FMT_Y16, "Y16 fourcc");
_Static_assert(FV_PIX_YUYV == V4L2_PIX_FMT_YUYV, "YUYV fourcc");
_Static_assert(FV_PIX_UYVY == V4L2_PIX_FMT_UYVY, "UYVY fourcc");

/* Deeper formats first: they carry the most of the sensor's range before the reduction. MJPEG
 * last: decoding costs CPU time and compression blurs the pupil edge. */
static const uint32_t default_formats[] = {FV_PIX_GREY,  FV_PIX_Y16,  FV_PIX_Y12,  FV_PIX_Y10,
                                           FV_PIX_YUYV, FV_PIX_UYVY, FV_PIX_MJPEG};
#define READS "GREY, Y16, Y12, Y10, YUYV, UYVY, MJPG"

static int readable(uint32_t fourcc) { return fv_pix_supported(fourcc) || fourcc == FV_PIX_MJPEG; }


/* ---- configuration ---------------------------------------------------------------------- */

void fv_v4l2_config_default(fv_v4l2_config *cfg, const char *path)
{
    memset(cfg, 0, sizeof *cfg);
    cfg->path = path;
    cfg->width = 640;
    cfg->height = 480;
    cfg->buffers = FV_V4L2_MIN_BUFFERS;
}

char *fv_v4l2_ctrl_norm(const char *name, char *out, size_t out_len)
{
    size_t n = 0;
    for (; *name && n + 1 < out_len; name++) {
        unsigned char c = (unsigned char)*name;
        if (c >= 'A' && c <= 'Z')
            out[n++] = (char)(c - 'A' + 'a');
        else if ((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9'))
            out[n++] = (char)c;
    }
    if (out_len)
        out[n] = 0;
    return out;
}

int fv_v4l2_ctrl_parse(const char *s, char *name_out, size_t name_len, int64_t *value, char *err, size_t err_len)
{
    const char *eq = strchr(s, '=');
    if (!eq || eq == s || !eq[1])
        return fv_err(err, err_len, "control '%s': expected name=value", s);
    size_t n = (size_t)(eq - s);
    char norm[128];
    char name[128];
    snprintf(name, sizeof name, "%.*s", (int)(n < sizeof name ? n : sizeof name - 1), s);
    if (!*fv_v4l2_ctrl_norm(name, norm, sizeof norm))
        return fv_err(err, err_len, "control '%s': the name has no letters or digits", s);
    const char *v = eq + 1;
    if (!strcasecmp(v, "true") || !strcasecmp(v, "on"))
        *value = 1;
    else if (!strcasecmp(v, "false") || !strcasecmp(v, "off"))
        *value = 0;
    else {
        /* Decimal unless 0x: a leading zero is not octal here. */
        const char *d = v + (*v == '-' || *v == '+');
        int hex = d[0] == '0' && (d[1] == 'x' || d[1] == 'X');
        char *end;
        errno = 0;
        long long x = strtoll(v, &end, hex ? 16 : 10);
        if (end == v || *end || errno)
            return fv_err(err, err_len, "control '%s': value '%s' is not an integer (or true/false/on/off)", s, v);
        *value = x;
    }
    if (name_out && name_len)
        snprintf(name_out, name_len, "%s", name);
    return 0;
}

int fv_v4l2_config_validate(const fv_v4l2_config *cfg, char *err, size_t err_len)
{
    if (!cfg->path || !*cfg->path)
        return fv_err(err, err_len, "v4l2: no device path");
    if (strlen(cfg->path) >= sizeof ((fv_v4l2 *)0)->path)
        return fv_err(err, err_len, "v4l2: device path too long");
    if (cfg->width <= 0 || cfg->height <= 0 || cfg->width > 16384 || cfg->height > 16384)
        return fv_err(err, err_len, "%s: bad frame size %dx%d", cfg->path, cfg->width, cfg->height);
    if (cfg->fps < 0 || cfg->fps > 10000)
        return fv_err(err, err_len, "%s: bad frame rate %d", cfg->path, cfg->fps);
    if (cfg->buffers < FV_V4L2_MIN_BUFFERS || cfg->buffers > FV_V4L2_MAX_BUFFERS)
        return fv_err(err, err_len, "%s: %d buffers requested; need %d to %d", cfg->path, cfg->buffers,
                      FV_V4L2_MIN_BUFFERS, FV_V4L2_MAX_BUFFERS);
    if (cfg->n_formats < 0 || cfg->n_formats > FV_V4L2_MAX_FORMATS)
        return fv_err(err, err_len, "%s: bad format count %d", cfg->path, cfg->n_formats);
    for (int i = 0; i < cfg->n_formats; i++) {
        char nm[5];
        if (!readable(cfg->formats[i]))
            return fv_err(err, err_len, "%s: pixel format '%s' is not one fovea reads (" READS ")", cfg->path,
                          fv_pix_name(cfg->formats[i], nm));
        for (int j = 0; j < i; j++)
            if (cfg->formats[j] == cfg->formats[i])
                return fv_err(err, err_len, "%s: pixel format '%s' listed twice", cfg->path, fv_pix_name(cfg->formats[i], nm));
    }
    if (cfg->n_ctrls < 0 || cfg->n_ctrls > FV_V4L2_MAX_CTRLS)
        return fv_err(err, err_len, "%s: bad control count %d (at most %d)", cfg->path, cfg->n_ctrls, FV_V4L2_MAX_CTRLS);
    for (int i = 0; i < cfg->n_ctrls; i++) {
        int64_t v;
        if (!cfg->ctrls[i])
            return fv_err(err, err_len, "%s: control %d is missing", cfg->path, i);
        if (strlen(cfg->ctrls[i]) >= sizeof ((fv_v4l2 *)0)->ctrl_text[0])
            return fv_err(err, err_len, "%s: control '%.40s...' too long", cfg->path, cfg->ctrls[i]);
        if (fv_v4l2_ctrl_parse(cfg->ctrls[i], NULL, 0, &v, err, err_len))
            return -1;
    }
    return 0;
}

int fv_v4l2_config_formats(fv_v4l2_config *cfg, const char *list, char *err, size_t err_len)
{
    uint32_t f[FV_V4L2_MAX_FORMATS];
    int n = 0;
    const char *p = list;
    for (;;) {
        size_t len = strcspn(p, ",");
        char name[8];
        if (len == 0 || len > 4)
            return fv_err(err, err_len, "pixel formats '%s': expected a comma-separated list like GREY,YUYV", list);
        snprintf(name, sizeof name, "%.*s", (int)len, p);
        uint32_t x = strcasecmp(name, "MJPG") ? fv_pix_parse(name) : FV_PIX_MJPEG;
        if (!x)
            return fv_err(err, err_len, "pixel format '%s' is not one fovea reads (" READS ")", name);
        for (int i = 0; i < n; i++)
            if (f[i] == x)
                return fv_err(err, err_len, "pixel format '%s' listed twice", name);
        if (n == FV_V4L2_MAX_FORMATS)
            return fv_err(err, err_len, "pixel formats '%s': too many", list);
        f[n++] = x;
        if (!p[len])
            break;
        p += len + 1;
    }
    memcpy(cfg->formats, f, sizeof f[0] * (size_t)n);
    cfg->n_formats = n;
    return 0;
}

int fv_v4l2_config_ctrl(fv_v4l2_config *cfg, const char *s, char *err, size_t err_len)
{
    int64_t v;
    if (fv_v4l2_ctrl_parse(s, NULL, 0, &v, err, err_len))
        return -1;
    if (strlen(s) >= sizeof ((fv_v4l2 *)0)->ctrl_text[0])
        return fv_err(err, err_len, "control '%.40s...' too long", s);
    if (cfg->n_ctrls >= FV_V4L2_MAX_CTRLS)
        return fv_err(err, err_len, "too many controls (at most %d)", FV_V4L2_MAX_CTRLS);
    cfg->ctrls[cfg->n_ctrls++] = s;
    return 0;
}

int64_t fv_v4l2_backoff_ns(int attempt)
{
    const int64_t first = 50000000, cap = 2000000000;
    if (attempt < 0)
        attempt = 0;
    if (attempt >= 6) /* 50 ms << 6 = 3.2 s: past the cap (and no shift overflow for large attempts) */
        return cap;
    int64_t d = first << attempt;
    return d < cap ? d : cap;
}

/* ---- device ------------------------------------------------------------------------------ */

/* The real system calls behind fv_v4l2_sys. */
static int sys_open(void *u, const char *path, int flags) { (void)u; return open(path, flags); }
static int sys_close(void *u, int fd) { (void)u; return close(fd); }
static int sys_ioctl(void *u, int fd, unsigned long req, void *arg) { (void)u; return ioctl(fd, req, arg); }
static int sys_poll(void *u, struct pollfd *pfd, int timeout_ms) { (void)u; return poll(pfd, 1, timeout_ms); }
static void *sys_mmap(void *u, int fd, size_t length, int64_t offset)
{
    (void)u;
    void *p = mmap(NULL, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, (off_t)offset);
    return p == MAP_FAILED ? NULL : p;
}
static int sys_munmap(void *u, void *start, size_t length) { (void)u; return munmap(start, length); }
static const fv_v4l2_sys real_sys = {NULL, sys_open, sys_close, sys_ioctl, sys_poll, sys_mmap, sys_munmap};

static int xioctl(fv_v4l2 *cam, unsigned long req, void *arg)
{
    int r;
    do
        r = cam->sys.ioctl(cam->sys.user, cam->fd, req, arg);
    while (r == -1 && errno == EINTR);
    return r;
}

/* Errnos that mean the device went away (unplugged, driver unbound, USB reset): reopen. */
static int errno_gone(int e) { return e == ENODEV || e == ENXIO || e == EIO; }

/* "VIDIOC_S_FMT on /dev/video0: Invalid argument"; errno is kept for the caller. */
static int call_err(const fv_v4l2 *cam, const char *call, int e, char *err, size_t err_len)
{
    fv_err(err, err_len, "%s on %s: %s", call, cam->path, strerror(e));
    errno = e;
    return -1;
}
#define VIOCTL(cam, req, arg, err, err_len) \
    (xioctl((cam), (req), (arg)) == 0 ? 0 : call_err((cam), #req, errno, (err), (err_len)))

static void unmap_all(fv_v4l2 *cam)
{
    for (int i = 0; i < FV_V4L2_MAX_BUFFERS; i++) {
        if (cam->bufs[i].start)
            cam->sys.munmap(cam->sys.user, cam->bufs[i].start, cam->bufs[i].length);
        cam->bufs[i].start = NULL;
        cam->bufs[i].length = 0;
    }
    cam->n_buffers = 0;
}

/* Tears the stream down, keeping the configuration (for a reopen) and the luma buffer. */
static void close_stream(fv_v4l2 *cam)
{
    if (cam->fd >= 0) {
        if (cam->streaming) {
            enum v4l2_buf_type t = V4L2_BUF_TYPE_VIDEO_CAPTURE;
            xioctl(cam, VIDIOC_STREAMOFF, &t); /* fails harmlessly on a vanished device */
        }
        unmap_all(cam);
        cam->sys.close(cam->sys.user, cam->fd); /* closing also frees the driver's buffers */
    }
    cam->fd = -1;
    cam->streaming = 0;
    cam->held = -1;
}

/* v4l2-ctl's spelling of a control name ("Exposure Time, Absolute" -> exposure_time_absolute),
 * for the list of available controls in an error. */
static void ctrl_cli_name(const char *name, char *out, size_t out_len)
{
    size_t n = 0;
    int sep = 0;
    for (; *name && n + 2 < out_len; name++) {
        unsigned char c = (unsigned char)*name;
        int alnum = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
        if (!alnum) {
            sep = n > 0;
            continue;
        }
        if (sep)
            out[n++] = '_';
        sep = 0;
        out[n++] = (char)((c >= 'A' && c <= 'Z') ? c - 'A' + 'a' : c);
    }
    out[n] = 0;
}

static void list_append(char *list, size_t cap, const char *item)
{
    size_t n = strlen(list);
    if (n + strlen(item) + 8 >= cap) {
        if (!strstr(list, ", ..."))
            snprintf(list + n, cap - n, ", ...");
        return;
    }
    snprintf(list + n, cap - n, "%s%s", n ? ", " : "", item);
}

/* Finds the control called `want` (normalised names) or with id 0xNNNN; fills qc. */
static int find_ctrl(fv_v4l2 *cam, const char *want, struct v4l2_queryctrl *qc, char *err, size_t err_len)
{
    if (want[0] == '0' && (want[1] == 'x' || want[1] == 'X')) {
        char *end;
        unsigned long id = strtoul(want, &end, 16);
        memset(qc, 0, sizeof *qc);
        qc->id = (uint32_t)id;
        if (!*end && xioctl(cam, VIDIOC_QUERYCTRL, qc) == 0)
            return 0;
        if (*end || errno == EINVAL)
            return fv_err(err, err_len, "%s: no control with id %s", cam->path, want);
        return call_err(cam, "VIDIOC_QUERYCTRL", errno, err, err_len);
    }
    char key[128], norm[128], cli[64], avail[320] = "";
    fv_v4l2_ctrl_norm(want, key, sizeof key);
    memset(qc, 0, sizeof *qc);
    qc->id = V4L2_CTRL_FLAG_NEXT_CTRL;
    int found = 0;
    while (xioctl(cam, VIDIOC_QUERYCTRL, qc) == 0) {
        if (!(qc->flags & V4L2_CTRL_FLAG_DISABLED) && qc->type != V4L2_CTRL_TYPE_CTRL_CLASS) {
            char name[sizeof qc->name + 1];
            memcpy(name, qc->name, sizeof qc->name);
            name[sizeof qc->name] = 0;
            if (!strcmp(fv_v4l2_ctrl_norm(name, norm, sizeof norm), key)) {
                found = 1;
                break;
            }
            ctrl_cli_name(name, cli, sizeof cli);
            list_append(avail, sizeof avail, cli);
        }
        qc->id |= V4L2_CTRL_FLAG_NEXT_CTRL;
    }
    if (found)
        return 0;
    if (errno != EINVAL) /* EINVAL ends the enumeration; anything else is a real failure */
        return call_err(cam, "VIDIOC_QUERYCTRL", errno, err, err_len);
    return fv_err(err, err_len, "%s: no control '%s' (it has: %s)", cam->path, want, *avail ? avail : "none");
}

static int apply_ctrls(fv_v4l2 *cam, char *err, size_t err_len)
{
    for (int i = 0; i < cam->cfg.n_ctrls; i++) {
        const char *s = cam->ctrl_text[i];
        char name[128];
        int64_t v;
        struct v4l2_queryctrl qc;
        if (fv_v4l2_ctrl_parse(s, name, sizeof name, &v, err, err_len) || find_ctrl(cam, name, &qc, err, err_len))
            return -1;
        const char *qname = (const char *)qc.name;
        int qlen = (int)strnlen(qname, sizeof qc.name);
        if (qc.flags & (V4L2_CTRL_FLAG_READ_ONLY | V4L2_CTRL_FLAG_GRABBED))
            return fv_err(err, err_len, "%s: control '%.*s' is %s", cam->path, qlen, qname,
                          (qc.flags & V4L2_CTRL_FLAG_READ_ONLY) ? "read-only" : "grabbed (busy)");
        switch (qc.type) {
        case V4L2_CTRL_TYPE_INTEGER: case V4L2_CTRL_TYPE_BOOLEAN: case V4L2_CTRL_TYPE_MENU:
        case V4L2_CTRL_TYPE_INTEGER_MENU: case V4L2_CTRL_TYPE_BUTTON:
            if (qc.type != V4L2_CTRL_TYPE_BUTTON && (v < qc.minimum || v > qc.maximum))
                return fv_err(err, err_len, "%s: control '%.*s' = %lld is outside %d..%d", cam->path, qlen, qname,
                              (long long)v, qc.minimum, qc.maximum);
            break;
        case V4L2_CTRL_TYPE_INTEGER64:
            break; /* QUERYCTRL's 32-bit range cannot describe it; the driver checks */
        default:
            return fv_err(err, err_len, "%s: control '%.*s' has a type (%u) fovea cannot set", cam->path, qlen, qname, qc.type);
        }
        struct v4l2_ext_control c;
        memset(&c, 0, sizeof c);
        c.id = qc.id;
        if (qc.type == V4L2_CTRL_TYPE_INTEGER64)
            c.value64 = v;
        else
            c.value = (int32_t)v;
        struct v4l2_ext_controls cs;
        memset(&cs, 0, sizeof cs);
        cs.which = V4L2_CTRL_ID2WHICH(qc.id);
        cs.count = 1;
        cs.controls = &c;
        const char *call = "VIDIOC_S_EXT_CTRLS";
        int r = xioctl(cam, VIDIOC_S_EXT_CTRLS, &cs);
        if (r < 0 && errno == ENOTTY && qc.type != V4L2_CTRL_TYPE_INTEGER64) { /* pre-extended-controls driver */
            struct v4l2_control c1 = {.id = qc.id, .value = (int32_t)v};
            call = "VIDIOC_S_CTRL";
            r = xioctl(cam, VIDIOC_S_CTRL, &c1);
        }
        if (r < 0) {
            int e = errno;
            call_err(cam, call, e, err, err_len);
            size_t n = strlen(err);
            if (n < err_len)
                snprintf(err + n, err_len - n, " (setting '%.*s' = %lld%s)", qlen, qname, (long long)v,
                         (qc.flags & V4L2_CTRL_FLAG_INACTIVE) ? "; inactive: an automatic mode may own it" : "");
            errno = e;
            return -1;
        }
    }
    return 0;
}

/* Fewest bytes a good frame has (a JPEG's size varies: at least something). */
static size_t frame_min_bytes(const fv_v4l2 *cam)
{
    if (cam->fourcc == FV_PIX_MJPEG)
        return 1;
    return fv_pix_min_size(cam->fourcc, cam->width, cam->height, cam->bytesperline);
}

static int choose_format(fv_v4l2 *cam, uint32_t *out, char *err, size_t err_len)
{
    uint32_t have[64];
    int n = 0;
    for (;;) {
        struct v4l2_fmtdesc d;
        memset(&d, 0, sizeof d);
        d.index = (uint32_t)n;
        d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        if (xioctl(cam, VIDIOC_ENUM_FMT, &d) < 0) {
            if (errno == EINVAL)
                break; /* end of the list */
            return call_err(cam, "VIDIOC_ENUM_FMT", errno, err, err_len);
        }
        have[n++] = d.pixelformat;
        if (n == (int)(sizeof have / sizeof *have))
            break;
    }
    const uint32_t *want = cam->cfg.n_formats ? cam->cfg.formats : default_formats;
    int n_want = cam->cfg.n_formats ? cam->cfg.n_formats : (int)(sizeof default_formats / sizeof *default_formats);
    for (int i = 0; i < n_want; i++)
        for (int j = 0; j < n; j++)
            if (have[j] == want[i]) {
                *out = want[i];
                return 0;
            }
    char offered[160] = "", wanted[64] = "", nm[5];
    for (int j = 0; j < n; j++)
        list_append(offered, sizeof offered, fv_pix_name(have[j], nm));
    for (int i = 0; i < n_want; i++)
        list_append(wanted, sizeof wanted, fv_pix_name(want[i], nm));
    return fv_err(err, err_len, "%s: no usable pixel format (device offers %s; fovea wants %s)", cam->path,
                  n ? offered : "none", wanted);
}

static int set_format(fv_v4l2 *cam, uint32_t fourcc, char *err, size_t err_len)
{
    struct v4l2_format f;
    memset(&f, 0, sizeof f);
    f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    f.fmt.pix.width = (uint32_t)cam->cfg.width;
    f.fmt.pix.height = (uint32_t)cam->cfg.height;
    f.fmt.pix.pixelformat = fourcc;
    f.fmt.pix.field = V4L2_FIELD_NONE;
    if (VIOCTL(cam, VIDIOC_S_FMT, &f, err, err_len))
        return -1;
    char a[5], b[5];
    if (f.fmt.pix.pixelformat != fourcc)
        return fv_err(err, err_len, "VIDIOC_S_FMT on %s: asked for %s, the driver chose %s", cam->path,
                      fv_pix_name(fourcc, a), fv_pix_name(f.fmt.pix.pixelformat, b));
    if (f.fmt.pix.width == 0 || f.fmt.pix.height == 0 || f.fmt.pix.width > 16384 || f.fmt.pix.height > 16384)
        return fv_err(err, err_len, "VIDIOC_S_FMT on %s: the driver set a size of %ux%u", cam->path, f.fmt.pix.width,
                      f.fmt.pix.height);
    cam->fourcc = fourcc;
    cam->width = (int)f.fmt.pix.width;
    cam->height = (int)f.fmt.pix.height;
    size_t min_bpl = fv_pix_min_stride(fourcc, cam->width);
    /* Some drivers leave bytesperline 0 for packed formats: it then means no padding. */
    cam->bytesperline = f.fmt.pix.bytesperline ? f.fmt.pix.bytesperline : min_bpl;
    if (cam->bytesperline < min_bpl)
        return fv_err(err, err_len, "VIDIOC_S_FMT on %s: bytesperline %zu is below the %zu a %s row of %d needs", cam->path,
                      cam->bytesperline, min_bpl, fv_pix_name(fourcc, a), cam->width);
    size_t need = fv_pix_min_size(fourcc, cam->width, cam->height, cam->bytesperline);
    cam->sizeimage = f.fmt.pix.sizeimage > need ? f.fmt.pix.sizeimage : need;
    return 0;
}

/* Frame rate: asked for when cfg.fps > 0 and the driver can set it; read back either way. */
static int set_rate(fv_v4l2 *cam, char *err, size_t err_len)
{
    struct v4l2_streamparm p;
    memset(&p, 0, sizeof p);
    p.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    cam->fps_num = cam->fps_den = 0;
    if (xioctl(cam, VIDIOC_G_PARM, &p) < 0) {
        if (cam->cfg.fps > 0 && errno != ENOTTY && errno != EINVAL)
            return call_err(cam, "VIDIOC_G_PARM", errno, err, err_len);
        return 0; /* the driver has no say about its rate: run at whatever it delivers */
    }
    if (cam->cfg.fps > 0 && (p.parm.capture.capability & V4L2_CAP_TIMEPERFRAME)) {
        p.parm.capture.timeperframe.numerator = 1;
        p.parm.capture.timeperframe.denominator = (uint32_t)cam->cfg.fps;
        if (VIOCTL(cam, VIDIOC_S_PARM, &p, err, err_len))
            return -1;
    }
    if (p.parm.capture.timeperframe.numerator && p.parm.capture.timeperframe.denominator) {
        cam->fps_num = p.parm.capture.timeperframe.denominator;
        cam->fps_den = p.parm.capture.timeperframe.numerator;
    }
    return 0;
}

static int map_buffers(fv_v4l2 *cam, char *err, size_t err_len)
{
    struct v4l2_requestbuffers rb;
    memset(&rb, 0, sizeof rb);
    rb.count = (uint32_t)cam->cfg.buffers;
    rb.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    rb.memory = V4L2_MEMORY_MMAP;
    if (VIOCTL(cam, VIDIOC_REQBUFS, &rb, err, err_len))
        return -1;
    /* Drivers may round the count; two is the least that can stream at all. */
    if (rb.count < 2 || rb.count > FV_V4L2_MAX_BUFFERS)
        return fv_err(err, err_len, "VIDIOC_REQBUFS on %s: the driver granted %u buffers (asked for %d)", cam->path,
                      rb.count, cam->cfg.buffers);
    for (uint32_t i = 0; i < rb.count; i++) {
        struct v4l2_buffer b;
        memset(&b, 0, sizeof b);
        b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        b.memory = V4L2_MEMORY_MMAP;
        b.index = i;
        if (VIOCTL(cam, VIDIOC_QUERYBUF, &b, err, err_len))
            return -1;
        if (i == 0)
            cam->timestamps_monotonic =
                (b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
        void *p = cam->sys.mmap(cam->sys.user, cam->fd, b.length, b.m.offset);
        if (!p) {
            fv_err(err, err_len, "mmap of buffer %u (%u bytes) on %s: %s", i, b.length, cam->path, strerror(errno));
            return -1;
        }
        cam->bufs[i].start = p;
        cam->bufs[i].length = b.length;
        cam->n_buffers = (int)i + 1;
        if (b.length < frame_min_bytes(cam))
            return fv_err(err, err_len, "VIDIOC_QUERYBUF on %s: buffer %u holds %u bytes, a frame needs %zu", cam->path, i,
                          b.length, frame_min_bytes(cam));
    }
    for (int i = 0; i < cam->n_buffers; i++) {
        struct v4l2_buffer b;
        memset(&b, 0, sizeof b);
        b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        b.memory = V4L2_MEMORY_MMAP;
        b.index = (uint32_t)i;
        if (VIOCTL(cam, VIDIOC_QBUF, &b, err, err_len))
            return -1;
    }
    return 0;
}

/* The whole open sequence. On failure the stream is torn down and *e_out holds the errno of the
 * failing call (0 when it was a mismatch rather than a failed call). */
static int open_stream(fv_v4l2 *cam, int *e_out, char *err, size_t err_len)
{
    *e_out = 0;
    /* Non-blocking: DQBUF must never stall the caller beyond its poll timeout. */
    cam->fd = cam->sys.open(cam->sys.user, cam->path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (cam->fd < 0) {
        *e_out = errno;
        return fv_err(err, err_len, "open on %s: %s", cam->path, strerror(errno));
    }
    struct v4l2_capability cap;
    memset(&cap, 0, sizeof cap);
    if (xioctl(cam, VIDIOC_QUERYCAP, &cap) < 0) {
        *e_out = errno;
        call_err(cam, "VIDIOC_QUERYCAP", errno, err, err_len);
        if (*e_out == ENOTTY) {
            size_t n = strlen(err);
            if (n < err_len)
                snprintf(err + n, err_len - n, " (not a V4L2 device)");
        }
        goto fail;
    }
    snprintf(cam->driver, sizeof cam->driver, "%.*s", (int)strnlen((const char *)cap.driver, sizeof cap.driver), (const char *)cap.driver);
    snprintf(cam->card, sizeof cam->card, "%.*s", (int)strnlen((const char *)cap.card, sizeof cap.card), (const char *)cap.card);
    snprintf(cam->bus_info, sizeof cam->bus_info, "%.*s", (int)strnlen((const char *)cap.bus_info, sizeof cap.bus_info),
             (const char *)cap.bus_info);
    /* device_caps describe this node; capabilities the whole physical device. */
    uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
        fv_err(err, err_len, "%s (%s): not a video capture device (capabilities 0x%08x%s)", cam->path, cam->driver, caps,
               (caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE) ? "; multi-planar capture is not supported yet" : "");
        goto fail;
    }
    if (!(caps & V4L2_CAP_STREAMING)) {
        fv_err(err, err_len, "%s (%s): no streaming I/O (capabilities 0x%08x)", cam->path, cam->driver, caps);
        goto fail;
    }
    uint32_t fourcc = 0;
    if (choose_format(cam, &fourcc, err, err_len) || set_format(cam, fourcc, err, err_len) ||
        set_rate(cam, err, err_len) || apply_ctrls(cam, err, err_len) || map_buffers(cam, err, err_len)) {
        *e_out = errno;
        goto fail;
    }
    if (cam->fourcc != FV_PIX_GREY || cam->cfg.copy_frames) {
        size_t need = (size_t)cam->width * (size_t)cam->height;
        if (need > cam->luma_size) {
            uint8_t *p = realloc(cam->luma, need);
            if (!p) {
                fv_err(err, err_len, "%s: out of memory for a %dx%d frame", cam->path, cam->width, cam->height);
                goto fail;
            }
            cam->luma = p;
            cam->luma_size = need;
        }
    }
    enum v4l2_buf_type t = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (VIOCTL(cam, VIDIOC_STREAMON, &t, err, err_len)) {
        *e_out = errno;
        goto fail;
    }
    cam->streaming = 1;
    return 0;
fail:
    close_stream(cam);
    return -1;
}

int fv_v4l2_open(fv_v4l2 *cam, const fv_v4l2_config *cfg, char *err, size_t err_len)
{
    memset(cam, 0, sizeof *cam);
    cam->fd = -1;
    cam->held = -1;
    if (fv_v4l2_config_validate(cfg, err, err_len))
        return -1;
    /* Own copies: the stream is renegotiated from them on every reopen. */
    cam->cfg = *cfg;
    cam->sys = cfg->sys ? *cfg->sys : real_sys;
    cam->cfg.sys = NULL;
    snprintf(cam->path, sizeof cam->path, "%s", cfg->path);
    for (int i = 0; i < cfg->n_ctrls; i++)
        snprintf(cam->ctrl_text[i], sizeof cam->ctrl_text[i], "%s", cfg->ctrls[i]);
    cam->cfg.path = NULL;
    memset(cam->cfg.ctrls, 0, sizeof cam->cfg.ctrls);
    int e;
    if (open_stream(cam, &e, cam->last_err, sizeof cam->last_err) == 0)
        return 0;
    if (cfg->wait_for_device && (e == ENOENT || e == ENODEV || e == ENXIO)) {
        cam->gone = 1;
        cam->next_try_ns = fv_time_ns() + fv_v4l2_backoff_ns(0);
        return 0;
    }
    fv_err(err, err_len, "%s", cam->last_err);
    fv_v4l2_close(cam);
    return -1;
}

void fv_v4l2_close(fv_v4l2 *cam)
{
    close_stream(cam);
    free(cam->luma);
    cam->luma = NULL;
    cam->luma_size = 0;
    cam->fd = -1;
    cam->gone = 0;
}

/* The device vanished: drop the stream now, first reopen attempt after the first back-off. */
static fv_v4l2_status go_gone(fv_v4l2 *cam, const char *call, const char *why, char *err, size_t err_len)
{
    close_stream(cam);
    cam->gone = 1;
    cam->reopen_attempts = 0;
    cam->next_try_ns = fv_time_ns() + fv_v4l2_backoff_ns(0);
    fv_err(cam->last_err, sizeof cam->last_err, "%s on %s: %s", call, cam->path, why);
    fv_err(err, err_len, "%s (device gone; reopening)", cam->last_err);
    return FV_V4L2_GONE;
}

/* Reopen attempts due before the deadline; sleeps between them. 0 once streaming again,
 * -1 with the state of affairs in err otherwise. */
static int reopen(fv_v4l2 *cam, int64_t deadline_ns, char *err, size_t err_len)
{
    for (;;) {
        if (fv_time_ns() >= cam->next_try_ns) {
            int e;
            if (open_stream(cam, &e, cam->last_err, sizeof cam->last_err) == 0) {
                cam->gone = 0;
                cam->reopen_attempts = 0;
                cam->reopens++;
                cam->last_err[0] = 0;
                return 0;
            }
            cam->next_try_ns = fv_time_ns() + fv_v4l2_backoff_ns(++cam->reopen_attempts);
        }
        /* Sleep to the next attempt or the caller's deadline, whichever is first: a tracking loop
         * calling next() with a timeout must not spin while the device is away. */
        int64_t now = fv_time_ns();
        if (now >= deadline_ns)
            break;
        int64_t until = cam->next_try_ns < deadline_ns ? cam->next_try_ns : deadline_ns;
        struct timespec ts = {(time_t)(until / 1000000000), (long)(until % 1000000000)};
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR)
            ;
    }
    int64_t wait = cam->next_try_ns - fv_time_ns();
    fv_err(err, err_len, "%s: device gone; %d reopen attempts failed, next in %lld ms; last error: %s", cam->path,
           cam->reopen_attempts, (long long)(wait > 0 ? wait / 1000000 : 0), cam->last_err);
    return -1;
}

static int requeue(fv_v4l2 *cam, int index)
{
    struct v4l2_buffer b;
    memset(&b, 0, sizeof b);
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = (uint32_t)index;
    return xioctl(cam, VIDIOC_QBUF, &b);
}

static size_t buffer_used(const fv_v4l2 *cam, const struct v4l2_buffer *b)
{
    size_t len = cam->bufs[b->index].length;
    size_t used = b->bytesused ? b->bytesused : len; /* 0 from old drivers means "all of it" */
    return used < len ? used : len;
}

/* Not flagged bad by the driver and long enough (MJPEG is checked by decoding it). */
static int buffer_ok(const fv_v4l2 *cam, const struct v4l2_buffer *b)
{
    return !(b->flags & V4L2_BUF_FLAG_ERROR) && buffer_used(cam, b) >= frame_min_bytes(cam);
}

/* A frame handed back unused because the driver flagged it or it is short: counted, and
 * last_err says why (for the caller's diagnostics). */
static void note_skip(fv_v4l2 *cam, const struct v4l2_buffer *b)
{
    cam->skipped++;
    fv_err(cam->last_err, sizeof cam->last_err, "%s: frame %u skipped: %s", cam->path, b->sequence,
           (b->flags & V4L2_BUF_FLAG_ERROR) ? "the driver flagged the buffer bad (V4L2_BUF_FLAG_ERROR)"
                                            : "shorter than a whole frame");
}

/* latest_only: while more frames are already waiting, hand the older one back and take the newer,
 * so the tracker sees the freshest eye image. Failures here are left for the next poll/DQBUF to
 * report (a vanished device fails those too); *b stays a good buffer throughout. */
static void drain_to_newest(fv_v4l2 *cam, struct v4l2_buffer *b)
{
    for (;;) {
        struct pollfd pfd = {.fd = cam->fd, .events = POLLIN};
        if (cam->sys.poll(cam->sys.user, &pfd, 0) <= 0 || !(pfd.revents & POLLIN))
            return;
        struct v4l2_buffer nb;
        memset(&nb, 0, sizeof nb);
        nb.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        nb.memory = V4L2_MEMORY_MMAP;
        if (xioctl(cam, VIDIOC_DQBUF, &nb) < 0 || nb.index >= (uint32_t)cam->n_buffers)
            return;
        if (!buffer_ok(cam, &nb)) {
            note_skip(cam, &nb);
            if (requeue(cam, (int)nb.index) < 0)
                return;
            continue;
        }
        if (requeue(cam, (int)b->index) < 0) {
            /* keep the newer frame; the older buffer is lost to the queue until a reopen */
            *b = nb;
            return;
        }
        *b = nb;
        cam->stale++;
    }
}

fv_v4l2_status fv_v4l2_next(fv_v4l2 *cam, int timeout_ms, fv_v4l2_frame *out, char *err, size_t err_len)
{
    int64_t deadline = fv_time_ns() + (int64_t)(timeout_ms > 0 ? timeout_ms : 0) * 1000000;
    if (cam->held >= 0) { /* the zero-copy frame lent by the previous call goes back */
        int i = cam->held;
        cam->held = -1;
        if (requeue(cam, i) < 0) {
            int e = errno;
            if (errno_gone(e))
                return go_gone(cam, "VIDIOC_QBUF", strerror(e), err, err_len);
            call_err(cam, "VIDIOC_QBUF", e, err, err_len);
            return FV_V4L2_ERROR;
        }
    }
    for (;;) {
        if (cam->gone && reopen(cam, deadline, err, err_len))
            return FV_V4L2_GONE;
        if (cam->fd < 0) {
            fv_err(err, err_len, "%s: camera not open", cam->path[0] ? cam->path : "v4l2");
            return FV_V4L2_ERROR;
        }
        int64_t now = fv_time_ns();
        int ms = deadline > now ? (int)((deadline - now + 999999) / 1000000) : 0;
        struct pollfd pfd = {.fd = cam->fd, .events = POLLIN};
        int r = cam->sys.poll(cam->sys.user, &pfd, ms);
        if (r < 0) {
            if (errno == EINTR)
                continue;
            call_err(cam, "poll", errno, err, err_len);
            return FV_V4L2_ERROR;
        }
        if (r == 0)
            return FV_V4L2_TIMEOUT;
        struct v4l2_buffer b;
        memset(&b, 0, sizeof b);
        b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        b.memory = V4L2_MEMORY_MMAP;
        if (xioctl(cam, VIDIOC_DQBUF, &b) < 0) {
            int e = errno;
            if (e == EAGAIN && !(pfd.revents & (POLLERR | POLLHUP))) {
                if (fv_time_ns() >= deadline)
                    return FV_V4L2_TIMEOUT;
                continue; /* woken without a buffer */
            }
            if (e == EAGAIN) /* POLLERR/POLLHUP with nothing to dequeue: the queue is dead; reopen */
                return go_gone(cam, "poll", "error condition with no buffer to dequeue", err, err_len);
            if (errno_gone(e))
                return go_gone(cam, "VIDIOC_DQBUF", strerror(e), err, err_len);
            call_err(cam, "VIDIOC_DQBUF", e, err, err_len);
            return FV_V4L2_ERROR;
        }
        if (b.index >= (uint32_t)cam->n_buffers) {
            fv_err(err, err_len, "VIDIOC_DQBUF on %s: buffer index %u out of range", cam->path, b.index);
            return FV_V4L2_ERROR;
        }
        const int bad_buf = !buffer_ok(cam, &b);
        int bad = bad_buf;
        if (!bad && cam->cfg.latest_only)
            drain_to_newest(cam, &b);
        int64_t t_deq = fv_time_ns();
        size_t used = buffer_used(cam, &b);
        const uint8_t *src = cam->bufs[b.index].start;
        if (!bad && cam->fourcc == FV_PIX_MJPEG)
            bad = fv_mjpeg_to_luma8(src, used, cam->width, cam->height, cam->luma, (size_t)cam->width, cam->last_err,
                                    sizeof cam->last_err) != 0;
        if (bad) {
            /* A corrupted or short frame (USB packet loss): hand it back and wait for the next
             * (an undecodable MJPEG frame's reason is already in last_err). */
            if (bad_buf)
                note_skip(cam, &b);
            else
                cam->skipped++;
            if (requeue(cam, (int)b.index) < 0) {
                int e = errno;
                if (errno_gone(e))
                    return go_gone(cam, "VIDIOC_QBUF", strerror(e), err, err_len);
                call_err(cam, "VIDIOC_QBUF", e, err, err_len);
                return FV_V4L2_ERROR;
            }
            if (fv_time_ns() >= deadline)
                return FV_V4L2_TIMEOUT;
            continue;
        }
        memset(out, 0, sizeof *out);
        out->width = cam->width;
        out->height = cam->height;
        out->sequence = b.sequence;
        out->fourcc = cam->fourcc;
        int mono = (b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
        int64_t t = (int64_t)b.timestamp.tv_sec * 1000000000 + (int64_t)b.timestamp.tv_usec * 1000;
        /* A monotonic stamp from the future is a driver bug: don't trust it. (An old one is not:
         * the frame may have waited in the queue while the caller was busy.) */
        if (mono && t > 0 && t <= t_deq) {
            out->t_ns = t;
            out->t_from_driver = 1;
        } else {
            out->t_ns = t_deq;
        }
        cam->timestamps_monotonic = mono;
        if (cam->fourcc == FV_PIX_GREY && !cam->cfg.copy_frames) {
            /* Zero-copy: the driver's buffer is lent until the next call. */
            out->luma = src;
            out->stride = cam->bytesperline;
            cam->held = (int)b.index;
            return FV_V4L2_FRAME;
        }
        if (cam->fourcc != FV_PIX_MJPEG) /* (MJPEG was decoded above) */
            fv_pix_to_luma8(cam->fourcc, src, used, cam->bytesperline, cam->width, cam->height, cam->luma,
                            (size_t)cam->width);
        out->luma = cam->luma;
        out->stride = (size_t)cam->width;
        if (requeue(cam, (int)b.index) < 0) {
            int e = errno;
            if (errno_gone(e)) /* this frame is good; the next call reports the loss */
                go_gone(cam, "VIDIOC_QBUF", strerror(e), err, err_len);
            else {
                call_err(cam, "VIDIOC_QBUF", e, err, err_len);
                return FV_V4L2_ERROR;
            }
        }
        return FV_V4L2_FRAME;
    }
}

static int cmp_int(const void *a, const void *b)
{
    int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

int fv_v4l2_list(const char *dir, const fv_v4l2_sys *sys, char *buf, size_t len)
{
    if (!dir)
        dir = "/dev";
    if (len)
        buf[0] = 0;
    int nums[256], n = 0;
    DIR *d = opendir(dir);
    if (!d)
        return 0;
    struct dirent *e;
    while ((e = readdir(d)) && n < (int)(sizeof nums / sizeof *nums)) {
        const char *p = e->d_name;
        if (strncmp(p, "video", 5) || p[5] < '0' || p[5] > '9' || strlen(p) > 9)
            continue;
        char *end;
        long k = strtol(p + 5, &end, 10);
        if (!*end)
            nums[n++] = (int)k;
    }
    closedir(d);
    qsort(nums, (size_t)n, sizeof *nums, cmp_int);
    fv_v4l2 probe; /* only path, fd and sys are used (xioctl's EINTR retry) */
    memset(&probe, 0, sizeof probe);
    probe.sys = sys ? *sys : real_sys;
    int found = 0;
    for (int i = 0; i < n; i++) {
        snprintf(probe.path, sizeof probe.path, "%s/video%d", dir, nums[i]);
        probe.fd = probe.sys.open(probe.sys.user, probe.path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
        if (probe.fd < 0)
            continue;
        struct v4l2_capability cap;
        memset(&cap, 0, sizeof cap);
        int ok = xioctl(&probe, VIDIOC_QUERYCAP, &cap) == 0;
        probe.sys.close(probe.sys.user, probe.fd);
        uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
        if (!ok || !(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING))
            continue; /* metadata and output nodes, codecs */
        size_t used = strlen(buf);
        if (used < len)
            snprintf(buf + used, len - used, "%s%s (%.*s)", found ? ", " : "", probe.path,
                     (int)strnlen((const char *)cap.card, sizeof cap.card), (const char *)cap.card);
        found++;
    }
    return found;
}

int fv_v4l2_fd(const fv_v4l2 *cam) { return cam->gone ? -1 : cam->fd; }

void fv_v4l2_describe(const fv_v4l2 *cam, char *buf, size_t len)
{
    if (cam->gone) {
        snprintf(buf, len, "%s: gone, %d reopen attempts so far", cam->path, cam->reopen_attempts);
        return;
    }
    if (cam->fd < 0) {
        snprintf(buf, len, "%s: not open", cam->path);
        return;
    }
    char nm[5], rate[32] = "driver's rate";
    if (cam->fps_num && cam->fps_den)
        snprintf(rate, sizeof rate, "%.2f fps", (double)cam->fps_num / cam->fps_den);
    snprintf(buf, len, "%s (%s, \"%s\", %s): %s %dx%d, %zu bytes/line, %s, %d buffers, %s timestamps", cam->path,
             cam->driver, cam->card, cam->bus_info, fv_pix_name(cam->fourcc, nm), cam->width, cam->height,
             cam->bytesperline, rate, cam->n_buffers,
             cam->timestamps_monotonic ? "driver monotonic" : "dequeue-time (driver's are not monotonic)");
}
