#include "metrics.h"

#include <math.h>
#include <stdlib.h>

static inline double luma(const uint8_t *p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

static inline int in_region(const fv_region *r, int x, int y)
{
    if (!r)
        return 1;
    const double dx = x + 0.5 - r->cx, dy = y + 0.5 - r->cy, ex = x + 0.5 - r->cx2, ey = y + 0.5 - r->cy2;
    const double rr = (double)r->r_px * r->r_px;
    const int in = dx * dx + dy * dy < rr || ex * ex + ey * ey < rr;
    return r->outside ? !in : in;
}

/* Sums |dY|^power (power 1 or 2) over the region; returns the pixel count. */
static long accumulate(const uint8_t *a, const uint8_t *b, int w, int h, ptrdiff_t stride, const fv_region *r,
                       int power, double *sum)
{
    long n = 0;
    double s = 0.0;
    for (int y = 0; y < h; y++) {
        const uint8_t *pa = a + y * stride, *pb = b + y * stride;
        for (int x = 0; x < w; x++) {
            if (!in_region(r, x, y))
                continue;
            const double d = luma(pa + 3 * x) - luma(pb + 3 * x);
            s += power == 2 ? d * d : fabs(d);
            n++;
        }
    }
    *sum = s;
    return n;
}

double fv_luma_psnr(const uint8_t *a, const uint8_t *b, int w, int h, ptrdiff_t stride, const fv_region *region)
{
    double s;
    long n = accumulate(a, b, w, h, stride, region, 2, &s);
    if (n == 0)
        return NAN;
    if (s == 0.0)
        return INFINITY;
    return 10.0 * log10(255.0 * 255.0 / (s / (double)n));
}

double fv_luma_mad(const uint8_t *a, const uint8_t *b, int w, int h, ptrdiff_t stride, const fv_region *region)
{
    double s;
    long n = accumulate(a, b, w, h, stride, region, 1, &s);
    return n ? s / (double)n : NAN;
}

void fv_luma_error(const uint8_t *a, const uint8_t *b, int w, int h, ptrdiff_t stride, float *err)
{
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            err[(size_t)y * w + x] = (float)(luma(b + y * stride + 3 * x) - luma(a + y * stride + 3 * x));
}

double fv_mean_abs_diff(const float *e0, const float *e1, int w, int h, const fv_region *region)
{
    double s = 0.0;
    long n = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            if (in_region(region, x, y)) {
                s += fabs((double)e1[(size_t)y * w + x] - e0[(size_t)y * w + x]);
                n++;
            }
    return n ? s / (double)n : NAN;
}

#define SSIM_R 5 /* window radius: 11 x 11 */

double fv_luma_ssim(const uint8_t *a, const uint8_t *b, int w, int h, ptrdiff_t stride, const fv_region *region)
{
    if (w < 2 * SSIM_R + 1 || h < 2 * SSIM_R + 1)
        return NAN;
    double g[2 * SSIM_R + 1], gs = 0.0;
    for (int i = -SSIM_R; i <= SSIM_R; i++)
        gs += g[i + SSIM_R] = exp(-(double)(i * i) / (2.0 * 1.5 * 1.5));
    for (int i = 0; i <= 2 * SSIM_R; i++)
        g[i] /= gs; /* the 2D window is g x g: separable, sums to 1 */
    const int ow = w - 2 * SSIM_R;
    /* a ring of 11 horizontally filtered rows of the 5 moments (ya, yb, ya^2, yb^2, ya yb),
     * ow values each, and one row of both lumas */
    double *ring = malloc(sizeof(double) * (size_t)(2 * SSIM_R + 1) * 5 * ow), *ly = malloc(sizeof(double) * 2 * (size_t)w);
    if (!ring || !ly) {
        free(ring);
        free(ly);
        return NAN;
    }
    double sum = 0.0;
    long n = 0;
    const double C1 = (0.01 * 255) * (0.01 * 255), C2 = (0.03 * 255) * (0.03 * 255);
    for (int y = 0; y < h; y++) {
        double *m = ring + (size_t)(y % (2 * SSIM_R + 1)) * 5 * ow;
        for (int x = 0; x < w; x++) {
            ly[x] = luma(a + y * stride + 3 * x);
            ly[w + x] = luma(b + y * stride + 3 * x);
        }
        for (int x = 0; x < ow; x++) {
            double s[5] = {0, 0, 0, 0, 0};
            for (int i = 0; i <= 2 * SSIM_R; i++) {
                const double va = ly[x + i], vb = ly[w + x + i];
                s[0] += g[i] * va;
                s[1] += g[i] * vb;
                s[2] += g[i] * va * va;
                s[3] += g[i] * vb * vb;
                s[4] += g[i] * va * vb;
            }
            for (int k = 0; k < 5; k++)
                m[k * ow + x] = s[k];
        }
        if (y < 2 * SSIM_R)
            continue;
        const int cy = y - SSIM_R; /* the window's centre row: rows cy-5 .. cy+5 are in the ring */
        for (int x = 0; x < ow; x++) {
            if (!in_region(region, x + SSIM_R, cy))
                continue;
            double s[5] = {0, 0, 0, 0, 0};
            for (int i = 0; i <= 2 * SSIM_R; i++) {
                const double *r = ring + (size_t)((cy - SSIM_R + i) % (2 * SSIM_R + 1)) * 5 * ow;
                for (int k = 0; k < 5; k++)
                    s[k] += g[i] * r[k * ow + x];
            }
            const double va = s[2] - s[0] * s[0], vb = s[3] - s[1] * s[1], cab = s[4] - s[0] * s[1];
            sum += (2.0 * s[0] * s[1] + C1) * (2.0 * cab + C2) / ((s[0] * s[0] + s[1] * s[1] + C1) * (va + vb + C2));
            n++;
        }
    }
    free(ring);
    free(ly);
    return n ? sum / (double)n : NAN;
}
