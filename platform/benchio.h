/* fovea platform: the bench's and the replay's measuring and reporting (core/bench.h holds the
 * arithmetic): timed runs with hardware counters (perf_event_open), the load average, the
 * fovea-bench table, roofline and counter printouts and its JSON (docs/bench.schema.json), and
 * fovea-replay's stats.csv lines, fovea-headset's latency CSV. Formats are the programs' contract: tests/cli.sh and
 * tools/check_schema.py check them. */
#ifndef FOVEA_BENCHIO_H
#define FOVEA_BENCHIO_H

#include <stdio.h>

#include "bench.h"
#include "displayloop.h"
#include "frameloop.h"
#include "prof.h"
#include "quality.h"
#include "scene.h"

/* getloadavg's 1, 5 and 15 minute averages; NAN each when unavailable. */
void fv_load_avg(double la[3]);

/* Options of one timed run beyond the pipeline's config. */
typedef struct fv_bench_opts {
    float yaw_rate; /* deg/s at 90 Hz (fv_bench_head_at) */
    int warmup, frames;
    int counters;   /* read hardware counters per stage */
    fv_prof *prof;  /* trace recorder or NULL */
    int ceiling;    /* after every frame, time bare Embree on its rays (core/ceiling.h) */
} fv_bench_opts;

/* Renders warmup + frames frames of one eye (gaze at the centre) with cfg (full: full
 * sampling) into r; with bo->ceiling, each frame is followed by fv_ceiling_trace on exactly its
 * rays (every pixel in full mode, else the sampler's set for the frame's gaze and phase) on the
 * pipeline's pool, so ray stage and ceiling share the run's load. 0, or -1 with a reason in err (bad config, out of memory, or
 * "FOVEATED|FULL frame N: rendering failed"). Counters that cannot be read are reported in r. */
int fv_bench_run_mode(const fv_scene *scene, fv_pipeline_config cfg, int full, const fv_pose *view,
                      const fv_bench_opts *bo, fv_bench_run *r, char *err, size_t err_len);

/* What the bench prints and writes besides the runs. */
typedef struct fv_bench_report {
    const char *scene_path;
    size_t triangles;
    double load_ms;
    int width, height, threads, warmup, frames, cpus;
    float yaw_rate;
    const char *isa;                 /* the kernels in use */
    const fv_pipeline_config *cfg;   /* the base config (dof; sweep points derive from it) */
    double copy_gbps_1t, copy_gbps;  /* 1 thread, `threads` threads */
    double load_avg[3];
    const fv_bench_run *runs;
    int nruns;
    const fv_sweep *sweeps;
    int nsweeps;
} fv_bench_report;

/* The start-up lines: scene, size, threads, kernels, frames, head, dof; bandwidth and load. */
void fv_bench_print_setup(FILE *f, const char *prog, const fv_bench_report *rep);
/* The table of Weier et al. 2018 (Table 1) for nres runs. */
void fv_bench_print_table(FILE *f, const fv_bench_run *res, int nres, int frames);
/* After the base runs: the table, the foveated/full ratios, the roofline and the first run's counters. */
void fv_bench_print_results(FILE *f, const fv_bench_report *rep);
/* With --ceiling: per run sampler, samples, trace ms, ceiling ms, their ratio, Mrays/s of both;
 * with both modes, a foveated ray's cost in full-frame bare-Embree rays. */
void fv_bench_print_ceiling(FILE *f, const fv_bench_run *res, int nres);
/* A sweep point's heading and table; a thread sweep's scaling efficiency. */
void fv_bench_print_sweep_point(FILE *f, const fv_sweep *sw, int k, int frames);
void fv_bench_print_scaling(FILE *f, const fv_sweep *sw);
/* The JSON document (docs/bench.schema.json) of the whole bench. */
void fv_bench_write_json(FILE *f, const fv_bench_report *rep);

/* fovea-replay's stats.csv: the header, and one frame's line (sum: both eyes' stats; q: the
 * frame's quality measures, NAN fields empty; focus_m NAN: empty). */
void fv_stats_csv_header(FILE *f);
void fv_stats_csv_row(FILE *f, long frame, double t_ms, float gaze_x, float gaze_y, const fv_frame_stats *sum,
                      const fv_quality_row *q, double focus_m);

/* fovea-headset's --latency-csv: one line per frame record, times in ms since t0_ns; written
 * atomically. 0, or -1 with a reason. */
/* The same one row at a time, for a run that streams its rows as they complete. */
void fv_latency_csv_header(FILE *f);
void fv_latency_csv_row(FILE *f, const fv_frame_record *r, int64_t t0_ns);
void fv_refresh_csv_header(FILE *f);
void fv_refresh_csv_row(FILE *f, const fv_refresh_record *r, int64_t t0_ns);
int fv_latency_csv_write(const char *path, const fv_frame_record *r, long n, int64_t t0_ns, char *err,
                         size_t err_len);
/* --timewarp on: one row per refresh (displayloop.h): refresh,frame,reused,late,head_t_ms,
 * gaze_t_ms,frame_start_ms,frame_done_ms,compose_start_ms,compose_done_ms,target_ms,photon_ms,
 * motion_to_photon_ms,gaze_to_photon_ms,photon_edge,vsync_state,margin_ms,disoccluded,
 * pose_err_deg,gaze_x,gaze_y (ms since t0; empty where unknown). 0, or -1 with err. */
int fv_refresh_csv_write(const char *path, const fv_refresh_record *r, long n, int64_t t0, char *err, size_t err_len);

#endif
