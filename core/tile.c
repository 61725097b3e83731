#include "tile.h"

#include <math.h>
#include <stdlib.h>
#include <stdatomic.h>
#include <string.h>

#include "base/clock.h"
#include "prof.h"
#include "raycast.h"
#include "sampling_dof.h"

/* The tiles' sums (rays, times) per worker, each on its own cache line: one shared counter, added
 * to after every tile by both workers, moved its line between the cores 2-3 times per tile
 * (7200 tiles a frame). A slot below the last is one thread's at a time (thread_id is unique
 * among the running items, core/pool.h; the pool's job start and end order its uses), so it is
 * added to by a relaxed load and store (SLOT_ADD): a locked add drains the store buffer, and right
 * after a tile's sample writes (stores waiting for their lines) it stalled there (86 % of
 * run_still's samples on the instruction after it). Worker ids from TILE_SLOTS - 1 on share the
 * last slot and add atomically. */
#define TILE_SLOTS 16 /* worker ids beyond share the last slot */
typedef struct {
    _Alignas(64) atomic_long rays;
    atomic_llong taa_ns;
    atomic_llong shade_ns;
} tile_slot;

typedef struct {
    const fv_scene *scene;
    const fv_camera *cam;
    const fv_sampler *smp;
    int gx, gy, tiles_x, tiles_y;
    fv_pyramid *pyr;
    const fv_render_dsp *dsp;
    int phase;
    const fv_taa_frame *taa;
    const fv_taa_params *taa_prm;
    tile_slot slot[TILE_SLOTS];
    int time_shading;
    struct fv_prof *prof; /* NULL: no trace recording */
    const struct fv_dofsamp_frame *dofs;
    uint32_t *rows_out;
    const fv_taa_aa_frame *aa;
    int still; /* the still head in place: level 0 is the history (fv_taa_still_*) */
} tile_job;

static inline tile_slot *slot_of(tile_job *j, int thread_id)
{
    return &j->slot[thread_id < TILE_SLOTS ? thread_id : TILE_SLOTS - 1];
}

#define SLOT_ADD(j, thread_id, field, v)                                                                       \
    do {                                                                                                       \
        tile_slot *s_ = slot_of(j, thread_id);                                                                 \
        if ((thread_id) < TILE_SLOTS - 1)                                                                      \
            atomic_store_explicit(&s_->field, atomic_load_explicit(&s_->field, memory_order_relaxed) + (v),  \
                                  memory_order_relaxed);                                                       \
        else                                                                                                   \
            atomic_fetch_add_explicit(&s_->field, (v), memory_order_relaxed);                                  \
    } while (0)

/* Pull the tile up the pyramid while it is in cache: a 16x16 tile is a 1x1 block of level 4.
 * Tiles start on multiples of 16, so every block starts on even coordinates. */
static void tile_end(tile_job *j, int index, int thread_id, int x0, int y0, int tw, int th, long rays,
                     int64_t tile_t0)
{
    int xl = x0, yl = y0, wl = tw, hl = th;
    for (int l = 0; l < FV_TILE_PULL_LEVELS && l + 1 < j->pyr->levels; l++) {
        fv_pull_block(j->pyr, &j->dsp->pp, l, xl, yl, wl, hl);
        xl >>= 1, yl >>= 1, wl = (wl + 1) >> 1, hl = (hl + 1) >> 1;
    }
    SLOT_ADD(j, thread_id, rays, rays);
    if (j->prof)
        fv_prof_span(j->prof, thread_id, thread_id, "tile", tile_t0, fv_time_ns(), index);
}

/* the still head's samples' history, saved by the ray caster just before it writes them */
typedef struct {
    const fv_pyr_level *l0;
    int x0, y0, tw, th;
    const uint32_t *rows;
    fv_taa_still_hist hist;
    int64_t ns;
} still_save;

static void save_hist(void *ctx)
{
    still_save *s = ctx;
    const int64_t t0 = fv_time_ns();
    fv_taa_still_save(s->l0, s->x0, s->y0, s->tw, s->th, s->rows, &s->hist);
    s->ns = fv_time_ns() - t0;
}

/* The still head in place (core/reproject.h): level 0 holds the history; the tile casts its rays
 * over it leaving the holes (the history) alone, its samples' texels saved just before they are
 * written, then blends them. The time saving the texels counts as reprojection. */
static void run_still(tile_job *j, int index, int thread_id, int x0, int y0, int tw, int th, const uint32_t *rows,
                      float keep, int aa, int64_t tile_t0)
{
    const fv_camera *cam = j->cam;
    const fv_pyr_level *l0 = &j->pyr->lv[0];
    still_save sv; /* its history filled by save_hist (5 KiB: not cleared) */
    sv.l0 = l0, sv.x0 = x0, sv.y0 = y0, sv.tw = tw, sv.th = th, sv.rows = rows, sv.ns = 0;
    int64_t shade_ns = 0;
    int64_t *sp = j->time_shading ? &shade_ns : NULL;
    const long rays = fv_raycast_tile_keep_holes(j->scene, cam, j->dsp, l0, x0, y0, tw, th, rows,
                                                 aa ? j->aa->ox : 0.5f, aa ? j->aa->oy : 0.5f, sp,
                                                 aa ? NULL : save_hist, &sv);
    int64_t taa_ns = sv.ns;
    const fv_taa_still_hist *hist = &sv.hist;
    if (shade_ns)
        SLOT_ADD(j, thread_id, shade_ns, shade_ns);
    if (j->aa && !aa)
        fv_taa_aa_clear(j->aa, x0, y0, tw, th);
    const int64_t t0 = fv_time_ns();
    if (aa)
        j->dsp->taa.taa_aa(j->taa, j->aa, l0, x0, y0, tw, th);
    else
        fv_taa_still_tile(j->taa, j->taa_prm, j->smp, j->gx, j->gy, l0, &j->dsp->taa, x0, y0, tw, th, rows, keep,
                          hist);
    const int64_t t1 = fv_time_ns();
    SLOT_ADD(j, thread_id, taa_ns, taa_ns + (t1 - t0));
    if (j->prof)
        fv_prof_span(j->prof, thread_id, thread_id, "reproject", t0, t1, index);
    tile_end(j, index, thread_id, x0, y0, tw, th, rays, tile_t0);
}

static void run_tile(void *ctx, int index, int thread_id)
{
    tile_job *j = ctx;
    const int64_t tile_t0 = j->prof ? fv_time_ns() : 0;
    const fv_camera *cam = j->cam;
    const fv_pyr_level *l0 = &j->pyr->lv[0];
    int tx = index % j->tiles_x, ty = index / j->tiles_x;
    int x0 = tx * FV_TILE, y0 = ty * FV_TILE;
    int tw = cam->width - x0 < FV_TILE ? cam->width - x0 : FV_TILE;
    int th = cam->height - y0 < FV_TILE ? cam->height - y0 : FV_TILE;

    if (j->taa && !j->still) /* early: the lines arrive while the rays are traced */
        fv_taa_prefetch(j->taa, FV_TILE_PULL_LEVELS, x0, y0, tw, th);
    if (j->still) /* the history is the tile itself: its samples' texels are read before they are written */
        for (int y = 0; y < th; y++) {
            const ptrdiff_t o = (ptrdiff_t)(y0 + y) * l0->stride + x0;
            for (int x = 0; x < tw; x += 4)
                __builtin_prefetch(l0->rgbd + 4 * (o + x), 1);
            __builtin_prefetch(l0->wgt + o, 1);
            __builtin_prefetch(l0->wgt + o + tw - 1, 1);
        }
    uint32_t rows[FV_TILE];
    fv_sampler_rows(j->smp, x0, y0, tw, th, j->gx, j->gy, j->phase, rows);
    /* fewer rays where the depth of field will blur (core/sampling_dof.h); keep: their share */
    const float keep = j->dofs ? fv_dofsamp_tile(j->dofs, x0, y0, tw, th, rows) : 1.0f;
    if (j->rows_out)
        for (int y = 0; y < FV_TILE; y++)
            j->rows_out[(size_t)index * FV_TILE + y] = y < th ? rows[y] : 0u;

    /* fovea anti-aliasing: a fully sampled tile's rays go through this frame's jittered point */
    const int aa = j->aa && fv_taa_aa_tile_eligible(j->smp, j->gx, j->gy, x0, y0, tw, th, rows);
    if (j->still) {
        run_still(j, index, thread_id, x0, y0, tw, th, rows, keep, aa, tile_t0);
        return;
    }
    /* writes every weight of the tile: pixels without a sample get 0 */
    int64_t shade_ns = 0;
    int64_t *sp = j->time_shading ? &shade_ns : NULL;
    const long rays = aa ? fv_raycast_tile_at(j->scene, cam, j->dsp, l0, x0, y0, tw, th, rows, j->aa->ox, j->aa->oy, sp)
                         : fv_raycast_tile(j->scene, cam, j->dsp, l0, x0, y0, tw, th, rows, sp);
    if (shade_ns)
        SLOT_ADD(j, thread_id, shade_ns, shade_ns);
    if (j->aa && !aa)
        fv_taa_aa_clear(j->aa, x0, y0, tw, th);
    if (aa) {
        const int64_t t0 = fv_time_ns();
        j->dsp->taa.taa_aa(j->taa, j->aa, l0, x0, y0, tw, th);
        const int64_t t1 = fv_time_ns();
        SLOT_ADD(j, thread_id, taa_ns, t1 - t0);
        if (j->prof)
            fv_prof_span(j->prof, thread_id, thread_id, "reproject", t0, t1, index);
    } else if (j->taa) {
        const int64_t t0 = fv_time_ns();
        fv_taa_tile_run_keep(j->taa, j->taa_prm, j->smp, j->gx, j->gy, &j->pyr->lv[0], &j->dsp->taa, x0, y0, tw, th,
                             keep);
        const int64_t t1 = fv_time_ns();
        SLOT_ADD(j, thread_id, taa_ns, t1 - t0);
        if (j->prof)
            fv_prof_span(j->prof, thread_id, thread_id, "reproject", t0, t1, index);
    }
    tile_end(j, index, thread_id, x0, y0, tw, th, rays, tile_t0);
}

static void job_init(tile_job *j, const fv_scene *scene, const fv_camera *cam, const fv_sampler *smp, int gx, int gy,
                     fv_pyramid *pyr, const fv_render_dsp *dsp, const fv_tile_opts *opt)
{
    memset(j, 0, sizeof *j);
    j->scene = scene, j->cam = cam, j->smp = smp, j->gx = gx, j->gy = gy, j->pyr = pyr, j->dsp = dsp;
    if (opt) {
        j->phase = opt->phase;
        j->taa = opt->taa;
        j->taa_prm = opt->taa_prm;
        j->prof = opt->prof;
        j->dofs = opt->dofs;
        j->rows_out = opt->rows_out;
        j->aa = opt->aa;
        j->still = opt->taa && opt->still;
        j->time_shading = opt->shade_ns != NULL;
    }
    j->tiles_x = (cam->width + FV_TILE - 1) / FV_TILE;
    j->tiles_y = (cam->height + FV_TILE - 1) / FV_TILE;
    for (int i = 0; i < TILE_SLOTS; i++) {
        atomic_init(&j->slot[i].rays, 0);
        atomic_init(&j->slot[i].taa_ns, 0);
        atomic_init(&j->slot[i].shade_ns, 0);
    }
}

/* the slots' sums (after the pool ran the job) */
static long job_rays(tile_job *j)
{
    long n = 0;
    for (int i = 0; i < TILE_SLOTS; i++) n += atomic_load(&j->slot[i].rays);
    return n;
}
static int64_t job_taa_ns(tile_job *j)
{
    int64_t n = 0;
    for (int i = 0; i < TILE_SLOTS; i++) n += atomic_load(&j->slot[i].taa_ns);
    return n;
}
static int64_t job_shade_ns(tile_job *j)
{
    int64_t n = 0;
    for (int i = 0; i < TILE_SLOTS; i++) n += atomic_load(&j->slot[i].shade_ns);
    return n;
}

/* a background tile pass (fv_tile_pass_post) */
struct fv_tile_async {
    tile_job job;
    atomic_llong tile_ns; /* the workers' time in its tiles */
};

static void run_async_tile(void *ctx, int index, int thread_id)
{
    fv_tile_async *a = ctx;
    const int64_t t0 = fv_time_ns();
    run_tile(&a->job, index, thread_id);
    atomic_fetch_add_explicit(&a->tile_ns, fv_time_ns() - t0, memory_order_relaxed);
}

long fv_tile_pass(const fv_scene *scene, const fv_camera *cam, const fv_sampler *smp, int gx, int gy, fv_pyramid *pyr,
                  const fv_render_dsp *dsp, fv_pool *pool, const fv_tile_opts *opt, double *taa_ms)
{
    tile_job j;
    job_init(&j, scene, cam, smp, gx, gy, pyr, dsp, opt);
    fv_pool_run(pool, j.tiles_x * j.tiles_y, run_tile, &j);
    if (j.time_shading)
        *opt->shade_ns = job_shade_ns(&j);
    if (taa_ms)
        *taa_ms = j.taa || j.aa ? (double)job_taa_ns(&j) * 1e-6 / fv_pool_threads(pool) : NAN;
    return job_rays(&j);
}

fv_tile_async *fv_tile_pass_post(const fv_scene *scene, const fv_sampler *smp, const fv_render_dsp *dsp, fv_pool *pool,
                                 const fv_tile_eye *eye)
{
    fv_tile_async *a = aligned_alloc(64, sizeof *a); /* the job's slots are cache-line aligned */
    if (!a)
        return NULL;
    job_init(&a->job, scene, eye->cam, smp, eye->gx, eye->gy, eye->pyr, dsp, &eye->opt);
    atomic_init(&a->tile_ns, 0);
    fv_pool_post(pool, a->job.tiles_x * a->job.tiles_y, run_async_tile, a);
    return a;
}

void fv_tile_pass_wait(fv_tile_async *a, fv_pool *pool, fv_tile_eye *eye)
{
    fv_pool_wait(pool);
    eye->rays = job_rays(&a->job);
    eye->tile_ms = (double)atomic_load(&a->tile_ns) * 1e-6;
    eye->taa_ms = a->job.taa || a->job.aa ? (double)job_taa_ns(&a->job) * 1e-6 / fv_pool_threads(pool) : NAN;
    if (a->job.time_shading)
        *eye->opt.shade_ns = job_shade_ns(&a->job);
    free(a);
}
