#include "displayloop.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int fv_mailbox_init(fv_frame_mailbox *m)
{
    memset(m->seq, 0, sizeof m->seq);
    m->newest = m->reading = m->writing = -1;
    m->published = 0;
    /* priority inheritance: the display thread runs above the renderer, which must not hold it
     * up while preempted inside the lock */
    pthread_mutexattr_t at;
    if (pthread_mutexattr_init(&at))
        return -1;
    pthread_mutexattr_setprotocol(&at, PTHREAD_PRIO_INHERIT); /* best effort */
    const int rc = pthread_mutex_init(&m->mu, &at);
    pthread_mutexattr_destroy(&at);
    return rc ? -1 : 0;
}

void fv_mailbox_destroy(fv_frame_mailbox *m) { pthread_mutex_destroy(&m->mu); }

int fv_mailbox_begin_write(fv_frame_mailbox *m)
{
    pthread_mutex_lock(&m->mu);
    int s = 0;
    while (s == m->newest || s == m->reading)
        s++; /* three slots, at most two taken */
    m->writing = s;
    pthread_mutex_unlock(&m->mu);
    return s;
}

void fv_mailbox_publish(fv_frame_mailbox *m, int slot, long seq)
{
    pthread_mutex_lock(&m->mu);
    m->seq[slot] = seq;
    m->newest = slot;
    m->writing = -1;
    m->published++;
    pthread_mutex_unlock(&m->mu);
}

int fv_mailbox_acquire(fv_frame_mailbox *m, long *seq)
{
    pthread_mutex_lock(&m->mu);
    m->reading = m->newest;
    const int s = m->reading;
    if (s >= 0 && seq)
        *seq = m->seq[s];
    pthread_mutex_unlock(&m->mu);
    return s;
}

void fv_mailbox_release(fv_frame_mailbox *m)
{
    pthread_mutex_lock(&m->mu);
    m->reading = -1;
    pthread_mutex_unlock(&m->mu);
}

void fv_displayloop_default_params(fv_displayloop_params *p, int64_t nominal_period_ns)
{
    p->nominal_period_ns = nominal_period_ns > 0 ? nominal_period_ns : 11111111;
    p->margin_scale = 1.25;
    p->margin_extra_ns = 500000;
    /* the first compositions are the slowest (cold caches, the images' first touch): start at the cap */
    p->initial_margin_ns = p->nominal_period_ns - p->nominal_period_ns / 8;
    p->edge_grace_ns = p->nominal_period_ns / 4;
    p->margin_frames = 16;
    p->margin_long_frames = 256;
    p->margin_rank = 3;
}

void fv_displayloop_init(fv_displayloop *l, const fv_displayloop_params *p, const fv_displayloop_ops *ops)
{
    memset(l, 0, sizeof *l);
    l->p = *p;
    if (l->p.margin_frames < 1)
        l->p.margin_frames = 1;
    if (l->p.margin_frames > FV_DISPLAYLOOP_MAX_MARGIN_FRAMES)
        l->p.margin_frames = FV_DISPLAYLOOP_MAX_MARGIN_FRAMES;
    if (l->p.margin_long_frames < 0)
        l->p.margin_long_frames = 0;
    if (l->p.margin_long_frames > FV_DISPLAYLOOP_MAX_LONG_FRAMES)
        l->p.margin_long_frames = FV_DISPLAYLOOP_MAX_LONG_FRAMES;
    l->p.margin_rank = l->p.margin_rank < 1 ? 1 : l->p.margin_rank > FV_DISPLAYLOOP_MAX_RANK ? FV_DISPLAYLOOP_MAX_RANK : l->p.margin_rank;
    l->ops = *ops;
    fv_vsync_pred_params pp;
    fv_vsync_pred_default_params(&pp, p->nominal_period_ns);
    fv_vsync_pred_init(&l->pred, &pp, ops->now_ns(ops->ctx));
    l->source_dead = ops->wait_edge == NULL;
    l->last_frame = -1;
}

/* long_window 0: the slowest of the last margin_frames alone */
static int64_t margin_of(const fv_displayloop *l, int long_window)
{
    if (l->ncompose == 0)
        return l->p.initial_margin_ns;
    int64_t worst = 0;
    const long n = l->ncompose < l->p.margin_frames ? l->ncompose : l->p.margin_frames;
    for (long i = 1; i <= n; i++) { /* the newest n */
        const int64_t c = l->compose_ns[(l->ncompose - i) % FV_DISPLAYLOOP_MAX_LONG_FRAMES];
        worst = c > worst ? c : worst;
    }
    /* the long window's rank-th slowest (a slow spell of the memory system every few hundred ms
     * would otherwise find the margin back at the typical composition's every time) */
    const long nl = !long_window ? 0 : l->ncompose < l->p.margin_long_frames ? l->ncompose : l->p.margin_long_frames;
    if (nl >= l->p.margin_rank) {
        int64_t top[FV_DISPLAYLOOP_MAX_RANK]; /* the rank slowest, slowest first */
        int k = 0;
        for (long i = 1; i <= nl; i++) {
            const int64_t c = l->compose_ns[(l->ncompose - i) % FV_DISPLAYLOOP_MAX_LONG_FRAMES];
            if (k == l->p.margin_rank && c <= top[k - 1])
                continue;
            int j = k < l->p.margin_rank ? k++ : k - 1;
            for (; j > 0 && top[j - 1] < c; j--)
                top[j] = top[j - 1];
            top[j] = c;
        }
        worst = top[l->p.margin_rank - 1] > worst ? top[l->p.margin_rank - 1] : worst;
    }
    const int64_t m = (int64_t)((double)worst * l->p.margin_scale) + l->p.margin_extra_ns;
    /* at most 7/8 of a period: waking before the vsync ahead of the target only skips refreshes
     * (a composition longer than a period is late whatever the margin), and one slow composition
     * (cold caches, first touch of the images) would otherwise space the next 16 refreshes by
     * several periods each; the 1/8 leaves the wake-up after the previous vsync's edge */
    const int64_t cap = l->p.nominal_period_ns - l->p.nominal_period_ns / 8;
    return m < cap ? m : cap;
}

int64_t fv_displayloop_margin_ns(const fv_displayloop *l) { return margin_of(l, 1); }
int64_t fv_displayloop_reach_ns(const fv_displayloop *l) { return margin_of(l, 0); }

/* the vsync side of this loop (fv_vsync_edges_take, fv_vsync_edges_wait) */
static fv_vsync_edges edges_of(fv_displayloop *l)
{
    return (fv_vsync_edges){l->ops.ctx, l->ops.now_ns, l->ops.sleep_until, l->ops.wait_edge, &l->pred, &l->source_dead,
                            &l->edges};
}

static int take_edges(fv_displayloop *l, int64_t deadline, int64_t lo, int64_t hi, int64_t *t)
{
    const fv_vsync_edges e = edges_of(l);
    return fv_vsync_edges_take(&e, deadline, lo, hi, t);
}

static int64_t wait_vsync(fv_displayloop *l, int64_t v, int *measured)
{
    const fv_vsync_edges e = edges_of(l);
    return fv_vsync_edges_wait(&e, v, l->p.nominal_period_ns, l->p.edge_grace_ns, measured);
}

int fv_displayloop_refresh(fv_displayloop *l, fv_refresh_record *rec)
{
    memset(rec, 0, sizeof *rec);
    rec->refresh = l->refreshes;
    rec->frame = -1;
    rec->pose_err_deg = rec->pose_err_mm = NAN;
    int64_t now = l->ops.now_ns(l->ops.ctx), dummy;
    take_edges(l, now, INT64_MAX, INT64_MAX, &dummy);
    const int64_t margin = fv_displayloop_margin_ns(l), reach = fv_displayloop_reach_ns(l);
    rec->margin_ns = margin;
    /* the first vsync a composition can still make (the recent compositions' margin): woken
     * after V - margin (a late wake-up, or a margin near the period), V is still the target */
    int64_t after = now + (reach < margin ? reach : margin);
    /* never the vsync just composed for (its edge may not have been taken yet) */
    if (after <= l->last_target_ns + l->p.nominal_period_ns / 2)
        after = l->last_target_ns + l->p.nominal_period_ns / 2;
    int64_t target = fv_vsync_pred_next(&l->pred, after, now);
    if (now < target - margin) {
        take_edges(l, target - margin, INT64_MAX, INT64_MAX, &dummy);
        now = l->ops.now_ns(l->ops.ctx);
        target = fv_vsync_pred_next(&l->pred, target - l->p.nominal_period_ns / 2, now);
    }
    rec->target_ns = target;
    rec->wake_ns = now;
    if (l->ops.compose(l->ops.ctx, target, rec) < 0)
        return -1;
    const int64_t done = l->ops.now_ns(l->ops.ctx);
    rec->done_ns = done;
    if (rec->frame >= 0) { /* the compositions that warped a frame (before the first, nothing is done) */
        l->compose_ns[l->ncompose % FV_DISPLAYLOOP_MAX_LONG_FRAMES] = done - now;
        l->ncompose++;
    }
    rec->reused = rec->frame >= 0 && rec->frame == l->last_frame;
    l->reused += rec->reused;
    if (rec->frame >= 0)
        l->last_frame = rec->frame;
    int measured;
    if (done <= target) {
        rec->photon_ns = wait_vsync(l, target, &measured);
    } else {
        rec->late = 1;
        l->late++;
        target = fv_vsync_pred_next(&l->pred, done, done);
        rec->photon_ns = wait_vsync(l, target, &measured);
    }
    l->last_target_ns = target;
    rec->photon_edge = measured;
    rec->vsync_state = l->source_dead ? FV_VSYNC_TIMER : fv_vsync_pred_state(&l->pred, l->ops.now_ns(l->ops.ctx));
    l->refreshes++;
    return 0;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double fv_percentile(double *v, long n, double p)
{
    if (n <= 0)
        return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    long i = (long)ceil(p * (double)n) - 1;
    i = i < 0 ? 0 : i >= n ? n - 1 : i;
    return v[i];
}

void fv_display_summarise(const fv_refresh_record *r, long n, double px_per_refresh, int64_t period_ns,
                          fv_display_summary *s)
{
    memset(s, 0, sizeof *s);
    s->displayed_hz = s->mtp_p50_ms = s->mtp_p99_ms = s->g2p_p50_ms = s->g2p_p99_ms = NAN;
    s->compose_p50_ms = s->compose_p99_ms = s->age_p50_ms = s->pose_err_p50_deg = s->pose_err_p99_deg = NAN;
    s->disoccluded_frac = s->grid_frac = NAN;
    s->refreshes = n;
    if (n <= 0)
        return;
    double *v = malloc((size_t)n * sizeof *v);
    if (!v)
        return;
    long m, warped = 0;
    double holes = 0, grid = 0;
    long last = -1;
    for (long i = 0; i < n; i++) {
        s->late += r[i].late;
        s->reused += r[i].reused;
        s->displayed += !r[i].late && r[i].frame >= 0;
        if (r[i].frame >= 0 && r[i].frame != last)
            s->frames_shown++;
        if (r[i].frame >= 0) {
            last = r[i].frame;
            warped++;
            holes += (double)r[i].disoccluded;
            grid += (double)r[i].grid_px;
        }
    }
    for (long i = 1; i < n && period_ns > 0; i++) {
        const long gap = lround((double)(r[i].photon_ns - r[i - 1].photon_ns) / (double)period_ns);
        s->skipped += gap > 1 ? gap - 1 : 0;
    }
    s->missed = s->late + s->skipped;
    if (n > 1 && r[n - 1].photon_ns > r[0].photon_ns)
        s->displayed_hz = (double)(s->displayed - 1) * 1e9 / (double)(r[n - 1].photon_ns - r[0].photon_ns);
    m = 0;
    for (long i = 0; i < n; i++)
        if (r[i].head_t_ns)
            v[m++] = (double)(r[i].photon_ns - r[i].head_t_ns) * 1e-6;
    s->mtp_p50_ms = fv_percentile(v, m, 0.5), s->mtp_p99_ms = fv_percentile(v, m, 0.99);
    m = 0;
    for (long i = 0; i < n; i++)
        if (r[i].has_gaze && r[i].frame >= 0)
            v[m++] = (double)(r[i].photon_ns - r[i].gaze_t_ns) * 1e-6;
    s->g2p_p50_ms = fv_percentile(v, m, 0.5), s->g2p_p99_ms = fv_percentile(v, m, 0.99);
    m = 0;
    for (long i = 0; i < n; i++) /* refreshes that warped a frame (before the first there is nothing to do) */
        if (r[i].frame >= 0)
            v[m++] = (double)(r[i].done_ns - r[i].wake_ns) * 1e-6;
    s->compose_p50_ms = fv_percentile(v, m, 0.5), s->compose_p99_ms = fv_percentile(v, m, 0.99);
    m = 0;
    for (long i = 0; i < n; i++)
        if (r[i].frame >= 0)
            v[m++] = (double)(r[i].photon_ns - r[i].frame_done_ns) * 1e-6;
    s->age_p50_ms = fv_percentile(v, m, 0.5);
    m = 0;
    for (long i = 0; i < n; i++)
        if (!isnan(r[i].pose_err_deg))
            v[m++] = r[i].pose_err_deg;
    s->pose_err_p50_deg = fv_percentile(v, m, 0.5), s->pose_err_p99_deg = fv_percentile(v, m, 0.99);
    if (warped && px_per_refresh > 0)
        s->disoccluded_frac = holes / ((double)warped * px_per_refresh),
        s->grid_frac = grid / ((double)warped * px_per_refresh);
    free(v);
}
