#include "output_dsp.h"

#include <math.h>
#include <string.h>

void fv_srgb_lut_init(uint8_t lut[FV_SRGB_LUT + 1 + FV_SRGB_LUT_PAD])
{
    memset(lut, 0, FV_SRGB_LUT + 1 + FV_SRGB_LUT_PAD);
    for (int i = 0; i <= FV_SRGB_LUT; i++) {
        const double v = (double)i / FV_SRGB_LUT;
        const double s = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
        lut[i] = (uint8_t)(s * 255.0 + 0.5);
    }
}

void fv_rgb8_row_c(uint8_t *restrict dst, const float *rgbd, int n, const uint8_t *lut)
{
    for (int x = 0; x < n; x++)
        for (int c = 0; c < 3; c++)
            dst[3 * x + c] = lut[fv_srgb_index(rgbd[4 * x + c])];
}

void fv_lca_row_c(uint8_t *restrict dst, int y, const fv_lca_geom *g, const fv_lens_lca *lca, const uint8_t *lut)
{
    const float ty = g->tan_top - ((float)y + 0.5f) * g->px_tan;
    const float *own = g->img + 4 * (ptrdiff_t)y * g->stride;
    for (int x = 0; x < g->w; x++)
        fv_lca_pixel(dst + 3 * x, x, ty, g, lca, own + 4 * x, lut);
}

void fv_output_dsp_init(fv_output_dsp *d, unsigned isa_mask)
{
    d->rgb8_row = fv_rgb8_row_c;
    d->lca_row = fv_lca_row_c;
    const unsigned avail = isa_mask & fv_cpu_isas();
    (void)avail;
#if defined(__x86_64__)
    if (avail & FV_ISA_SSE41)
        fv_output_dsp_init_sse41(d);
    if (avail & FV_ISA_AVX2)
        fv_output_dsp_init_avx2(d);
#elif defined(__aarch64__)
    if (avail & FV_ISA_NEON)
        fv_output_dsp_init_neon(d);
#endif
}
