/* fovea: the pull-push kernels' plain-C references (contracts in pullpush_dsp.h) and the
 * table's init. */
#include "pullpush_dsp.h"

void fv_pull_row_c(float *restrict dst_rgbd, float *restrict dst_wgt, const float *src0_rgbd,
                   const float *src0_wgt, const float *src1_rgbd, const float *src1_wgt, int n)
{
    for (int x = 0; x < n; x++) {
        const float wa0 = src0_wgt[2 * x], wa1 = src0_wgt[2 * x + 1];
        const float wb0 = src1_wgt[2 * x], wb1 = src1_wgt[2 * x + 1];
        const float *a = src0_rgbd + 8 * x, *b = src1_rgbd + 8 * x;
        const float sw = (wa0 + wb0) + (wa1 + wb1);
        for (int c = 0; c < 4; c++) {
            /* a zero-weight child contributes +0 whatever its colour (never read as a value) */
            const float ta0 = wa0 > 0.0f ? wa0 * a[c] : 0.0f, tb0 = wb0 > 0.0f ? wb0 * b[c] : 0.0f;
            const float ta1 = wa1 > 0.0f ? wa1 * a[4 + c] : 0.0f, tb1 = wb1 > 0.0f ? wb1 * b[4 + c] : 0.0f;
            const float t = (ta0 + tb0) + (ta1 + tb1);
            dst_rgbd[4 * x + c] = sw > 0.0f ? t / sw : 0.0f;
        }
        dst_wgt[x] = sw < 1.0f ? sw : 1.0f;
    }
}

void fv_push_row_c(float *restrict fine_rgbd, const float *fine_wgt, const float *coarse_near,
                   const float *coarse_far, int n)
{
    for (int x = 0; x < n; x++) {
        const float w = fine_wgt[x];
        const int cx = x >> 1, fx = (x & 1) ? cx + 1 : cx - 1;
        const int keep = !(w < 1.0f), own = w > 0.0f; /* keep: full confidence, bits unchanged */
        const float om = 1.0f - w;
        float *o = fine_rgbd + 4 * x;
        for (int c = 0; c < 4; c++) {
            const float n0 = coarse_near[4 * cx + c], f0 = coarse_far[4 * cx + c];
            const float n1 = coarse_near[4 * fx + c], f1 = coarse_far[4 * fx + c];
            const float v0 = n0 + 0.25f * (f0 - n0);
            const float v1 = n1 + 0.25f * (f1 - n1);
            const float ip = v0 + 0.25f * (v1 - v0);
            const float cv = own ? o[c] : 0.0f; /* a hole's own colour is never used */
            const float r = cv + om * (ip - cv);
            o[c] = keep ? o[c] : r;
        }
    }
}

void fv_pullpush_dsp_init(fv_pullpush_dsp *d, unsigned isa_mask)
{
    const unsigned isas = isa_mask & fv_cpu_isas();
    d->pull_row = fv_pull_row_c;
    d->push_row = fv_push_row_c;
#if defined(__x86_64__)
    if (isas & FV_ISA_SSE41)
        fv_pullpush_dsp_init_sse41(d);
    if (isas & FV_ISA_AVX2)
        fv_pullpush_dsp_init_avx2(d);
#elif defined(__aarch64__)
    if (isas & FV_ISA_NEON)
        fv_pullpush_dsp_init_neon(d);
#else
    (void)isas;
#endif
}
