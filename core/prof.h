/* fovea: a cheap in-process trace recorder (spans and instant markers) for profiling.
 *
 * Off by default: every hook in the pipeline, the pool and the ray caster checks a NULL recorder
 * first. When on, each recording slot (one per pool worker, slot = the worker's thread_id; the
 * calling thread is worker 0) has its own ring buffer of fixed capacity: a slot is written by
 * one thread only, so recording takes no lock and no atomic read-modify-write. When a ring is
 * full the oldest events are overwritten (fv_prof_dropped counts them). Events are read back
 * (fv_prof_event_at) only when no thread records any more (after fv_pool_run returned), and
 * written out as Chrome trace-event JSON by platform/proftrace.c.
 *
 * An event lies on a track: tracks 0 .. slots-1 are the worker threads, FV_PROF_TRACK_STAGE + s
 * the pipeline stage s (FV_PROF_* below), FV_PROF_TRACK_MARKERS the frame loop's markers (vsync,
 * gaze latch: fv_prof_instant from the headset loop). Names are string literals (or strings that
 * outlive the recorder): only the pointer is stored. */
#ifndef FOVEA_PROF_H
#define FOVEA_PROF_H

#include <stddef.h>
#include <stdint.h>

#include "stage.h"

/* Stage spans and the counter hook use the pipeline's stage ids (core/stage.h), plus one past
 * them for the whole frame. A stage fused into another's pass has no span of its own: the
 * reprojection runs inside the ray-casting tiles (its spans are on the workers' tracks) and the
 * layered filter's combine inside its vertical pass (the dof_filter span holds both; with its band
 * pipeline the coc span holds the CoC, filter and combine work of the bands the pipeline fuses,
 * core/dof/weier_pipe.c). */
#define FV_PROF_FRAME FV_STAGE_COUNT        /* the whole fv_pipeline_render */
#define FV_PROF_STAGES (FV_STAGE_COUNT + 1) /* ids a stage span or hook call may carry */
const char *fv_prof_stage_name(int stage);  /* fv_stage_names[stage], "frame"; "?" otherwise */
#define FV_PROF_TRACK_STAGE 1000
#define FV_PROF_TRACK_MARKERS 2000

typedef struct fv_prof fv_prof;

typedef struct fv_prof_event {
    int64_t t0_ns, t1_ns; /* CLOCK_MONOTONIC; t1 == t0 for an instant */
    const char *name;
    int32_t track;
    int32_t arg;          /* e.g. the tile index; -1: none */
    char kind;            /* 'X' span, 'i' instant */
} fv_prof_event;

/* slots: recording threads (>= the pool's threads); capacity: events per slot (rounded up to a
 * power of two). NULL when out of memory. */
fv_prof *fv_prof_create(int slots, size_t capacity);
void fv_prof_destroy(fv_prof *p);
int fv_prof_slots(const fv_prof *p);

/* Recording (slot: the calling thread's slot; out-of-range slots are ignored). */
void fv_prof_span(fv_prof *p, int slot, int track, const char *name, int64_t t0_ns, int64_t t1_ns, int arg);
void fv_prof_instant(fv_prof *p, int slot, int track, const char *name, int64_t t_ns, int arg);

/* The frame loop's markers (core/frameloop.h's fv_frame_record, CLOCK_MONOTONIC times), for the
 * headset: instants "gaze latch" (the newest gaze sample taken, just before the rays) and "vsync"
 * (the photon time: the edge the frame was shown from) on the markers track, "late" when the
 * frame missed its target vsync; arg = the frame number. Records on slot 0: call it from the
 * thread that renders (the pipeline pool's worker 0). p may be NULL. */
void fv_prof_frame_markers(fv_prof *p, long frame, int64_t gaze_latch_ns, int64_t photon_ns, int late);

/* Per-stage hook (hardware counters): called on the rendering thread at the start (end = 0) and
 * the end (end = 1) of each stage span (stage: an fv_stage or FV_PROF_FRAME). */
typedef void (*fv_prof_stage_hook)(void *ctx, int stage, int end);
void fv_prof_set_stage_hook(fv_prof *p, fv_prof_stage_hook fn, void *ctx);
/* The one way stages are timed. begin calls the hook and returns the start time; end returns the
 * end time, calls the hook and records the span (slot 0, track FV_PROF_TRACK_STAGE + stage, arg,
 * e.g. the eye). Call both from the rendering thread. The hook runs outside the span, so its own
 * cost is not in the stage's time. p may be NULL: then they only read the clock. */
int64_t fv_prof_stage_begin(fv_prof *p, int stage);
int64_t fv_prof_stage_end(fv_prof *p, int stage, int64_t t0_ns, int arg);

/* Reading back (no thread recording). Events of a slot, oldest first: index in [0, count). */
size_t fv_prof_count(const fv_prof *p, int slot);
const fv_prof_event *fv_prof_event_at(const fv_prof *p, int slot, size_t index);
size_t fv_prof_dropped(const fv_prof *p, int slot);

#endif
