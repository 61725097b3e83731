/* Displays by spec: KMS (display_kms.c), fbdev, SDL2 window (display_sdl.c), PNG, Y4M, none. */
#include "display.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/fb.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include "display_sdl.h"
#include "base/err.h"
#include "output.h"

enum { D_KMS, D_FBDEV, D_WINDOW, D_PNG, D_Y4M, D_NONE };
static const char *const kind_names[] = {"kms", "fbdev", "window", "png", "y4m", "none"};

struct fv_display {
    int kind;
    fv_kms *kms;
    fv_window *win;
    fv_y4m_writer y4m;
    char dir[4096];
    long frame;
    /* fbdev */
    int fb_fd;
    uint8_t *fb;
    size_t fb_len;
    int fb_w, fb_h, fb_bpp, fb_line;
};

static int fbdev_open(fv_display *d, const char *dev, char *err, size_t err_len)
{
    d->fb_fd = open(dev, O_RDWR | O_CLOEXEC);
    if (d->fb_fd < 0)
        return fv_err(err, err_len, "open(%s): %s", dev, strerror(errno));
    struct fb_var_screeninfo var;
    struct fb_fix_screeninfo fix;
    if (ioctl(d->fb_fd, FBIOGET_VSCREENINFO, &var) || ioctl(d->fb_fd, FBIOGET_FSCREENINFO, &fix))
        return fv_err(err, err_len, "FBIOGET_*SCREENINFO(%s): %s", dev, strerror(errno));
    if (var.bits_per_pixel != 32 && var.bits_per_pixel != 16)
        return fv_err(err, err_len, "fbdev %s: %u bits per pixel (16 or 32 supported)", dev, var.bits_per_pixel);
    d->fb_w = (int)var.xres;
    d->fb_h = (int)var.yres;
    d->fb_bpp = (int)var.bits_per_pixel;
    d->fb_line = (int)fix.line_length;
    d->fb_len = (size_t)fix.line_length * var.yres_virtual;
    void *p = mmap(NULL, d->fb_len, PROT_READ | PROT_WRITE, MAP_SHARED, d->fb_fd, 0);
    if (p == MAP_FAILED)
        return fv_err(err, err_len, "mmap(%s): %s", dev, strerror(errno));
    d->fb = p;
    return 0;
}

static void fbdev_present(fv_display *d, const uint8_t *rgb, int w, int h, ptrdiff_t stride)
{
    const int ox = (w - d->fb_w) / 2, oy = (h - d->fb_h) / 2;
    for (int y = 0; y < d->fb_h; y++) {
        uint8_t *row = d->fb + (size_t)y * (size_t)d->fb_line;
        for (int x = 0; x < d->fb_w; x++) {
            int sx = x + ox, sy = y + oy;
            uint8_t r = 0, g = 0, b = 0;
            if (sx >= 0 && sx < w && sy >= 0 && sy < h) {
                const uint8_t *s = rgb + sy * stride + 3 * sx;
                r = s[0], g = s[1], b = s[2];
            }
            if (d->fb_bpp == 32)
                ((uint32_t *)row)[x] = (uint32_t)r << 16 | (uint32_t)g << 8 | b;
            else
                ((uint16_t *)row)[x] = (uint16_t)((r >> 3) << 11 | (g >> 2) << 5 | (b >> 3));
        }
    }
}

int fv_display_open(fv_display **out, const char *spec, int w, int h, int fps, char *err, size_t err_len)
{
    *out = NULL;
    fv_display *d = calloc(1, sizeof *d);
    if (!d)
        return fv_err(err, err_len, "display: out of memory");
    d->fb_fd = -1;
    int rc = 0;
    if (!strcmp(spec, "kms") || !strncmp(spec, "kms:", 4)) {
        d->kind = D_KMS;
        rc = fv_kms_open(&d->kms, spec[3] ? spec + 4 : NULL, NULL, err, err_len);
    } else if (!strcmp(spec, "fbdev") || !strncmp(spec, "fbdev:", 6)) {
        d->kind = D_FBDEV;
        char dev[256];
        const char *a = spec[5] ? spec + 6 : "0";
        if (a[0] >= '0' && a[0] <= '9') /* "1" */
            snprintf(dev, sizeof dev, "/dev/fb%s", a);
        else if (!strchr(a, '/')) /* "fb1" */
            snprintf(dev, sizeof dev, "/dev/%s", a);
        else
            snprintf(dev, sizeof dev, "%s", a);
        rc = fbdev_open(d, dev, err, err_len);
    } else if (!strcmp(spec, "window")) {
        d->kind = D_WINDOW;
        rc = fv_window_open(&d->win, w, h, err, err_len);
    } else if (!strncmp(spec, "png:", 4) && spec[4]) {
        d->kind = D_PNG;
        snprintf(d->dir, sizeof d->dir, "%s", spec + 4);
        rc = fv_mkdirs(d->dir, err, err_len);
    } else if (!strncmp(spec, "y4m:", 4) && spec[4]) {
        d->kind = D_Y4M;
        rc = fv_y4m_open(&d->y4m, spec + 4, w, h, fps, err, err_len);
    } else if (!strcmp(spec, "none")) {
        d->kind = D_NONE;
    } else {
        free(d);
        return fv_err(err, err_len, "--display %s: want kms[:CARD], fbdev[:DEV], window, png:DIR, y4m:FILE or none",
                      spec);
    }
    if (rc) {
        if (d->kind != D_Y4M) /* a failed y4m open leaves nothing to abort */
            fv_display_close(d, NULL, 0);
        else
            free(d);
        return -1;
    }
    *out = d;
    return 0;
}

int fv_display_present(fv_display *d, const uint8_t *rgb, int w, int h, ptrdiff_t stride, char *err, size_t err_len)
{
    char path[4200];
    switch (d->kind) {
    case D_KMS:
        return fv_kms_present(d->kms, rgb, w, h, stride, err, err_len);
    case D_FBDEV:
        fbdev_present(d, rgb, w, h, stride);
        return 0;
    case D_WINDOW:
        return fv_window_present(d->win, rgb, w, h, stride, err, err_len);
    case D_PNG:
        snprintf(path, sizeof path, "%s/frame_%05ld.png", d->dir, d->frame++);
        return fv_write_png(path, rgb, w, h, stride, err, err_len);
    case D_Y4M:
        return fv_y4m_write_rgb(&d->y4m, rgb, stride, err, err_len);
    default:
        return 0;
    }
}

int fv_display_mouse_gaze(fv_display *d, float *gx, float *gy)
{
    return d->kind == D_WINDOW && fv_window_mouse_gaze(d->win, gx, gy);
}

int fv_display_quit_requested(fv_display *d) { return d->kind == D_WINDOW && fv_window_quit_requested(d->win); }

const char *fv_display_kind(const fv_display *d) { return kind_names[d->kind]; }

int fv_display_close(fv_display *d, char *err, size_t err_len)
{
    if (!d)
        return 0;
    int rc = 0;
    if (d->kind == D_Y4M)
        rc = fv_y4m_close(&d->y4m, err, err_len);
    fv_kms_close(d->kms);
    fv_window_close(d->win);
    if (d->fb)
        munmap(d->fb, d->fb_len);
    if (d->fb_fd >= 0)
        close(d->fb_fd);
    free(d);
    return rc;
}
