#include "output_dsp.h"

void fv_rgb8_row_c(uint8_t *restrict dst, const float *rgbd, int n, const uint8_t *lut)
{
    for (int x = 0; x < n; x++)
        for (int c = 0; c < 3; c++)
            dst[3 * x + c] = lut[fv_srgb_index(rgbd[4 * x + c])];
}

void fv_output_dsp_init(fv_output_dsp *d, unsigned isa_mask)
{
    d->rgb8_row = fv_rgb8_row_c;
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
