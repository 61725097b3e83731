/* fovea platform: displays. Every back end takes 8-bit RGB images (the stereo pair side by side)
 * and shows or stores them; none blocks longer than its timeout.
 *  - kms[:CARD]: DRM/KMS through libdrm: the first connected connector and its preferred mode
 *    (or the first), two dumb buffers, a page flip per frame with its event (platform/display_kms.c);
 *  - fbdev[:DEV]: the Linux framebuffer (/dev/fb0; DEV "1", "fb1" or a path), 16 or 32 bits per
 *    pixel, fallback for boards without KMS;
 *  - window: an SDL2 window on a PC; its mouse position can stand in for the gaze;
 *  - png:DIR (DIR/frame_NNNNN.png), y4m:FILE (YUV4MPEG2), none.
 * An image larger than the screen is cropped around its centre, a smaller one centred (no
 * scaling: one panel pixel per rendered pixel). */
#ifndef FOVEA_DISPLAY_H
#define FOVEA_DISPLAY_H

#include <stddef.h>
#include <stdint.h>

/* ---- DRM/KMS (-ldrm) ---- */
typedef struct fv_kms fv_kms;
/* card: a path ("/dev/dri/card0"), a name ("card0"), a number ("0"), or NULL for card0; mode: "WxH" or NULL for
 * the connector's preferred mode. Sets the mode showing a black buffer. 0, or -1 with the
 * failing call and reason in err. Without libdrm at build time: always -1. */
int fv_kms_open(fv_kms **k, const char *card, const char *mode, char *err, size_t err_len);
void fv_kms_size(const fv_kms *k, int *w, int *h);
/* Copies rgb into the back buffer and queues a page flip to it (the flip happens at the next
 * vblank). A flip still pending is waited for first (up to 100 ms). */
int fv_kms_present(fv_kms *k, const uint8_t *rgb, int w, int h, ptrdiff_t stride, char *err, size_t err_len);
/* Waits for the queued flip's event: 1 with its vblank time (CLOCK_MONOTONIC) in *t_ns, 0 on
 * timeout or when no flip is pending, -1 on error. */
int fv_kms_wait_flip(fv_kms *k, int64_t timeout_ns, int64_t *t_ns, char *err, size_t err_len);
/* Restores the CRTC as found and frees everything. */
void fv_kms_close(fv_kms *k);

/* ---- any display by spec ---- */
typedef struct fv_display fv_display;
/* spec as above; w x h: the images that will be presented; fps: for y4m. */
int fv_display_open(fv_display **d, const char *spec, int w, int h, int fps, char *err, size_t err_len);
/* 0, or -1 with a reason (the display is then unusable: the caller falls back to `none`). */
int fv_display_present(fv_display *d, const uint8_t *rgb, int w, int h, ptrdiff_t stride, char *err, size_t err_len);
/* Window only: 1 with the mouse position in normalised coordinates of one eye's image (the
 * window shows both eyes side by side) when the mouse is over the window; 0 otherwise. */
int fv_display_mouse_gaze(fv_display *d, float *gx, float *gy);
/* Window only: the window was closed (or Escape pressed). */
int fv_display_quit_requested(fv_display *d);
const char *fv_display_kind(const fv_display *d); /* "kms", "fbdev", "window", "png", "y4m", "none" */
/* Commits file sinks (PNG frames are complete as written; the Y4M file is renamed into place).
 * 0, or -1 with a reason. Frees d in any case. */
int fv_display_close(fv_display *d, char *err, size_t err_len);

#endif
