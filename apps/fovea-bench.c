/* fovea-bench: per-stage timings of the frame pipeline in the layout of Weier et al. 2018,
 * Table 1 (one eye, static head and gaze), printed and written as JSON. */
#define _DEFAULT_SOURCE /* getloadavg */
#include <getopt.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "base/clock.h"
#include "checkasm/bench.h" /* --kernels: tests/checkasm/bench.c */
#include "output.h"
#include "perfctr.h"
#include "pipeline.h"
#include "prof.h"
#include "proftrace.h"
#include "scene.h"

static const char *prog = "fovea-bench";

static void usage(FILE *f)
{
    fprintf(f,
            "usage: fovea-bench --scene FILE [--frames N] [--mode foveated|full|both] [--json FILE] [options]\n"
            "       fovea-bench --kernels [--json FILE] [--kernel-reps N] [--kernel NAME --calls N [--isa I]]\n"
            "Times every pipeline stage for one eye with the gaze at the image centre; prints the\n"
            "table of Weier et al. 2018 (Table 1) and writes JSON. Times are means over the frames\n"
            "after warm-up (medians are in the JSON too).\n"
            "  --scene FILE       glTF 2.0 scene (.gltf or .glb)\n"
            "  --frames N         timed frames per mode (default 30)\n"
            "  --warmup N         untimed frames first (default 3)\n"
            "  --mode M           foveated, full or both (default both)\n"
            "  --json FILE        write the results as JSON\n"
            "  --yaw-rate DEG_S   turn the head about the vertical axis at this rate (degrees per\n"
            "                     second at 90 Hz; default 0: a static head, as in Weier's table)\n"
            "  --trace-out FILE   write a Chrome trace-event JSON of every frame (Perfetto,\n"
            "                     chrome://tracing): worker, stage and ray-tile tracks\n"
            "  --counters on|off  hardware counters per stage through perf_event_open (default on;\n"
            "                     reported as unavailable where the kernel or VM has none)\n"
            "  --sweep P=VALUES   repeatable; runs every value of P after the base run, all in the\n"
            "                     JSON: threads=1..N or threads=1,2; size=WxH,WxH; pmin=P,P;\n"
            "                     r0=DEG,DEG; r1=DEG,DEG\n"
            "  --kernels          time every hand-vectorised kernel against its C reference and\n"
            "                     each ISA this CPU runs at production sizes, print speed-ups\n"
            "                     (median of --kernel-reps runs, default 7; no scene; the same as\n"
            "                     build/tests/checkasm/checkasm --bench)\n"
            "  --kernel NAME      with --kernels: only that kernel\n"
            "  --calls N          with --kernel: no timing; set NAME up and call it N times with the\n"
            "                     kernels of --isa (instruction counts under qemu:\n"
            "                     tools/kernel_icount.py)\n"
            FV_COMMON_HELP "  --help             this text\n");
}

typedef struct {
    const char *mode;
    long samples;
    double stage_mean[FV_STAGE_COUNT], total_mean, total_median, mrays;
    int counters;                          /* hardware counters were read */
    char counters_why[160];                /* else why not */
    double ctr[FV_PROF_STAGES][FV_PERF_N]; /* per frame, per profiled stage */
} run_result;

/* Options of one bench run beyond the pipeline's config. */
typedef struct {
    float yaw_rate;
    int warmup, frames, counters;
    fv_prof *prof; /* trace recorder or NULL */
} bench_opts;

/* Counter hook: at each stage boundary the totals are read; deltas accumulate per stage. */
typedef struct {
    fv_perfctr *pc;
    uint64_t start[FV_PROF_STAGES][FV_PERF_N];
    double sum[FV_PROF_STAGES][FV_PERF_N];
    int on; /* accumulate (after warm-up) */
    int failed;
} ctr_state;

static void ctr_hook(void *ctx, int stage, int end)
{
    ctr_state *c = ctx;
    uint64_t v[FV_PERF_N];
    if (c->failed || stage < 0 || stage >= FV_PROF_STAGES)
        return;
    if (fv_perfctr_read(c->pc, v)) {
        c->failed = 1;
        return;
    }
    for (int k = 0; k < FV_PERF_N; k++)
        if (!end)
            c->start[stage][k] = v[k];
        else if (c->on)
            c->sum[stage][k] += (double)(v[k] - c->start[stage][k]);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The head pose of frame f: the view turned by yaw_rate * f / 90 Hz about its vertical axis. */
static fv_pose head_at(const fv_pose *view, float yaw_rate_dps, int f)
{
    const float a = yaw_rate_dps * (float)f / 90.0f * 3.14159265f / 180.0f;
    const float q[4] = {0.0f, sinf(0.5f * a), 0.0f, cosf(0.5f * a)};
    fv_pose p = *view;
    fv_quat_mul(view->quat, q, p.quat); /* about the head's own up axis */
    return p;
}

static int bench_mode(const fv_scene *scene, fv_pipeline_config cfg, int full, const fv_pose *view,
                      const bench_opts *bo, run_result *r, char *err, size_t err_len)
{
    const int warmup = bo->warmup, frames = bo->frames;
    cfg.samp.full = full;
    fv_pipeline *pl = fv_pipeline_create(scene, &cfg, err, err_len);
    if (!pl)
        return -1;
    double *tot = calloc((size_t)frames, sizeof *tot);
    if (!tot) {
        fv_pipeline_destroy(pl);
        snprintf(err, err_len, "out of memory");
        return -1;
    }
    memset(r, 0, sizeof *r);
    r->mode = full ? "full" : "foveated";
    /* counters: opened after the pool started, so every worker thread is counted */
    ctr_state cs;
    memset(&cs, 0, sizeof cs);
    fv_prof *hook_prof = NULL;
    if (bo->counters) {
        cs.pc = fv_perfctr_open(r->counters_why, sizeof r->counters_why);
        /* the stage hook rides on a recorder: the trace's own, or a one-slot one just for it */
        if (cs.pc)
            hook_prof = bo->prof ? bo->prof : fv_prof_create(1, 1);
        if (cs.pc && !hook_prof) {
            snprintf(r->counters_why, sizeof r->counters_why, "out of memory");
            fv_perfctr_close(cs.pc);
            cs.pc = NULL;
        }
    } else {
        snprintf(r->counters_why, sizeof r->counters_why, "switched off (--counters off)");
    }
    if (hook_prof)
        fv_prof_set_stage_hook(hook_prof, ctr_hook, &cs);
    fv_pipeline_set_prof(pl, hook_prof ? hook_prof : bo->prof);
    fv_frame_stats st;
    for (int f = 0; f < warmup + frames; f++) {
        const fv_pose head = head_at(view, bo->yaw_rate, f);
        cs.on = f >= warmup;
        fv_pipeline_render(pl, FV_EYE_CENTER, &head, 0.5f, 0.5f, &st);
        if (f < warmup)
            continue;
        for (int s = 0; s < FV_STAGE_COUNT; s++)
            r->stage_mean[s] += st.stage_ms[s] / frames; /* NAN stays NAN: stage not built */
        r->total_mean += st.total_ms / frames;
        tot[f - warmup] = st.total_ms;
        r->samples = st.samples;
    }
    fv_pipeline_set_prof(pl, NULL);
    if (hook_prof)
        fv_prof_set_stage_hook(hook_prof, NULL, NULL);
    if (hook_prof && hook_prof != bo->prof)
        fv_prof_destroy(hook_prof);
    if (cs.pc) {
        if (cs.failed) {
            snprintf(r->counters_why, sizeof r->counters_why, "a counter read failed");
        } else {
            r->counters = 1;
            for (int s = 0; s < FV_PROF_STAGES; s++)
                for (int k = 0; k < FV_PERF_N; k++)
                    r->ctr[s][k] = cs.sum[s][k] / frames;
        }
        fv_perfctr_close(cs.pc);
    }
    qsort(tot, (size_t)frames, sizeof *tot, cmp_double);
    r->total_median = frames & 1 ? tot[frames / 2] : 0.5 * (tot[frames / 2 - 1] + tot[frames / 2]);
    r->mrays = r->samples / (r->stage_mean[FV_STAGE_TRACE] * 1e3);
    free(tot);
    fv_pipeline_destroy(pl);
    return 0;
}

static void cell(double v, int width, int prec)
{
    if (isnan(v))
        printf("%*s", width, "-");
    else
        printf("%*.*f", width, prec, v);
}

static void json_num(FILE *f, double v)
{
    if (isnan(v))
        fputs("null", f);
    else
        fprintf(f, "%.4f", v);
}

/* ---- machine: copy bandwidth (memcpy of 64 MiB, best of 5), 1 thread and the pool's ---- */
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
/* GB/s of read + written bytes (2 x 64 MiB per copy); 0 when out of memory */
static double copy_gbps(int threads)
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

static void load_avg(double la[3])
{
    if (getloadavg(la, 3) != 3)
        la[0] = la[1] = la[2] = NAN;
}

/* ---- sweeps ---- */
enum { SW_THREADS, SW_SIZE, SW_PMIN, SW_R0, SW_R1 };
static const char *const sweep_names[] = {"threads", "size", "pmin", "r0", "r1"};
#define MAX_POINTS 32
typedef struct {
    int param, n;
    char label[MAX_POINTS][24];
    int iv[MAX_POINTS], w[MAX_POINTS], h[MAX_POINTS];
    float fv[MAX_POINTS];
    run_result res[MAX_POINTS][2];
    int nres[MAX_POINTS];
} sweep;

static void parse_sweep(const char *spec, sweep *sw)
{
    const char *eq = strchr(spec, '=');
    memset(sw, 0, sizeof *sw);
    sw->param = -1;
    for (int i = 0; i < 5 && eq; i++)
        if ((size_t)(eq - spec) == strlen(sweep_names[i]) && !strncmp(spec, sweep_names[i], (size_t)(eq - spec)))
            sw->param = i;
    if (sw->param < 0 || !eq[1])
        fv_usage_error(prog, "--sweep: '%s' is not P=VALUES with P one of threads, size, pmin, r0, r1", spec);
    const char *v = eq + 1;
    if (sw->param == SW_THREADS && strstr(v, "..")) {
        char a[32];
        const char *dots = strstr(v, "..");
        if ((size_t)(dots - v) >= sizeof a)
            fv_usage_error(prog, "--sweep: '%s' is not threads=A..B", spec);
        memcpy(a, v, (size_t)(dots - v));
        a[dots - v] = 0;
        const int lo = (int)fv_arg_long(prog, "--sweep threads", a, 1, 256);
        const int hi = (int)fv_arg_long(prog, "--sweep threads", dots + 2, lo, lo + MAX_POINTS - 1);
        for (int t = lo; t <= hi; t++) {
            sw->iv[sw->n] = t;
            snprintf(sw->label[sw->n], sizeof sw->label[0], "%d", t);
            sw->n++;
        }
        return;
    }
    char buf[512];
    if (strlen(v) >= sizeof buf)
        fv_usage_error(prog, "--sweep: '%s' is too long", spec);
    strcpy(buf, v);
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        if (sw->n == MAX_POINTS)
            fv_usage_error(prog, "--sweep: more than %d values", MAX_POINTS);
        const int i = sw->n;
        switch (sw->param) {
        case SW_THREADS: sw->iv[i] = (int)fv_arg_long(prog, "--sweep threads", tok, 1, 256); break;
        case SW_SIZE: fv_arg_size(prog, "--sweep size", tok, &sw->w[i], &sw->h[i]); break;
        case SW_PMIN: sw->fv[i] = fv_arg_float(prog, "--sweep pmin", tok, 1e-3f, 1.0f); break;
        default: sw->fv[i] = fv_arg_float(prog, sw->param == SW_R0 ? "--sweep r0" : "--sweep r1", tok, 0.1f, 90.0f);
        }
        snprintf(sw->label[i], sizeof sw->label[0], "%s", tok);
        sw->n++;
    }
    if (sw->n == 0)
        fv_usage_error(prog, "--sweep: '%s' has no values", spec);
}

static fv_pipeline_config sweep_cfg(const sweep *sw, int i, fv_pipeline_config c)
{
    switch (sw->param) {
    case SW_THREADS: c.threads = sw->iv[i]; break;
    case SW_SIZE: c.cam.width = sw->w[i], c.cam.height = sw->h[i]; break;
    case SW_PMIN: c.samp.p_min = sw->fv[i]; break;
    case SW_R0: c.samp.r0_deg = sw->fv[i]; break;
    default: c.samp.r1_deg = sw->fv[i];
    }
    return c;
}

/* ---- output ---- */
static const int roof_stages[] = {FV_STAGE_REPROJECT, FV_STAGE_RECONSTRUCT, FV_STAGE_COC, FV_STAGE_DOF_FILTER,
                                  FV_STAGE_COMBINE};
#define NROOF 5

static void print_table(const run_result *res, int nres, int frames)
{
    printf("\n%-10s %11s %13s %15s %8s %8s %8s %9s %10s %9s\n", "Mode", "Ray Tracing", "Reprojection",
           "Reconstruction", "CoC", "Filter", "Combine", "Total", "# Samples", "Mrays/s");
    printf("%-10s %11s %13s %15s %8s %8s %8s %9s %10s %9s\n", "", "", "(TAA)", "(PPI)", "", "", "", "", "", "");
    for (int i = 0; i < nres; i++) {
        const run_result *r = &res[i];
        printf("%-10s", r->mode);
        cell(r->stage_mean[FV_STAGE_TRACE], 12, 2);
        cell(r->stage_mean[FV_STAGE_REPROJECT], 14, 2);
        cell(r->stage_mean[FV_STAGE_RECONSTRUCT], 16, 3);
        cell(r->stage_mean[FV_STAGE_COC], 9, 2);
        cell(r->stage_mean[FV_STAGE_DOF_FILTER], 9, 2);
        cell(r->stage_mean[FV_STAGE_COMBINE], 9, 2);
        cell(r->total_mean, 10, 2);
        printf(" %10ld", r->samples);
        cell(r->mrays, 10, 1);
        printf("\n");
    }
    printf("(ms per frame, means over %d frames; one eye)\n", frames);
}

/* the fraction of pixels pull-push fills: those without a ray this frame */
static double holes_of(const run_result *r, int w, int h)
{
    const double f = 1.0 - (double)r->samples / ((double)w * (double)h);
    return f > 0.0 ? f : 0.0;
}

static void print_roofline(const run_result *res, int nres, int w, int h, double gbps)
{
    printf("roofline (compulsory bytes per frame / stage time, against the measured copy bandwidth %.2f GB/s):\n",
           gbps);
    for (int i = 0; i < nres; i++) {
        printf("  %-9s", res[i].mode);
        for (int k = 0; k < NROOF; k++) {
            const int s = roof_stages[k];
            double rd, wr;
            const double ms = res[i].stage_mean[s];
            if (fv_prof_stage_bytes(s, w, h, holes_of(&res[i], w, h), &rd, &wr) || isnan(ms) || ms <= 0.0 ||
                rd + wr <= 0.0) {
                printf(" %s -", fv_stage_names[s]);
                continue;
            }
            const double g = (rd + wr) / (ms * 1e6);
            printf(" %s %.2f GB/s (%.0f%%)", fv_stage_names[s], g, gbps > 0.0 ? 100.0 * g / gbps : NAN);
        }
        printf("\n");
    }
}

static void print_counters(const run_result *r)
{
    if (!r->counters) {
        printf("counters (%s): unavailable: %s\n", r->mode, r->counters_why);
        return;
    }
    printf("counters (%s, per frame, all threads):\n", r->mode);
    for (int s = 0; s < FV_PROF_STAGES; s++) {
        printf("  %-12s", fv_prof_stage_names[s]);
        for (int k = 0; k < FV_PERF_N; k++)
            printf(" %s %.4g", fv_perf_names[k], r->ctr[s][k]);
        printf("\n");
    }
}

static void json_run(FILE *f, const run_result *r, int w, int h, double gbps)
{
    fprintf(f, "{\"mode\": \"%s\", \"samples_per_frame\": %ld, \"total_ms\": ", r->mode, r->samples);
    json_num(f, r->total_mean);
    fprintf(f, ", \"total_ms_median\": ");
    json_num(f, r->total_median);
    fprintf(f, ",\n   \"stages_ms\": {");
    for (int s = 0; s < FV_STAGE_COUNT; s++) {
        fprintf(f, "%s\"%s\": ", s ? ", " : "", fv_stage_names[s]);
        json_num(f, r->stage_mean[s]);
    }
    fprintf(f, "},\n   \"mrays_per_s\": ");
    json_num(f, r->mrays);
    fprintf(f, ",\n   \"roofline\": {");
    for (int k = 0; k < NROOF; k++) {
        const int s = roof_stages[k];
        double rd = 0.0, wr = 0.0;
        const double ms = r->stage_mean[s];
        fprintf(f, "%s\"%s\": ", k ? ", " : "", fv_stage_names[s]);
        if (fv_prof_stage_bytes(s, w, h, holes_of(r, w, h), &rd, &wr) || isnan(ms) || ms <= 0.0 ||
            rd + wr <= 0.0) {
            fputs("null", f);
            continue;
        }
        const double g = (rd + wr) / (ms * 1e6);
        fprintf(f, "{\"read_bytes\": %.0f, \"written_bytes\": %.0f, \"gbps\": %.4f, \"fraction\": ", rd, wr, g);
        json_num(f, gbps > 0.0 ? g / gbps : NAN);
        fputc('}', f);
    }
    fprintf(f, "},\n   \"counters\": {\"available\": %s", r->counters ? "true" : "false");
    if (!r->counters) {
        fprintf(f, ", \"reason\": \"");
        for (const char *c = r->counters_why; *c; c++)
            if (*c == '"' || *c == '\\')
                fprintf(f, "\\%c", *c);
            else if ((unsigned char)*c >= 0x20)
                fputc(*c, f);
        fputc('"', f);
    } else {
        fprintf(f, ", \"per_frame\": {");
        for (int s = 0; s < FV_PROF_STAGES; s++) {
            fprintf(f, "%s\"%s\": {", s ? ", " : "", fv_prof_stage_names[s]);
            for (int k = 0; k < FV_PERF_N; k++)
                fprintf(f, "%s\"%s\": %.0f", k ? ", " : "", fv_perf_names[k], r->ctr[s][k]);
            fputc('}', f);
        }
        fputc('}', f);
    }
    fprintf(f, "}}");
}

int main(int argc, char **argv)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    const char *scene_path = NULL, *json_path = NULL, *mode = "both", *trace_path = NULL, *kernel = NULL;
    bench_opts bo = {.yaw_rate = 0.0f, .warmup = 3, .frames = 30, .counters = 1, .prof = NULL};
    int kernels = 0, kreps = 7;
    long calls = 0;
    static sweep sweeps[4];
    int nsweeps = 0;
    enum { OPT_SCENE = 1, OPT_FRAMES, OPT_WARMUP, OPT_MODE, OPT_JSON, OPT_YAW, OPT_HELP, OPT_TRACE_OUT, OPT_COUNTERS,
           OPT_SWEEP, OPT_KERNELS, OPT_KREPS, OPT_KERNEL, OPT_CALLS };
    static const struct option opts[] = {
        {"scene", required_argument, 0, OPT_SCENE}, {"frames", required_argument, 0, OPT_FRAMES},
        {"warmup", required_argument, 0, OPT_WARMUP}, {"mode", required_argument, 0, OPT_MODE},
        {"json", required_argument, 0, OPT_JSON}, {"yaw-rate", required_argument, 0, OPT_YAW},
        {"trace-out", required_argument, 0, OPT_TRACE_OUT}, {"counters", required_argument, 0, OPT_COUNTERS},
        {"sweep", required_argument, 0, OPT_SWEEP}, {"kernels", no_argument, 0, OPT_KERNELS},
        {"kernel-reps", required_argument, 0, OPT_KREPS}, {"kernel", required_argument, 0, OPT_KERNEL},
        {"calls", required_argument, 0, OPT_CALLS},
        {"help", no_argument, 0, OPT_HELP}, FV_COMMON_LONGOPTS,
        {0, 0, 0, 0}};
    opterr = 0;
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case OPT_SCENE: scene_path = optarg; break;
        case OPT_FRAMES: bo.frames = (int)fv_arg_long(prog, "--frames", optarg, 1, 100000); break;
        case OPT_WARMUP: bo.warmup = (int)fv_arg_long(prog, "--warmup", optarg, 0, 100000); break;
        case OPT_MODE:
            if (strcmp(optarg, "foveated") && strcmp(optarg, "full") && strcmp(optarg, "both"))
                fv_usage_error(prog, "--mode: '%s' is not one of foveated, full, both", optarg);
            mode = optarg;
            break;
        case OPT_JSON: json_path = optarg; break;
        case OPT_YAW: bo.yaw_rate = fv_arg_float(prog, "--yaw-rate", optarg, -720.0f, 720.0f); break;
        case OPT_TRACE_OUT: trace_path = optarg; break;
        case OPT_COUNTERS: bo.counters = fv_arg_onoff(prog, "--counters", optarg); break;
        case OPT_SWEEP:
            if (nsweeps == 4)
                fv_usage_error(prog, "--sweep: at most 4 sweeps");
            parse_sweep(optarg, &sweeps[nsweeps++]);
            break;
        case OPT_KERNELS: kernels = 1; break;
        case OPT_KREPS: kreps = (int)fv_arg_long(prog, "--kernel-reps", optarg, 1, 64); break;
        case OPT_KERNEL: kernel = optarg; break;
        case OPT_CALLS: calls = fv_arg_long(prog, "--calls", optarg, 0, 100000000); break;
        case OPT_HELP: usage(stdout); return FV_EXIT_OK;
        case '?': fv_bad_option(prog, argv);
        default:
            if (!fv_common_option(prog, o, optarg, &cfg))
                fv_usage_error(prog, "unhandled option (see --help)");
        }
    }
    if (kernels) {
        if (optind < argc)
            fv_usage_error(prog, "unexpected argument '%s' (see --help)", argv[optind]);
        if (calls > 0 && !kernel)
            fv_usage_error(prog, "--calls N needs --kernel NAME");
        return checkasm_bench_run(prog, json_path, kreps, kernel, calls, cfg.isa_mask);
    }
    if (kernel || calls)
        fv_usage_error(prog, "--kernel and --calls need --kernels");
    fv_common_validate(prog, argc, argv, scene_path, &cfg);
    for (int i = 0; i < nsweeps; i++)
        for (int k = 0; k < sweeps[i].n; k++) {
            const fv_pipeline_config c = sweep_cfg(&sweeps[i], k, cfg);
            if (c.samp.r0_deg > c.samp.r1_deg)
                fv_usage_error(prog, "--sweep %s: r0 %g must not exceed r1 %g", sweep_names[sweeps[i].param],
                               (double)c.samp.r0_deg, (double)c.samp.r1_deg);
        }

    char err[512];
    int64_t t0 = fv_time_ns();
    fv_scene *scene = fv_scene_load(scene_path, err, sizeof err);
    if (!scene)
        fv_usage_error(prog, "%s", err);
    double load_ms = (double)(fv_time_ns() - t0) * 1e-6;
    int W = cfg.cam.width, H = cfg.cam.height;
    fv_pose view;
    fv_scene_default_view(scene, cfg.cam.fov_y_deg, (float)W / (float)H, view.pos, view.quat);
    int threads = cfg.threads > 0 ? cfg.threads : fv_online_cpus();
    int max_threads = threads;
    for (int i = 0; i < nsweeps; i++)
        for (int k = 0; k < sweeps[i].n; k++)
            if (sweeps[i].param == SW_THREADS && sweeps[i].iv[k] > max_threads)
                max_threads = sweeps[i].iv[k];
    if (trace_path && !(bo.prof = fv_prof_create(max_threads, (size_t)1 << 18))) {
        fv_scene_free(scene);
        fv_fail(prog, FV_EXIT_FAIL, "out of memory for the trace recorder");
    }
    fv_render_dsp dsp;
    fv_render_dsp_init(&dsp, cfg.isa_mask);
    double la[3];
    load_avg(la);
    const double gbps1 = copy_gbps(1), gbps = threads > 1 ? copy_gbps(threads) : gbps1;
    printf("%s: %s, %zu triangles (loaded in %.0f ms), %dx%d, %d thread%s, kernels %s, %d+%d frames, head %s, "
           "dof %s%s%s\n",
           prog, scene_path, fv_scene_triangle_count(scene), load_ms, W, H, threads, threads == 1 ? "" : "s",
           fv_isa_name(dsp.isa), bo.warmup, bo.frames, bo.yaw_rate != 0.0f ? "turning" : "static",
           fv_dof_presets[cfg.dof.preset].name, cfg.dof.preset ? " " : "",
           cfg.dof.preset ? fv_dof_model_names[cfg.dof.model] : "");
    printf("%s: copy bandwidth %.2f GB/s (1 thread), %.2f GB/s (%d threads); load average %.2f %.2f %.2f\n", prog,
           gbps1, gbps, threads, la[0], la[1], la[2]);
    if (bo.yaw_rate != 0.0f)
        printf("%s: head turning at %g deg/s (%.3f deg per 90 Hz frame)\n", prog, (double)bo.yaw_rate,
               (double)bo.yaw_rate / 90.0);

    run_result res[2];
    int nres = 0;
    for (int full = 0; full < 2; full++) {
        if ((full && !strcmp(mode, "foveated")) || (!full && !strcmp(mode, "full")))
            continue;
        if (bench_mode(scene, cfg, full, &view, &bo, &res[nres], err, sizeof err)) {
            fv_scene_free(scene);
            fv_fail(prog, FV_EXIT_FAIL, "%s", err);
        }
        nres++;
    }
    print_table(res, nres, bo.frames);
    if (nres == 2)
        printf("samples foveated/full = %.3f   total foveated/full = %.3f\n", (double)res[0].samples / res[1].samples,
               res[0].total_mean / res[1].total_mean);
    print_roofline(res, nres, W, H, gbps);
    print_counters(&res[0]);

    for (int i = 0; i < nsweeps; i++) {
        sweep *sw = &sweeps[i];
        for (int k = 0; k < sw->n; k++) {
            const fv_pipeline_config c = sweep_cfg(sw, k, cfg);
            sw->nres[k] = 0;
            for (int full = 0; full < 2; full++) {
                if ((full && !strcmp(mode, "foveated")) || (!full && !strcmp(mode, "full")))
                    continue;
                if (bench_mode(scene, c, full, &view, &bo, &sw->res[k][sw->nres[k]], err, sizeof err)) {
                    fv_scene_free(scene);
                    fv_fail(prog, FV_EXIT_FAIL, "--sweep %s=%s: %s", sweep_names[sw->param], sw->label[k], err);
                }
                sw->nres[k]++;
            }
            printf("\nsweep %s = %s", sweep_names[sw->param], sw->label[k]);
            print_table(sw->res[k], sw->nres[k], bo.frames);
        }
        if (sw->param == SW_THREADS && sw->n > 1) { /* scaling efficiency t(first) n0 / (t(n) n) */
            printf("\nscaling efficiency against %d thread%s (per stage, first mode):\n", sw->iv[0],
                   sw->iv[0] == 1 ? "" : "s");
            for (int k = 0; k < sw->n; k++) {
                printf("  threads %-3d", sw->iv[k]);
                for (int s = 0; s < FV_STAGE_COUNT; s++) {
                    const double a = sw->res[0][0].stage_mean[s], b = sw->res[k][0].stage_mean[s];
                    if (!isnan(a) && !isnan(b) && b > 0.0)
                        printf(" %s %.2f", fv_stage_names[s], a * sw->iv[0] / (b * sw->iv[k]));
                }
                printf(" total %.2f\n",
                       sw->res[0][0].total_mean * sw->iv[0] / (sw->res[k][0].total_mean * sw->iv[k]));
            }
        }
    }

    int status = FV_EXIT_OK;
    if (json_path) {
        fv_afile a;
        if (fv_afile_open(&a, json_path, err, sizeof err)) {
            fv_scene_free(scene);
            fv_fail(prog, FV_EXIT_FAIL, "%s", err);
        }
        FILE *f = a.f;
        fprintf(f, "{\"scene\": \"");
        for (const char *c = scene_path; *c; c++) /* JSON string escape */
            if (*c == '"' || *c == '\\')
                fprintf(f, "\\%c", *c);
            else if ((unsigned char)*c < 0x20)
                fprintf(f, "\\u%04x", *c);
            else
                fputc(*c, f);
        fprintf(f, "\", \"width\": %d, \"height\": %d, \"threads\": %d, \"frames\": %d, \"warmup\": %d, "
                   "\"isa\": \"%s\", \"triangles\": %zu, \"load_ms\": %.1f, \"yaw_rate_dps\": %g, "
                   "\"dof\": \"%s\", \"dof_model\": \"%s\",\n \"machine\": {\"cpus\": %d, \"copy_gbps_1t\": %.3f, "
                   "\"copy_gbps\": %.3f, \"load_avg\": [%.2f, %.2f, %.2f]},\n \"runs\": [",
                W, H, threads, bo.frames, bo.warmup, fv_isa_name(dsp.isa), fv_scene_triangle_count(scene), load_ms,
                (double)bo.yaw_rate, fv_dof_presets[cfg.dof.preset].name, fv_dof_model_names[cfg.dof.model],
                fv_online_cpus(), gbps1, gbps, la[0], la[1], la[2]);
        for (int i = 0; i < nres; i++) {
            fprintf(f, "%s\n  ", i ? "," : "");
            json_run(f, &res[i], W, H, gbps);
        }
        fprintf(f, "],\n \"sweeps\": [");
        for (int i = 0; i < nsweeps; i++) {
            const sweep *sw = &sweeps[i];
            fprintf(f, "%s\n  {\"param\": \"%s\", \"points\": [", i ? "," : "", sweep_names[sw->param]);
            for (int k = 0; k < sw->n; k++) {
                const fv_pipeline_config c = sweep_cfg(sw, k, cfg);
                fprintf(f, "%s\n   {\"value\": \"%s\", \"width\": %d, \"height\": %d, \"threads\": %d, \"pmin\": %g, "
                           "\"r0\": %g, \"r1\": %g, \"runs\": [",
                        k ? "," : "", sw->label[k], c.cam.width, c.cam.height,
                        c.threads > 0 ? c.threads : fv_online_cpus(), (double)c.samp.p_min, (double)c.samp.r0_deg,
                        (double)c.samp.r1_deg);
                for (int j = 0; j < sw->nres[k]; j++) {
                    fprintf(f, "%s\n    ", j ? "," : "");
                    json_run(f, &sw->res[k][j], c.cam.width, c.cam.height, gbps);
                }
                fprintf(f, "]}");
            }
            fprintf(f, "]}");
        }
        fprintf(f, "]}\n");
        if (fv_afile_commit(&a, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", prog, err);
            status = FV_EXIT_FAIL;
        }
    }
    if (bo.prof) {
        char label[600];
        snprintf(label, sizeof label, "fovea-bench %s", scene_path);
        if (fv_prof_write_json(bo.prof, trace_path, label, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", prog, err);
            status = FV_EXIT_FAIL;
        }
        fv_prof_destroy(bo.prof);
    }
    fv_scene_free(scene);
    return status;
}
