/* fovea: the bench's bookkeeping, free of I/O (fovea-bench wires it; platform/benchio.c prints
 * and writes it): per-stage means and the median frame time over the timed frames, hardware
 * counter deltas per stage through the profiler's stage hook, the roofline (compulsory bytes over
 * stage time against the copy bandwidth), --sweep specs and the config of each sweep point, the
 * turning head of --yaw-rate and the copy-bandwidth probe. */
#ifndef FOVEA_BENCH_H
#define FOVEA_BENCH_H

#include <stddef.h>
#include <stdint.h>

#include "camera.h"
#include "pipeline.h"
#include "prof.h"

/* Median of v[0..n) (sorts v in place); NAN for n = 0. */
double fv_median(double *v, int n);

/* ---- one timed run of one mode ---- */
#define FV_BENCH_MAX_CTRS 8 /* hardware counters per stage (platform/perfctr.h has 4) */
typedef struct fv_bench_run {
    const char *mode;                  /* "foveated" or "full" */
    long samples;                      /* rays of the last timed frame */
    double stage_mean[FV_STAGE_COUNT]; /* ms; NAN: the stage is not built */
    double total_mean, total_median;   /* ms */
    double mrays;                      /* samples over the mean ray-tracing time */
    const char *sampler;               /* the sampling pattern, fv_sampler_names: "weier" | "liu" */
    double ceiling_ms;                 /* mean bare-Embree time of the same rays (core/ceiling.h); NAN: not run */
    double ceiling_mrays;              /* samples over ceiling_ms */
    double shade_ms;                   /* mean time shading hits inside the ray stage (all threads' time over
                                          the thread count, as the stage is wall time); NAN: not measured */
    int counters;                      /* hardware counters were read */
    char counters_why[160];            /* else why not */
    double ctr[FV_PROF_STAGES][FV_BENCH_MAX_CTRS]; /* per frame, per profiled stage */
    fv_pipeline_memory mem;            /* the bytes the pipeline keeps (fv_pipeline_memory_bytes) */
} fv_bench_run;

/* Stage statistics over `frames` timed frames into r (means as sums of value / frames, so a
 * stage that is not built stays NAN). init clears r; -1 when out of memory. Frames past
 * `frames` are ignored. finish sets the median and Mrays/s and frees the accumulator. */
typedef struct fv_bench_acc {
    fv_bench_run *r;
    int frames, n;
    double *total; /* each frame's total_ms */
    double ceil_sum;
    int ceil_n;
    double shade_sum;
    int shade_n;
} fv_bench_acc;
int fv_bench_acc_init(fv_bench_acc *a, fv_bench_run *r, const char *mode, int frames);
void fv_bench_acc_add(fv_bench_acc *a, const fv_frame_stats *st);
void fv_bench_acc_finish(fv_bench_acc *a);
/* One timed frame's ceiling time (--ceiling): finish sets ceiling_ms to their mean. */
void fv_bench_acc_add_ceiling(fv_bench_acc *a, double ms);
/* One timed frame's shading time in ms (fv_frame_stats.shade_ms, with the pipeline's
 * time_shading: the workers' time over their count): finish sets shade_ms to their mean. */
void fv_bench_acc_add_shade(fv_bench_acc *a, double ms);
/* shade_ms as a fraction of the ray stage's time (NAN when either is missing). */
double fv_bench_shade_share(const fv_bench_run *r);
/* The ray stage against its ceiling: trace / ceiling time of one run (NAN without a ceiling),
 * and a foveated ray's cost in units of a full-frame bare-Embree ray (fov's trace time per ray
 * over full's ceiling time per ray; NAN when either is missing). */
double fv_bench_ceiling_ratio(const fv_bench_run *r);
double fv_bench_ray_cost(const fv_bench_run *fov, const fv_bench_run *full);

/* Sum of both eyes' stats (stage times, total, samples); first: st starts the sum. */
void fv_frame_stats_sum(fv_frame_stats *sum, const fv_frame_stats *st, int first);

/* ---- hardware counters per stage ----
 * fv_bench_ctrs_hook is an fv_prof_stage_hook: at each stage boundary it reads the n counter
 * totals through `read` (0, or -1 on failure: the accumulator then stops for good); while `on`,
 * the deltas from a stage's start to its end are summed per stage. */
typedef int (*fv_bench_ctr_read)(void *ctx, uint64_t *v);
typedef struct fv_bench_ctrs {
    fv_bench_ctr_read read;
    void *read_ctx;
    int n;      /* counters, <= FV_BENCH_MAX_CTRS */
    int on;     /* accumulate (after warm-up) */
    int failed; /* a read failed */
    uint64_t start[FV_PROF_STAGES][FV_BENCH_MAX_CTRS];
    double sum[FV_PROF_STAGES][FV_BENCH_MAX_CTRS];
} fv_bench_ctrs;
void fv_bench_ctrs_init(fv_bench_ctrs *c, fv_bench_ctr_read read, void *read_ctx, int n);
void fv_bench_ctrs_hook(void *ctx, int stage, int end);
/* The sums per frame into r->ctr (and r->counters = 1). */
void fv_bench_ctrs_mean(const fv_bench_ctrs *c, int frames, fv_bench_run *r);

/* ---- roofline ---- */
#define FV_BENCH_NROOF 6
extern const int fv_bench_roof_stages[FV_BENCH_NROOF]; /* reproject .. output: the memory-bound passes */
typedef struct fv_roof {
    double read_bytes, written_bytes; /* compulsory bytes per frame (fv_bench_stage_bytes) */
    double gbps;                      /* their sum over the stage's mean time */
    double fraction;                  /* of the copy bandwidth; NAN when that is unknown (0) */
} fv_roof;
/* The fraction of a w x h image pull-push fills: pixels without a ray, 0 at full sampling. */
double fv_bench_holes(long samples, int w, int h);
/* 0 with *out, or -1 when the stage has no byte model, no time (not built) or no bytes. */
int fv_bench_roofline(const fv_bench_run *r, int stage, int w, int h, double copy_gbps, fv_roof *out);

/* Thread-scaling efficiency of time t on n threads against t0 on n0: t0 n0 / (t n). */
double fv_bench_scaling(double t0, int n0, double t, int n);

/* ---- --sweep P=VALUES ---- */
enum { FV_SWEEP_THREADS, FV_SWEEP_SIZE, FV_SWEEP_PMIN, FV_SWEEP_R0, FV_SWEEP_R1, FV_SWEEP_PARAMS };
extern const char *const fv_sweep_names[FV_SWEEP_PARAMS]; /* threads, size, pmin, r0, r1 */
#define FV_SWEEP_MAX_POINTS 32
#define FV_BENCH_MAX_SWEEPS 4
typedef struct fv_sweep {
    int param, n;
    char label[FV_SWEEP_MAX_POINTS][24]; /* each value as given ("640x720", "0.1") */
    int iv[FV_SWEEP_MAX_POINTS], w[FV_SWEEP_MAX_POINTS], h[FV_SWEEP_MAX_POINTS];
    float fv[FV_SWEEP_MAX_POINTS];
    fv_bench_run res[FV_SWEEP_MAX_POINTS][2]; /* filled by the caller: the modes run at each point */
    int nres[FV_SWEEP_MAX_POINTS];
} fv_sweep;
/* spec: threads=A..B, threads=N,N, size=WxH,WxH, pmin=P,P, r0=DEG,DEG, r1=DEG,DEG (at most
 * FV_SWEEP_MAX_POINTS values). 0, or -1 with the --sweep usage message in err. */
int fv_sweep_parse(const char *spec, fv_sweep *sw, char *err, size_t err_len);
/* base with point i's value applied. */
fv_pipeline_config fv_sweep_config(const fv_sweep *sw, int i, const fv_pipeline_config *base);
/* Every point keeps r0 <= r1: 0, or -1 with the message naming the sweep. */
int fv_sweep_check(const fv_sweep *sw, const fv_pipeline_config *base, char *err, size_t err_len);
/* The most threads any point of the sweeps asks for, at least `threads`. */
int fv_sweep_max_threads(const fv_sweep *sw, int nsweeps, int threads);

/* ---- machine and motion ---- */
/* The head pose of frame f: the view turned by yaw_rate * f / 90 Hz about its own vertical axis. */
fv_pose fv_bench_head_at(const fv_pose *view, float yaw_rate_dps, int f);
/* --stereo: the stereo pair (foveated, gaze at the centre) rendered one eye after the other
 * (fv_pipeline_render left, right) and with fv_pipeline_render_stereo (the right eye's tiles
 * beside the left eye's stages), alternating frame by frame on one pipeline (the same bytes either
 * way, so the history is the same); medians of `frames` pairs each after `warmup` pairs, wall
 * ms. With ceiling: bare Embree on both eyes' rays after every pair (untimed in the pair). */
typedef struct fv_bench_stereo {
    double seq_ms, joint_ms, ceiling_ms; /* ceiling_ms NAN without */
    int pairs;                           /* timed pairs of each kind */
} fv_bench_stereo;
int fv_bench_stereo_run(const fv_scene *scene, fv_pipeline_config cfg, const fv_pose *view, float yaw_rate_dps,
                        int warmup, int frames, int ceiling, fv_bench_stereo *r, char *err, size_t err_len);

/* memcpy bandwidth in GB/s of read + written bytes (64 MiB, best of 5) on `threads` threads of a
 * core pool; 0 when out of memory. */
double fv_bench_copy_gbps(int threads);

/* Memory roofline model: bytes a post-processing stage reads and writes per frame on a w x h eye
 * image, counted from the buffers it touches (each byte of a buffer once: the compulsory traffic;
 * docs/bench-2026-11-22-profile.md lists the buffers). stage: FV_STAGE_* (core/stage.h).
 * holes: the fraction of level-0 pixels pull-push has to fill (weight < 1; 1 - samples / pixels;
 * 0 with full sampling, where push only reads the weights). 0 on success, -1 for a stage without
 * a model (trace). */
int fv_bench_stage_bytes(int stage, int w, int h, double holes, double *read_bytes, double *written_bytes);

#endif
