#include "metrics.h"

#include <math.h>

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
