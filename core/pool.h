/* fovea: persistent worker pool. Work items are claimed with one atomic counter, so the
 * split between threads is dynamic while every item's result depends only on its index:
 * outputs are identical for any thread count. */
#ifndef FOVEA_POOL_H
#define FOVEA_POOL_H

typedef struct fv_pool fv_pool;

/* Runs fn(ctx, index, thread_id) for index in [0, count). thread_id is in [0, threads). */
typedef void (*fv_task_fn)(void *ctx, int index, int thread_id);

/* threads <= 0 means the number of online CPUs. The calling thread is worker 0, so
 * threads - 1 pthreads are started. Returns NULL on failure. */
fv_pool *fv_pool_create(int threads);
void fv_pool_destroy(fv_pool *pool);
int fv_pool_threads(const fv_pool *pool); /* 1 for a NULL pool */

/* Blocks until all items are done. pool may be NULL: runs serially on the caller. */
void fv_pool_run(fv_pool *pool, int count, fv_task_fn fn, void *ctx);

/* A background job: fn(ctx, index, thread_id) for index in [0, count), run by the pool's workers
 * whenever they have no item of a foreground job (fv_pool_run) to do, and by the caller in
 * fv_pool_wait, which returns when every item is done. Between the two the caller may run
 * foreground jobs (their items come first; a foreground job waits for a worker to finish the
 * background item it is in); the items of both may run at the same time, so they must not
 * touch the same data. A thread runs one item at a time: thread_id is unique among the running
 * items. One background job at a time, posted and waited for by the thread that runs the
 * foreground jobs. pool NULL: fv_pool_post runs the items at once. */
void fv_pool_post(fv_pool *pool, int count, fv_task_fn fn, void *ctx);
void fv_pool_wait(fv_pool *pool);

/* Trace recorder (core/prof.h) for the following jobs, NULL = off (the default): each worker
 * records its share of every job ("pool job") on its own track, slot = thread_id, so prof needs
 * at least fv_pool_threads slots. Call it between jobs, from the thread that runs them. */
struct fv_prof;
void fv_pool_set_prof(fv_pool *pool, struct fv_prof *prof);

/* Flush-to-zero / denormals-are-zero for the calling thread (every pool worker sets it). */
void fv_set_ftz(void);

int fv_online_cpus(void);

#endif
