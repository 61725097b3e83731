/* fovea: the vsync-locked frame loop, OS-free (clock, sleeping, the vsync line, gaze, rendering
 * and the display come in as callbacks, so the tests drive it with a fake clock).
 *
 * Per frame:
 *   1. take the vsync edges that came in (they feed the predictor, core/vsyncpred.h);
 *   2. target vsync V = the first predicted vsync at least one render budget away; sleep until
 *      V - budget, taking edges meanwhile (budget = the slowest of the recent render times
 *      times budget_scale plus budget_margin_ns);
 *   3. latch the newest gaze sample taken at or before that moment, just before the rays;
 *   4. render both eyes;
 *   5. done before V: present the new frame now, to be shown from V, and wait for V's edge (the
 *      photon time; the predicted V when the line is silent or gone);
 *      done after V (late): V showed the previous frame again (present(PREVIOUS)); the new
 *      frame is presented for the next vsync after it is done;
 *   6. record gaze-sample time, ray start, frame done and photon time.
 * A vsync source that fails (wait_edge returns -1) is dropped for good: the loop then runs on
 * the predictor, which coasts and falls back to the nominal timer. */
#ifndef FOVEA_FRAMELOOP_H
#define FOVEA_FRAMELOOP_H

#include <pthread.h>
#include <stdint.h>

#include "vsyncpred.h"

/* ---- gaze samples: a small ring written by the tracker (or trace / mouse), read by the loop ---- */
typedef struct fv_gaze_sample {
    int64_t t_ns;     /* when the eye was there (camera capture time) */
    float x, y;       /* normalised image coordinates of the eye's image */
    float confidence; /* 0..1 */
} fv_gaze_sample;

#define FV_GAZE_RING 64
typedef struct fv_gaze_ring {
    pthread_mutex_t mu;
    fv_gaze_sample s[FV_GAZE_RING];
    long n; /* samples pushed so far */
} fv_gaze_ring;

int fv_gaze_ring_init(fv_gaze_ring *r);
void fv_gaze_ring_destroy(fv_gaze_ring *r);
void fv_gaze_ring_push(fv_gaze_ring *r, const fv_gaze_sample *s);
/* The newest sample with t_ns <= before_ns: 1, or 0 when there is none. */
int fv_gaze_ring_latest(fv_gaze_ring *r, int64_t before_ns, fv_gaze_sample *out);

/* ---- the loop ---- */
enum { FV_PRESENT_NEW = 0, FV_PRESENT_PREVIOUS = 1 };

typedef struct fv_frameloop_ops {
    void *ctx;
    int64_t (*now_ns)(void *ctx);
    void (*sleep_until)(void *ctx, int64_t t_ns);
    /* Waits for the next vsync edge until deadline_ns (deadline <= now: just poll). 1 with its
     * time in *t_ns, 0 none by the deadline, -1 the source failed. NULL: no source (timer only). */
    int (*wait_edge)(void *ctx, int64_t deadline_ns, int64_t *t_ns);
    /* Called just before latching: a gaze source sampled on demand (trace, mouse) pushes its
     * sample for now_ns into the ring. May be NULL. */
    void (*sample_gaze)(void *ctx, int64_t now_ns);
    /* Renders both eyes with gaze g (NULL: none yet, use the image centre) and head pose at t_ns
     * into the back image. 0, or -1 to end the loop. */
    int (*render)(void *ctx, const fv_gaze_sample *g, int64_t t_ns);
    /* FV_PRESENT_NEW: show the back image from vsync_ns on (it becomes the front);
     * FV_PRESENT_PREVIOUS: vsync_ns shows the front image again. 0, or -1 (the caller's
     * display failed; the loop goes on, the caller swaps in another display). */
    int (*present)(void *ctx, int which, int64_t vsync_ns);
} fv_frameloop_ops;

typedef struct fv_frameloop_params {
    int64_t nominal_period_ns; /* for the predictor (and the timer fallback) */
    double budget_scale;       /* 1.05: a late frame costs one period, so the budget need not be generous */
    int64_t budget_margin_ns;  /* 1 ms: wake-up and present slack */
    int64_t edge_grace_ns;     /* wait this long past a predicted vsync for its edge: period / 4 */
    int budget_frames;         /* render times remembered: 16 */
    int64_t initial_budget_ns; /* before any frame: one period */
} fv_frameloop_params;

typedef struct fv_frame_record {
    long frame;
    int has_gaze;
    float gaze_x, gaze_y;
    int64_t gaze_t_ns;    /* capture time of the latched sample (0 without) */
    int64_t wake_ns;      /* when the loop woke for this frame */
    int64_t ray_start_ns; /* gaze latched, rays begin */
    int64_t done_ns;      /* both eyes rendered */
    int64_t target_ns;    /* the vsync it was meant for */
    int64_t photon_ns;    /* the vsync it was shown from (edge time, or predicted) */
    int late;             /* missed its target: the previous frame was shown again */
    int photon_edge;      /* photon_ns is a measured edge (1) or a prediction (0) */
    int vsync_state;      /* FV_VSYNC_* when presented */
    int64_t budget_ns;
    /* filled by the caller (the frame loop leaves them 0 / NAN): the head pose sample the frame
     * was rendered from, and its prediction's error against the true pose at photon_ns */
    int64_t head_t_ns;
    double pose_err_deg;
} fv_frame_record;

#define FV_FRAMELOOP_MAX_BUDGET_FRAMES 64
typedef struct fv_frameloop {
    fv_frameloop_params p;
    fv_frameloop_ops ops;
    fv_gaze_ring *gaze;
    fv_vsync_pred pred;
    int source_dead;   /* the vsync source failed: predictor / timer only */
    int64_t render_ns[FV_FRAMELOOP_MAX_BUDGET_FRAMES];
    int nrender;
    long frames, late, repeats, edges;
} fv_frameloop;

void fv_frameloop_default_params(fv_frameloop_params *p, int64_t nominal_period_ns);
/* gaze may be NULL (no gaze: the image centre). */
void fv_frameloop_init(fv_frameloop *l, const fv_frameloop_params *p, const fv_frameloop_ops *ops,
                       fv_gaze_ring *gaze);
/* The budget the next frame will use. */
int64_t fv_frameloop_budget_ns(const fv_frameloop *l);
/* One frame, recorded in *rec. 0, or -1 when render() asked to stop. */
int fv_frameloop_frame(fv_frameloop *l, fv_frame_record *rec);

/* ---- latency summary ---- */
typedef struct fv_latency_summary {
    long frames, late;
    double p50_ms, p99_ms, max_ms; /* gaze sample -> photon */
    double render_p50_ms, render_p99_ms;
    double fps;                    /* frames presented per second of photon time */
} fv_latency_summary;
/* Over n records (records without gaze are left out of the latency figures). */
void fv_latency_summarise(const fv_frame_record *r, long n, fv_latency_summary *s);

#endif
