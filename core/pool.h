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

/* Trace recorder (core/prof.h) for the following jobs, NULL = off (the default): each worker
 * records its share of every job ("pool job") on its own track, slot = thread_id, so prof needs
 * at least fv_pool_threads slots. Call it between jobs, from the thread that runs them. */
struct fv_prof;
void fv_pool_set_prof(fv_pool *pool, struct fv_prof *prof);

/* Flush-to-zero / denormals-are-zero for the calling thread (every pool worker sets it). */
void fv_set_ftz(void);

int fv_online_cpus(void);

#endif
