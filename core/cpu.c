/* fovea: run-time CPU detection (cpu.h has the kernel pattern). */
#include "cpu.h"

#include <string.h>

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

unsigned fv_cpu_best_isa(unsigned isa_mask)
{
    unsigned avail = isa_mask & fv_cpu_isas(), best = FV_ISA_C;
    for (unsigned bit = 1; bit && bit <= avail; bit <<= 1)
        if (avail & bit)
            best = bit;
    return best;
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

int fv_isa_mask_parse(const char *name, unsigned *mask)
{
    static const struct {
        const char *name;
        unsigned mask;
    } caps[] = {{"c", FV_ISA_C}, {"sse41", FV_ISA_SSE41}, {"avx2", FV_ISA_SSE41 | FV_ISA_AVX2}, {"neon", FV_ISA_NEON}};
    for (size_t i = 0; i < sizeof caps / sizeof caps[0]; i++)
        if (!strcmp(name, caps[i].name)) {
            *mask = caps[i].mask;
            return 0;
        }
    return -1;
}
