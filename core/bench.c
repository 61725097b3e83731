/* The bench's bookkeeping (core/bench.h): statistics, counters, roofline, sweeps. No I/O. */
#include "bench.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "base/err.h"
#include "base/parse.h"
#include "ceiling.h"
#include "pool.h"
#include "tile.h" /* FV_TILE_PULL_LEVELS: the levels the tiles pull */

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double fv_median(double *v, int n)
{
    if (n <= 0)
        return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n & 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int fv_bench_acc_init(fv_bench_acc *a, fv_bench_run *r, const char *mode, int frames)
{
    memset(a, 0, sizeof *a);
    memset(r, 0, sizeof *r);
    r->mode = mode;
    r->sampler = "weier";
    r->ceiling_ms = r->ceiling_mrays = r->shade_ms = NAN;
    a->r = r;
    a->frames = frames;
    a->total = calloc((size_t)(frames > 0 ? frames : 1), sizeof *a->total);
    return a->total ? 0 : -1;
}

void fv_bench_acc_add(fv_bench_acc *a, const fv_frame_stats *st)
{
    if (a->n >= a->frames)
        return;
    fv_bench_run *r = a->r;
    for (int s = 0; s < FV_STAGE_COUNT; s++)
        r->stage_mean[s] += st->stage_ms[s] / a->frames; /* NAN stays NAN: stage not built */
    r->total_mean += st->total_ms / a->frames;
    a->total[a->n++] = st->total_ms;
    r->samples = st->samples;
}

void fv_bench_acc_finish(fv_bench_acc *a)
{
    fv_bench_run *r = a->r;
    r->total_median = fv_median(a->total, a->n);
    r->mrays = (double)r->samples / (r->stage_mean[FV_STAGE_TRACE] * 1e3);
    if (a->ceil_n > 0) {
        r->ceiling_ms = a->ceil_sum / a->ceil_n;
        r->ceiling_mrays = (double)r->samples / (r->ceiling_ms * 1e3);
    }
    if (a->shade_n > 0)
        r->shade_ms = a->shade_sum / a->shade_n;
    free(a->total);
    a->total = NULL;
}

void fv_bench_acc_add_ceiling(fv_bench_acc *a, double ms)
{
    if (a->ceil_n >= a->frames)
        return;
    a->ceil_sum += ms;
    a->ceil_n++;
}

void fv_bench_acc_add_shade(fv_bench_acc *a, double ms)
{
    if (a->shade_n >= a->frames)
        return;
    a->shade_sum += ms;
    a->shade_n++;
}

double fv_bench_shade_share(const fv_bench_run *r)
{
    const double t = r->stage_mean[FV_STAGE_TRACE];
    return t > 0.0 && r->shade_ms >= 0.0 ? r->shade_ms / t : NAN;
}

double fv_bench_ceiling_ratio(const fv_bench_run *r)
{
    return r->ceiling_ms > 0.0 ? r->stage_mean[FV_STAGE_TRACE] / r->ceiling_ms : NAN;
}

double fv_bench_ray_cost(const fv_bench_run *fov, const fv_bench_run *full)
{
    if (!(full->ceiling_ms > 0.0) || fov->samples <= 0 || full->samples <= 0)
        return NAN;
    return (fov->stage_mean[FV_STAGE_TRACE] / (double)fov->samples) / (full->ceiling_ms / (double)full->samples);
}

void fv_frame_stats_sum(fv_frame_stats *sum, const fv_frame_stats *st, int first)
{
    if (first)
        memset(sum, 0, sizeof *sum);
    for (int s = 0; s < FV_STAGE_COUNT; s++)
        sum->stage_ms[s] = first ? st->stage_ms[s] : sum->stage_ms[s] + st->stage_ms[s];
    sum->shade_ms = first ? st->shade_ms : sum->shade_ms + st->shade_ms; /* NAN: not timed */
    sum->total_ms += st->total_ms;
    sum->samples += st->samples;
}

void fv_bench_ctrs_init(fv_bench_ctrs *c, fv_bench_ctr_read read, void *read_ctx, int n)
{
    memset(c, 0, sizeof *c);
    c->read = read;
    c->read_ctx = read_ctx;
    c->n = n < FV_BENCH_MAX_CTRS ? n : FV_BENCH_MAX_CTRS;
}

void fv_bench_ctrs_hook(void *ctx, int stage, int end)
{
    fv_bench_ctrs *c = ctx;
    uint64_t v[FV_BENCH_MAX_CTRS];
    if (c->failed || stage < 0 || stage >= FV_PROF_STAGES)
        return;
    if (c->read(c->read_ctx, v)) {
        c->failed = 1;
        return;
    }
    for (int k = 0; k < c->n; k++)
        if (!end)
            c->start[stage][k] = v[k];
        else if (c->on)
            c->sum[stage][k] += (double)(v[k] - c->start[stage][k]);
}

void fv_bench_ctrs_mean(const fv_bench_ctrs *c, int frames, fv_bench_run *r)
{
    r->counters = 1;
    for (int s = 0; s < FV_PROF_STAGES; s++)
        for (int k = 0; k < c->n; k++)
            r->ctr[s][k] = c->sum[s][k] / frames;
}

const int fv_bench_roof_stages[FV_BENCH_NROOF] = {FV_STAGE_REPROJECT, FV_STAGE_RECONSTRUCT, FV_STAGE_COC,
                                                  FV_STAGE_DOF_FILTER, FV_STAGE_COMBINE, FV_STAGE_OUTPUT};

double fv_bench_holes(long samples, int w, int h)
{
    const double f = 1.0 - (double)samples / ((double)w * (double)h);
    return f > 0.0 ? f : 0.0;
}

int fv_bench_roofline(const fv_bench_run *r, int stage, int w, int h, double copy_gbps, fv_roof *out)
{
    double rd = 0.0, wr = 0.0;
    const double ms = r->stage_mean[stage];
    if (fv_bench_stage_bytes(stage, w, h, fv_bench_holes(r->samples, w, h), &rd, &wr) || isnan(ms) || ms <= 0.0 ||
        rd + wr <= 0.0)
        return -1;
    out->read_bytes = rd;
    out->written_bytes = wr;
    out->gbps = (rd + wr) / (ms * 1e6);
    out->fraction = copy_gbps > 0.0 ? out->gbps / copy_gbps : NAN;
    return 0;
}

double fv_bench_scaling(double t0, int n0, double t, int n) { return t0 * n0 / (t * n); }

/* ---- sweeps ---- */
const char *const fv_sweep_names[FV_SWEEP_PARAMS] = {"threads", "size", "pmin", "r0", "r1"};

int fv_sweep_parse(const char *spec, fv_sweep *sw, char *err, size_t err_len)
{
    const char *eq = strchr(spec, '=');
    memset(sw, 0, sizeof *sw);
    sw->param = -1;
    for (int i = 0; i < FV_SWEEP_PARAMS && eq; i++)
        if ((size_t)(eq - spec) == strlen(fv_sweep_names[i]) && !strncmp(spec, fv_sweep_names[i], (size_t)(eq - spec)))
            sw->param = i;
    if (sw->param < 0 || !eq[1])
        return fv_err(err, err_len, "--sweep: '%s' is not P=VALUES with P one of threads, size, pmin, r0, r1", spec);
    const char *v = eq + 1;
    const char *dots = strstr(v, "..");
    if (sw->param == FV_SWEEP_THREADS && dots) { /* a range A..B */
        char a[32];
        long lo, hi;
        if ((size_t)(dots - v) >= sizeof a)
            return fv_err(err, err_len, "--sweep: '%s' is not threads=A..B", spec);
        memcpy(a, v, (size_t)(dots - v));
        a[dots - v] = 0;
        if (fv_parse_long("--sweep threads", a, 1, 256, &lo, err, err_len) ||
            fv_parse_long("--sweep threads", dots + 2, lo, lo + FV_SWEEP_MAX_POINTS - 1, &hi, err, err_len))
            return -1;
        for (long t = lo; t <= hi; t++) {
            sw->iv[sw->n] = (int)t;
            snprintf(sw->label[sw->n], sizeof sw->label[0], "%ld", t);
            sw->n++;
        }
        return 0;
    }
    char buf[512];
    if (strlen(v) >= sizeof buf)
        return fv_err(err, err_len, "--sweep: '%s' is too long", spec);
    strcpy(buf, v);
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        if (sw->n == FV_SWEEP_MAX_POINTS)
            return fv_err(err, err_len, "--sweep: more than %d values", FV_SWEEP_MAX_POINTS);
        const int i = sw->n;
        long t;
        int rc;
        switch (sw->param) {
        case FV_SWEEP_THREADS:
            rc = fv_parse_long("--sweep threads", tok, 1, 256, &t, err, err_len);
            sw->iv[i] = (int)t;
            break;
        case FV_SWEEP_SIZE: rc = fv_parse_size("--sweep size", tok, &sw->w[i], &sw->h[i], err, err_len); break;
        case FV_SWEEP_PMIN: rc = fv_parse_float("--sweep pmin", tok, 1e-3f, 1.0f, &sw->fv[i], err, err_len); break;
        default:
            rc = fv_parse_float(sw->param == FV_SWEEP_R0 ? "--sweep r0" : "--sweep r1", tok, 0.1f, 90.0f, &sw->fv[i],
                                err, err_len);
        }
        if (rc)
            return -1;
        snprintf(sw->label[i], sizeof sw->label[0], "%s", tok);
        sw->n++;
    }
    if (sw->n == 0)
        return fv_err(err, err_len, "--sweep: '%s' has no values", spec);
    return 0;
}

fv_pipeline_config fv_sweep_config(const fv_sweep *sw, int i, const fv_pipeline_config *base)
{
    fv_pipeline_config c = *base;
    switch (sw->param) {
    case FV_SWEEP_THREADS: c.threads = sw->iv[i]; break;
    case FV_SWEEP_SIZE: c.cam.width = sw->w[i], c.cam.height = sw->h[i]; break;
    case FV_SWEEP_PMIN: c.samp.p_min = sw->fv[i]; break;
    case FV_SWEEP_R0: c.samp.r0_deg = sw->fv[i]; break;
    default: c.samp.r1_deg = sw->fv[i];
    }
    return c;
}

int fv_sweep_check(const fv_sweep *sw, const fv_pipeline_config *base, char *err, size_t err_len)
{
    for (int k = 0; k < sw->n; k++) {
        const fv_pipeline_config c = fv_sweep_config(sw, k, base);
        if (c.samp.r0_deg > c.samp.r1_deg)
            return fv_err(err, err_len, "--sweep %s: r0 %g must not exceed r1 %g", fv_sweep_names[sw->param],
                          (double)c.samp.r0_deg, (double)c.samp.r1_deg);
    }
    return 0;
}

int fv_sweep_max_threads(const fv_sweep *sw, int nsweeps, int threads)
{
    for (int i = 0; i < nsweeps; i++)
        for (int k = 0; k < sw[i].n; k++)
            if (sw[i].param == FV_SWEEP_THREADS && sw[i].iv[k] > threads)
                threads = sw[i].iv[k];
    return threads;
}

fv_pose fv_bench_head_at(const fv_pose *view, float yaw_rate_dps, int f)
{
    const float a = yaw_rate_dps * (float)f / 90.0f * 3.14159265f / 180.0f;
    const float q[4] = {0.0f, sinf(0.5f * a), 0.0f, cosf(0.5f * a)};
    fv_pose p = *view;
    fv_quat_mul(view->quat, q, p.quat); /* about the head's own up axis */
    return p;
}

/* ---- copy bandwidth: 64 MiB in 64 chunks, one pool job each ---- */
#define COPY_BYTES ((size_t)64 << 20)
typedef struct {
    char *src, *dst;
    size_t chunk;
} copy_job;
static void copy_part(void *ctx, int i, int tid)
{
    (void)tid;
    copy_job *j = ctx;
    memcpy(j->dst + (size_t)i * j->chunk, j->src + (size_t)i * j->chunk, j->chunk);
}
double fv_bench_copy_gbps(int threads)
{
    copy_job j = {malloc(COPY_BYTES), malloc(COPY_BYTES), COPY_BYTES / 64};
    fv_pool *pool = threads > 1 ? fv_pool_create(threads) : NULL;
    double best = 0.0;
    if (j.src && j.dst && (threads <= 1 || pool)) {
        memset(j.src, 1, COPY_BYTES);
        memset(j.dst, 2, COPY_BYTES);
        for (int r = 0; r < 5; r++) {
            const int64_t t0 = fv_time_ns();
            fv_pool_run(pool, 64, copy_part, &j);
            const double s = (double)(fv_time_ns() - t0) * 1e-9;
            const double g = 2.0 * (double)COPY_BYTES / s * 1e-9;
            best = g > best ? g : best;
        }
    }
    fv_pool_destroy(pool);
    free(j.src);
    free(j.dst);
    return best;
}

int fv_bench_stage_bytes(int stage, int w, int h, double holes, double *rd, double *wr)
{
    const double N = (double)w * (double)h;
    const double px = 16.0, wt = 4.0; /* a pixel: r, g, b, depth floats; a weight: one float */
    *rd = *wr = 0.0;
    switch (stage) {
    case FV_STAGE_RECONSTRUCT: {
        /* levels above the tiles' pulls are pulled (fine level read, coarse level written), then
         * every level but the top is pushed: fine weights read; where a pixel is a hole (the
         * fraction `holes`, taken for every level), its colour and the coarse colour above it
         * read and its colour written */
        int lw[32], lh[32], L = 0;
        for (int cw = w, ch = h; L < 32; L++) {
            lw[L] = cw, lh[L] = ch;
            if (cw == 1 && ch == 1)
                break;
            cw = (cw + 1) / 2, ch = (ch + 1) / 2;
        }
        const int levels = L + 1;
        const int pulled = levels - 1 < FV_TILE_PULL_LEVELS ? levels - 1 : FV_TILE_PULL_LEVELS;
        for (int l = pulled; l + 1 < levels; l++) {
            *rd += (px + wt) * lw[l] * (double)lh[l];
            *wr += (px + wt) * lw[l + 1] * (double)lh[l + 1];
        }
        for (int l = 0; l + 1 < levels; l++) {
            *rd += wt * lw[l] * (double)lh[l] + holes * (px * lw[l] * (double)lh[l] + px * lw[l + 1] * (double)lh[l + 1]);
            *wr += holes * px * lw[l] * (double)lh[l];
        }
        return 0;
    }
    case FV_STAGE_REPROJECT:
        if (!(holes > 0.0))
            return 0; /* full sampling has no reprojection */
        /* level 0 colour + weight read and written; the history's level 0 and, for holes, its
         * coarser levels (a third more) read */
        *rd = (px + wt) * N + (px + wt) * N * (4.0 / 3.0);
        *wr = (px + wt) * N;
        return 0;
    case FV_STAGE_COC: /* level 0 colour + depth read, the CoC plane written */
        *rd = px * N;
        *wr = wt * N;
        return 0;
    case FV_STAGE_DOF_FILTER: /* level 0 + CoC read; the horizontal pass's layer written, read back */
        *rd = (px + wt) * N + px * N;
        *wr = px * N;
        return 0;
    case FV_STAGE_COMBINE: /* sharp, CoC, the blurred layer read; the output written */
        *rd = (px + wt + px) * N;
        *wr = px * N;
        return 0;
    case FV_STAGE_OUTPUT: /* the final float image read; 8-bit RGB written */
        *rd = px * N;
        *wr = 3.0 * N;
        return 0;
    default:
        return -1;
    }
}

int fv_bench_stereo_run(const fv_scene *scene, fv_pipeline_config cfg, const fv_pose *view, float yaw_rate_dps,
                        int warmup, int frames, int ceiling, fv_bench_stereo *r, char *err, size_t err_len)
{
    cfg.samp.full = 0;
    fv_pipeline *pl = fv_pipeline_create(scene, &cfg, err, err_len);
    if (!pl)
        return -1;
    double *t = malloc(4 * (size_t)frames * sizeof *t); /* frames a kind, the ceiling's 2 frames */
    if (!t) {
        fv_pipeline_destroy(pl);
        return fv_err(err, err_len, "out of memory");
    }
    int n[2] = {0, 0}, nc = 0, rc = 0;
    for (int f = 0; f < 2 * (warmup + frames) && !rc; f++) {
        const int joint = f & 1; /* alternately: one eye after the other, fv_pipeline_render_stereo */
        const fv_pose head = fv_bench_head_at(view, yaw_rate_dps, f);
        fv_frame_stats st[2];
        const int64_t t0 = fv_time_ns();
        int bad = 0;
        if (joint)
            bad = fv_pipeline_render_stereo(pl, &head, 0.5f, 0.5f, st);
        else
            for (int e = 0; e < 2 && !bad; e++)
                bad = fv_pipeline_render(pl, e ? FV_EYE_RIGHT : FV_EYE_LEFT, &head, 0.5f, 0.5f, &st[e]);
        const double ms = (double)(fv_time_ns() - t0) * 1e-6;
        if (bad) {
            rc = fv_err(err, err_len, "stereo pair %d: rendering failed", f);
            break;
        }
        const int timed = f >= 2 * warmup;
        if (timed)
            t[joint * frames + n[joint]++] = ms;
        if (ceiling) {
            double cms = 0.0;
            for (int e = 0; e < 2; e++) {
                const fv_eye eye = e ? FV_EYE_RIGHT : FV_EYE_LEFT;
                const fv_camera *cam = fv_pipeline_camera(pl, eye);
                const fv_ceiling_opts co = {.smp = fv_pipeline_sampler(pl),
                                            .gx = (int)floorf(0.5f * (float)cam->width),
                                            .gy = (int)floorf(0.5f * (float)cam->height),
                                            .phase = fv_pipeline_last_phase(pl, eye),
                                            .rows = fv_pipeline_last_rows(pl, eye)};
                const int64_t c0 = fv_time_ns();
                const long rays = fv_ceiling_trace(scene, cam, fv_pipeline_pool(pl), &co, NULL);
                cms += (double)(fv_time_ns() - c0) * 1e-6;
                if (rays != st[e].samples) { /* not the same rays: the ratio would mean nothing */
                    rc = fv_err(err, err_len, "stereo pair %d: the ceiling traced %ld rays, the eye %ld", f, rays,
                                st[e].samples);
                    break;
                }
            }
            if (timed && !rc)
                t[2 * frames + nc++] = cms;
        }
    }
    r->pairs = n[0] < n[1] ? n[0] : n[1];
    r->seq_ms = fv_median(t, n[0]);
    r->joint_ms = fv_median(t + frames, n[1]);
    r->ceiling_ms = ceiling ? fv_median(t + 2 * frames, nc) : NAN;
    free(t);
    fv_pipeline_destroy(pl);
    return rc;
}
