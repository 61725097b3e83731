/* fovea checkasm --bench (and fovea-bench --kernels, which links this file): one entry per
 * hand-vectorised kernel, with a set-up that makes production-sized inputs (1280-wide rows of a
 * 1280x1440 eye frame, the reprojection in the pipeline's 16x16 tiles, the Gaussians in its
 * 128-pixel spans; the eye tracker's kernels on a 640x480 eye camera image) and a run that calls
 * the kernel over a whole frame through a given set of tables. Every entry is timed for the C
 * reference and each ISA this CPU runs (checkasm_dsp_init(&d, mask) per ISA, so a new ISA's
 * kernels are picked up as soon as its module's init fills them in); under qemu it counts
 * instructions instead (--kernel NAME --calls N, tools/kernel_icount.py).
 *
 * To add a kernel: a setup that allocates and fills its inputs (deterministic), a run that
 * makes `rows` calls starting at call `row0` (wrapping at calls_per_frame), and the offsets of
 * the checkasm_dsp fields it exercises (an ISA has its own version when any of them differs
 * from the C tables'). Needs neither cmocka nor the test helpers. */
#ifndef FOVEA_CHECKASM_BENCH_H
#define FOVEA_CHECKASM_BENCH_H

#include <stddef.h>

#include "dof/dof_dsp.h"
#include "eyetrack/eyetrack_dsp.h"
#include "output_dsp.h"
#include "pullpush_dsp.h"
#include "raygen_dsp.h"
#include "reproject_dsp.h"
#include "shade_dsp.h"
#include "timewarp_dsp.h"

/* Every module's table, for one ISA mask. */
typedef struct checkasm_dsp {
    unsigned isa; /* the ISA selected (first: no kernel field is at offset 0) */
    fv_pullpush_dsp pp;
    fv_reproject_dsp taa;
    fv_dof_dsp dof;
    fv_eyetrack_dsp et;
    fv_output_dsp out;
    fv_shade_dsp shade;
    fv_raygen_dsp ray;
    fv_timewarp_dsp tw;
} checkasm_dsp;
void checkasm_dsp_init(checkasm_dsp *d, unsigned isa_mask);

#define CHECKASM_BENCH_MAX_FIELDS 2

typedef struct checkasm_bench_kernel {
    const char *name;                        /* the table field(s), e.g. "pull_row" */
    const char *shape;                       /* what one frame of calls covers */
    size_t field[CHECKASM_BENCH_MAX_FIELDS]; /* offsetof(checkasm_dsp, ...); unused: 0 */
    int calls_per_frame;                     /* kernel calls that cover one frame */
    void *(*setup)(void);                    /* NULL: out of memory */
    void (*reset)(void *st);                 /* restores inputs a run changed (untimed); may be NULL */
    void (*run)(void *st, const checkasm_dsp *d, int row0, int rows);
    void (*free)(void *st);
} checkasm_bench_kernel;

extern const checkasm_bench_kernel checkasm_bench_kernels[];
extern const int checkasm_bench_count;

/* 1 when d has its own version of k (any of its fields differs from ref's), else 0. */
int checkasm_bench_differs(const checkasm_bench_kernel *k, const checkasm_dsp *d, const checkasm_dsp *ref);
/* The kernel named name, or NULL. */
const checkasm_bench_kernel *checkasm_bench_find(const char *name);

/* Times every kernel (or only `only`) for C and each ISA this CPU runs, median of reps runs,
 * prints speed-ups and writes json_path (may be NULL) as {"kernels_bench": ...}
 * (docs/bench.schema.json). With only and calls > 0: no timing, `calls` calls with the kernels
 * of isa_mask, then prints where their code is. Returns an exit status. */
int checkasm_bench_run(const char *prog, const char *json_path, int reps, const char *only, long calls,
                       unsigned isa_mask);
/* The same from options: --json FILE, --kernel-reps N, --kernel NAME, --calls N, --isa I. */
int checkasm_bench_main(const char *prog, int argc, char **argv);

#endif
