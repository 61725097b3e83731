#include "vsyncpred.h"

#include <math.h>
#include <string.h>

void fv_vsync_pred_default_params(fv_vsync_pred_params *p, int64_t nominal_period_ns)
{
    p->nominal_period_ns = nominal_period_ns > 0 ? nominal_period_ns : 11111111;
    p->tolerance = 0.25;
    p->window = 32;
    p->coast_periods = 3;
    p->timer_after_ns = 500000000;
    p->relock_after = 4;
}

void fv_vsync_pred_init(fv_vsync_pred *v, const fv_vsync_pred_params *p, int64_t start_ns)
{
    memset(v, 0, sizeof *v);
    v->p = *p;
    if (v->p.window < 2)
        v->p.window = 2;
    if (v->p.window > FV_VSYNC_PRED_MAX_WINDOW)
        v->p.window = FV_VSYNC_PRED_MAX_WINDOW;
    v->start_ns = start_ns;
    v->period_ns = (double)p->nominal_period_ns;
}

static void restart(fv_vsync_pred *v, int64_t t_ns)
{
    v->n = 0;
    v->head = 0;
    v->ref_t = t_ns;
    v->ref_k = 0;
    v->a_ns = 0.0;
    v->last_t = t_ns;
    v->last_k = 0;
    v->t[0] = t_ns;
    v->k[0] = 0;
    v->resid[0] = NAN; /* no prediction to differ from */
    v->n = 1;
    v->head = 1 % v->p.window;
    v->rejects_in_row = 0;
    /* a re-lock starts from the nominal period: a period fitted to edges that no longer fit is
     * exactly what must not survive (a wrong one would keep every third edge "in phase") */
    v->period_ns = (double)v->p.nominal_period_ns;
    v->tentative = 0;
    v->last_innovation_ns = 0.0;
}

/* Least squares over the window, relative to the newest edge (keeps doubles exact enough). */
static void refit(fv_vsync_pred *v)
{
    const double nom = (double)v->p.nominal_period_ns;
    v->ref_t = v->last_t;
    v->ref_k = v->last_k;
    if (v->n < 2) {
        v->a_ns = 0.0;
        return;
    }
    double sk = 0, st = 0, skk = 0, skt = 0;
    for (int i = 0; i < v->n; i++) {
        double k = (double)(v->k[i] - v->ref_k), t = (double)(v->t[i] - v->ref_t);
        sk += k, st += t, skk += k * k, skt += k * t;
    }
    const double n = v->n, den = n * skk - sk * sk;
    if (den <= 0.0)
        return;
    double b = (n * skt - sk * st) / den;
    if (b < 0.5 * nom)
        b = 0.5 * nom;
    if (b > 2.0 * nom)
        b = 2.0 * nom;
    v->period_ns = b;
    v->a_ns = (st - b * sk) / n;
}

int fv_vsync_pred_edge(fv_vsync_pred *v, int64_t t_ns)
{
    v->edges++;
    if (v->accepted == 0 || t_ns - v->last_t > v->p.timer_after_ns) {
        /* first edge, or the first after a long silence: the old phase is stale */
        if (v->accepted)
            v->relocks++;
        v->accepted++;
        restart(v, t_ns);
        return v->accepted == 1 ? FV_EDGE_ACCEPTED : FV_EDGE_RELOCK;
    }
    if (v->n == 1) {
        /* acquiring: a first interval well off the nominal one but not a doubled or missed edge
         * (a 60 Hz panel when 90 was assumed) sets the period */
        const double dt = (double)(t_ns - v->last_t), nom = (double)v->p.nominal_period_ns;
        if (dt >= 0.6 * nom && dt <= 1.6 * nom && fabs(dt - nom) > v->p.tolerance * nom)
            v->period_ns = dt, v->tentative = 2; /* this edge and the next must agree */
    }
    const double pred_k = (double)(t_ns - v->ref_t) - v->a_ns;
    const double kf = (double)v->ref_k + pred_k / v->period_ns;
    const int64_t k = (int64_t)llround(kf);
    const double frac = kf - (double)k;
    int verdict = FV_EDGE_ACCEPTED;
    if (fabs(frac) > v->p.tolerance)
        verdict = FV_EDGE_SPURIOUS;
    else if (k <= v->last_k)
        verdict = FV_EDGE_DOUBLED;
    if (verdict != FV_EDGE_ACCEPTED) {
        if (verdict == FV_EDGE_SPURIOUS)
            v->spurious++;
        else
            v->doubled++;
        if (v->tentative) {
            /* the one interval that set the period was not the line's (a late or early edge at
             * acquisition): the next one disagrees, so acquire again from this edge */
            v->relocks++;
            v->accepted++;
            restart(v, t_ns);
            return FV_EDGE_RELOCK;
        }
        if (++v->rejects_in_row >= v->p.relock_after) {
            v->relocks++;
            v->accepted++;
            restart(v, t_ns);
            return FV_EDGE_RELOCK;
        }
        return verdict;
    }
    v->rejects_in_row = 0;
    if (v->tentative)
        v->tentative--; /* 0 once a second interval agreed */
    v->accepted++;
    if (k > v->last_k + 1)
        v->missed += k - v->last_k - 1;
    const double predicted = (double)(v->ref_t - t_ns) + v->a_ns + v->period_ns * (double)(k - v->ref_k);
    v->last_innovation_ns = -predicted; /* edge minus prediction */
    v->t[v->head] = t_ns;
    v->k[v->head] = k;
    v->resid[v->head] = v->last_innovation_ns;
    v->head = (v->head + 1) % v->p.window;
    if (v->n < v->p.window)
        v->n++;
    v->last_t = t_ns;
    v->last_k = k;
    refit(v);
    return FV_EDGE_ACCEPTED;
}

int fv_vsync_pred_state(const fv_vsync_pred *v, int64_t now_ns)
{
    if (v->accepted == 0)
        return now_ns - v->start_ns > v->p.timer_after_ns ? FV_VSYNC_TIMER : FV_VSYNC_ACQUIRE;
    const int64_t silent = now_ns - v->last_t;
    if (silent > v->p.timer_after_ns)
        return FV_VSYNC_TIMER;
    if ((double)silent > v->p.coast_periods * v->period_ns)
        return FV_VSYNC_COAST;
    return v->n < 3 ? FV_VSYNC_ACQUIRE : FV_VSYNC_LOCKED;
}

int64_t fv_vsync_pred_next(const fv_vsync_pred *v, int64_t after_ns, int64_t now_ns)
{
    double base, period;
    if (v->accepted == 0) {
        base = (double)v->start_ns;
        period = (double)v->p.nominal_period_ns;
    } else if (fv_vsync_pred_state(v, now_ns) == FV_VSYNC_TIMER) {
        base = (double)v->last_t; /* the line's last word on the phase, at the nominal rate */
        period = (double)v->p.nominal_period_ns;
    } else {
        base = (double)v->ref_t + v->a_ns;
        period = v->period_ns;
    }
    double n = ceil(((double)after_ns - base) / period);
    int64_t t = (int64_t)llround(base + n * period);
    while (t <= after_ns) /* rounding */
        t = (int64_t)llround(base + ++n * period);
    return t;
}

double fv_vsync_pred_period_ns(const fv_vsync_pred *v) { return v->period_ns; }

double fv_vsync_pred_jitter_ns(const fv_vsync_pred *v)
{
    if (v->n < 2)
        return 0.0;
    double s = 0.0;
    int m = 0;
    for (int i = 0; i < v->n; i++) {
        if (isnan(v->resid[i]))
            continue;
        s += v->resid[i] * v->resid[i];
        m++;
    }
    return m ? sqrt(s / m) : 0.0;
}

const char *fv_vsync_state_name(int state)
{
    static const char *const names[] = {"acquire", "locked", "coast", "timer"};
    return state >= 0 && state <= FV_VSYNC_TIMER ? names[state] : "?";
}

int fv_vsync_edges_take(const fv_vsync_edges *e, int64_t deadline, int64_t lo, int64_t hi, int64_t *t)
{
    for (;;) {
        if (*e->source_dead) {
            if (e->now_ns(e->ctx) < deadline)
                e->sleep_until(e->ctx, deadline);
            return 0;
        }
        int64_t te;
        const int rc = e->wait_edge(e->ctx, deadline, &te);
        if (rc < 0) {
            *e->source_dead = 1;
            continue;
        }
        if (rc == 0)
            return 0;
        (*e->edges)++;
        fv_vsync_pred_edge(e->pred, te);
        if (te >= lo && te <= hi) {
            *t = te;
            return 1;
        }
        if (te > hi)
            return 0;
    }
}

int64_t fv_vsync_edges_wait(const fv_vsync_edges *e, int64_t v, int64_t nominal_period_ns, int64_t grace_ns, int *measured)
{
    int64_t te;
    const int64_t half = nominal_period_ns / 2;
    *measured = fv_vsync_edges_take(e, v + grace_ns, v - half, v + half, &te);
    return *measured ? te : v;
}
