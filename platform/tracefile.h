/* fovea platform: gaze / head trace files (the format and its parser: core/trace.h). */
#ifndef FOVEA_TRACEFILE_H
#define FOVEA_TRACEFILE_H

#include <stddef.h>

#include "trace.h"

/* Reads path whole and parses it (fv_trace_parse, messages named after path). 0 on success;
 * -1 with a one-line reason ("PATH: reason" or "PATH:LINE: reason") in err and tr empty. */
int fv_trace_load(fv_trace *tr, const char *path, char *err, size_t err_len);

#endif
