/* The frame loop on a fake clock: it wakes one learnt render budget before the predicted vsync,
 * latches the newest gaze sample taken before the rays start, presents on vsync, counts late
 * frames and shows the previous frame when late, rides through missed edges and a dead source. */
#include <stdio.h>
#include <string.h>

#include "frameloop.h"
#include "testutil.h"

#define P 11111111LL
#define T0 1000000000LL
#define GAZE_DT 4166667LL /* a 240 Hz tracker */
#define GAZE_T0 (T0 - 50000000LL + 1234)

typedef struct {
    int64_t now;
    int64_t edge_k;       /* next edge index to deliver */
    const int *missing;   /* edge indices that never come */
    int nmissing;
    int64_t fail_after;   /* the source fails once now passes this (0: never) */
    int64_t render_ns[64];
    long frame;
    long gaze_pushed;
    fv_gaze_ring *ring;
    /* log */
    int which[256];
    int64_t vs[256];
    int npresent;
    int64_t seen_gaze_t[64];
} fake;

static int is_missing(const fake *f, int64_t k)
{
    for (int i = 0; i < f->nmissing; i++)
        if (f->missing[i] == k)
            return 1;
    return 0;
}

static int64_t f_now(void *c) { return ((fake *)c)->now; }
static void f_sleep(void *c, int64_t t)
{
    fake *f = c;
    if (t > f->now)
        f->now = t;
}
static int f_wait(void *c, int64_t deadline, int64_t *t)
{
    fake *f = c;
    if (f->fail_after && f->now > f->fail_after)
        return -1;
    while (is_missing(f, f->edge_k))
        f->edge_k++;
    int64_t te = T0 + f->edge_k * P;
    if (te <= f->now) { /* queued by the kernel: returned at once */
        f->edge_k++;
        *t = te;
        return 1;
    }
    if (te <= deadline) {
        f->now = te;
        f->edge_k++;
        *t = te;
        return 1;
    }
    if (deadline > f->now)
        f->now = deadline;
    return 0;
}
static void f_sample(void *c, int64_t now)
{
    fake *f = c;
    /* a source that stamps some samples ahead of now: the loop must not take them */
    for (;;) {
        int64_t t = GAZE_T0 + f->gaze_pushed * GAZE_DT;
        if (t > now + 20000000)
            break;
        fv_gaze_sample s = {t, (float)(f->gaze_pushed % 100) / 100.0f, 0.5f, 1.0f};
        fv_gaze_ring_push(f->ring, &s);
        f->gaze_pushed++;
    }
}
static int f_render(void *c, const fv_gaze_sample *g, int64_t t)
{
    (void)t;
    fake *f = c;
    f->seen_gaze_t[f->frame % 64] = g ? g->t_ns : -1;
    f->now += f->render_ns[f->frame % 64] ? f->render_ns[f->frame % 64] : 5000000;
    f->frame++;
    return 0;
}
static int f_present(void *c, int which, int64_t vs)
{
    fake *f = c;
    if (f->npresent < 256) {
        f->which[f->npresent] = which;
        f->vs[f->npresent] = vs;
        f->npresent++;
    }
    return 0;
}

static void setup(fake *f, fv_frameloop *l, fv_gaze_ring *ring)
{
    memset(f, 0, sizeof *f);
    f->now = T0 - 3 * P + 777;
    f->ring = ring;
    fv_gaze_ring_init(ring);
    fv_frameloop_ops ops = {f, f_now, f_sleep, f_wait, f_sample, f_render, f_present};
    fv_frameloop_params p;
    fv_frameloop_default_params(&p, P);
    fv_frameloop_init(l, &p, &ops, ring);
}

static void test_steady_and_latch(void **st)
{
    (void)st;
    fake f;
    fv_frameloop l;
    fv_gaze_ring ring;
    setup(&f, &l, &ring);
    fv_frame_record r[40];
    for (int i = 0; i < 40; i++)
        assert_int_equal(fv_frameloop_frame(&l, &r[i]), 0);
    for (int i = 0; i < 40; i++) {
        /* the newest sample at or before the ray start, not a newer (future-stamped) one */
        assert_true(r[i].has_gaze);
        assert_true(r[i].gaze_t_ns <= r[i].ray_start_ns);
        assert_true(r[i].gaze_t_ns + GAZE_DT > r[i].ray_start_ns);
        assert_int_equal(f.seen_gaze_t[i], r[i].gaze_t_ns);
        assert_true(r[i].done_ns <= r[i].target_ns);
        assert_false(r[i].late);
    }
    for (int i = 10; i < 40; i++) {
        /* one frame per vsync, on the edge; woken one budget (5 ms x 1.05 + 1 ms) before it */
        assert_int_equal(r[i].photon_ns, r[i].target_ns);
        assert_true(r[i].photon_edge);
        assert_int_equal((r[i].photon_ns - T0) % P, 0);
        assert_int_equal(r[i].photon_ns - r[i - 1].photon_ns, P);
        assert_int_equal(r[i].budget_ns, 6250000);
        assert_int_equal(r[i].target_ns - r[i].ray_start_ns, 6250000);
        assert_int_equal(r[i].vsync_state, FV_VSYNC_LOCKED);
    }
    assert_int_equal(l.late, 0);
    for (int i = 0; i < f.npresent; i++)
        assert_int_equal(f.which[i], FV_PRESENT_NEW);
    fv_latency_summary s;
    fv_latency_summarise(r + 10, 30, &s);
    printf("latency p50 %.2f ms p99 %.2f ms, fps %.2f\n", s.p50_ms, s.p99_ms, s.fps);
    assert_true(s.p99_ms <= 6.25 + 4.17 + 0.01);
    assert_true(s.fps > 89.99 && s.fps < 90.01);
    fv_gaze_ring_destroy(&ring);
}

static void test_late_frame(void **st)
{
    (void)st;
    fake f;
    fv_frameloop l;
    fv_gaze_ring ring;
    setup(&f, &l, &ring);
    f.render_ns[20] = 15000000; /* one frame takes 15 ms against a 6.25 ms budget */
    fv_frame_record r[30];
    int present_before = 0;
    for (int i = 0; i < 30; i++) {
        if (i == 20)
            present_before = f.npresent;
        assert_int_equal(fv_frameloop_frame(&l, &r[i]), 0);
    }
    assert_int_equal(l.late, 1);
    assert_true(r[20].late);
    assert_true(r[20].done_ns > r[20].target_ns);
    /* the target vsync showed the previous frame again, the late one went to the next vsync */
    assert_int_equal(f.which[present_before], FV_PRESENT_PREVIOUS);
    assert_int_equal(f.vs[present_before], r[20].target_ns);
    assert_int_equal(f.which[present_before + 1], FV_PRESENT_NEW);
    assert_int_equal(f.vs[present_before + 1], r[20].target_ns + P);
    assert_int_equal(r[20].photon_ns, r[20].target_ns + P);
    /* the budget learnt the slow frame: the next frames wake earlier and are not late */
    assert_true(r[21].budget_ns > 15000000);
    for (int i = 21; i < 30; i++)
        assert_false(r[i].late);
    fv_latency_summary s;
    fv_latency_summarise(r, 30, &s);
    assert_int_equal(s.late, 1);
    fv_gaze_ring_destroy(&ring);
}

static void test_missed_edges_and_dead_source(void **st)
{
    (void)st;
    fake f;
    fv_frameloop l;
    fv_gaze_ring ring;
    setup(&f, &l, &ring);
    static const int missing[] = {15, 16, 22};
    f.missing = missing;
    f.nmissing = 3;
    f.fail_after = T0 + 40 * P + 100;
    fv_frame_record r[80];
    for (int i = 0; i < 80; i++)
        assert_int_equal(fv_frameloop_frame(&l, &r[i]), 0);
    int predicted = 0;
    for (int i = 5; i < 80; i++) {
        /* every frame presented, one per vsync, on the true grid, edge or not */
        assert_false(r[i].late);
        assert_int_equal(r[i].photon_ns - r[i - 1].photon_ns, P);
        int64_t k = (r[i].photon_ns - T0) / P;
        assert_true(llabs(r[i].photon_ns - (T0 + k * P)) < 1000);
        if (k == 15 || k == 16 || k == 22)
            assert_false(r[i].photon_edge);
        predicted += !r[i].photon_edge;
    }
    assert_true(l.source_dead);
    assert_int_equal(r[79].vsync_state, FV_VSYNC_TIMER);
    assert_true(predicted >= 3 + 35);
    fv_gaze_ring_destroy(&ring);
}

static void test_no_gaze(void **st)
{
    (void)st;
    fake f;
    fv_frameloop l;
    fv_gaze_ring ring;
    setup(&f, &l, &ring);
    fv_frameloop_ops ops = l.ops;
    ops.sample_gaze = NULL; /* nothing ever pushed */
    fv_frameloop_params p = l.p;
    fv_frameloop_init(&l, &p, &ops, &ring);
    fv_frame_record r;
    assert_int_equal(fv_frameloop_frame(&l, &r), 0);
    assert_false(r.has_gaze);
    assert_int_equal(f.seen_gaze_t[0], -1);
    fv_gaze_ring_destroy(&ring);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_steady_and_latch),
        cmocka_unit_test(test_late_frame),
        cmocka_unit_test(test_missed_edges_and_dead_source),
        cmocka_unit_test(test_no_gaze),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
