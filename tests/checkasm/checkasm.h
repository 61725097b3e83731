/* fovea checkasm (dav1d's tests/checkasm idea): every ISA version of every kernel against its
 * plain-C reference, one file per module (pullpush.c, reproject.c, dof.c, eyetrack.c, shade.c, raygen.c,
 * output.c, timewarp.c), and with
 * --bench their speed at production sizes (bench.c). Shared here: the seeded RNG, canaried
 * output buffers, the compare helper and the ISA bookkeeping.
 *
 * Bound: every kernel today is exact (bit-identical, so -0 vs +0 counts; cpu.h has why);
 * checkasm_compare takes a bound in ULPs so a kernel whose contract allows less states it. */
#ifndef FOVEA_CHECKASM_H
#define FOVEA_CHECKASM_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "testutil.h"

#include "cpu.h"

/* The shared RNG (splitmix64). Each module reseeds it at its first test, so a module's inputs do
 * not depend on which modules ran before it. */
extern uint64_t checkasm_rng;
static inline uint64_t checkasm_rand(void) { return fv_test_rand(&checkasm_rng); }
static inline float checkasm_randf(void) { return fv_test_randf(&checkasm_rng); } /* [0,1) */

/* This build's ISAs with kernels (the ones a module may declare an _init_<isa> for), 0-ended. */
extern const unsigned checkasm_isas[];
/* 1 if this CPU runs isa; else prints that kernel's isa is skipped and returns 0. */
int checkasm_cpu_runs(unsigned isa, const char *kernel);

/* Outputs: off elements into their allocation (unaligned rows), with CHECKASM_GUARD bytes before
 * and after; guards and contents start as the canary pattern (the float NaN 0x7fc0dead, which no
 * kernel computes, repeated by address), so an element a kernel must not touch compares equal
 * too. checkasm_check_guards_* fail (naming isa, kernel, n) if a guard byte changed. */
#define CHECKASM_GUARD 64
void *checkasm_out(size_t bytes, size_t off_bytes, void **base); /* free(*base) */
void checkasm_check_guards(const void *p, size_t bytes, const char *isa, const char *kernel, int n);
static inline buf checkasm_out_f32(size_t count, int off) /* free(b.base) */
{
    void *base;
    buf b;
    b.p = (float *)checkasm_out(count * sizeof(float), (size_t)off * sizeof(float), &base);
    b.base = (float *)base;
    return b;
}
static inline void checkasm_check_guards_f32(const buf *b, size_t count, const char *isa, const char *kernel, int n)
{
    checkasm_check_guards(b->p, count * sizeof(float), isa, kernel, n);
}
static inline uint8_t *checkasm_out_u8(size_t count, int off, uint8_t **base)
{
    void *b;
    uint8_t *p = (uint8_t *)checkasm_out(count, (size_t)off, &b);
    *base = (uint8_t *)b;
    return p;
}

typedef enum { CHECKASM_F32, CHECKASM_U32, CHECKASM_U8 } checkasm_type;
/* Fails on the first element of got that is further than max_ulp from ref (floats: ULPs on the
 * ordered integer line, so +0 and -0 are 1 apart; a NaN must match bit for bit; integers: the
 * difference); per_px groups elements into pixels for the message; ctx (printf) says which call. */
void checkasm_compare(const void *ref, const void *got, size_t count, checkasm_type type, size_t per_px,
                      unsigned max_ulp, const char *ctx, ...) __attribute__((format(printf, 7, 8)));
#define CHECKASM_EXACT 0u /* the bound of every kernel today */

/* A module's own table for one ISA: a zeroed table filled by that ISA's init alone. Every entry
 * must be set and differ from the reference's, else the module declares an ISA version it does
 * not have: a failure (never a skip). own / ref are tables of n function pointers. */
void checkasm_check_table(const char *module, unsigned isa, const void *own, const void *ref, size_t size,
                          const char *const *names);

/* The loop of every module's table test: for each ISA of this build, a zeroed table of `type`
 * (fv_<module>_dsp) filled by that ISA's init alone (type##_init_sse41 / _avx2 on x86,
 * type##_init_neon on aarch64) goes through checkasm_check_table against ref (the C table). */
#if defined(__x86_64__)
#define CHECKASM_ISA_INIT_CASES(prefix, t)                                                         \
    case FV_ISA_SSE41: prefix##_init_sse41(t); break;                                              \
    case FV_ISA_AVX2: prefix##_init_avx2(t); break;
#elif defined(__aarch64__)
#define CHECKASM_ISA_INIT_CASES(prefix, t) case FV_ISA_NEON: prefix##_init_neon(t); break;
#else
#define CHECKASM_ISA_INIT_CASES(prefix, t)
#endif
#define CHECKASM_CHECK_ISA_TABLES(module, type, ref, names)                                        \
    do {                                                                                           \
        for (int k_ = 0; checkasm_isas[k_]; k_++) {                                                \
            type own_;                                                                             \
            memset(&own_, 0, sizeof own_);                                                         \
            switch (checkasm_isas[k_]) {                                                           \
                CHECKASM_ISA_INIT_CASES(type, &own_)                                               \
            default: fail_msg("%s: no init for this build's ISA", fv_isa_name(checkasm_isas[k_])); \
            }                                                                                      \
            checkasm_check_table(module, checkasm_isas[k_], &own_, (ref), sizeof own_, names);     \
        }                                                                                          \
    } while (0)

/* The modules' tests (each array ends with a zeroed entry). */
extern const struct CMUnitTest checkasm_pullpush_tests[], checkasm_reproject_tests[], checkasm_dof_tests[],
    checkasm_eyetrack_tests[], checkasm_shade_tests[], checkasm_raygen_tests[], checkasm_output_tests[],
    checkasm_timewarp_tests[], checkasm_bench_tests[];

#endif
