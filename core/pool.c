#define _GNU_SOURCE
#include "pool.h"
#include "base/clock.h"
#include "prof.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>
#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#include <pmmintrin.h>
#endif

struct fv_pool {
    int threads;
    pthread_t *tids;
    pthread_mutex_t mu;
    pthread_cond_t start_cv, done_cv;
    /* current job, published under mu */
    fv_task_fn fn;
    void *ctx;
    int count;
    unsigned long generation; /* bumped per job so sleepers know there is new work */
    int quit;
    /* the next item to claim, tagged with its job's generation (high 32 bits): a worker that read
     * an older job claims nothing from a newer one, so the caller need not wait for every worker
     * to check in, only for the job's items (done) */
    _Atomic uint64_t claim;
    atomic_int done;          /* items of the current job finished */
    atomic_int inflight;      /* threads inside drain: the caller waits for them too, since a
                               * worker that ran items still writes its span after its last */
    fv_prof *prof;            /* trace recorder (NULL: off), published under mu with the job */
    /* the background job (fv_pool_post): items claimed under mu, by idle workers between the
     * foreground jobs' items and by the caller in fv_pool_wait */
    fv_task_fn bg_fn;
    void *bg_ctx;
    int bg_count, bg_next, bg_done, bg_on;
    pthread_cond_t bg_cv; /* bg_done reached bg_count */
};

typedef struct { fv_pool *pool; int id; } worker_arg;

void fv_set_ftz(void)
{
#if defined(__x86_64__) || defined(__i386__)
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#elif defined(__aarch64__)
    unsigned long fpcr;
    __asm__ volatile("mrs %0, fpcr" : "=r"(fpcr));
    fpcr |= 1ul << 24; /* FZ */
    __asm__ volatile("msr fpcr, %0" : : "r"(fpcr));
#endif
}

int fv_online_cpus(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : (int)n;
}

/* the job's next unclaimed item, or -1 when none is left or the job is not the current one */
static int claim(fv_pool *p, uint32_t gen, int count)
{
    uint64_t v = atomic_load_explicit(&p->claim, memory_order_relaxed);
    for (;;) {
        if ((uint32_t)(v >> 32) != gen || (int)(uint32_t)v >= count)
            return -1;
        if (atomic_compare_exchange_weak_explicit(&p->claim, &v, v + 1, memory_order_relaxed, memory_order_relaxed))
            return (int)(uint32_t)v;
    }
}

static void drain(fv_pool *p, fv_task_fn fn, void *ctx, int count, uint32_t gen, int id, fv_prof *prof)
{
    atomic_fetch_add_explicit(&p->inflight, 1, memory_order_acq_rel); /* before any claim */
    const int64_t t0 = prof ? fv_time_ns() : 0;
    int ran = 0;
    for (int i; (i = claim(p, gen, count)) >= 0;) {
        fn(ctx, i, id);
        ran = 1;
        /* release: the item's writes happen before the caller sees the job done */
        if (atomic_fetch_add_explicit(&p->done, 1, memory_order_acq_rel) + 1 == count) {
            pthread_mutex_lock(&p->mu);
            pthread_cond_signal(&p->done_cv);
            pthread_mutex_unlock(&p->mu);
        }
    }
    /* this worker's share of the job, on its own track; a worker that woke too late to claim
     * anything touches neither the job nor prof (both may be gone by then) */
    if (prof && ran)
        fv_prof_span(prof, id, id, "pool job", t0, fv_time_ns(), count);
    if (atomic_fetch_sub_explicit(&p->inflight, 1, memory_order_acq_rel) == 1) {
        pthread_mutex_lock(&p->mu);
        pthread_cond_signal(&p->done_cv);
        pthread_mutex_unlock(&p->mu);
    }
}

static void *worker_main(void *arg)
{
    worker_arg wa = *(worker_arg *)arg;
    free(arg);
    fv_pool *p = wa.pool;
    fv_set_ftz();
    unsigned long seen = 0;
    pthread_mutex_lock(&p->mu);
    for (;;) {
        while (!p->quit && p->generation == seen && !(p->bg_on && p->bg_next < p->bg_count))
            pthread_cond_wait(&p->start_cv, &p->mu);
        if (p->quit)
            break;
        if (p->generation == seen) { /* no new foreground job: one background item */
            const int i = p->bg_next++;
            fv_task_fn fn = p->bg_fn;
            void *ctx = p->bg_ctx;
            pthread_mutex_unlock(&p->mu);
            fn(ctx, i, wa.id);
            pthread_mutex_lock(&p->mu);
            if (++p->bg_done == p->bg_count)
                pthread_cond_broadcast(&p->bg_cv);
            continue;
        }
        seen = p->generation;
        fv_task_fn fn = p->fn;
        void *ctx = p->ctx;
        int count = p->count;
        fv_prof *prof = p->prof;
        pthread_mutex_unlock(&p->mu);
        drain(p, fn, ctx, count, (uint32_t)seen, wa.id, prof);
        pthread_mutex_lock(&p->mu);
    }
    pthread_mutex_unlock(&p->mu);
    return NULL;
}

fv_pool *fv_pool_create(int threads)
{
    if (threads <= 0)
        threads = fv_online_cpus();
    fv_pool *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    p->threads = threads;
    atomic_init(&p->claim, 0);
    atomic_init(&p->done, 0);
    atomic_init(&p->inflight, 0);
    pthread_mutex_init(&p->mu, NULL);
    pthread_cond_init(&p->start_cv, NULL);
    pthread_cond_init(&p->done_cv, NULL);
    pthread_cond_init(&p->bg_cv, NULL);
    p->tids = calloc((size_t)threads, sizeof *p->tids);
    if (!p->tids) {
        free(p);
        return NULL;
    }
    for (int i = 1; i < threads; i++) {
        worker_arg *wa = malloc(sizeof *wa);
        if (!wa || (wa->pool = p, wa->id = i, pthread_create(&p->tids[i], NULL, worker_main, wa)) != 0) {
            free(wa);
            p->threads = i; /* destroy joins only the started ones */
            fv_pool_destroy(p);
            return NULL;
        }
    }
    fv_set_ftz();
    return p;
}

void fv_pool_destroy(fv_pool *p)
{
    if (!p)
        return;
    pthread_mutex_lock(&p->mu);
    p->quit = 1;
    pthread_cond_broadcast(&p->start_cv);
    pthread_mutex_unlock(&p->mu);
    for (int i = 1; i < p->threads; i++)
        pthread_join(p->tids[i], NULL);
    pthread_mutex_destroy(&p->mu);
    pthread_cond_destroy(&p->start_cv);
    pthread_cond_destroy(&p->done_cv);
    pthread_cond_destroy(&p->bg_cv);
    free(p->tids);
    free(p);
}

int fv_pool_threads(const fv_pool *p) { return p ? p->threads : 1; }

void fv_pool_run(fv_pool *p, int count, fv_task_fn fn, void *ctx)
{
    if (count <= 0)
        return;
    if (!p || p->threads == 1 || count == 1) {
        fv_prof *prof = p ? p->prof : NULL;
        const int64_t t0 = prof ? fv_time_ns() : 0;
        for (int i = 0; i < count; i++)
            fn(ctx, i, 0);
        if (prof)
            fv_prof_span(prof, 0, 0, "pool job", t0, fv_time_ns(), count);
        return;
    }
    pthread_mutex_lock(&p->mu);
    p->fn = fn;
    p->ctx = ctx;
    p->count = count;
    p->generation++;
    const uint32_t gen = (uint32_t)p->generation;
    atomic_store_explicit(&p->done, 0, memory_order_relaxed);
    atomic_store_explicit(&p->claim, (uint64_t)gen << 32, memory_order_relaxed);
    pthread_cond_broadcast(&p->start_cv);
    pthread_mutex_unlock(&p->mu);
    fv_prof *prof = p->prof; /* only the caller writes it (fv_pool_set_prof) */
    drain(p, fn, ctx, count, gen, 0, prof);
    /* done when every item is and the threads that ran them are out of drain: a worker still in
     * a background item, or not yet awake, holds nothing of this job */
    pthread_mutex_lock(&p->mu);
    while (atomic_load_explicit(&p->done, memory_order_acquire) < count ||
           atomic_load_explicit(&p->inflight, memory_order_acquire) > 0)
        pthread_cond_wait(&p->done_cv, &p->mu);
    pthread_mutex_unlock(&p->mu);
}

void fv_pool_set_prof(fv_pool *p, fv_prof *prof)
{
    if (!p)
        return;
    pthread_mutex_lock(&p->mu);
    p->prof = prof;
    pthread_mutex_unlock(&p->mu);
}

void fv_pool_post(fv_pool *p, int count, fv_task_fn fn, void *ctx)
{
    if (!p) { /* no pool: run at fv_pool_wait... there is none to hold it, so now */
        for (int i = 0; i < count; i++)
            fn(ctx, i, 0);
        return;
    }
    pthread_mutex_lock(&p->mu);
    p->bg_fn = fn, p->bg_ctx = ctx;
    p->bg_count = count > 0 ? count : 0, p->bg_next = 0, p->bg_done = 0, p->bg_on = 1;
    pthread_cond_broadcast(&p->start_cv);
    pthread_mutex_unlock(&p->mu);
}

void fv_pool_wait(fv_pool *p)
{
    if (!p)
        return;
    pthread_mutex_lock(&p->mu);
    if (!p->bg_on) {
        pthread_mutex_unlock(&p->mu);
        return;
    }
    while (p->bg_next < p->bg_count) { /* the caller takes the items left, as thread 0 */
        const int i = p->bg_next++;
        pthread_mutex_unlock(&p->mu);
        p->bg_fn(p->bg_ctx, i, 0);
        pthread_mutex_lock(&p->mu);
        p->bg_done++;
    }
    while (p->bg_done < p->bg_count)
        pthread_cond_wait(&p->bg_cv, &p->mu);
    p->bg_on = 0;
    pthread_mutex_unlock(&p->mu);
}
