/* fovea-bench: per-stage timings of the frame pipeline in the layout of Weier et al. 2018,
 * Table 1 (one eye, static head and gaze), printed and written as JSON. The runs and reports are
 * platform/benchio.c's, the bookkeeping core/bench.c's; this file parses and wires. */
#include <getopt.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "bench.h"
#include "benchio.h"
#include "cli.h"
#include "checkasm/bench.h" /* --kernels: tests/checkasm/bench.c */
#include "lens.h"
#include "output.h"
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
            FV_ASSET_ROOT_HELP FV_SHADOWS_HELP FV_LENS_HELP
            "  --frames N         timed frames per mode (default 30)\n"
            "  --warmup N         untimed frames first (default 3)\n"
            "  --mode M           foveated, full or both (default both)\n"
            "  --json FILE        write the results as JSON\n"
            "  --yaw-rate DEG_S   turn the head about the vertical axis at this rate (degrees per\n"
            "                     second at 90 Hz; default 0: a static head, as in Weier's table)\n"
            "  --trace-out FILE   write a Chrome trace-event JSON of every frame (Perfetto,\n"
            "                     chrome://tracing): worker, stage and ray-tile tracks\n"
            "  --ceiling          after every frame, trace the same rays with bare Embree\n"
            "                     (rtcIntersect16, no shading: core/ceiling.h) and report the\n"
            "                     ray stage's time against it per mode (ceiling_ms in the JSON)\n"
            "  --stereo           afterwards, time the stereo pair (foveated) one eye after the\n"
            "                     other and with fv_pipeline_render_stereo (the right eye's tiles\n"
            "                     beside the left eye's stages), alternately,\n"
            "                     --frames pairs of each (medians; with --ceiling against bare\n"
            "                     Embree on both eyes' rays)\n"
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
/* The modes --mode asks for (foveated first), each run with cfg into res; their count. On failure
 * frees the scene and exits 1 naming `what` (a sweep point). */
static int run_modes(fv_scene *scene, const fv_pipeline_config *cfg, const char *mode, const fv_pose *view,
                     const fv_bench_opts *bo, fv_bench_run res[2], const char *what)
{
    char err[512];
    int n = 0;
    for (int full = 0; full < 2; full++) {
        if ((full && !strcmp(mode, "foveated")) || (!full && !strcmp(mode, "full")))
            continue;
        if (fv_bench_run_mode(scene, *cfg, full, view, bo, &res[n], err, sizeof err)) {
            fv_scene_free(scene);
            fv_fail(prog, FV_EXIT_FAIL, "%s%s%s", what ? what : "", what ? ": " : "", err);
        }
        n++;
    }
    return n;
}

int main(int argc, char **argv)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    const char *asset_root = NULL; /* --asset-root */
    int shadows = 0;               /* --shadows */
    const char *lens_path = NULL;  /* --lens */
    const char *scene_path = NULL, *json_path = NULL, *mode = "both", *trace_path = NULL, *kernel = NULL;
    fv_bench_opts bo = {.yaw_rate = 0.0f, .warmup = 3, .frames = 30, .counters = 1, .prof = NULL};
    int kernels = 0, kreps = 7, stereo = 0;
    long calls = 0;
    static fv_sweep sweeps[FV_BENCH_MAX_SWEEPS];
    int nsweeps = 0;
    char err[512];
    enum { OPT_LENS = 500, OPT_SCENE = 1, OPT_FRAMES, OPT_WARMUP, OPT_MODE, OPT_JSON, OPT_YAW, OPT_HELP, OPT_TRACE_OUT, OPT_COUNTERS,
           OPT_SWEEP, OPT_KERNELS, OPT_KREPS, OPT_KERNEL, OPT_CALLS, OPT_CEILING, OPT_STEREO };
    static const struct option opts[] = {
        {"scene", required_argument, 0, OPT_SCENE}, FV_ASSET_ROOT_LONGOPT, FV_SHADOWS_LONGOPT, {"lens", required_argument, 0, OPT_LENS}, {"frames", required_argument, 0, OPT_FRAMES},
        {"warmup", required_argument, 0, OPT_WARMUP}, {"mode", required_argument, 0, OPT_MODE},
        {"json", required_argument, 0, OPT_JSON}, {"yaw-rate", required_argument, 0, OPT_YAW},
        {"trace-out", required_argument, 0, OPT_TRACE_OUT}, {"counters", required_argument, 0, OPT_COUNTERS},
        {"sweep", required_argument, 0, OPT_SWEEP}, {"kernels", no_argument, 0, OPT_KERNELS},
        {"kernel-reps", required_argument, 0, OPT_KREPS}, {"kernel", required_argument, 0, OPT_KERNEL},
        {"calls", required_argument, 0, OPT_CALLS}, {"ceiling", no_argument, 0, OPT_CEILING},
        {"stereo", no_argument, 0, OPT_STEREO}, {"help", no_argument, 0, OPT_HELP}, FV_COMMON_LONGOPTS,
        {0, 0, 0, 0}};
    opterr = 0;
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case OPT_SCENE: scene_path = optarg; break;
        case FV_OPT_ASSET_ROOT: asset_root = optarg; break;
        case FV_OPT_SHADOWS: shadows = fv_arg_onoff(prog, "--shadows", optarg); break;
        case OPT_LENS: lens_path = optarg; break;
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
            if (nsweeps == FV_BENCH_MAX_SWEEPS)
                fv_usage_error(prog, "--sweep: at most %d sweeps", FV_BENCH_MAX_SWEEPS);
            if (fv_sweep_parse(optarg, &sweeps[nsweeps++], err, sizeof err))
                fv_usage_error(prog, "%s", err);
            break;
        case OPT_KERNELS: kernels = 1; break;
        case OPT_CEILING: bo.ceiling = 1; break;
        case OPT_STEREO: stereo = 1; break;
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
    /* outputs first: an unwritable one is bad usage found now, not after the run */
    if ((json_path && fv_output_probe(json_path, err, sizeof err)) ||
        (trace_path && fv_output_probe(trace_path, err, sizeof err)))
        fv_usage_error(prog, "%s", err);
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
    fv_lens lens; /* --lens: outlives the pipeline (its cameras point at it) */
    if (lens_path)
        fv_cli_lens(prog, lens_path, &lens, &cfg);
    for (int i = 0; i < nsweeps; i++)
        if (fv_sweep_check(&sweeps[i], &cfg, err, sizeof err))
            fv_usage_error(prog, "%s", err);

    int64_t t0 = fv_time_ns();
    fv_scene *scene = fv_scene_load_in(scene_path, asset_root, err, sizeof err);
    if (!scene)
        fv_usage_error(prog, "%s", err);
    if (fv_scene_warning(scene)[0]) /* once, before any output */
        fprintf(stderr, "%s: %s: warning: %s\n", prog, scene_path, fv_scene_warning(scene));
    if (shadows && fv_scene_set_shadows(scene, 1))
        fprintf(stderr, "%s: %s: warning: more than 16 KHR lights, shadows off\n", prog, scene_path);
    fv_bench_report rep = {.scene_path = scene_path, .triangles = fv_scene_triangle_count(scene),
                           .load_ms = (double)(fv_time_ns() - t0) * 1e-6, .width = cfg.cam.width,
                           .height = cfg.cam.height, .warmup = bo.warmup, .frames = bo.frames,
                           .cpus = fv_online_cpus(), .yaw_rate = bo.yaw_rate, .cfg = &cfg, .sweeps = sweeps,
                           .nsweeps = nsweeps};
    rep.threads = cfg.threads > 0 ? cfg.threads : fv_online_cpus();
    fv_pose view;
    fv_scene_default_view(scene, cfg.cam.fov_y_deg, (float)rep.width / (float)rep.height, view.pos, view.quat);
    if (trace_path && !(bo.prof = fv_prof_create(fv_sweep_max_threads(sweeps, nsweeps, rep.threads), (size_t)1 << 18))) {
        fv_scene_free(scene);
        fv_fail(prog, FV_EXIT_FAIL, "out of memory for the trace recorder");
    }
    fv_render_dsp dsp;
    fv_render_dsp_init(&dsp, cfg.isa_mask);
    rep.isa = fv_isa_name(dsp.isa);
    fv_load_avg(rep.load_avg);
    rep.copy_gbps_1t = fv_bench_copy_gbps(1);
    rep.copy_gbps = rep.threads > 1 ? fv_bench_copy_gbps(rep.threads) : rep.copy_gbps_1t;
    fv_bench_print_setup(stdout, prog, &rep);

    fv_bench_run res[2];
    rep.runs = res;
    rep.nruns = run_modes(scene, &cfg, mode, &view, &bo, res, NULL);
    fv_bench_print_results(stdout, &rep);
    for (int i = 0; i < nsweeps; i++) {
        fv_sweep *sw = &sweeps[i];
        for (int k = 0; k < sw->n; k++) {
            const fv_pipeline_config c = fv_sweep_config(sw, k, &cfg);
            char what[64];
            snprintf(what, sizeof what, "--sweep %s=%s", fv_sweep_names[sw->param], sw->label[k]);
            sw->nres[k] = run_modes(scene, &c, mode, &view, &bo, sw->res[k], what);
            fv_bench_print_sweep_point(stdout, sw, k, bo.frames);
        }
        fv_bench_print_scaling(stdout, sw);
    }

    if (stereo) {
        fv_bench_stereo sr;
        if (fv_bench_stereo_run(scene, cfg, &view, bo.yaw_rate, bo.warmup, bo.frames, bo.ceiling, &sr, err, sizeof err)) {
            fv_scene_free(scene);
            fv_fail(prog, FV_EXIT_FAIL, "--stereo: %s", err);
        }
        printf("stereo pair (foveated, 2 x %dx%d, medians of %d pairs each, alternated): one eye after the other "
               "%.2f ms, fv_pipeline_render_stereo %.2f ms (%.3fx)",
               rep.width, rep.height, sr.pairs, sr.seq_ms, sr.joint_ms, sr.joint_ms / sr.seq_ms);
        if (bo.ceiling)
            printf("; ceiling (both eyes' rays) %.2f ms: %.2fx / %.2fx of it", sr.ceiling_ms, sr.seq_ms / sr.ceiling_ms,
                   sr.joint_ms / sr.ceiling_ms);
        printf("\n");
    }

    int status = FV_EXIT_OK;
    if (json_path) {
        fv_afile a;
        if (fv_afile_open(&a, json_path, err, sizeof err)) {
            fv_scene_free(scene);
            fv_fail(prog, FV_EXIT_FAIL, "%s", err);
        }
        fv_bench_write_json(a.f, &rep);
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
