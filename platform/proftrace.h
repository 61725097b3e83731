/* fovea: writes a trace recorder's events (core/prof.h) as Chrome trace-event JSON, which
 * Perfetto (ui.perfetto.dev) and chrome://tracing open: one process, one track (tid) per worker
 * thread (tid = slot), per pipeline stage (tid 1000 + stage) and for the frame loop's markers
 * (tid 2000). Spans become matched "B"/"E" pairs, properly nested per track; instants "i".
 * Times are microseconds since the first event. */
#ifndef FOVEA_PROFTRACE_H
#define FOVEA_PROFTRACE_H

#include <stddef.h>

#include "prof.h"

/* label: the process name shown (e.g. the program and scene). 0, or -1 with a reason in err. */
int fv_prof_write_json(const fv_prof *p, const char *path, const char *label, char *err, size_t err_len);

#endif
