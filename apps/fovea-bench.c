/* fovea-bench: per-stage timings of the frame pipeline in the layout of Weier et al. 2018,
 * Table 1 (one eye, static head and gaze), printed and written as JSON. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "output.h"
#include "pipeline.h"
#include "scene.h"

static const char *prog = "fovea-bench";

static void usage(FILE *f)
{
    fprintf(f,
            "usage: fovea-bench --scene FILE [--frames N] [--mode foveated|full|both] [--json FILE] [options]\n"
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
            FV_COMMON_HELP "  --help             this text\n");
}

typedef struct {
    const char *mode;
    long samples;
    double stage_mean[FV_STAGE_COUNT], total_mean, total_median, mrays;
} run_result;

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

static int bench_mode(const fv_scene *scene, fv_pipeline_config cfg, int full, const fv_pose *view, float yaw_rate,
                      int warmup, int frames, run_result *r, char *err, size_t err_len)
{
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
    fv_frame_stats st;
    for (int f = 0; f < warmup + frames; f++) {
        const fv_pose head = head_at(view, yaw_rate, f);
        fv_pipeline_render(pl, FV_EYE_CENTER, &head, 0.5f, 0.5f, &st);
        if (f < warmup)
            continue;
        for (int s = 0; s < FV_STAGE_COUNT; s++)
            r->stage_mean[s] += st.stage_ms[s] / frames; /* NAN stays NAN: stage not built */
        r->total_mean += st.total_ms / frames;
        tot[f - warmup] = st.total_ms;
        r->samples = st.samples;
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

int main(int argc, char **argv)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    const char *scene_path = NULL, *json_path = NULL, *mode = "both";
    int frames = 30, warmup = 3;
    float yaw_rate = 0.0f;
    enum { OPT_SCENE = 1, OPT_FRAMES, OPT_WARMUP, OPT_MODE, OPT_JSON, OPT_YAW, OPT_HELP };
    static const struct option opts[] = {
        {"scene", required_argument, 0, OPT_SCENE}, {"frames", required_argument, 0, OPT_FRAMES},
        {"warmup", required_argument, 0, OPT_WARMUP}, {"mode", required_argument, 0, OPT_MODE},
        {"json", required_argument, 0, OPT_JSON}, {"yaw-rate", required_argument, 0, OPT_YAW},
        {"help", no_argument, 0, OPT_HELP}, FV_COMMON_LONGOPTS,
        {0, 0, 0, 0}};
    opterr = 0;
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case OPT_SCENE: scene_path = optarg; break;
        case OPT_FRAMES: frames = (int)fv_arg_long(prog, "--frames", optarg, 1, 100000); break;
        case OPT_WARMUP: warmup = (int)fv_arg_long(prog, "--warmup", optarg, 0, 100000); break;
        case OPT_MODE:
            if (strcmp(optarg, "foveated") && strcmp(optarg, "full") && strcmp(optarg, "both"))
                fv_usage_error(prog, "--mode: '%s' is not one of foveated, full, both", optarg);
            mode = optarg;
            break;
        case OPT_JSON: json_path = optarg; break;
        case OPT_YAW: yaw_rate = fv_arg_float(prog, "--yaw-rate", optarg, -720.0f, 720.0f); break;
        case OPT_HELP: usage(stdout); return FV_EXIT_OK;
        case '?': fv_bad_option(prog, argv);
        default:
            if (!fv_common_option(prog, o, optarg, &cfg))
                fv_usage_error(prog, "unhandled option (see --help)");
        }
    }
    fv_common_validate(prog, argc, argv, scene_path, &cfg);

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
    fv_dsp dsp;
    fv_dsp_init(&dsp, cfg.isa_mask);
    printf("%s: %s, %zu triangles (loaded in %.0f ms), %dx%d, %d thread%s, kernels %s, %d+%d frames, head %s, "
           "dof %s%s%s\n",
           prog, scene_path, fv_scene_triangle_count(scene), load_ms, W, H, threads, threads == 1 ? "" : "s",
           fv_isa_name(dsp.isa), warmup, frames, yaw_rate != 0.0f ? "turning" : "static",
           fv_dof_presets[cfg.dof.preset].name, cfg.dof.preset ? " " : "",
           cfg.dof.preset ? fv_dof_model_names[cfg.dof.model] : "");
    if (yaw_rate != 0.0f)
        printf("%s: head turning at %g deg/s (%.3f deg per 90 Hz frame)\n", prog, (double)yaw_rate,
               (double)yaw_rate / 90.0);

    run_result res[2];
    int nres = 0;
    for (int full = 0; full < 2; full++) {
        if ((full && !strcmp(mode, "foveated")) || (!full && !strcmp(mode, "full")))
            continue;
        if (bench_mode(scene, cfg, full, &view, yaw_rate, warmup, frames, &res[nres], err, sizeof err)) {
            fv_scene_free(scene);
            fv_fail(prog, FV_EXIT_FAIL, "%s", err);
        }
        nres++;
    }

    printf("\n%-10s %11s %13s %15s %8s %8s %8s %9s %10s %9s\n", "Mode", "Ray Tracing", "Reprojection",
           "Reconstruction", "CoC", "Filter", "Combine", "Total", "# Samples", "Mrays/s");
    printf("%-10s %11s %13s %15s %8s %8s %8s %9s %10s %9s\n", "", "", "(TAA)", "(PPI)", "", "", "", "", "", "");
    for (int i = 0; i < nres; i++) {
        run_result *r = &res[i];
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
    if (nres == 2)
        printf("samples foveated/full = %.3f   total foveated/full = %.3f\n", (double)res[0].samples / res[1].samples,
               res[0].total_mean / res[1].total_mean);

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
                   "\"dof\": \"%s\", \"dof_model\": \"%s\",\n \"runs\": [",
                W, H, threads, frames, warmup, fv_isa_name(dsp.isa), fv_scene_triangle_count(scene), load_ms,
                (double)yaw_rate, fv_dof_presets[cfg.dof.preset].name, fv_dof_model_names[cfg.dof.model]);
        for (int i = 0; i < nres; i++) {
            run_result *r = &res[i];
            fprintf(f, "%s\n  {\"mode\": \"%s\", \"samples_per_frame\": %ld, \"total_ms\": ", i ? "," : "", r->mode,
                    r->samples);
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
            fprintf(f, "}");
        }
        fprintf(f, "]}\n");
        if (fv_afile_commit(&a, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", prog, err);
            status = FV_EXIT_FAIL;
        }
    }
    fv_scene_free(scene);
    return status;
}
