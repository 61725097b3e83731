/* fovea: vsync predictor (pure: no clocks, no I/O; times are CLOCK_MONOTONIC ns given by the
 * caller). A least-squares line t = a + period * k through the last `window` accepted edges,
 * each edge given its vsync index k by rounding its phase against the current fit:
 *  - an edge more than `tolerance` periods off any predicted vsync is spurious (ignored);
 *  - a second edge on the same vsync index is a doubled edge (ignored);
 *  - index gaps are missed edges (counted; the fit does not care);
 *  - `relock_after` rejected edges in a row mean the phase really moved: start again from them;
 *  - the window follows slow drift of the rate.
 * When the line goes silent the prediction goes on: from the fit for `coast_periods`
 * (state COAST), then, after `timer_after_ns`, at the nominal period from the last edge
 * (state TIMER). Frames never stop: fv_vsync_pred_next always answers. */
#ifndef FOVEA_VSYNCPRED_H
#define FOVEA_VSYNCPRED_H

#include <stdint.h>

#define FV_VSYNC_PRED_MAX_WINDOW 64

enum { FV_VSYNC_ACQUIRE = 0, FV_VSYNC_LOCKED, FV_VSYNC_COAST, FV_VSYNC_TIMER };
enum { FV_EDGE_ACCEPTED = 0, FV_EDGE_SPURIOUS, FV_EDGE_DOUBLED, FV_EDGE_RELOCK };

typedef struct fv_vsync_pred_params {
    int64_t nominal_period_ns; /* 11111111 (90 Hz) */
    double tolerance;          /* phase tolerance, periods: 0.25 */
    int window;                /* edges in the fit: 32 */
    int coast_periods;         /* silent this many periods: COAST (3) */
    int64_t timer_after_ns;    /* silent this long: TIMER (500 ms) */
    int relock_after;          /* rejected edges in a row that force a re-lock (4) */
} fv_vsync_pred_params;

typedef struct fv_vsync_pred {
    fv_vsync_pred_params p;
    int64_t start_ns;                 /* before any edge: free-run from here */
    int64_t t[FV_VSYNC_PRED_MAX_WINDOW], k[FV_VSYNC_PRED_MAX_WINDOW];
    double resid[FV_VSYNC_PRED_MAX_WINDOW]; /* innovation of each edge in the window, ns */
    int n, head;                      /* ring of accepted edges */
    int64_t ref_t, ref_k;             /* the fit: t(k) = ref_t + a_ns + period_ns * (k - ref_k) */
    double a_ns, period_ns;
    int64_t last_t, last_k;           /* newest accepted edge */
    int rejects_in_row;
    int tentative;                    /* > 0: period_ns is one interval's guess, not confirmed yet */
    double last_innovation_ns;        /* newest accepted edge minus its prediction */
    long edges, accepted, missed, spurious, doubled, relocks;
} fv_vsync_pred;

void fv_vsync_pred_default_params(fv_vsync_pred_params *p, int64_t nominal_period_ns);
void fv_vsync_pred_init(fv_vsync_pred *v, const fv_vsync_pred_params *p, int64_t start_ns);
/* One edge at t_ns (non-decreasing): FV_EDGE_*. */
int fv_vsync_pred_edge(fv_vsync_pred *v, int64_t t_ns);
/* FV_VSYNC_* at time now_ns (silence is judged against it). */
int fv_vsync_pred_state(const fv_vsync_pred *v, int64_t now_ns);
/* The first predicted vsync strictly after after_ns, as things stand at now_ns. */
int64_t fv_vsync_pred_next(const fv_vsync_pred *v, int64_t after_ns, int64_t now_ns);
double fv_vsync_pred_period_ns(const fv_vsync_pred *v);
/* RMS of the innovations (edge minus its prediction) over the window, ns. */
double fv_vsync_pred_jitter_ns(const fv_vsync_pred *v);
const char *fv_vsync_state_name(int state);

/* The vsync side both frame loops share (core/frameloop.c, core/displayloop.c): their clock and
 * edge source and the predictor the edges feed. */
typedef struct fv_vsync_edges {
    void *ctx;
    int64_t (*now_ns)(void *ctx);
    void (*sleep_until)(void *ctx, int64_t t_ns);
    /* next edge until deadline_ns: 1 with its time, 0 none, -1 the source failed; NULL: none */
    int (*wait_edge)(void *ctx, int64_t deadline_ns, int64_t *t_ns);
    fv_vsync_pred *pred;
    int *source_dead; /* set when the source fails: the rest of every wait is a sleep */
    long *edges;      /* edges seen */
} fv_vsync_edges;

/* Waits for edges until deadline, feeding the predictor. 1 when an edge in [lo, hi] came (its
 * time in *t); an edge after hi ends the wait with 0 (that vsync has passed without its edge). */
int fv_vsync_edges_take(const fv_vsync_edges *e, int64_t deadline, int64_t lo, int64_t hi, int64_t *t);
/* Waits for the edge of vsync v (within half a nominal period of it, until v + grace): its time,
 * or v (predicted) with *measured 0. */
int64_t fv_vsync_edges_wait(const fv_vsync_edges *e, int64_t v, int64_t nominal_period_ns, int64_t grace_ns, int *measured);

#endif
