/* The bench's timed runs and reports, the replay's stats.csv (platform/benchio.h). */
#define _DEFAULT_SOURCE /* getloadavg */
#include "benchio.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "base/err.h"
#include "ceiling.h"
#include "cpu.h"
#include "output.h"
#include "perfctr.h"
#include "pool.h"
#include "raycast.h"
#include "vsyncpred.h"

_Static_assert(FV_PERF_N <= FV_BENCH_MAX_CTRS, "fv_bench_run holds too few counters");

void fv_load_avg(double la[3])
{
    if (getloadavg(la, 3) != 3)
        la[0] = la[1] = la[2] = NAN;
}

static int read_perf(void *ctx, uint64_t *v) { return fv_perfctr_read(ctx, v); }

int fv_bench_run_mode(const fv_scene *scene, fv_pipeline_config cfg, int full, const fv_pose *view,
                      const fv_bench_opts *bo, fv_bench_run *r, char *err, size_t err_len)
{
    const int warmup = bo->warmup, frames = bo->frames;
    cfg.samp.full = full;
    cfg.time_shading = 1; /* the shading share of the ray stage (two clock reads a tile) */
    fv_pipeline *pl = fv_pipeline_create(scene, &cfg, err, err_len);
    if (!pl)
        return -1;
    fv_bench_acc acc;
    if (fv_bench_acc_init(&acc, r, full ? "full" : "foveated", frames)) {
        fv_bench_acc_finish(&acc);
        fv_pipeline_destroy(pl);
        return fv_err(err, err_len, "out of memory");
    }
    r->sampler = fv_sampler_names[cfg.samp.kind]; /* full mode: the pattern its foveated twin uses */
    /* counters: opened after the pool started, so every worker thread is counted */
    fv_perfctr *pc = NULL;
    fv_bench_ctrs cs;
    fv_prof *hook_prof = NULL;
    if (bo->counters) {
        pc = fv_perfctr_open(r->counters_why, sizeof r->counters_why);
        /* the stage hook rides on a recorder: the trace's own, or a one-slot one just for it */
        if (pc)
            hook_prof = bo->prof ? bo->prof : fv_prof_create(1, 1);
        if (pc && !hook_prof) {
            snprintf(r->counters_why, sizeof r->counters_why, "out of memory");
            fv_perfctr_close(pc);
            pc = NULL;
        }
    } else {
        snprintf(r->counters_why, sizeof r->counters_why, "switched off (--counters off)");
    }
    fv_bench_ctrs_init(&cs, read_perf, pc, FV_PERF_N);
    if (hook_prof)
        fv_prof_set_stage_hook(hook_prof, fv_bench_ctrs_hook, &cs);
    fv_pipeline_set_prof(pl, hook_prof ? hook_prof : bo->prof);
    int rc = 0;
    for (int f = 0; f < warmup + frames; f++) {
        const fv_pose head = fv_bench_head_at(view, bo->yaw_rate, f);
        fv_frame_stats st;
        cs.on = f >= warmup;
        if (fv_pipeline_render(pl, FV_EYE_CENTER, &head, 0.5f, 0.5f, &st)) {
            rc = fv_err(err, err_len, "%s frame %d: rendering failed", r->mode, f);
            break;
        }
        if (f >= warmup) {
            fv_bench_acc_add(&acc, &st);
            fv_bench_acc_add_shade(&acc, st.shade_ms); /* all threads' over their count */
        }
        if (bo->ceiling) {
            const fv_camera *cam = fv_pipeline_camera(pl, FV_EYE_CENTER);
            const fv_ceiling_opts co = {.smp = full ? NULL : fv_pipeline_sampler(pl),
                                        .gx = (int)floorf(0.5f * (float)cam->width),
                                        .gy = (int)floorf(0.5f * (float)cam->height),
                                        .phase = fv_pipeline_last_phase(pl, FV_EYE_CENTER),
                                        .rows = fv_pipeline_last_rows(pl, FV_EYE_CENTER)};
            const int64_t c0 = fv_time_ns();
            const long n = fv_ceiling_trace(scene, cam, fv_pipeline_pool(pl), &co, NULL);
            const double ms = (double)(fv_time_ns() - c0) * 1e-6;
            if (n != st.samples) { /* not the same rays: the ratio would mean nothing */
                rc = fv_err(err, err_len, "%s frame %d: the ceiling traced %ld rays, the frame %ld", r->mode, f, n,
                            st.samples);
                break;
            }
            if (f >= warmup)
                fv_bench_acc_add_ceiling(&acc, ms);
        }
    }
    fv_pipeline_set_prof(pl, NULL);
    if (hook_prof)
        fv_prof_set_stage_hook(hook_prof, NULL, NULL);
    if (hook_prof && hook_prof != bo->prof)
        fv_prof_destroy(hook_prof);
    if (pc) {
        if (cs.failed)
            snprintf(r->counters_why, sizeof r->counters_why, "a counter read failed");
        else
            fv_bench_ctrs_mean(&cs, frames, r);
        fv_perfctr_close(pc);
    }
    fv_bench_acc_finish(&acc);
    fv_pipeline_memory_bytes(pl, FV_EYE_CENTER, &r->mem);
    fv_pipeline_destroy(pl);
    return rc;
}

static void print_memory(FILE *f, const fv_bench_run *res, int nres)
{
    const double mb = 1.0 / (1024.0 * 1024.0);
    for (int i = 0; i < nres; i++) {
        const fv_pipeline_memory *m = &res[i].mem;
        fprintf(f, "memory (%s): per eye %.1f MiB (pyramids %.1f, final float image %.1f, display image %.1f, other "
                   "%.2f); DoF scratch for both eyes %.1f MiB\n",
                res[i].mode, (double)(m->pyramids + m->image + m->display + m->other) * mb, (double)m->pyramids * mb,
                (double)m->image * mb, (double)m->display * mb, (double)m->other * mb, (double)m->shared * mb);
    }
}

/* ---- printing ---- */
static void cell(FILE *f, double v, int width, int prec)
{
    if (isnan(v))
        fprintf(f, "%*s", width, "-");
    else
        fprintf(f, "%*.*f", width, prec, v);
}

static void json_num(FILE *f, double v)
{
    if (isnan(v))
        fputs("null", f);
    else
        fprintf(f, "%.4f", v);
}

/* s as the inside of a JSON string; `controls`: escape control characters as \u00XX (else drop them) */
static void json_str(FILE *f, const char *s, int controls)
{
    for (const char *c = s; *c; c++)
        if (*c == '"' || *c == '\\')
            fprintf(f, "\\%c", *c);
        else if ((unsigned char)*c >= 0x20)
            fputc(*c, f);
        else if (controls)
            fprintf(f, "\\u%04x", *c);
}

void fv_bench_print_setup(FILE *f, const char *prog, const fv_bench_report *rep)
{
    const fv_pipeline_config *cfg = rep->cfg;
    fprintf(f,
            "%s: %s, %zu triangles (loaded in %.0f ms), %dx%d, %d thread%s, kernels %s, %d+%d frames, head %s, "
            "dof %s%s%s\n",
            prog, rep->scene_path, rep->triangles, rep->load_ms, rep->width, rep->height, rep->threads,
            rep->threads == 1 ? "" : "s", rep->isa, rep->warmup, rep->frames,
            rep->yaw_rate != 0.0f ? "turning" : "static", fv_dof_presets[cfg->dof.preset].name,
            cfg->dof.preset ? " " : "", cfg->dof.preset ? fv_dof_models[cfg->dof.model].name : "");
    fprintf(f, "%s: copy bandwidth %.2f GB/s (1 thread), %.2f GB/s (%d threads); load average %.2f %.2f %.2f\n",
            prog, rep->copy_gbps_1t, rep->copy_gbps, rep->threads, rep->load_avg[0], rep->load_avg[1],
            rep->load_avg[2]);
    if (rep->yaw_rate != 0.0f)
        fprintf(f, "%s: head turning at %g deg/s (%.3f deg per 90 Hz frame)\n", prog, (double)rep->yaw_rate,
                (double)rep->yaw_rate / 90.0);
}

void fv_bench_print_table(FILE *f, const fv_bench_run *res, int nres, int frames)
{
    fprintf(f, "\n%-10s %11s %13s %15s %8s %8s %8s %8s %9s %10s %9s\n", "Mode", "Ray Tracing", "Reprojection",
            "Reconstruction", "CoC", "Filter", "Combine", "Output", "Total", "# Samples", "Mrays/s");
    fprintf(f, "%-10s %11s %13s %15s %8s %8s %8s %8s %9s %10s %9s\n", "", "", "(TAA)", "(PPI)", "", "", "", "(sRGB)", "",
            "", "");
    for (int i = 0; i < nres; i++) {
        const fv_bench_run *r = &res[i];
        fprintf(f, "%-10s", r->mode);
        cell(f, r->stage_mean[FV_STAGE_TRACE], 12, 2);
        cell(f, r->stage_mean[FV_STAGE_REPROJECT], 14, 2);
        cell(f, r->stage_mean[FV_STAGE_RECONSTRUCT], 16, 3);
        cell(f, r->stage_mean[FV_STAGE_COC], 9, 2);
        cell(f, r->stage_mean[FV_STAGE_DOF_FILTER], 9, 2);
        cell(f, r->stage_mean[FV_STAGE_COMBINE], 9, 2);
        cell(f, r->stage_mean[FV_STAGE_OUTPUT], 9, 2);
        cell(f, r->total_mean, 10, 2);
        fprintf(f, " %10ld", r->samples);
        cell(f, r->mrays, 10, 1);
        fprintf(f, "\n");
    }
    fprintf(f, "(ms per frame, means over %d frames; one eye)\n", frames);
}

static void print_roofline(FILE *f, const fv_bench_run *res, int nres, int w, int h, double gbps)
{
    fprintf(f, "roofline (compulsory bytes per frame / stage time, against the measured copy bandwidth %.2f GB/s):\n",
            gbps);
    for (int i = 0; i < nres; i++) {
        fprintf(f, "  %-9s", res[i].mode);
        for (int k = 0; k < FV_BENCH_NROOF; k++) {
            const int s = fv_bench_roof_stages[k];
            fv_roof rf;
            if (fv_bench_roofline(&res[i], s, w, h, gbps, &rf)) {
                fprintf(f, " %s -", fv_stage_names[s]);
                continue;
            }
            fprintf(f, " %s %.2f GB/s (%.0f%%)", fv_stage_names[s], rf.gbps, 100.0 * rf.fraction);
        }
        fprintf(f, "\n");
    }
}

static void print_counters(FILE *f, const fv_bench_run *r)
{
    if (!r->counters) {
        fprintf(f, "counters (%s): unavailable: %s\n", r->mode, r->counters_why);
        return;
    }
    fprintf(f, "counters (%s, per frame, all threads):\n", r->mode);
    for (int s = 0; s < FV_PROF_STAGES; s++) {
        fprintf(f, "  %-12s", fv_prof_stage_name(s));
        for (int k = 0; k < FV_PERF_N; k++)
            fprintf(f, " %s %.4g", fv_perf_names[k], r->ctr[s][k]);
        fprintf(f, "\n");
    }
}

void fv_bench_print_ceiling(FILE *f, const fv_bench_run *res, int nres)
{
    int any = 0;
    for (int i = 0; i < nres; i++)
        any |= !isnan(res[i].ceiling_ms);
    if (!any)
        return;
    fprintf(f, "ray stage against bare Embree on the same rays (--ceiling, same run):\n");
    fprintf(f, "  %-9s %-8s %10s %9s %11s %14s %8s %16s\n", "mode", "sampler", "samples", "trace ms", "ceiling ms",
            "trace/ceiling", "Mrays/s", "ceiling Mrays/s");
    for (int i = 0; i < nres; i++) {
        const fv_bench_run *r = &res[i];
        fprintf(f, "  %-9s %-8s %10ld", r->mode, r->sampler, r->samples);
        cell(f, r->stage_mean[FV_STAGE_TRACE], 10, 2);
        cell(f, r->ceiling_ms, 12, 2);
        cell(f, fv_bench_ceiling_ratio(r), 15, 2);
        cell(f, r->mrays, 9, 1);
        cell(f, r->ceiling_mrays, 17, 1);
        fprintf(f, "\n");
    }
    if (nres == 2 && !strcmp(res[0].mode, "foveated") && !strcmp(res[1].mode, "full"))
        fprintf(f, "  a foveated ray costs %.2f full-frame bare-Embree rays\n", fv_bench_ray_cost(&res[0], &res[1]));
}

/* issue 17: shading must stay inside the ray stage's budget */
static void print_shade(FILE *f, const fv_bench_run *res, int nres)
{
    int any = 0;
    for (int i = 0; i < nres; i++)
        any |= !isnan(res[i].shade_ms);
    if (!any)
        return;
    fprintf(f, "shading inside the ray stage (threads' time / threads):");
    for (int i = 0; i < nres; i++)
        fprintf(f, "%s %s %.2f ms (%.0f %%)", i ? "," : "", res[i].mode, res[i].shade_ms,
                100.0 * fv_bench_shade_share(&res[i]));
    fprintf(f, "\n");
}

void fv_bench_print_results(FILE *f, const fv_bench_report *rep)
{
    const fv_bench_run *res = rep->runs;
    fv_bench_print_table(f, res, rep->nruns, rep->frames);
    if (rep->nruns == 2)
        fprintf(f, "samples foveated/full = %.3f   total foveated/full = %.3f\n",
                (double)res[0].samples / res[1].samples, res[0].total_mean / res[1].total_mean);
    print_shade(f, res, rep->nruns);
    fv_bench_print_ceiling(f, res, rep->nruns);
    print_roofline(f, res, rep->nruns, rep->width, rep->height, rep->copy_gbps);
    print_memory(f, res, rep->nruns);
    if (rep->nruns > 0)
        print_counters(f, &res[0]);
}

void fv_bench_print_sweep_point(FILE *f, const fv_sweep *sw, int k, int frames)
{
    fprintf(f, "\nsweep %s = %s", fv_sweep_names[sw->param], sw->label[k]);
    fv_bench_print_table(f, sw->res[k], sw->nres[k], frames);
    fv_bench_print_ceiling(f, sw->res[k], sw->nres[k]);
}

void fv_bench_print_scaling(FILE *f, const fv_sweep *sw)
{
    if (sw->param != FV_SWEEP_THREADS || sw->n < 2)
        return;
    fprintf(f, "\nscaling efficiency against %d thread%s (per stage, first mode):\n", sw->iv[0],
            sw->iv[0] == 1 ? "" : "s");
    for (int k = 0; k < sw->n; k++) {
        fprintf(f, "  threads %-3d", sw->iv[k]);
        for (int s = 0; s < FV_STAGE_COUNT; s++) {
            const double a = sw->res[0][0].stage_mean[s], b = sw->res[k][0].stage_mean[s];
            if (!isnan(a) && !isnan(b) && b > 0.0)
                fprintf(f, " %s %.2f", fv_stage_names[s], fv_bench_scaling(a, sw->iv[0], b, sw->iv[k]));
        }
        fprintf(f, " total %.2f\n",
                fv_bench_scaling(sw->res[0][0].total_mean, sw->iv[0], sw->res[k][0].total_mean, sw->iv[k]));
    }
}

/* ---- JSON ---- */
static void json_run(FILE *f, const fv_bench_run *r, int w, int h, double gbps)
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
    fprintf(f, ", \"sampler\": \"%s\", \"ceiling_ms\": ", r->sampler);
    json_num(f, r->ceiling_ms);
    fprintf(f, ", \"shade_ms\": ");
    json_num(f, r->shade_ms);
    fprintf(f, ",\n   \"memory_bytes\": {\"pyramids\": %zu, \"image\": %zu, \"display\": %zu, \"other\": %zu, "
               "\"shared\": %zu}",
            r->mem.pyramids, r->mem.image, r->mem.display, r->mem.other, r->mem.shared);
    fprintf(f, ",\n   \"roofline\": {");
    for (int k = 0; k < FV_BENCH_NROOF; k++) {
        const int s = fv_bench_roof_stages[k];
        fv_roof rf;
        fprintf(f, "%s\"%s\": ", k ? ", " : "", fv_stage_names[s]);
        if (fv_bench_roofline(r, s, w, h, gbps, &rf)) {
            fputs("null", f);
            continue;
        }
        fprintf(f, "{\"read_bytes\": %.0f, \"written_bytes\": %.0f, \"gbps\": %.4f, \"fraction\": ", rf.read_bytes,
                rf.written_bytes, rf.gbps);
        json_num(f, rf.fraction);
        fputc('}', f);
    }
    fprintf(f, "},\n   \"counters\": {\"available\": %s", r->counters ? "true" : "false");
    if (!r->counters) {
        fprintf(f, ", \"reason\": \"");
        json_str(f, r->counters_why, 0);
        fputc('"', f);
    } else {
        fprintf(f, ", \"per_frame\": {");
        for (int s = 0; s < FV_PROF_STAGES; s++) {
            fprintf(f, "%s\"%s\": {", s ? ", " : "", fv_prof_stage_name(s));
            for (int k = 0; k < FV_PERF_N; k++)
                fprintf(f, "%s\"%s\": %.0f", k ? ", " : "", fv_perf_names[k], r->ctr[s][k]);
            fputc('}', f);
        }
        fputc('}', f);
    }
    fprintf(f, "}}");
}

void fv_bench_write_json(FILE *f, const fv_bench_report *rep)
{
    const fv_pipeline_config *cfg = rep->cfg;
    fprintf(f, "{\"scene\": \"");
    json_str(f, rep->scene_path, 1);
    fprintf(f, "\", \"width\": %d, \"height\": %d, \"threads\": %d, \"frames\": %d, \"warmup\": %d, "
               "\"isa\": \"%s\", \"triangles\": %zu, \"load_ms\": %.1f, \"yaw_rate_dps\": %g, "
               "\"dof\": \"%s\", \"dof_model\": \"%s\",\n \"machine\": {\"cpus\": %d, \"copy_gbps_1t\": %.3f, "
               "\"copy_gbps\": %.3f, \"load_avg\": [%.2f, %.2f, %.2f]},\n \"runs\": [",
            rep->width, rep->height, rep->threads, rep->frames, rep->warmup, rep->isa, rep->triangles, rep->load_ms,
            (double)rep->yaw_rate, fv_dof_presets[cfg->dof.preset].name, fv_dof_models[cfg->dof.model].name,
            rep->cpus, rep->copy_gbps_1t, rep->copy_gbps, rep->load_avg[0], rep->load_avg[1], rep->load_avg[2]);
    for (int i = 0; i < rep->nruns; i++) {
        fprintf(f, "%s\n  ", i ? "," : "");
        json_run(f, &rep->runs[i], rep->width, rep->height, rep->copy_gbps);
    }
    fprintf(f, "],\n \"sweeps\": [");
    for (int i = 0; i < rep->nsweeps; i++) {
        const fv_sweep *sw = &rep->sweeps[i];
        fprintf(f, "%s\n  {\"param\": \"%s\", \"points\": [", i ? "," : "", fv_sweep_names[sw->param]);
        for (int k = 0; k < sw->n; k++) {
            const fv_pipeline_config c = fv_sweep_config(sw, k, cfg);
            fprintf(f, "%s\n   {\"value\": \"%s\", \"width\": %d, \"height\": %d, \"threads\": %d, \"pmin\": %g, "
                       "\"r0\": %g, \"r1\": %g, \"runs\": [",
                    k ? "," : "", sw->label[k], c.cam.width, c.cam.height, c.threads > 0 ? c.threads : rep->cpus,
                    (double)c.samp.p_min, (double)c.samp.r0_deg, (double)c.samp.r1_deg);
            for (int j = 0; j < sw->nres[k]; j++) {
                fprintf(f, "%s\n    ", j ? "," : "");
                json_run(f, &sw->res[k][j], c.cam.width, c.cam.height, rep->copy_gbps);
            }
            fprintf(f, "]}");
        }
        fprintf(f, "]}");
    }
    fprintf(f, "]}\n");
}

/* ---- fovea-replay's stats.csv ---- */
void fv_stats_csv_header(FILE *f)
{
    fprintf(f, "frame,t_ms,gaze_x,gaze_y,samples");
    for (int s = 0; s < FV_STAGE_COUNT; s++)
        fprintf(f, ",%s_ms", fv_stage_names[s]);
    /* dluma_periph: mean |luma change| against the previous frame outside r1 of both gazes
     * (temporal stability); psnr_*: against full sampling of the same frame (--vs-full) */
    fprintf(f, ",total_ms,dluma_periph,psnr_all,psnr_fovea,psnr_periph,flicker_periph,focus_m\n");
}

static void csv_num(FILE *f, double v, const char *fmt)
{
    fputc(',', f);
    if (!isnan(v))
        fprintf(f, fmt, v); /* inf prints as inf: identical images */
}

void fv_stats_csv_row(FILE *f, long frame, double t_ms, float gaze_x, float gaze_y, const fv_frame_stats *sum,
                      const fv_quality_row *q, double focus_m)
{
    fprintf(f, "%ld,%.3f,%.5f,%.5f,%ld", frame, t_ms, (double)gaze_x, (double)gaze_y, sum->samples);
    for (int s = 0; s < FV_STAGE_COUNT; s++) {
        if (isnan(sum->stage_ms[s]))
            fputs(",", f); /* stage not built: empty field */
        else
            fprintf(f, ",%.3f", sum->stage_ms[s]);
    }
    fprintf(f, ",%.3f", sum->total_ms);
    csv_num(f, q->dluma_periph, "%.4f");
    csv_num(f, q->psnr_all, "%.3f");
    csv_num(f, q->psnr_fovea, "%.3f");
    csv_num(f, q->psnr_periph, "%.3f");
    csv_num(f, q->flicker_periph, "%.4f");
    csv_num(f, focus_m, "%.4f");
    fputc('\n', f);
}

/* ---- fovea-headset's latency CSV ---- */
void fv_latency_csv_header(FILE *f)
{
    fprintf(f, "frame,gaze_t_ms,ray_start_ms,done_ms,target_ms,photon_ms,gaze_to_photon_ms,render_ms,late,"
               "photon_edge,vsync_state,budget_ms,gaze_x,gaze_y,head_t_ms,motion_to_photon_ms,pose_err_deg\n");
}

void fv_latency_csv_row(FILE *out, const fv_frame_record *q, int64_t t0)
{
#define MS(t) ((double)((t) - t0) * 1e-6)
    fprintf(out, "%ld,", q->frame);
    if (q->has_gaze)
        fprintf(out, "%.3f", MS(q->gaze_t_ns));
    fprintf(out, ",%.3f,%.3f,%.3f,%.3f,", MS(q->ray_start_ns), MS(q->done_ns), MS(q->target_ns), MS(q->photon_ns));
    if (q->has_gaze) /* empty without a gaze sample */
        fprintf(out, "%.3f", (double)(q->photon_ns - q->gaze_t_ns) * 1e-6);
    fprintf(out, ",%.3f,%d,%d,%s,%.3f,", (double)(q->done_ns - q->ray_start_ns) * 1e-6, q->late, q->photon_edge,
            fv_vsync_state_name(q->vsync_state), (double)q->budget_ns * 1e-6);
    if (q->has_gaze)
        fprintf(out, "%.4f,%.4f", (double)q->gaze_x, (double)q->gaze_y);
    else
        fputc(',', out);
    fputc(',', out);
    if (q->head_t_ns)
        fprintf(out, "%.3f,%.3f", MS(q->head_t_ns), (double)(q->photon_ns - q->head_t_ns) * 1e-6);
    else
        fputc(',', out);
    fputc(',', out);
    if (q->pose_err_deg == q->pose_err_deg && q->head_t_ns)
        fprintf(out, "%.4f", q->pose_err_deg);
    fputc('\n', out);
#undef MS
}

int fv_latency_csv_write(const char *path, const fv_frame_record *r, long n, int64_t t0, char *err, size_t err_len)
{
    fv_afile f;
    if (fv_afile_open(&f, path, err, err_len))
        return -1;
    fv_latency_csv_header(f.f);
    for (long i = 0; i < n; i++)
        fv_latency_csv_row(f.f, &r[i], t0);
    return fv_afile_commit(&f, err, err_len);
}

void fv_refresh_csv_header(FILE *f)
{
    fprintf(f, "refresh,frame,reused,late,head_t_ms,gaze_t_ms,frame_start_ms,frame_done_ms,compose_start_ms,"
               "compose_done_ms,target_ms,photon_ms,motion_to_photon_ms,gaze_to_photon_ms,photon_edge,vsync_state,"
               "margin_ms,disoccluded,pose_err_deg,gaze_x,gaze_y\n");
}

void fv_refresh_csv_row(FILE *out, const fv_refresh_record *q, int64_t t0)
{
#define MS(t) ((double)((t) - t0) * 1e-6)
    const int shown = q->frame >= 0;
    fprintf(out, "%ld,%ld,%d,%d,", q->refresh, q->frame, q->reused, q->late);
    if (shown && q->head_t_ns)
        fprintf(out, "%.3f", MS(q->head_t_ns));
    fputc(',', out);
    if (shown && q->has_gaze)
        fprintf(out, "%.3f", MS(q->gaze_t_ns));
    fputc(',', out);
    if (shown)
        fprintf(out, "%.3f,%.3f", MS(q->frame_start_ns), MS(q->frame_done_ns));
    else
        fputc(',', out);
    fprintf(out, ",%.3f,%.3f,%.3f,%.3f,", MS(q->wake_ns), MS(q->done_ns), MS(q->target_ns), MS(q->photon_ns));
    if (shown && q->head_t_ns)
        fprintf(out, "%.3f", (double)(q->photon_ns - q->head_t_ns) * 1e-6);
    fputc(',', out);
    if (shown && q->has_gaze)
        fprintf(out, "%.3f", (double)(q->photon_ns - q->gaze_t_ns) * 1e-6);
    fprintf(out, ",%d,%s,%.3f,%ld,", q->photon_edge, fv_vsync_state_name(q->vsync_state), (double)q->margin_ns * 1e-6,
            q->disoccluded);
    if (q->pose_err_deg == q->pose_err_deg)
        fprintf(out, "%.4f", q->pose_err_deg);
    fputc(',', out);
    if (shown && q->has_gaze)
        fprintf(out, "%.4f,%.4f", (double)q->gaze_x, (double)q->gaze_y);
    else
        fputc(',', out);
    fputc('\n', out);
#undef MS
}

int fv_refresh_csv_write(const char *path, const fv_refresh_record *r, long n, int64_t t0, char *err, size_t err_len)
{
    fv_afile f;
    if (fv_afile_open(&f, path, err, err_len))
        return -1;
    fv_refresh_csv_header(f.f);
    for (long i = 0; i < n; i++)
        fv_refresh_csv_row(f.f, &r[i], t0);
    return fv_afile_commit(&f, err, err_len);
}
