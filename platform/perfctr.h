/* fovea: hardware counters (cycles, instructions, cache misses, branch misses) through Linux
 * perf_event_open, summed over every thread of the process that exists when they are opened
 * (open them after the pipeline's pool has started). Where the kernel, the VM or
 * perf_event_paranoid does not allow them, fv_perfctr_open returns NULL with the reason: callers
 * report the counters as unavailable and carry on. FOVEA_PERF=off in the environment makes them
 * unavailable on purpose (the tests use it). */
#ifndef FOVEA_PERFCTR_H
#define FOVEA_PERFCTR_H

#include <stddef.h>
#include <stdint.h>

enum { FV_PERF_CYCLES, FV_PERF_INSTRUCTIONS, FV_PERF_CACHE_MISSES, FV_PERF_BRANCH_MISSES, FV_PERF_N };
extern const char *const fv_perf_names[FV_PERF_N]; /* cycles, instructions, cache_misses, branch_misses */

typedef struct fv_perfctr fv_perfctr;

fv_perfctr *fv_perfctr_open(char *why, size_t why_len);
/* Current totals (counting since open, scaled for multiplexing). 0, or -1 if a read failed. */
int fv_perfctr_read(fv_perfctr *pc, uint64_t v[FV_PERF_N]);
void fv_perfctr_close(fv_perfctr *pc);

#endif
