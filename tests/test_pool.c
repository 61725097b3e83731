/* The worker pool: every item of a job runs once with a thread id in range, and a background job
 * (fv_pool_post / fv_pool_wait) runs every item once while foreground jobs run beside it, on any
 * thread count; no two running items share a thread id. */
#include <stdatomic.h>
#include <string.h>

#include "testutil.h"
#include "pool.h"

enum { FG_ITEMS = 300, BG_ITEMS = 2000, MAXT = 8 };

typedef struct {
    atomic_int runs[BG_ITEMS]; /* times each item ran */
    atomic_uint sink[BG_ITEMS]; /* each item's busy work, kept */
    atomic_int inside[MAXT];   /* items running on each thread id now */
    atomic_int bad_id, overlap;
    int threads;
} job;

static void item(void *ctx, int index, int tid)
{
    job *j = ctx;
    if (tid < 0 || tid >= j->threads) {
        atomic_fetch_add(&j->bad_id, 1);
        return;
    }
    if (atomic_fetch_add(&j->inside[tid], 1) != 0) /* another item on this id right now */
        atomic_fetch_add(&j->overlap, 1);
    unsigned spin = 0; /* some work, so the jobs overlap */
    for (int k = 0; k < 200 + index % 50; k++)
        spin = spin * 31u + (unsigned)k;
    atomic_store_explicit(&j->sink[index], spin, memory_order_relaxed); /* kept: the loop is not optimised away */
    atomic_fetch_add(&j->runs[index], 1);
    atomic_fetch_sub(&j->inside[tid], 1);
}

static void test_background_job(void **st)
{
    (void)st;
    static job fg, bg; /* large: not on the stack */
    const int threads[] = {1, 2, 5};
    for (int k = 0; k < 3; k++) {
        fv_pool *p = fv_pool_create(threads[k]);
        assert_non_null(p);
        for (int round = 0; round < 3; round++) {
            memset(&fg, 0, sizeof fg);
            memset(&bg, 0, sizeof bg);
            fg.threads = bg.threads = threads[k];
            fv_pool_post(p, BG_ITEMS, item, &bg);
            for (int r = 0; r < 5; r++) /* foreground jobs while the background one runs */
                fv_pool_run(p, FG_ITEMS, item, &fg);
            for (int i = 0; i < FG_ITEMS; i++)
                assert_int_equal(atomic_load(&fg.runs[i]), 5);
            fv_pool_wait(p);
            for (int i = 0; i < BG_ITEMS; i++)
                assert_int_equal(atomic_load(&bg.runs[i]), 1);
            assert_int_equal(atomic_load(&fg.bad_id) + atomic_load(&bg.bad_id), 0);
            fv_pool_wait(p); /* nothing posted: returns */
        }
        fv_pool_destroy(p);
    }
}

/* both jobs' items count in one id table: a thread runs one item at a time */
static void test_ids_unique_across_jobs(void **st)
{
    (void)st;
    static job j;
    for (int t = 2; t <= 5; t += 3) {
        memset(&j, 0, sizeof j);
        j.threads = t;
        fv_pool *p = fv_pool_create(t);
        assert_non_null(p);
        fv_pool_post(p, BG_ITEMS, item, &j); /* the same table: runs[] of the first FG_ITEMS count both */
        for (int r = 0; r < 4; r++)
            fv_pool_run(p, FG_ITEMS, item, &j);
        fv_pool_wait(p);
        assert_int_equal(atomic_load(&j.overlap), 0);
        for (int i = 0; i < BG_ITEMS; i++)
            assert_int_equal(atomic_load(&j.runs[i]), i < FG_ITEMS ? 5 : 1);
        fv_pool_destroy(p);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_background_job),
        cmocka_unit_test(test_ids_unique_across_jobs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
