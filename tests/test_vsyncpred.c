/* The vsync predictor against synthetic edge streams: jitter, missed, doubled and spurious
 * edges, drift of the rate, silence, a rate other than the nominal one. */
#include <math.h>
#include <stdio.h>

#include "testutil.h"
#include "vsyncpred.h"

#define P90 11111111.0 /* ns */

/* True vsync k of a line starting at t0 whose period drifts linearly by drift_ns per frame. */
static double true_vsync(double t0, double period, double drift_ns, long k)
{
    return t0 + period * (double)k + 0.5 * drift_ns * (double)k * (double)(k - 1);
}

static double jitter(uint64_t *rng, double amp_ns) { return amp_ns * (2.0 * fv_test_randf(rng) - 1.0); }

typedef struct {
    double max_err_ns; /* |predicted next vsync - true next vsync|, after warm-up */
    long fed, dropped, dropped_tail; /* dropped_tail: after the last fed edge (no gap seen yet) */
} run_result;

/* Feeds edges of vsyncs [0, n) (dropped with probability p_drop, doubled with p_double 0.3 ms
 * later, a spurious edge at mid-frame with p_spur) and checks, after each true vsync from
 * warm-up on, the prediction of the next one. */
static run_result run(fv_vsync_pred *v, double period, double drift_ns, double jit_ns, double p_drop, double p_double,
                      double p_spur, long n, uint64_t seed)
{
    uint64_t rng = seed;
    run_result r = {0};
    const double t0 = 1e9;
    for (long k = 0; k < n; k++) {
        const double tv = true_vsync(t0, period, drift_ns, k);
        if (k > 0 && fv_test_randf(&rng) < p_drop) {
            r.dropped++;
            r.dropped_tail++;
        } else {
            r.dropped_tail = 0;
            fv_vsync_pred_edge(v, (int64_t)(tv + jitter(&rng, jit_ns)));
            r.fed++;
            if (fv_test_randf(&rng) < p_double)
                fv_vsync_pred_edge(v, (int64_t)(tv + 300000.0));
        }
        if (fv_test_randf(&rng) < p_spur)
            fv_vsync_pred_edge(v, (int64_t)(tv + 0.5 * period));
        if (k >= 40) {
            const double now = tv + 0.4 * period;
            const double next = true_vsync(t0, period, drift_ns, k + 1);
            double e = fabs((double)fv_vsync_pred_next(v, (int64_t)now, (int64_t)now) - next);
            if (e > r.max_err_ns)
                r.max_err_ns = e;
        }
    }
    return r;
}

static void init90(fv_vsync_pred *v)
{
    fv_vsync_pred_params p;
    fv_vsync_pred_default_params(&p, (int64_t)P90);
    fv_vsync_pred_init(v, &p, 0);
}

static void test_clean_and_jitter(void **st)
{
    (void)st;
    fv_vsync_pred v;
    init90(&v);
    run_result r = run(&v, P90, 0, 0, 0, 0, 0, 300, 1);
    assert_true(r.max_err_ns < 1000.0); /* integer ns rounding only */
    assert_int_equal(v.missed, 0);
    assert_int_equal(v.accepted, 300);

    /* +-150 us uniform jitter (sigma 87 us): the 32-edge fit predicts far better than one edge */
    init90(&v);
    r = run(&v, P90 * 1.002, 0, 150000.0, 0, 0, 0, 600, 2);
    printf("jitter: max err %.1f us, reported jitter %.1f us, period %.1f ns\n", r.max_err_ns / 1e3,
           fv_vsync_pred_jitter_ns(&v) / 1e3, fv_vsync_pred_period_ns(&v));
    assert_true(r.max_err_ns < 90000.0);
    assert_true(fv_vsync_pred_jitter_ns(&v) > 60000.0 && fv_vsync_pred_jitter_ns(&v) < 130000.0);
    assert_true(fabs(fv_vsync_pred_period_ns(&v) - P90 * 1.002) < 5000.0);
    assert_int_equal(fv_vsync_pred_state(&v, (int64_t)(1e9 + 600 * P90)), FV_VSYNC_LOCKED);
    assert_int_equal(v.spurious + v.doubled, 0);
}

static void test_missed_edges(void **st)
{
    (void)st;
    fv_vsync_pred v;
    init90(&v);
    run_result r = run(&v, P90, 0, 20000.0, 0.3, 0, 0, 600, 3);
    printf("missed: %ld dropped, %ld counted, max err %.1f us\n", r.dropped, v.missed, r.max_err_ns / 1e3);
    assert_true(r.dropped > 100);
    assert_int_equal(v.missed, r.dropped - r.dropped_tail);
    assert_true(r.max_err_ns < 40000.0);
}

static void test_doubled_and_spurious(void **st)
{
    (void)st;
    fv_vsync_pred v;
    init90(&v);
    run_result r = run(&v, P90, 0, 20000.0, 0, 0.2, 0.1, 600, 4);
    printf("doubled %ld, spurious %ld, relocks %ld, max err %.1f us\n", v.doubled, v.spurious, v.relocks,
           r.max_err_ns / 1e3);
    assert_true(v.doubled > 60);
    assert_true(v.spurious > 30);
    assert_int_equal(v.relocks, 0);
    assert_int_equal(v.accepted, r.fed);
    assert_true(r.max_err_ns < 40000.0);
}

static void test_drift(void **st)
{
    (void)st;
    fv_vsync_pred v;
    init90(&v);
    /* 90 -> ~88 Hz over 1800 frames (20 s): +0.14 us per frame */
    const double drift = (1e9 / 88.0 - P90) / 1800.0;
    run_result r = run(&v, P90, drift, 30000.0, 0.05, 0, 0, 1800, 5);
    printf("drift: max err %.1f us, final period %.0f ns (true %.0f)\n", r.max_err_ns / 1e3,
           fv_vsync_pred_period_ns(&v), P90 + drift * 1799);
    assert_true(r.max_err_ns < 60000.0);
    assert_true(fabs(fv_vsync_pred_period_ns(&v) - (P90 + drift * 1799)) < 3000.0);
    assert_int_equal(v.relocks, 0);
}

static void test_silence(void **st)
{
    (void)st;
    fv_vsync_pred v;
    init90(&v);
    const double per = P90 * 0.999;
    run(&v, per, 0, 0, 0, 0, 0, 100, 6);
    const double last = true_vsync(1e9, per, 0, 99);
    assert_int_equal(fv_vsync_pred_state(&v, (int64_t)(last + 0.5 * per)), FV_VSYNC_LOCKED);
    assert_int_equal(fv_vsync_pred_state(&v, (int64_t)(last + 5 * per)), FV_VSYNC_COAST);
    /* coasting predicts from the fit: still on the true grid 20 frames on */
    double now = last + 20.4 * per;
    assert_true(fabs((double)fv_vsync_pred_next(&v, (int64_t)now, (int64_t)now) - (last + 21 * per)) < 2000.0);
    /* after 500 ms: the timer at the nominal period from the last edge; frames never stop */
    now = last + 0.6e9;
    assert_int_equal(fv_vsync_pred_state(&v, (int64_t)now), FV_VSYNC_TIMER);
    int64_t a = fv_vsync_pred_next(&v, (int64_t)now, (int64_t)now);
    int64_t b = fv_vsync_pred_next(&v, a, (int64_t)now);
    assert_true(a > (int64_t)now && a - (int64_t)now <= (int64_t)P90 + 1);
    assert_true(llabs(b - a - (int64_t)P90) <= 1);
    assert_true(fabs(fmod((double)a - last, P90)) < 2.0 || fabs(fmod((double)a - last, P90) - P90) < 2.0);
    /* the line comes back 3 ms out of phase: re-locks on the first edge and predicts it */
    const double t1 = last + 1e9 + 3e6;
    long relocks = v.relocks;
    for (int k = 0; k < 40; k++)
        fv_vsync_pred_edge(&v, (int64_t)(t1 + k * per));
    assert_int_equal(v.relocks, relocks + 1);
    now = t1 + 39.5 * per;
    assert_true(fabs((double)fv_vsync_pred_next(&v, (int64_t)now, (int64_t)now) - (t1 + 40 * per)) < 2000.0);
    assert_int_equal(fv_vsync_pred_state(&v, (int64_t)now), FV_VSYNC_LOCKED);
}

static void test_phase_jump_and_other_rate(void **st)
{
    (void)st;
    fv_vsync_pred v;
    init90(&v);
    /* a 60 Hz panel while 90 Hz was assumed: the first interval sets the period */
    run_result r = run(&v, 1e9 / 60.0, 0, 10000.0, 0, 0, 0, 200, 7);
    assert_true(fabs(fv_vsync_pred_period_ns(&v) - 1e9 / 60.0) < 2000.0);
    assert_true(r.max_err_ns < 20000.0);
    /* the phase jumps by half a period with no silence (a mode change): re-locks after a few */
    init90(&v);
    for (int k = 0; k < 50; k++)
        fv_vsync_pred_edge(&v, (int64_t)(1e9 + k * P90));
    const double t1 = 1e9 + 49.5 * P90 + P90;
    for (int k = 0; k < 20; k++)
        fv_vsync_pred_edge(&v, (int64_t)(t1 + k * P90));
    assert_int_equal(v.relocks, 1);
    double now = t1 + 19.5 * P90;
    assert_true(fabs((double)fv_vsync_pred_next(&v, (int64_t)now, (int64_t)now) - (t1 + 20 * P90)) < 2000.0);
}

/* Found by the QEMU GPIO test (docs/hil.md): one short first interval after (re-)acquisition
 * (a late edge, then an on-time one) used to set the period to 8.3 ms for good, and at 3/4 of
 * the true period every third edge fits: "locked" at 120 Hz on a 90 Hz line forever. */
static void test_short_first_interval(void **st)
{
    (void)st;
    fv_vsync_pred v;
    init90(&v);
    int64_t t = 1000000000;
    fv_vsync_pred_edge(&v, t);
    t += 8300000;
    fv_vsync_pred_edge(&v, t);
    for (int i = 0; i < 900; i++) { /* 10 s of a perfect 90 Hz line */
        t += 11111111;
        fv_vsync_pred_edge(&v, t);
    }
    assert_true(fabs(fv_vsync_pred_period_ns(&v) - P90) < 1000.0);
    assert_int_equal(fv_vsync_pred_state(&v, t + 1000), FV_VSYNC_LOCKED);
    assert_true(v.spurious <= 2);
    assert_true(fabs((double)fv_vsync_pred_next(&v, t + 1000, t + 1000) - (double)(t + 11111111)) < 2000.0);
    /* the same after a re-lock from silence: the old period does not survive it */
    t += 2000000000;
    fv_vsync_pred_edge(&v, t);
    t += 8300000;
    fv_vsync_pred_edge(&v, t);
    for (int i = 0; i < 90; i++) {
        t += 11111111;
        fv_vsync_pred_edge(&v, t);
    }
    assert_true(fabs(fv_vsync_pred_period_ns(&v) - P90) < 1000.0);
}

static void test_no_edges(void **st)
{
    (void)st;
    fv_vsync_pred v;
    init90(&v);
    /* never an edge: free-runs at the nominal rate from the start time */
    assert_int_equal(fv_vsync_pred_state(&v, 1000), FV_VSYNC_ACQUIRE);
    assert_int_equal(fv_vsync_pred_state(&v, 600000000), FV_VSYNC_TIMER);
    assert_int_equal(fv_vsync_pred_next(&v, 0, 0), (int64_t)P90);
    assert_int_equal(fv_vsync_pred_next(&v, (int64_t)P90, 0), 2 * (int64_t)P90);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_clean_and_jitter), cmocka_unit_test(test_missed_edges),
        cmocka_unit_test(test_doubled_and_spurious), cmocka_unit_test(test_drift),
        cmocka_unit_test(test_silence), cmocka_unit_test(test_phase_jump_and_other_rate),
        cmocka_unit_test(test_short_first_interval),
        cmocka_unit_test(test_no_edges),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
