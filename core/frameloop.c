#include "frameloop.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int fv_gaze_ring_init(fv_gaze_ring *r)
{
    memset(r->s, 0, sizeof r->s);
    r->n = 0;
    return pthread_mutex_init(&r->mu, NULL) ? -1 : 0;
}

void fv_gaze_ring_destroy(fv_gaze_ring *r) { pthread_mutex_destroy(&r->mu); }

void fv_gaze_ring_push(fv_gaze_ring *r, const fv_gaze_sample *s)
{
    pthread_mutex_lock(&r->mu);
    r->s[r->n % FV_GAZE_RING] = *s;
    r->n++;
    pthread_mutex_unlock(&r->mu);
}

int fv_gaze_ring_latest(fv_gaze_ring *r, int64_t before_ns, fv_gaze_sample *out)
{
    int found = 0;
    pthread_mutex_lock(&r->mu);
    /* newest first; samples arrive in time order, but a source may stamp ahead of now */
    long oldest = r->n > FV_GAZE_RING ? r->n - FV_GAZE_RING : 0;
    for (long i = r->n - 1; i >= oldest; i--) {
        const fv_gaze_sample *s = &r->s[i % FV_GAZE_RING];
        if (s->t_ns <= before_ns && (!found || s->t_ns > out->t_ns)) {
            *out = *s;
            found = 1;
        }
    }
    pthread_mutex_unlock(&r->mu);
    return found;
}

void fv_frameloop_default_params(fv_frameloop_params *p, int64_t nominal_period_ns)
{
    p->nominal_period_ns = nominal_period_ns > 0 ? nominal_period_ns : 11111111;
    p->budget_scale = 1.05;
    p->budget_margin_ns = 1000000;
    p->edge_grace_ns = p->nominal_period_ns / 4;
    p->budget_frames = 16;
    p->initial_budget_ns = p->nominal_period_ns;
}

void fv_frameloop_init(fv_frameloop *l, const fv_frameloop_params *p, const fv_frameloop_ops *ops,
                       fv_gaze_ring *gaze)
{
    memset(l, 0, sizeof *l);
    l->p = *p;
    if (l->p.budget_frames < 1)
        l->p.budget_frames = 1;
    if (l->p.budget_frames > FV_FRAMELOOP_MAX_BUDGET_FRAMES)
        l->p.budget_frames = FV_FRAMELOOP_MAX_BUDGET_FRAMES;
    l->ops = *ops;
    l->gaze = gaze;
    fv_vsync_pred_params pp;
    fv_vsync_pred_default_params(&pp, p->nominal_period_ns);
    fv_vsync_pred_init(&l->pred, &pp, ops->now_ns(ops->ctx));
    l->source_dead = ops->wait_edge == NULL;
}

int64_t fv_frameloop_budget_ns(const fv_frameloop *l)
{
    if (l->nrender == 0)
        return l->p.initial_budget_ns;
    int64_t worst = 0;
    const int n = l->nrender < l->p.budget_frames ? l->nrender : l->p.budget_frames;
    for (int i = 0; i < n; i++)
        if (l->render_ns[i] > worst)
            worst = l->render_ns[i];
    return (int64_t)((double)worst * l->p.budget_scale) + l->p.budget_margin_ns;
}

/* the vsync side of this loop (fv_vsync_edges_take, fv_vsync_edges_wait) */
static fv_vsync_edges edges_of(fv_frameloop *l)
{
    return (fv_vsync_edges){l->ops.ctx, l->ops.now_ns, l->ops.sleep_until, l->ops.wait_edge, &l->pred, &l->source_dead,
                            &l->edges};
}

static int take_edges(fv_frameloop *l, int64_t deadline, int64_t lo, int64_t hi, int64_t *t)
{
    const fv_vsync_edges e = edges_of(l);
    return fv_vsync_edges_take(&e, deadline, lo, hi, t);
}

static int64_t wait_vsync(fv_frameloop *l, int64_t v, int *measured)
{
    const fv_vsync_edges e = edges_of(l);
    return fv_vsync_edges_wait(&e, v, l->p.nominal_period_ns, l->p.edge_grace_ns, measured);
}

int fv_frameloop_frame(fv_frameloop *l, fv_frame_record *rec)
{
    memset(rec, 0, sizeof *rec);
    rec->frame = l->frames;
    int64_t now = l->ops.now_ns(l->ops.ctx);
    int64_t dummy;
    take_edges(l, now, INT64_MAX, INT64_MAX, &dummy); /* whatever came in meanwhile */
    const int64_t budget = fv_frameloop_budget_ns(l);
    rec->budget_ns = budget;
    int64_t target = fv_vsync_pred_next(&l->pred, now + budget, now);
    const int64_t wake = target - budget;
    if (now < wake) {
        take_edges(l, wake, INT64_MAX, INT64_MAX, &dummy);
        now = l->ops.now_ns(l->ops.ctx);
        /* the new edges refine the phase: the same vsync, predicted better */
        target = fv_vsync_pred_next(&l->pred, target - l->p.nominal_period_ns / 2, now);
    }
    rec->wake_ns = now;
    rec->target_ns = target;

    if (l->ops.sample_gaze)
        l->ops.sample_gaze(l->ops.ctx, now);
    fv_gaze_sample g;
    const int64_t ray_start = l->ops.now_ns(l->ops.ctx);
    rec->has_gaze = l->gaze && fv_gaze_ring_latest(l->gaze, ray_start, &g);
    if (rec->has_gaze) {
        rec->gaze_x = g.x;
        rec->gaze_y = g.y;
        rec->gaze_t_ns = g.t_ns;
    }
    rec->ray_start_ns = ray_start;
    if (l->ops.render(l->ops.ctx, rec->has_gaze ? &g : NULL, target) < 0)
        return -1;
    const int64_t done = l->ops.now_ns(l->ops.ctx);
    rec->done_ns = done;
    l->render_ns[l->nrender % l->p.budget_frames] = done - ray_start;
    l->nrender++;

    int measured;
    if (done <= target) {
        l->ops.present(l->ops.ctx, FV_PRESENT_NEW, target);
        rec->photon_ns = wait_vsync(l, target, &measured);
    } else {
        /* late: the target vsync has shown the previous frame (no tearing); this one goes to
         * the next vsync after it is done */
        rec->late = 1;
        l->late++;
        l->repeats++;
        l->ops.present(l->ops.ctx, FV_PRESENT_PREVIOUS, target);
        const int64_t next = fv_vsync_pred_next(&l->pred, done, done);
        l->ops.present(l->ops.ctx, FV_PRESENT_NEW, next);
        rec->photon_ns = wait_vsync(l, next, &measured);
    }
    rec->photon_edge = measured;
    rec->vsync_state = l->source_dead ? FV_VSYNC_TIMER : fv_vsync_pred_state(&l->pred, l->ops.now_ns(l->ops.ctx));
    l->frames++;
    return 0;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double pct(const double *v, long n, double q)
{
    if (n == 0)
        return NAN;
    long i = (long)ceil(q * (double)n) - 1; /* nearest rank */
    if (i < 0)
        i = 0;
    if (i >= n)
        i = n - 1;
    return v[i];
}

void fv_latency_summarise(const fv_frame_record *r, long n, fv_latency_summary *s)
{
    memset(s, 0, sizeof *s);
    s->frames = n;
    s->p50_ms = s->p99_ms = s->max_ms = s->render_p50_ms = s->render_p99_ms = s->fps = NAN;
    if (n <= 0)
        return;
    double *lat = malloc((size_t)n * sizeof *lat), *ren = malloc((size_t)n * sizeof *ren);
    if (!lat || !ren) {
        free(lat);
        free(ren);
        return;
    }
    long m = 0;
    for (long i = 0; i < n; i++) {
        s->late += r[i].late;
        ren[i] = (double)(r[i].done_ns - r[i].ray_start_ns) * 1e-6;
        if (r[i].has_gaze)
            lat[m++] = (double)(r[i].photon_ns - r[i].gaze_t_ns) * 1e-6;
    }
    qsort(lat, (size_t)m, sizeof *lat, cmp_double);
    qsort(ren, (size_t)n, sizeof *ren, cmp_double);
    s->p50_ms = pct(lat, m, 0.50);
    s->p99_ms = pct(lat, m, 0.99);
    s->max_ms = m ? lat[m - 1] : NAN;
    s->render_p50_ms = pct(ren, n, 0.50);
    s->render_p99_ms = pct(ren, n, 0.99);
    if (n > 1 && r[n - 1].photon_ns > r[0].photon_ns)
        s->fps = (double)(n - 1) * 1e9 / (double)(r[n - 1].photon_ns - r[0].photon_ns);
    free(lat);
    free(ren);
}
