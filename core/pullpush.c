/* fovea: pull-push reconstruction (Marroquim et al. 2007; Weier et al. 2018 §3.1).
 *
 * Memory: one allocation; every level has a 1-pixel border around its w x h pixels: columns
 * x = -1 and x = w, rows y = -1 and y = h are addressable (stride >= w + 2, row 0 64-byte
 * aligned, stride a multiple of 16 pixels; the left border of row y is the last pixel of row
 * y - 1's storage). Border weights are always 0: the pull kernels read the right column / bottom
 * row as zero-weight padding for odd sizes. After fv_pullpush the border colours hold a
 * replicated copy of the edge pixels on every level (so consumers can sample with clamp-to-edge
 * without branching), which is what the push kernels read.
 *
 * The colour of a zero-weight pixel is never used (see pullpush_dsp.h), so before a frame only the level-0
 * weights need to be zero; fv_pyramid_clear zeroes colours too, as pullpush.h documents.
 *
 * Pull: level l+1 row Y from level l rows 2Y, 2Y+1 (dsp->pull_row). Push, coarsest first:
 * level l row y in place from level l+1 rows y>>1 and its vertical neighbour (dsp->push_row),
 * then the border of level l is replicated. Every output pixel depends only on its inputs, so
 * row chunking (and therefore the thread count) never changes a bit. Weights are kept: level l
 * weight = min(1, pulled weight), i.e. the confidence of the level before push. */
#define _GNU_SOURCE
#include "pullpush.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

/* ---------------------------------------------------------------- pyramid memory */

#define PAD_PX 16 /* pixels before row -1: alignment + the (x = -1, y = -1) corner */

static size_t level_px(int w, int h, ptrdiff_t stride)
{
    (void)w;
    return (size_t)PAD_PX + (size_t)(h + 2) * (size_t)stride;
}

int fv_pyramid_init(fv_pyramid *p, int w, int h)
{
    memset(p, 0, sizeof *p);
    if (w < 1 || h < 1 || w > (1 << 16) || h > (1 << 16))
        return -1;
    int lw[FV_PYR_MAX_LEVELS], lh[FV_PYR_MAX_LEVELS], levels = 0;
    for (int cw = w, ch = h;; cw = (cw + 1) / 2, ch = (ch + 1) / 2) {
        if (levels == FV_PYR_MAX_LEVELS)
            return -1;
        lw[levels] = cw;
        lh[levels] = ch;
        levels++;
        if (cw == 1 && ch == 1)
            break;
    }
    size_t total = 0; /* floats */
    ptrdiff_t strides[FV_PYR_MAX_LEVELS];
    for (int l = 0; l < levels; l++) {
        strides[l] = ((ptrdiff_t)lw[l] + 2 + 15) & ~(ptrdiff_t)15;
        total += 5 * level_px(lw[l], lh[l], strides[l]);
    }
    const size_t bytes = total * sizeof(float);
    const size_t align = bytes >= ((size_t)4 << 20) ? ((size_t)2 << 20) : 64;
    void *mem = NULL;
    if (posix_memalign(&mem, align, (bytes + align - 1) / align * align) != 0)
        return -1;
#ifdef MADV_HUGEPAGE
    if (align > 64) /* fewer TLB misses streaming ~50 MB per frame; advisory only */
        madvise(mem, (bytes + align - 1) / align * align, MADV_HUGEPAGE);
#endif
    memset(mem, 0, bytes);
    float *f = mem;
    for (int l = 0; l < levels; l++) {
        const size_t px = level_px(lw[l], lh[l], strides[l]);
        fv_pyr_level *L = &p->lv[l];
        L->w = lw[l];
        L->h = lh[l];
        L->stride = strides[l];
        L->rgbd = f + 4 * (PAD_PX + strides[l]);
        L->wgt = f + 4 * px + PAD_PX + strides[l];
        f += 5 * px;
    }
    p->levels = levels;
    p->mem = mem;
    return 0;
}

void fv_pyramid_free(fv_pyramid *p)
{
    free(p->mem);
    memset(p, 0, sizeof *p);
}

/* ---------------------------------------------------------------- clear */

#define CLEAR_CHUNKS 32

typedef struct {
    char *rgbd, *wgt;
    size_t rgbd_bytes, wgt_bytes;
} clear_ctx;

static void span(size_t total, int i, int n, size_t *lo, size_t *hi)
{
    /* 64-byte granular split: no two tasks write the same cache line */
    const size_t lines = (total + 63) / 64;
    *lo = lines * (size_t)i / (size_t)n * 64;
    *hi = lines * (size_t)(i + 1) / (size_t)n * 64;
    if (*hi > total)
        *hi = total;
    if (*lo > *hi)
        *lo = *hi;
}

static void clear_task(void *vctx, int i, int thread_id)
{
    (void)thread_id;
    const clear_ctx *c = vctx;
    size_t lo, hi;
    span(c->rgbd_bytes, i, CLEAR_CHUNKS, &lo, &hi);
    memset(c->rgbd + lo, 0, hi - lo);
    span(c->wgt_bytes, i, CLEAR_CHUNKS, &lo, &hi);
    memset(c->wgt + lo, 0, hi - lo);
}

void fv_pyramid_clear(fv_pyramid *p, fv_pool *pool)
{
    if (!p->mem || p->levels < 1)
        return;
    const fv_pyr_level *L = &p->lv[0];
    const size_t px = level_px(L->w, L->h, L->stride);
    clear_ctx c = {
        .rgbd = (char *)(L->rgbd - 4 * (PAD_PX + L->stride)),
        .wgt = (char *)(L->wgt - (PAD_PX + L->stride)),
        .rgbd_bytes = 4 * px * sizeof(float),
        .wgt_bytes = px * sizeof(float),
    };
    fv_pool_run(px >= 65536 ? pool : NULL, CLEAR_CHUNKS, clear_task, &c);
}

/* ---------------------------------------------------------------- pull-push */

/* Levels with fewer output pixels than this run on the calling thread: waking the pool costs
 * more than the work. */
#define PAR_MIN_PX 16384
#define CHUNK_PX 16384 /* target output pixels per work item */

typedef struct {
    const fv_pullpush_dsp *dsp;
    const fv_pyr_level *src, *dst; /* pull: fine -> coarse; push: coarse -> fine */
    int rows, chunks, reverse;
} pp_ctx;

static inline float *px_rgbd(const fv_pyr_level *L, int x, int y)
{
    return L->rgbd + 4 * ((ptrdiff_t)y * L->stride + x);
}

static void chunk_rows(const pp_ctx *c, int i, int h, int *y0, int *y1)
{
    const int k = c->reverse ? c->chunks - 1 - i : i;
    *y0 = k * c->rows;
    *y1 = *y0 + c->rows < h ? *y0 + c->rows : h;
}

static void pull_task(void *vctx, int i, int thread_id)
{
    (void)thread_id;
    const pp_ctx *c = vctx;
    const fv_pyr_level *s = c->src, *d = c->dst;
    int y0, y1;
    chunk_rows(c, i, d->h, &y0, &y1);
    for (int y = y0; y < y1; y++) {
        const ptrdiff_t r0 = (ptrdiff_t)(2 * y) * s->stride, r1 = r0 + s->stride;
        c->dsp->pull_row(px_rgbd(d, 0, y), d->wgt + (ptrdiff_t)y * d->stride, s->rgbd + 4 * r0, s->wgt + r0,
                         s->rgbd + 4 * r1, s->wgt + r1, d->w);
    }
}

static void replicate_sides(const fv_pyr_level *L, int y)
{
    float *row = px_rgbd(L, 0, y);
    memcpy(row - 4, row, 4 * sizeof(float));
    memcpy(row + 4 * L->w, row + 4 * (L->w - 1), 4 * sizeof(float));
}

static void replicate_row(const fv_pyr_level *L, int dst_y, int src_y)
{
    memcpy(px_rgbd(L, -1, dst_y), px_rgbd(L, -1, src_y), 4 * sizeof(float) * (size_t)(L->w + 2));
}

static void push_task(void *vctx, int i, int thread_id)
{
    (void)thread_id;
    const pp_ctx *c = vctx;
    const fv_pyr_level *s = c->src, *d = c->dst;
    int y0, y1;
    chunk_rows(c, i, d->h, &y0, &y1);
    for (int y = y0; y < y1; y++) {
        const int cy = y >> 1, fy = (y & 1) ? cy + 1 : cy - 1;
        c->dsp->push_row(px_rgbd(d, 0, y), d->wgt + (ptrdiff_t)y * d->stride, px_rgbd(s, 0, cy),
                         px_rgbd(s, 0, fy), d->w);
        replicate_sides(d, y);
    }
    if (y0 == 0)
        replicate_row(d, -1, 0);
    if (y1 == d->h)
        replicate_row(d, d->h, d->h - 1);
}

static void run_level(fv_pool *pool, fv_task_fn fn, pp_ctx *c)
{
    const fv_pyr_level *out = c->dst;
    const int threads = fv_pool_threads(pool);
    const long px = (long)out->w * out->h;
    if (px < PAR_MIN_PX || threads == 1) {
        c->rows = out->h;
        c->chunks = 1;
        fn(c, 0, 0);
        return;
    }
    int rows = CHUNK_PX / out->w;
    const int max_rows = (out->h + 4 * threads - 1) / (4 * threads); /* >= 4 items per thread */
    if (rows > max_rows)
        rows = max_rows;
    if (rows < 1)
        rows = 1;
    c->rows = rows;
    c->chunks = (out->h + rows - 1) / rows;
    fv_pool_run(pool, c->chunks, fn, c);
}

void fv_pull_block(fv_pyramid *p, const fv_pullpush_dsp *dsp, int level, int x0, int y0, int w, int h)
{
    const fv_pyr_level *s = &p->lv[level], *d = &p->lv[level + 1];
    /* rows 2Y+1 == s->h and column s->w are the zero-weight border: odd edges need no care */
    for (int y = y0 >> 1; y < (y0 + h + 1) >> 1; y++) {
        const ptrdiff_t r0 = (ptrdiff_t)(2 * y) * s->stride + x0, r1 = r0 + s->stride;
        dsp->pull_row(px_rgbd(d, x0 >> 1, y), d->wgt + (ptrdiff_t)y * d->stride + (x0 >> 1), s->rgbd + 4 * r0,
                      s->wgt + r0, s->rgbd + 4 * r1, s->wgt + r1, (w + 1) >> 1);
    }
}

void fv_pullpush(fv_pyramid *p, const fv_pullpush_dsp *dsp, fv_pool *pool)
{
    fv_pullpush_from(p, dsp, pool, 0);
}

void fv_pullpush_from(fv_pyramid *p, const fv_pullpush_dsp *dsp, fv_pool *pool, int pulled)
{
    if (!p->mem || p->levels < 1)
        return;
    /* Directions alternate so that each pass starts where the previous pass over the same
     * level ended (most recently touched rows are still in cache): pull 0->1 top-down, 1->2
     * bottom-up, ...; pushing into level l runs opposite to the pull that last read it. */
    for (int l = pulled; l + 1 < p->levels; l++) {
        pp_ctx c = { .dsp = dsp, .src = &p->lv[l], .dst = &p->lv[l + 1], .reverse = l & 1 };
        run_level(pool, pull_task, &c);
    }
    const fv_pyr_level *top = &p->lv[p->levels - 1];
    for (int y = 0; y < top->h; y++)
        replicate_sides(top, y);
    replicate_row(top, -1, 0);
    replicate_row(top, top->h, top->h - 1);
    for (int l = p->levels - 2; l >= 0; l--) {
        pp_ctx c = { .dsp = dsp, .src = &p->lv[l + 1], .dst = &p->lv[l], .reverse = !(l & 1) };
        run_level(pool, push_task, &c);
    }
}
