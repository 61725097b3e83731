/* DRM/KMS display: dumb buffers, double buffered, page flips with their events. */
#include "display.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "base/err.h"

#ifdef FV_HAVE_DRM
#include <xf86drm.h>
#include <xf86drmMode.h>

typedef struct {
    uint32_t handle, fb_id, pitch;
    uint64_t size;
    uint8_t *map;
} dumb_buf;

struct fv_kms {
    int fd;
    uint32_t conn_id, crtc_id;
    drmModeModeInfo mode;
    drmModeCrtc *saved; /* CRTC as found, restored on close */
    dumb_buf buf[2];
    int front;          /* buffer on screen (or being flipped to) */
    int flip_pending;
    int64_t flip_t_ns;
};

static int buf_create(fv_kms *k, dumb_buf *b, char *err, size_t err_len)
{
    struct drm_mode_create_dumb c = {.width = k->mode.hdisplay, .height = k->mode.vdisplay, .bpp = 32};
    if (drmIoctl(k->fd, DRM_IOCTL_MODE_CREATE_DUMB, &c))
        return fv_err(err, err_len, "DRM_IOCTL_MODE_CREATE_DUMB %ux%u: %s", c.width, c.height, strerror(errno));
    b->handle = c.handle;
    b->pitch = c.pitch;
    b->size = c.size;
    if (drmModeAddFB(k->fd, c.width, c.height, 24, 32, c.pitch, c.handle, &b->fb_id))
        return fv_err(err, err_len, "drmModeAddFB: %s", strerror(errno));
    struct drm_mode_map_dumb m = {.handle = c.handle};
    if (drmIoctl(k->fd, DRM_IOCTL_MODE_MAP_DUMB, &m))
        return fv_err(err, err_len, "DRM_IOCTL_MODE_MAP_DUMB: %s", strerror(errno));
    void *p = mmap(NULL, (size_t)c.size, PROT_READ | PROT_WRITE, MAP_SHARED, k->fd, (off_t)m.offset);
    if (p == MAP_FAILED)
        return fv_err(err, err_len, "mmap of a dumb buffer: %s", strerror(errno));
    b->map = p;
    memset(b->map, 0, (size_t)b->size);
    return 0;
}

static void buf_destroy(fv_kms *k, dumb_buf *b)
{
    if (b->map)
        munmap(b->map, (size_t)b->size);
    if (b->fb_id)
        drmModeRmFB(k->fd, b->fb_id);
    if (b->handle) {
        struct drm_mode_destroy_dumb d = {.handle = b->handle};
        drmIoctl(k->fd, DRM_IOCTL_MODE_DESTROY_DUMB, &d);
    }
    memset(b, 0, sizeof *b);
}

/* A CRTC the connector can drive: its encoder's current one, else the first possible one. */
static int find_crtc(int fd, drmModeRes *res, drmModeConnector *conn, uint32_t *crtc_id)
{
    if (conn->encoder_id) {
        drmModeEncoder *e = drmModeGetEncoder(fd, conn->encoder_id);
        if (e) {
            uint32_t c = e->crtc_id;
            drmModeFreeEncoder(e);
            if (c) {
                *crtc_id = c;
                return 0;
            }
        }
    }
    for (int i = 0; i < conn->count_encoders; i++) {
        drmModeEncoder *e = drmModeGetEncoder(fd, conn->encoders[i]);
        if (!e)
            continue;
        for (int j = 0; j < res->count_crtcs; j++)
            if (e->possible_crtcs & (1u << j)) {
                *crtc_id = res->crtcs[j];
                drmModeFreeEncoder(e);
                return 0;
            }
        drmModeFreeEncoder(e);
    }
    return -1;
}

int fv_kms_open(fv_kms **out, const char *card, const char *mode, char *err, size_t err_len)
{
    *out = NULL;
    char path[256];
    if (!card || !*card)
        card = "/dev/dri/card0";
    if (card[0] >= '0' && card[0] <= '9') /* "1" */
        snprintf(path, sizeof path, "/dev/dri/card%s", card);
    else if (!strchr(card, '/')) /* "card1" */
        snprintf(path, sizeof path, "/dev/dri/%s", card);
    else
        snprintf(path, sizeof path, "%s", card);
    int mw = 0, mh = 0;
    if (mode && (sscanf(mode, "%dx%d", &mw, &mh) != 2 || mw <= 0 || mh <= 0))
        return fv_err(err, err_len, "kms mode %s: want WxH", mode);
    fv_kms *k = calloc(1, sizeof *k);
    if (!k)
        return fv_err(err, err_len, "kms: out of memory");
    k->fd = open(path, O_RDWR | O_CLOEXEC);
    if (k->fd < 0) {
        fv_err(err, err_len, "open(%s): %s", path, strerror(errno));
        free(k);
        return -1;
    }
    drmModeRes *res = drmModeGetResources(k->fd);
    if (!res) {
        fv_err(err, err_len, "drmModeGetResources(%s): %s", path, strerror(errno));
        goto bad;
    }
    drmModeConnector *conn = NULL;
    for (int i = 0; i < res->count_connectors && !conn; i++) {
        drmModeConnector *c = drmModeGetConnector(k->fd, res->connectors[i]);
        if (c && c->connection == DRM_MODE_CONNECTED && c->count_modes > 0)
            conn = c;
        else if (c)
            drmModeFreeConnector(c);
    }
    if (!conn) {
        drmModeFreeResources(res);
        fv_err(err, err_len, "kms %s: no connected connector with a mode", path);
        goto bad;
    }
    int mi = -1;
    for (int i = 0; i < conn->count_modes; i++) {
        const drmModeModeInfo *m = &conn->modes[i];
        if (mode ? (m->hdisplay == mw && m->vdisplay == mh) : (m->type & DRM_MODE_TYPE_PREFERRED) != 0) {
            mi = i;
            break;
        }
    }
    if (mi < 0 && mode) {
        drmModeFreeConnector(conn);
        drmModeFreeResources(res);
        fv_err(err, err_len, "kms %s: connector has no %s mode", path, mode);
        goto bad;
    }
    k->mode = conn->modes[mi < 0 ? 0 : mi];
    k->conn_id = conn->connector_id;
    int rc = find_crtc(k->fd, res, conn, &k->crtc_id);
    drmModeFreeConnector(conn);
    drmModeFreeResources(res);
    if (rc) {
        fv_err(err, err_len, "kms %s: no CRTC for the connector", path);
        goto bad;
    }
    k->saved = drmModeGetCrtc(k->fd, k->crtc_id);
    for (int b = 0; b < 2; b++)
        if (buf_create(k, &k->buf[b], err, err_len))
            goto bad;
    if (drmModeSetCrtc(k->fd, k->crtc_id, k->buf[0].fb_id, 0, 0, &k->conn_id, 1, &k->mode)) {
        fv_err(err, err_len, "drmModeSetCrtc(%s, %ux%u): %s", path, k->mode.hdisplay, k->mode.vdisplay,
               strerror(errno));
        goto bad;
    }
    k->front = 0;
    *out = k;
    return 0;
bad:
    fv_kms_close(k);
    return -1;
}

void fv_kms_size(const fv_kms *k, int *w, int *h)
{
    *w = k->mode.hdisplay;
    *h = k->mode.vdisplay;
}

static void on_flip(int fd, unsigned seq, unsigned sec, unsigned usec, void *user)
{
    (void)fd;
    (void)seq;
    fv_kms *k = user;
    k->flip_pending = 0;
    k->flip_t_ns = (int64_t)sec * 1000000000 + (int64_t)usec * 1000;
}

int fv_kms_wait_flip(fv_kms *k, int64_t timeout_ns, int64_t *t_ns, char *err, size_t err_len)
{
    if (!k->flip_pending)
        return 0;
    struct pollfd pf = {.fd = k->fd, .events = POLLIN};
    int ms = timeout_ns <= 0 ? 0 : (int)((timeout_ns + 999999) / 1000000);
    int rc = poll(&pf, 1, ms);
    if (rc < 0)
        return errno == EINTR ? 0 : fv_err(err, err_len, "poll(drm fd): %s", strerror(errno));
    if (rc == 0)
        return 0;
    drmEventContext ev = {.version = 2, .page_flip_handler = on_flip};
    if (drmHandleEvent(k->fd, &ev))
        return fv_err(err, err_len, "drmHandleEvent: %s", strerror(errno));
    if (k->flip_pending)
        return 0;
    if (t_ns)
        *t_ns = k->flip_t_ns;
    return 1;
}

int fv_kms_present(fv_kms *k, const uint8_t *rgb, int w, int h, ptrdiff_t stride, char *err, size_t err_len)
{
    if (k->flip_pending && fv_kms_wait_flip(k, 100000000, NULL, err, err_len) < 0)
        return -1;
    if (k->flip_pending)
        return fv_err(err, err_len, "kms: page flip event did not come within 100 ms");
    dumb_buf *b = &k->buf[k->front ^ 1];
    const int sw = k->mode.hdisplay, sh = k->mode.vdisplay;
    /* centre: crop a larger image, border a smaller one */
    const int ox = (w - sw) / 2, oy = (h - sh) / 2;
    for (int y = 0; y < sh; y++) {
        uint32_t *d = (uint32_t *)(b->map + (size_t)y * b->pitch);
        const int sy = y + oy;
        for (int x = 0; x < sw; x++) {
            const int sx = x + ox;
            if (sy < 0 || sy >= h || sx < 0 || sx >= w) {
                d[x] = 0;
                continue;
            }
            const uint8_t *s = rgb + sy * stride + 3 * sx;
            d[x] = (uint32_t)s[0] << 16 | (uint32_t)s[1] << 8 | s[2];
        }
    }
    if (drmModePageFlip(k->fd, k->crtc_id, b->fb_id, DRM_MODE_PAGE_FLIP_EVENT, k))
        return fv_err(err, err_len, "drmModePageFlip: %s", strerror(errno));
    k->flip_pending = 1;
    k->front ^= 1;
    return 0;
}

void fv_kms_close(fv_kms *k)
{
    if (!k)
        return;
    if (k->flip_pending)
        fv_kms_wait_flip(k, 100000000, NULL, NULL, 0);
    if (k->saved) {
        drmModeSetCrtc(k->fd, k->saved->crtc_id, k->saved->buffer_id, k->saved->x, k->saved->y, &k->conn_id, 1,
                       &k->saved->mode);
        drmModeFreeCrtc(k->saved);
    }
    for (int b = 0; b < 2; b++)
        buf_destroy(k, &k->buf[b]);
    if (k->fd >= 0)
        close(k->fd);
    free(k);
}

#else /* no libdrm at build time */

struct fv_kms {
    int unused;
};
int fv_kms_open(fv_kms **k, const char *card, const char *mode, char *err, size_t err_len)
{
    (void)mode;
    *k = NULL;
    return fv_err(err, err_len, "kms %s: fovea was built without libdrm", card ? card : "card0");
}
void fv_kms_size(const fv_kms *k, int *w, int *h)
{
    (void)k;
    *w = *h = 0;
}
int fv_kms_present(fv_kms *k, const uint8_t *rgb, int w, int h, ptrdiff_t stride, char *err, size_t err_len)
{
    (void)k, (void)rgb, (void)w, (void)h, (void)stride;
    return fv_err(err, err_len, "kms: fovea was built without libdrm");
}
int fv_kms_wait_flip(fv_kms *k, int64_t timeout_ns, int64_t *t_ns, char *err, size_t err_len)
{
    (void)k, (void)timeout_ns, (void)t_ns, (void)err, (void)err_len;
    return 0;
}
void fv_kms_close(fv_kms *k) { (void)k; }
#endif
