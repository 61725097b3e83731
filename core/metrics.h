/* fovea: image comparison metrics on displayed images (8-bit sRGB RGB): luma PSNR, SSIM and the
 * mean absolute luma difference, over the whole image or a disc / the outside of a disc (fovea and
 * periphery around a point of regard). Luma is Rec. 709 on the encoded values, 0..255. */
#ifndef FOVEA_METRICS_H
#define FOVEA_METRICS_H

#include <stddef.h>
#include <stdint.h>

typedef struct fv_region {
    float cx, cy, r_px; /* disc centre and radius in pixels */
    float cx2, cy2;     /* a second disc of the same radius (set equal to cx, cy for one) */
    int outside;        /* 0: pixels inside either disc; 1: pixels outside both */
} fv_region;

/* One disc around (cx, cy). */
static inline fv_region fv_region_disc(float cx, float cy, float r_px, int outside)
{
    fv_region r = {cx, cy, r_px, cx, cy, outside};
    return r;
}

/* Luma PSNR in dB of b against a (INFINITY when equal; NAN when the region is empty). rows of
 * stride bytes, w x h pixels; region NULL = every pixel. */
double fv_luma_psnr(const uint8_t *a, const uint8_t *b, int w, int h, ptrdiff_t stride, const fv_region *region);
/* Mean absolute luma difference (0..255) over the region (NAN when empty). */
double fv_luma_mad(const uint8_t *a, const uint8_t *b, int w, int h, ptrdiff_t stride, const fv_region *region);

/* Mean SSIM (Wang, Bovik, Sheikh, Simoncelli 2004) of b against a on the same luma (0..255):
 * local means, variances and covariance under an 11x11 Gaussian window (sigma 1.5, weights
 * normalised to sum 1), SSIM = (2 mu_a mu_b + C1)(2 s_ab + C2) / ((mu_a^2 + mu_b^2 + C1)
 * (s_a^2 + s_b^2 + C2)) with C1 = (0.01 * 255)^2, C2 = (0.03 * 255)^2, averaged over the
 * region's pixels whose whole window lies inside the image (pixels 5 or more from every edge,
 * the "valid" map of the authors' code). 1 for identical images; NAN when no pixel qualifies
 * (region empty there, image under 11x11) or memory runs out. */
double fv_luma_ssim(const uint8_t *a, const uint8_t *b, int w, int h, ptrdiff_t stride, const fv_region *region);

/* Signed luma error b - a per pixel into err (w * h floats, row-major). */
void fv_luma_error(const uint8_t *a, const uint8_t *b, int w, int h, ptrdiff_t stride, float *err);
/* Mean |e1 - e0| over the region of two w x h float images (NAN when empty). */
double fv_mean_abs_diff(const float *e0, const float *e1, int w, int h, const fv_region *region);

#endif
