/* fovea: gaze / head-pose traces (CSV, see DESIGN.md):
 *   t_ms,gaze_x,gaze_y[,head_px,head_py,head_pz,head_qx,head_qy,head_qz,head_qw]
 * Gaze is in normalised image coordinates of the eye's image (x right, y down, [0,1]).
 * A header line is required; lines starting with '#' and blank lines are ignored. */
#ifndef FOVEA_TRACE_H
#define FOVEA_TRACE_H

#include <stddef.h>
#include "camera.h"

/* Input ranges (bad input beyond them): times up to about 31 years, head positions within 1000 km. */
#define FV_TRACE_MAX_T_MS 1e12
#define FV_TRACE_MAX_POS_M 1e6
/* The largest trace file read (a 10-million-row trace is about 0.5 GiB). */
#define FV_TRACE_MAX_FILE_BYTES ((size_t)1 << 30)

typedef struct fv_trace_sample {
    double t_ms;
    float gaze_x, gaze_y;
    fv_pose head; /* valid when the trace has head columns */
} fv_trace_sample;

typedef struct fv_trace {
    fv_trace_sample *s;
    int n;
    int has_head;
} fv_trace;

/* Parses CSV text in memory (len bytes, no terminator needed; name, e.g. the file's path, is
 * used in messages only). 0 on success; -1 with a one-line reason ("NAME:LINE: reason" or
 * "NAME: reason") in err and tr empty. Files: fv_trace_load (platform/tracefile.h). */
int fv_trace_parse(fv_trace *tr, const char *text, size_t len, const char *name, char *err, size_t err_len);
void fv_trace_free(fv_trace *tr);

/* State at time t_ms: linear gaze and position, slerped rotation; held at the ends. */
void fv_trace_at(const fv_trace *tr, double t_ms, fv_trace_sample *out);
/* The trace time elapsed_ms after its start when it is played in a loop (a live headset runs
 * longer than a recorded trace): the first sample's time plus elapsed_ms modulo the trace's
 * span (the first sample's time for a trace of one instant). */
double fv_trace_loop_ms(const fv_trace *tr, double elapsed_ms);

#endif
