/* fovea: the kernel benchmark table (checkasm's idea applied to speed): one entry per
 * hand-vectorised kernel of fv_dsp, with a set-up that makes production-sized inputs (1280-wide
 * rows of a 1280x1440 eye frame; the eye tracker's kernels on a 640x480 eye camera image) and a
 * run that calls the kernel over a whole frame through a given dispatch table. fovea-bench
 * --kernels times every entry for the C reference and each ISA this CPU runs
 * (fv_dsp_init(&d, mask) per ISA, so a new ISA's kernels are picked up as soon as fv_dsp_init
 * fills them in); under qemu it counts instructions instead (tools/kernel_icount.sh).
 *
 * To add a kernel: a setup that allocates and fills its inputs (deterministic), a run that
 * makes `rows` calls starting at call `row0` (wrapping at calls_per_frame), and the offsets of
 * the fv_dsp fields it exercises (an ISA has its own version when any of them differs from the
 * C table's). */
#ifndef FOVEA_KBENCH_H
#define FOVEA_KBENCH_H

#include <stddef.h>

#include "dsp.h"

#define FV_KBENCH_MAX_FIELDS 2

typedef struct fv_kbench_kernel {
    const char *name;                     /* the fv_dsp field(s), e.g. "pull_row" */
    const char *shape;                    /* what one frame of calls covers */
    size_t field[FV_KBENCH_MAX_FIELDS];   /* offsetof(fv_dsp, ...); unused: 0 (the isa field) */
    int calls_per_frame;                  /* kernel calls that cover one frame */
    void *(*setup)(void);                 /* NULL: out of memory */
    void (*reset)(void *st);              /* restores inputs a run changed (untimed); may be NULL */
    void (*run)(void *st, const fv_dsp *d, int row0, int rows);
    void (*free)(void *st);
} fv_kbench_kernel;

extern const fv_kbench_kernel fv_kbench_kernels[];
extern const int fv_kbench_count;

/* 1 when d has its own version of k (any of its fields differs from ref's), else 0. */
int fv_kbench_differs(const fv_kbench_kernel *k, const fv_dsp *d, const fv_dsp *ref);
/* The kernel named name, or NULL. */
const fv_kbench_kernel *fv_kbench_find(const char *name);

#endif
