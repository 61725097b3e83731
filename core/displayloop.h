/* fovea: the decoupled display loop (timewarp). Rendering runs at its own rate on its own thread
 * and publishes each complete stereo frame into a mailbox; the display loop wakes at every vsync
 * minus a measured margin, takes the newest complete frame, has it warped to the head pose
 * predicted for that vsync's photon time (compose callback) and presented, and waits for the
 * vsync. OS-free: clock, sleep, vsync line and composition come in as callbacks, so the tests run
 * it on a fake clock (tests/test_displayloop.c).
 *
 * Per refresh:
 *   1. take the vsync edges that came in (the predictor: core/vsyncpred.h);
 *   2. target V = the first predicted vsync at least one margin away; sleep to V - margin
 *      (margin = x 1.25 + 0.5 ms of the larger of the slowest of the last 16 compositions and the
 *      third slowest of the last 256 (about their p99), at most 7/8 of a period: a late refresh
 *      costs a whole period, so it errs early; the long window keeps it over the slow
 *      compositions that recur every few hundred ms on a machine with memory stalls);
 *      A wake-up later than V - margin (the thread held up, the previous edge taken late) still
 *      aims at V if V is at least the recent compositions' margin away (fv_displayloop_reach_ns);
 *   3. compose(V): newest frame, pose predicted for V, warp, present;
 *   4. done by V: shown from V; wait for V's edge (photon time). Done after V (late): V showed
 *      the previous image again; this one shows from the next vsync.
 * The mailbox has three slots: the display holds one, the newest complete frame is in another,
 * the renderer writes the third, so the display never sees a frame being written (never torn)
 * and the renderer never waits for the display. */
#ifndef FOVEA_DISPLAYLOOP_H
#define FOVEA_DISPLAYLOOP_H

#include <pthread.h>
#include <stdint.h>

#include "vsyncpred.h"

/* ---- the mailbox of rendered frames ---- */
#define FV_MAILBOX_SLOTS 3
typedef struct fv_frame_mailbox {
    pthread_mutex_t mu;
    int newest;  /* slot of the newest complete frame, -1: none yet */
    int reading; /* slot the display holds, -1: none */
    int writing; /* slot the renderer writes, -1: none */
    long seq[FV_MAILBOX_SLOTS];
    long published;
} fv_frame_mailbox;

int fv_mailbox_init(fv_frame_mailbox *m);
void fv_mailbox_destroy(fv_frame_mailbox *m);
/* The renderer: a slot to write (neither the newest nor the display's). */
int fv_mailbox_begin_write(fv_frame_mailbox *m);
/* The renderer: the slot is complete; it becomes the newest. */
void fv_mailbox_publish(fv_frame_mailbox *m, int slot, long seq);
/* The display: the newest complete frame's slot (held until the next acquire or release), its
 * number in *seq; -1 when nothing was published yet. */
int fv_mailbox_acquire(fv_frame_mailbox *m, long *seq);
void fv_mailbox_release(fv_frame_mailbox *m);

/* ---- one refresh ---- */
typedef struct fv_refresh_record {
    long refresh;
    long frame;             /* the rendered frame shown (-1: none yet: the compose showed nothing new) */
    int reused;             /* the same rendered frame as the refresh before (warped again) */
    int late;               /* composed after its vsync: that vsync showed the previous image */
    int64_t wake_ns;        /* compose start */
    int64_t done_ns;        /* compose done (presented) */
    int64_t target_ns;      /* the vsync it was composed for */
    int64_t photon_ns;      /* the vsync it was shown from (edge, or predicted) */
    int photon_edge;        /* photon_ns is a measured edge */
    int vsync_state;
    int64_t margin_ns;
    /* filled by compose */
    int64_t head_t_ns;      /* newest head pose sample warped to (0: no head source) */
    int has_gaze;
    int64_t gaze_t_ns;      /* the gaze sample of the rendered frame */
    float gaze_x, gaze_y;
    int64_t frame_start_ns; /* the rendered frame's ray start and completion */
    int64_t frame_done_ns;
    long disoccluded;       /* pixels of both eyes filled as disocclusions */
    long grid_px;           /* pixels of both eyes warped as grid cells (the bounded warp's fallback) */
    double pose_err_deg;    /* predicted head pose vs the true one at photon_ns (NAN: unknown) */
    double pose_err_mm;
} fv_refresh_record;

typedef struct fv_displayloop_ops {
    void *ctx;
    int64_t (*now_ns)(void *ctx);
    void (*sleep_until)(void *ctx, int64_t t_ns);
    /* as fv_frameloop_ops.wait_edge; NULL: no source (timer only) */
    int (*wait_edge)(void *ctx, int64_t deadline_ns, int64_t *t_ns);
    /* Composes and presents the image for vsync_ns, filling rec's compose fields and rec->frame.
     * 0, or -1 to end the loop. */
    int (*compose)(void *ctx, int64_t vsync_ns, fv_refresh_record *rec);
} fv_displayloop_ops;

typedef struct fv_displayloop_params {
    int64_t nominal_period_ns;
    double margin_scale;       /* 1.25 */
    int64_t margin_extra_ns;   /* 0.5 ms: wake-up slack */
    int64_t initial_margin_ns; /* 7/8 of a period (the cap): before any composition that warped a frame */
    int64_t edge_grace_ns;     /* period / 4 */
    int margin_frames;         /* 16 */
    /* the long window: the margin also covers the margin_rank-th slowest of the last
     * margin_long_frames compositions (256 and 3: the p99; 0 frames: off) */
    int margin_long_frames;
    int margin_rank;
} fv_displayloop_params;

#define FV_DISPLAYLOOP_MAX_MARGIN_FRAMES 64
#define FV_DISPLAYLOOP_MAX_LONG_FRAMES 1024
#define FV_DISPLAYLOOP_MAX_RANK 16
typedef struct fv_displayloop {
    fv_displayloop_params p;
    fv_displayloop_ops ops;
    fv_vsync_pred pred;
    int source_dead;
    int64_t compose_ns[FV_DISPLAYLOOP_MAX_LONG_FRAMES]; /* the last compositions, a ring */
    long ncompose;
    long refreshes, late, reused, edges, last_frame;
    int64_t last_target_ns;
} fv_displayloop;

void fv_displayloop_default_params(fv_displayloop_params *p, int64_t nominal_period_ns);
void fv_displayloop_init(fv_displayloop *l, const fv_displayloop_params *p, const fv_displayloop_ops *ops);
int64_t fv_displayloop_margin_ns(const fv_displayloop *l);
/* The margin of the recent compositions alone (the last margin_frames): a refresh that wakes
 * after V - margin still targets V when V is at least this far away. */
int64_t fv_displayloop_reach_ns(const fv_displayloop *l);
/* One refresh into *rec: 0, or -1 when compose asked to stop. */
int fv_displayloop_refresh(fv_displayloop *l, fv_refresh_record *rec);

/* ---- accounting ---- */
typedef struct fv_display_summary {
    long refreshes, displayed, late, reused, frames_shown; /* frames_shown: distinct rendered frames */
    long skipped;            /* vsyncs between two refreshes' photons that got no new image */
    long missed;             /* late + skipped: vsyncs without a newly composed image */
    double displayed_hz;                                   /* on-time refreshes per second of photon time */
    double mtp_p50_ms, mtp_p99_ms;                         /* head pose sample -> photon */
    double g2p_p50_ms, g2p_p99_ms;                         /* gaze sample -> photon */
    double compose_p50_ms, compose_p99_ms;                 /* of the refreshes that warped a frame */
    double age_p50_ms;                                     /* rendered frame's completion -> photon */
    double pose_err_p50_deg, pose_err_p99_deg;
    double disoccluded_frac;                               /* of the pixels warped */
    double grid_frac;                                      /* of the pixels warped: grid cells */
} fv_display_summary;
/* px_per_refresh: pixels warped per refresh (both eyes), for disoccluded_frac; period_ns: the
 * refresh period, for the vsyncs skipped between refreshes (a composition longer than a period). */
void fv_display_summarise(const fv_refresh_record *r, long n, double px_per_refresh, int64_t period_ns,
                          fv_display_summary *s);
/* p (0..1) of v[0..n) by nearest rank, sorting v; NAN when n == 0. */
double fv_percentile(double *v, long n, double p);

#endif
