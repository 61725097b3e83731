/* fovea eye tracker: plain-C reference kernels (the contracts are in eyetrack_dsp.h) and the table's init. The SIMD versions
 * live in core/x86/eyetrack_{sse41,avx2}.c and core/arm/eyetrack_neon.c and must match these
 * exactly (integer arithmetic, or float operations in the same order). */
#include <math.h>

#include "eyetrack/eyetrack_dsp.h"

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

float fv_et_box_score_row_c(float *restrict dst, const uint32_t *it, const uint32_t *ib, int din, const uint32_t *ot,
                            const uint32_t *ob, int dout, int n, float inv_a, float inv_r, float dark)
{
    float m = -INFINITY;
    for (int x = 0; x < n; x++) {
        const uint32_t si = ib[x + din] - it[x + din] - ib[x] + it[x];
        const uint32_t so = ob[x + dout] - ot[x + dout] - ob[x] + ot[x] - si;
        const float mi = (float)si * inv_a, mo = (float)so * inv_r;
        const float s = (mo - mi) - (mi - dark);
        dst[x] = s;
        m = s > m ? s : m;
    }
    return m;
}

void fv_et_box3_row_c(uint8_t *restrict dst, const uint8_t *r0, const uint8_t *r1, const uint8_t *r2, int n)
{
    for (int x = 0; x < n; x++)
        dst[x] = fv_et_box3_px(r0, r1, r2, n, x);
}

void fv_eyetrack_dsp_init(fv_eyetrack_dsp *d, unsigned isa_mask)
{
    const unsigned isas = isa_mask & fv_cpu_isas();
    d->et_down2_row = fv_et_down2_row_c;
    d->et_integral_row = fv_et_integral_row_c;
    d->et_thresh_row = fv_et_thresh_row_c;
    d->et_box_score_row = fv_et_box_score_row_c;
    d->et_box3_row = fv_et_box3_row_c;
#if defined(__x86_64__)
    if (isas & FV_ISA_SSE41)
        fv_eyetrack_dsp_init_sse41(d);
    if (isas & FV_ISA_AVX2)
        fv_eyetrack_dsp_init_avx2(d);
#elif defined(__aarch64__)
    if (isas & FV_ISA_NEON)
        fv_eyetrack_dsp_init_neon(d);
#else
    (void)isas;
#endif
}
