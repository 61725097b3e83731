/* fovea: run-time CPU detection and the kernel table (see dsp.h for the pattern). */
#include "dsp.h"

#include <stddef.h>

unsigned fv_cpu_isas(void)
{
    unsigned isas = 0;
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    /* libgcc / compiler-rt only report AVX features when the OS saves the YMM state. */
    __builtin_cpu_init();
    if (__builtin_cpu_supports("sse4.1"))
        isas |= FV_ISA_SSE41;
    if ((isas & FV_ISA_SSE41) && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
        isas |= FV_ISA_AVX2;
#elif defined(__aarch64__)
    isas |= FV_ISA_NEON; /* Advanced SIMD is mandatory on AArch64 */
#endif
    return isas;
}

void fv_dsp_init(fv_dsp *d, unsigned isa_mask)
{
    unsigned avail = isa_mask & fv_cpu_isas();
    d->isa = FV_ISA_C;
    fv_pullpush_init_c(d);
    fv_reproject_init_c(d);
    fv_eyetrack_init_c(d);
    fv_dof_init_c(d);
#if defined(__x86_64__)
    if (avail & FV_ISA_SSE41) {
        fv_pullpush_init_sse41(d);
        fv_reproject_init_sse41(d);
        fv_eyetrack_init_sse41(d);
        fv_dof_init_sse41(d);
        d->isa = FV_ISA_SSE41;
    }
    if (avail & FV_ISA_AVX2) {
        fv_pullpush_init_avx2(d);
        fv_reproject_init_avx2(d);
        fv_eyetrack_init_avx2(d);
        fv_dof_init_avx2(d);
        d->isa = FV_ISA_AVX2;
    }
#elif defined(__aarch64__)
    if (avail & FV_ISA_NEON) {
        fv_pullpush_init_neon(d);
        fv_reproject_init_neon(d);
        fv_eyetrack_init_neon(d);
        fv_dof_init_neon(d);
        d->isa = FV_ISA_NEON;
    }
#else
    (void)avail;
#endif
}

const char *fv_isa_name(unsigned isa)
{
    switch (isa) {
    case FV_ISA_C: return "c";
    case FV_ISA_SSE41: return "sse4.1";
    case FV_ISA_AVX2: return "avx2";
    case FV_ISA_NEON: return "neon";
    default: return "?";
    }
}
