/* fovea HIL: KMS display adapter over libdrm: first connected connector, its preferred mode, two
 * dumb XRGB8888 buffers, drmModeSetCrtc for the first frame, drmModePageFlip with its event for
 * the next. Stand-in until the headset's platform KMS display lands (issue 6); then this file
 * becomes a thin wrapper over it. */
#include "hil_display.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include <xf86drm.h>
#include <xf86drmMode.h>

typedef struct dumb {
    uint32_t handle, fb, pitch;
    uint64_t size;
    uint32_t *map;
} dumb;

struct fv_hil_display {
    int fd;
    uint32_t conn_id, crtc_id;
    drmModeModeInfo mode;
    dumb buf[2];
    int back;
    int shown;          /* a mode is set */
    int flip_pending;
};

static void flip_done(int fd, unsigned seq, unsigned sec, unsigned usec, void *data)
{
    (void)fd;
    (void)seq;
    (void)sec;
    (void)usec;
    *(int *)data = 0;
}

static int make_dumb(fv_hil_display *d, dumb *b, char *err, size_t err_len)
{
    struct drm_mode_create_dumb c = {.width = d->mode.hdisplay, .height = d->mode.vdisplay, .bpp = 32};
    if (drmIoctl(d->fd, DRM_IOCTL_MODE_CREATE_DUMB, &c)) {
        snprintf(err, err_len, "DRM_IOCTL_MODE_CREATE_DUMB %ux%u: %s", c.width, c.height, strerror(errno));
        return -1;
    }
    b->handle = c.handle;
    b->pitch = c.pitch;
    b->size = c.size;
    if (drmModeAddFB(d->fd, c.width, c.height, 24, 32, c.pitch, c.handle, &b->fb)) {
        snprintf(err, err_len, "drmModeAddFB: %s", strerror(errno));
        return -1;
    }
    struct drm_mode_map_dumb m = {.handle = c.handle};
    if (drmIoctl(d->fd, DRM_IOCTL_MODE_MAP_DUMB, &m)) {
        snprintf(err, err_len, "DRM_IOCTL_MODE_MAP_DUMB: %s", strerror(errno));
        return -1;
    }
    void *p = mmap(NULL, (size_t)c.size, PROT_READ | PROT_WRITE, MAP_SHARED, d->fd, (off_t)m.offset);
    if (p == MAP_FAILED) {
        snprintf(err, err_len, "mmap dumb buffer: %s", strerror(errno));
        return -1;
    }
    b->map = p;
    return 0;
}

fv_hil_display *fv_hil_display_open(const char *card, char *err, size_t err_len)
{
    fv_hil_display *d = calloc(1, sizeof *d);
    if (!d) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    d->fd = open(card, O_RDWR | O_CLOEXEC);
    if (d->fd < 0) {
        snprintf(err, err_len, "open %s: %s", card, strerror(errno));
        free(d);
        return NULL;
    }
    drmModeRes *res = drmModeGetResources(d->fd);
    if (!res) {
        snprintf(err, err_len, "drmModeGetResources on %s: %s", card, strerror(errno));
        fv_hil_display_close(d);
        return NULL;
    }
    drmModeConnector *conn = NULL;
    for (int i = 0; i < res->count_connectors && !conn; i++) {
        drmModeConnector *c = drmModeGetConnector(d->fd, res->connectors[i]);
        if (c && c->connection == DRM_MODE_CONNECTED && c->count_modes > 0)
            conn = c;
        else
            drmModeFreeConnector(c);
    }
    if (!conn) {
        snprintf(err, err_len, "%s: no connected connector with a mode", card);
        drmModeFreeResources(res);
        fv_hil_display_close(d);
        return NULL;
    }
    d->conn_id = conn->connector_id;
    d->mode = conn->modes[0];
    for (int i = 0; i < conn->count_modes; i++)
        if (conn->modes[i].type & DRM_MODE_TYPE_PREFERRED) {
            d->mode = conn->modes[i];
            break;
        }
    /* a CRTC the connector's encoders can drive */
    for (int e = 0; e < conn->count_encoders && !d->crtc_id; e++) {
        drmModeEncoder *enc = drmModeGetEncoder(d->fd, conn->encoders[e]);
        if (!enc)
            continue;
        for (int c = 0; c < res->count_crtcs; c++)
            if (enc->possible_crtcs & (1u << c)) {
                d->crtc_id = res->crtcs[c];
                break;
            }
        drmModeFreeEncoder(enc);
    }
    drmModeFreeConnector(conn);
    drmModeFreeResources(res);
    if (!d->crtc_id) {
        snprintf(err, err_len, "%s: no CRTC for the connector", card);
        fv_hil_display_close(d);
        return NULL;
    }
    for (int i = 0; i < 2; i++)
        if (make_dumb(d, &d->buf[i], err, err_len)) {
            fv_hil_display_close(d);
            return NULL;
        }
    return d;
}

int fv_hil_display_width(const fv_hil_display *d)
{
    return d->mode.hdisplay;
}

int fv_hil_display_height(const fv_hil_display *d)
{
    return d->mode.vdisplay;
}

int fv_hil_display_back(fv_hil_display *d, uint32_t **px, size_t *pitch, char *err, size_t err_len)
{
    (void)err;
    (void)err_len;
    *px = d->buf[d->back].map;
    *pitch = d->buf[d->back].pitch;
    return 0;
}

int fv_hil_display_present(fv_hil_display *d, char *err, size_t err_len)
{
    dumb *b = &d->buf[d->back];
    if (!d->shown) {
        if (drmModeSetCrtc(d->fd, d->crtc_id, b->fb, 0, 0, &d->conn_id, 1, &d->mode)) {
            snprintf(err, err_len, "drmModeSetCrtc %ux%u: %s", d->mode.hdisplay, d->mode.vdisplay, strerror(errno));
            return -1;
        }
        d->shown = 1;
    } else {
        d->flip_pending = 1;
        if (drmModePageFlip(d->fd, d->crtc_id, b->fb, DRM_MODE_PAGE_FLIP_EVENT, &d->flip_pending)) {
            snprintf(err, err_len, "drmModePageFlip: %s", strerror(errno));
            return -1;
        }
        drmEventContext ev = {.version = 2, .page_flip_handler = flip_done};
        while (d->flip_pending) {
            struct pollfd p = {.fd = d->fd, .events = POLLIN};
            int r = poll(&p, 1, 1000);
            if (r <= 0) {
                snprintf(err, err_len, "page flip: no event within 1 s");
                return -1;
            }
            if (drmHandleEvent(d->fd, &ev)) {
                snprintf(err, err_len, "drmHandleEvent: %s", strerror(errno));
                return -1;
            }
        }
    }
    d->back ^= 1;
    return 0;
}

void fv_hil_display_close(fv_hil_display *d)
{
    if (!d)
        return;
    for (int i = 0; i < 2; i++) {
        dumb *b = &d->buf[i];
        if (b->map)
            munmap(b->map, (size_t)b->size);
        if (b->fb)
            drmModeRmFB(d->fd, b->fb);
        if (b->handle) {
            struct drm_mode_destroy_dumb x = {.handle = b->handle};
            drmIoctl(d->fd, DRM_IOCTL_MODE_DESTROY_DUMB, &x);
        }
    }
    if (d->fd >= 0)
        close(d->fd);
    free(d);
}
