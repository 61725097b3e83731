/* fovea: run-time CPU detection for the hand-vectorised kernels (dav1d / libjpeg-turbo style).
 *
 * Every module with kernels has its own table and init (core/pullpush_dsp.h,
 * core/reproject_dsp.h, core/shade_dsp.h, core/raygen_dsp.h, core/dof/dof_dsp.h,
 * core/output_dsp.h, core/eyetrack/eyetrack_dsp.h):
 *   <module>_ref.c         plain-C references + fv_<module>_dsp_init(ctx, isa_mask), which fills
 *                          the references, then lets every allowed ISA, lowest first, overwrite
 *                          the entries it implements
 *   x86/<module>_sse41.c   fv_<module>_dsp_init_sse41   (built with -msse4.1, x86_64 only)
 *   x86/<module>_avx2.c    fv_<module>_dsp_init_avx2    (built with -mavx2 -mfma, x86_64 only)
 *   arm/<module>_neon.c    fv_<module>_dsp_init_neon    (aarch64 only)
 * Code shared by the SSE4.1 and AVX2 files of a module sits in x86/<module>_tmpl.h, which each
 * includes once after defining FV_X86_W (4 or 8 floats: its vector width).
 * tests/checkasm checks every ISA version against its reference and times it (--bench).
 *
 * Contract for every ISA version of a kernel: bit-identical to its C reference for all finite
 * inputs (same IEEE operations in the same order, true division, no FMA contraction: the whole
 * tree is built with -ffp-contract=off), under the same FTZ/DAZ mode. Kernels read and write
 * exactly the pixels their contract names (no over-reads, no writes past n), take any row
 * alignment (4-byte aligned floats), and keep no state. */
#ifndef FOVEA_CPU_H
#define FOVEA_CPU_H

enum {
    FV_ISA_C = 0,
    FV_ISA_SSE41 = 1 << 0,
    FV_ISA_AVX2 = 1 << 1,
    FV_ISA_NEON = 1 << 2,
};

unsigned fv_cpu_isas(void); /* FV_ISA_* bits this CPU runs (and this build has kernels for) */
/* The ISA a module's init selects for isa_mask: the highest bit of isa_mask & fv_cpu_isas(),
 * FV_ISA_C if none. */
unsigned fv_cpu_best_isa(unsigned isa_mask);
const char *fv_isa_name(unsigned isa); /* "c", "sse4.1", "avx2", "neon"; "?" otherwise */
/* The --isa cap by name: "c", "sse41", "avx2" (with SSE4.1), "neon" -> the mask of the ISAs it
 * allows. 0, or -1 for another name. */
int fv_isa_mask_parse(const char *name, unsigned *mask);

#endif
