#include "prof.h"
#include "stage.h"
#include "base/clock.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>


const char *fv_prof_stage_name(int stage)
{
    if (stage >= 0 && stage < FV_STAGE_COUNT)
        return fv_stage_names[stage];
    return stage == FV_PROF_FRAME ? "frame" : "?";
}

/* One slot's ring: written by one thread only; padded so neighbours' counters do not share a
 * cache line. */
typedef struct {
    fv_prof_event *ev;
    size_t n; /* events ever recorded; the ring holds the last min(n, cap) */
    char pad[64 - sizeof(fv_prof_event *) - sizeof(size_t)];
} ring;

struct fv_prof {
    int slots;
    size_t cap, mask;
    ring *r;
    fv_prof_stage_hook hook;
    void *hook_ctx;
};

fv_prof *fv_prof_create(int slots, size_t capacity)
{
    if (slots < 1 || capacity < 1)
        return NULL;
    size_t cap = 1;
    while (cap < capacity)
        cap <<= 1;
    fv_prof *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    p->slots = slots;
    p->cap = cap;
    p->mask = cap - 1;
    p->r = calloc((size_t)slots, sizeof *p->r);
    if (!p->r) {
        free(p);
        return NULL;
    }
    for (int s = 0; s < slots; s++) {
        if (!(p->r[s].ev = malloc(cap * sizeof *p->r[s].ev))) {
            fv_prof_destroy(p);
            return NULL;
        }
        /* touched now, so that no page fault lands in a recorded frame */
        memset(p->r[s].ev, 0, cap * sizeof *p->r[s].ev);
    }
    return p;
}

void fv_prof_destroy(fv_prof *p)
{
    if (!p)
        return;
    if (p->r)
        for (int s = 0; s < p->slots; s++)
            free(p->r[s].ev);
    free(p->r);
    free(p);
}

int fv_prof_slots(const fv_prof *p) { return p ? p->slots : 0; }


static inline void put(fv_prof *p, int slot, int track, const char *name, int64_t t0, int64_t t1, int arg, char kind)
{
    if (!p || slot < 0 || slot >= p->slots)
        return;
    ring *r = &p->r[slot];
    fv_prof_event *e = &r->ev[r->n & p->mask];
    e->t0_ns = t0;
    e->t1_ns = t1 < t0 ? t0 : t1;
    e->name = name;
    e->track = track;
    e->arg = arg;
    e->kind = kind;
    r->n++;
}

void fv_prof_span(fv_prof *p, int slot, int track, const char *name, int64_t t0_ns, int64_t t1_ns, int arg)
{
    put(p, slot, track, name, t0_ns, t1_ns, arg, 'X');
}

void fv_prof_instant(fv_prof *p, int slot, int track, const char *name, int64_t t_ns, int arg)
{
    put(p, slot, track, name, t_ns, t_ns, arg, 'i');
}

void fv_prof_frame_markers(fv_prof *p, long frame, int64_t gaze_latch_ns, int64_t photon_ns, int late)
{
    if (!p)
        return;
    const int f = (int)(frame & 0x7fffffff);
    put(p, 0, FV_PROF_TRACK_MARKERS, "gaze latch", gaze_latch_ns, gaze_latch_ns, f, 'i');
    if (late)
        put(p, 0, FV_PROF_TRACK_MARKERS, "late", photon_ns, photon_ns, f, 'i');
    put(p, 0, FV_PROF_TRACK_MARKERS, "vsync", photon_ns, photon_ns, f, 'i');
}

void fv_prof_set_stage_hook(fv_prof *p, fv_prof_stage_hook fn, void *ctx)
{
    p->hook = fn;
    p->hook_ctx = ctx;
}

int64_t fv_prof_stage_begin(fv_prof *p, int stage)
{
    if (p && p->hook)
        p->hook(p->hook_ctx, stage, 0);
    return fv_time_ns();
}

int64_t fv_prof_stage_end(fv_prof *p, int stage, int64_t t0_ns, int arg)
{
    const int64_t t = fv_time_ns();
    if (p) {
        if (p->hook)
            p->hook(p->hook_ctx, stage, 1);
        fv_prof_span(p, 0, FV_PROF_TRACK_STAGE + stage, fv_prof_stage_name(stage), t0_ns, t, arg);
    }
    return t;
}

size_t fv_prof_count(const fv_prof *p, int slot)
{
    if (!p || slot < 0 || slot >= p->slots)
        return 0;
    return p->r[slot].n < p->cap ? p->r[slot].n : p->cap;
}

const fv_prof_event *fv_prof_event_at(const fv_prof *p, int slot, size_t index)
{
    if (index >= fv_prof_count(p, slot))
        return NULL;
    const ring *r = &p->r[slot];
    const size_t first = r->n - fv_prof_count(p, slot);
    return &r->ev[(first + index) & p->mask];
}

size_t fv_prof_dropped(const fv_prof *p, int slot)
{
    if (!p || slot < 0 || slot >= p->slots)
        return 0;
    return p->r[slot].n - fv_prof_count(p, slot);
}

