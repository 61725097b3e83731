/* fovea eye tracker: plain-C reference kernels (the contracts are in dsp.h). The SIMD versions
 * live in core/x86/eyetrack_{sse41,avx2}.c and core/arm/eyetrack_neon.c and must match these
 * exactly (integer arithmetic). */
#include "dsp.h"

void fv_et_down2_row_c(uint8_t *restrict dst, const uint8_t *a, const uint8_t *b, int n)
{
    for (int x = 0; x < n; x++)
        dst[x] = (uint8_t)((a[2 * x] + a[2 * x + 1] + b[2 * x] + b[2 * x + 1] + 2) >> 2);
}

void fv_et_integral_row_c(uint32_t *restrict dst, const uint32_t *above, const uint8_t *src, int n)
{
    uint32_t run = 0;
    for (int x = 0; x < n; x++) {
        run += src[x];
        dst[x] = above[x] + run;
    }
}

int fv_et_thresh_row_c(uint8_t *restrict dst, const uint8_t *src, int n, int t)
{
    int count = 0;
    for (int x = 0; x < n; x++) {
        const int on = src[x] >= t;
        dst[x] = on ? 255 : 0;
        count += on;
    }
    return count;
}

void fv_eyetrack_init_c(fv_dsp *d)
{
    d->et_down2_row = fv_et_down2_row_c;
    d->et_integral_row = fv_et_integral_row_c;
    d->et_thresh_row = fv_et_thresh_row_c;
}
