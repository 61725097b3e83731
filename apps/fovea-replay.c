/* fovea-replay: renders a scene along a recorded gaze / head trace, frame by frame, into PNGs
 * and a per-frame stats CSV. The development and evaluation loop on a PC without a headset. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "cli.h"
#include "metrics.h"
#include "output.h"
#include "pipeline.h"
#include "reference.h"
#include "scene.h"
#include "tracefile.h"
#include "prof.h"
#include "proftrace.h"

static const char *prog = "fovea-replay";

/* A normalised gaze coordinate in pixels (as the pipeline centres its pattern). */
static float smp_gaze_px(float g, int size) { return floorf(g * (float)size) + 0.5f; }

static void usage(FILE *f)
{
    fprintf(f,
            "usage: fovea-replay --scene FILE --out DIR [--trace FILE] [--frames N] [options]\n"
            "Renders the scene along a gaze/head trace; writes DIR/frame_NNNNN.png (left eye, or\n"
            "both eyes side by side with --stereo) and DIR/stats.csv (per-stage ms and samples).\n"
            "  --scene FILE       glTF 2.0 scene (.gltf or .glb)\n"
            "  --trace FILE       CSV t_ms,gaze_x,gaze_y[,head pose]; without it the gaze rests at the\n"
            "                     image centre and the head at the scene's default viewpoint\n"
            "  --frames N         frames to render (default: the trace's length at --hz, or 1)\n"
            "  --hz HZ            display rate that maps frames to trace time (default 90)\n"
            "  --out DIR          output directory (created)\n"
            "  --full             sample every pixel (no foveation)\n"
            "  --stereo           render both eyes, side by side\n"
            "  --y4m FILE         also write the frames as a YUV4MPEG2 video\n"
            "  --vs-full          also render every frame with full sampling and report the luma\n"
            "                     PSNR against it (whole image, fovea < r0, periphery > r1)\n"
            "  --reference SPP    render ground-truth depth of field instead: SPP thin-lens rays\n"
            "                     per pixel (every pixel; stage columns empty, total_ms its time)\n"
            "                     (--focus-m and --pupil-mm below set its lens; the default focus\n"
            "                     is the view depth at the point of regard)\n"
            "  --trace-out FILE   write a Chrome trace-event JSON of the run (Perfetto,\n"
            "                     chrome://tracing): worker, stage and ray-tile tracks, frame markers\n"
            "  --window           show frames in a window (not built yet)\n"
            "  --quiet            no progress output\n" FV_COMMON_HELP "  --help             this text\n");
}

enum { OPT_SCENE = 1, OPT_TRACE, OPT_FRAMES, OPT_OUT, OPT_FULL, OPT_STEREO, OPT_Y4M, OPT_REF, OPT_WINDOW, OPT_HZ,
       OPT_QUIET, OPT_VS_FULL, OPT_TRACE_OUT, OPT_HELP };

/* --reference: the thin-lens ground truth (core/reference.h) of one eye into rgb8. The focus is
 * fixed by the caller for both eyes (they accommodate together). Progress counts tiles. */
typedef struct {
    fv_progress *bar;
    long base;
    int quiet;
} ref_progress;
static void on_ref_progress(void *ctx, long done, long total)
{
    (void)total;
    ref_progress *r = ctx;
    if (!r->quiet)
        fv_progress_update(r->bar, r->base + done);
}
static long ref_tiles(int w, int h) { return (long)((w + 15) / 16) * ((h + 15) / 16); }
static void render_reference(const fv_scene *scene, const fv_camera *cam, const fv_reference_params *prm,
                             fv_pool *pool, float *rgbd, uint8_t *rgb8, ptrdiff_t stride, ref_progress *rp,
                             fv_frame_stats *st)
{
    const int64_t t0 = fv_time_ns();
    st->samples = fv_reference_render(scene, cam, prm, pool, rgbd, on_ref_progress, rp);
    fv_reference_to_rgb8(rgbd, cam->width, cam->height, rgb8, stride);
    for (int s = 0; s < FV_STAGE_COUNT; s++)
        st->stage_ms[s] = NAN; /* none of the pipeline's stages ran */
    st->total_ms = (double)(fv_time_ns() - t0) * 1e-6;
    rp->base += ref_tiles(cam->width, cam->height);
}

/* Mean of the finite values of a column (NAN when there are none). */
typedef struct {
    double sum;
    long n, inf; /* inf: PSNR of identical images, left out of the mean */
} mean_acc;
static void mean_add(mean_acc *m, double v)
{
    if (isfinite(v)) {
        m->sum += v;
        m->n++;
    } else if (isinf(v)) {
        m->inf++;
    }
}
static double mean_get(const mean_acc *m) { return m->n ? m->sum / (double)m->n : m->inf ? INFINITY : NAN; }
static void csv_num(FILE *f, double v, const char *fmt)
{
    fputc(',', f);
    if (!isnan(v))
        fprintf(f, fmt, v); /* inf prints as inf: identical images */
}

int main(int argc, char **argv)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    const char *scene_path = NULL, *trace_path = NULL, *out_dir = NULL, *y4m_path = NULL, *prof_path = NULL;
    long frames = -1;
    int stereo = 0, quiet = 0, vs_full = 0;
    fv_reference_params refp = {.spp = 0, .pupil_mm = 4.49f, .focus_m = 0.0f}; /* spp 0: no --reference */
    float hz = 90.0f;
    static const struct option opts[] = {
        {"scene", required_argument, 0, OPT_SCENE}, {"trace", required_argument, 0, OPT_TRACE},
        {"frames", required_argument, 0, OPT_FRAMES}, {"out", required_argument, 0, OPT_OUT},
        {"full", no_argument, 0, OPT_FULL}, {"stereo", no_argument, 0, OPT_STEREO},
        {"y4m", required_argument, 0, OPT_Y4M}, {"reference", required_argument, 0, OPT_REF},
        {"window", no_argument, 0, OPT_WINDOW}, {"hz", required_argument, 0, OPT_HZ},
        {"quiet", no_argument, 0, OPT_QUIET}, {"vs-full", no_argument, 0, OPT_VS_FULL},
        {"trace-out", required_argument, 0, OPT_TRACE_OUT},
        {"help", no_argument, 0, OPT_HELP}, FV_COMMON_LONGOPTS, {0, 0, 0, 0}};
    opterr = 0;
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case OPT_SCENE: scene_path = optarg; break;
        case OPT_TRACE: trace_path = optarg; break;
        case OPT_FRAMES: frames = fv_arg_long(prog, "--frames", optarg, 1, 10000000); break;
        case OPT_OUT: out_dir = optarg; break;
        case OPT_FULL: cfg.samp.full = 1; break;
        case OPT_STEREO: stereo = 1; break;
        case OPT_Y4M: y4m_path = optarg; break;
        case OPT_HZ: hz = fv_arg_float(prog, "--hz", optarg, 1.0f, 1000.0f); break;
        case OPT_QUIET: quiet = 1; break;
        case OPT_VS_FULL: vs_full = 1; break;
        case OPT_TRACE_OUT: prof_path = optarg; break;
        case OPT_REF: refp.spp = (int)fv_arg_long(prog, "--reference", optarg, 1, 65536); break;
        case OPT_WINDOW: fv_usage_error(prog, "--window: the window display is not built yet; use --out / --y4m");
        case OPT_HELP: usage(stdout); return FV_EXIT_OK;
        case '?': fv_bad_option(prog, argv);
        default:
            if (!fv_common_option(prog, o, optarg, &cfg))
                fv_usage_error(prog, "unhandled option (see --help)");
        }
    }
    fv_common_validate(prog, argc, argv, scene_path, &cfg);
    if (!out_dir)
        fv_usage_error(prog, "--out DIR is required (see --help)");
    /* the reference's lens is the pipeline's eye: same pupil, same fixed focus if one is given */
    const int focus_given = cfg.dof.focus.fixed_m > 0.0f;
    refp.pupil_mm = cfg.dof.pupil_mm;
    refp.focus_m = cfg.dof.focus.fixed_m;
    if (refp.spp && vs_full)
        fv_usage_error(prog, "--vs-full and --reference exclude each other");
    if (y4m_path && ((cfg.cam.width & 1) || (cfg.cam.height & 1)))
        fv_usage_error(prog, "--y4m: 4:2:0 video needs even frame sizes, got %dx%d", cfg.cam.width, cfg.cam.height);

    char err[512];
    fv_trace tr = {0};
    if (trace_path && fv_trace_load(&tr, trace_path, err, sizeof err))
        fv_usage_error(prog, "%s", err);
    if (frames < 0)
        frames = trace_path ? 1 + (long)floor((tr.s[tr.n - 1].t_ms - tr.s[0].t_ms) * hz / 1000.0) : 1;

    fv_scene *scene = fv_scene_load(scene_path, err, sizeof err);
    if (!scene) {
        fv_trace_free(&tr);
        fv_usage_error(prog, "%s", err);
    }
    int W = cfg.cam.width, H = cfg.cam.height;
    fv_pose view;
    fv_scene_default_view(scene, cfg.cam.fov_y_deg, (float)W / (float)H, view.pos, view.quat);
    fv_pipeline *pl = fv_pipeline_create(scene, &cfg, err, sizeof err), *ref = NULL;
    if (pl && vs_full) {
        fv_pipeline_config rc = cfg;
        rc.samp.full = 1;
        ref = fv_pipeline_create(scene, &rc, err, sizeof err);
    }
    if (!pl || (vs_full && !ref)) {
        fv_pipeline_destroy(pl);
        fv_scene_free(scene);
        fv_trace_free(&tr);
        fv_usage_error(prog, "%s", err);
    }

    int status = FV_EXIT_FAIL;
    /* the trace recorder: one slot per worker of the (rendering) pipeline's pool */
    fv_prof *prof = NULL;
    if (prof_path) {
        if (!(prof = fv_prof_create(fv_pool_threads(fv_pipeline_pool(pl)), (size_t)1 << 18))) {
            fv_pipeline_destroy(ref);
            fv_pipeline_destroy(pl);
            fv_scene_free(scene);
            fv_trace_free(&tr);
            fv_fail(prog, FV_EXIT_FAIL, "out of memory for the trace recorder");
        }
        fv_pipeline_set_prof(pl, prof);
    }
    int outw = stereo ? 2 * W : W;
    /* cur / prev: the (left) eye's image of this and the last frame, W * 3 bytes a row */
    uint8_t *rgb = malloc((size_t)outw * H * 3), *prev = malloc((size_t)W * H * 3), *cur = malloc((size_t)W * H * 3);
    uint8_t *full = NULL;
    float *refbuf = refp.spp ? malloc(sizeof(float) * 4 * (size_t)W * H) : NULL;
    float *err_prev = NULL, *err_cur = NULL;
    if (vs_full) {
        full = malloc((size_t)W * H * 3);
        err_prev = malloc((size_t)W * H * sizeof(float));
        err_cur = malloc((size_t)W * H * sizeof(float));
    }
    mean_acc m_dl = {0}, m_all = {0}, m_fov = {0}, m_per = {0}, m_fl = {0};
    float prev_gx = 0.0f, prev_gy = 0.0f;
    fv_afile csv = {0};
    fv_y4m_writer y4m = {0};
    int y4m_open = 0;
    char path[4200];
    if (!rgb || !prev || !cur || (refp.spp && !refbuf) || (vs_full && (!full || !err_prev || !err_cur))) {
        fprintf(stderr, "%s: out of memory\n", prog);
        goto done;
    }
    if (fv_mkdirs(out_dir, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", prog, err);
        goto done;
    }
    snprintf(path, sizeof path, "%s/stats.csv", out_dir);
    if (fv_afile_open(&csv, path, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", prog, err);
        goto done;
    }
    if (y4m_path) {
        if (fv_y4m_open(&y4m, y4m_path, outw, H, (int)lrintf(hz), err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", prog, err);
            goto done;
        }
        y4m_open = 1;
    }
    fprintf(csv.f, "frame,t_ms,gaze_x,gaze_y,samples");
    for (int s = 0; s < FV_STAGE_COUNT; s++)
        fprintf(csv.f, ",%s_ms", fv_stage_names[s]);
    /* dluma_periph: mean |luma change| against the previous frame outside r1 of both gazes
     * (temporal stability); psnr_*: against full sampling of the same frame (--vs-full) */
    fprintf(csv.f, ",total_ms,dluma_periph,psnr_all,psnr_fovea,psnr_periph,flicker_periph,focus_m\n");

    fv_progress prog_bar;
    const int neyes = stereo ? 2 : 1;
    if (refp.spp)
        fv_progress_begin(&prog_bar, "reference: tile", frames * neyes * ref_tiles(W, H));
    else
        fv_progress_begin(&prog_bar, "rendering frame", frames);
    ref_progress rprog = {&prog_bar, 0, quiet};
    double t_first = trace_path ? tr.s[0].t_ms : 0.0;
    for (long f = 0; f < frames; f++) {
        fv_trace_sample smp;
        double t_ms = t_first + (double)f * 1000.0 / hz;
        fv_trace_at(&tr, t_ms, &smp);
        fv_pipeline_set_time_ns(pl, (int64_t)llround(t_ms * 1e6)); /* the focus filter's clock */
        if (ref)
            fv_pipeline_set_time_ns(ref, (int64_t)llround(t_ms * 1e6));
        fv_pose head = tr.has_head ? smp.head : view;
        fv_prof_instant(prof, 0, FV_PROF_TRACK_MARKERS, "frame", fv_time_ns(), (int)f);
        fv_frame_stats st[2], sum;
        memset(&sum, 0, sizeof sum);
        for (int e = 0; e < neyes; e++) {
            fv_eye eye = stereo ? (e == 0 ? FV_EYE_LEFT : FV_EYE_RIGHT) : FV_EYE_CENTER;
            if (refp.spp) {
                fv_camera_desc cd = cfg.cam;
                fv_camera cam;
                cd.eye = eye;
                fv_camera_setup(&cam, &cd, &head); /* the size and FOV passed fv_pipeline_create */
                if (e == 0 && !focus_given) { /* the first eye's depth at the point of regard, for both */
                    refp.focus_m = fv_reference_depth_at(scene, &cam, smp_gaze_px(smp.gaze_x, W),
                                                         smp_gaze_px(smp.gaze_y, H));
                    refp.focus_m = refp.focus_m > 0.05f ? refp.focus_m : 0.05f; /* as --focus-m's minimum */
                }
                render_reference(scene, &cam, &refp, fv_pipeline_pool(pl), refbuf, rgb + (size_t)e * W * 3,
                                 (ptrdiff_t)outw * 3, &rprog, &st[e]);
            } else {
                fv_pipeline_render(pl, eye, &head, smp.gaze_x, smp.gaze_y, &st[e]);
                fv_pipeline_to_rgb8(pl, eye, rgb + (size_t)e * W * 3, (ptrdiff_t)outw * 3);
            }
            for (int s = 0; s < FV_STAGE_COUNT; s++)
                sum.stage_ms[s] = e ? sum.stage_ms[s] + st[e].stage_ms[s] : st[e].stage_ms[s];
            sum.total_ms += st[e].total_ms;
            sum.samples += st[e].samples;
        }
        /* metrics on the (left) eye's image */
        const float gpx = smp_gaze_px(smp.gaze_x, W), gpy = smp_gaze_px(smp.gaze_y, H);
        const fv_sampler *sm = fv_pipeline_sampler(pl);
        double dl = NAN, p_all = NAN, p_fov = NAN, p_per = NAN, fl = NAN;
        for (int y = 0; y < H; y++)
            memcpy(cur + (size_t)y * W * 3, rgb + (size_t)y * outw * 3, (size_t)W * 3);
        if (f > 0) {
            fv_region per = {gpx, gpy, sm->r1_px, prev_gx, prev_gy, 1};
            dl = fv_luma_mad(prev, cur, W, H, (ptrdiff_t)W * 3, &per);
        }
        if (vs_full) {
            fv_eye eye = stereo ? FV_EYE_LEFT : FV_EYE_CENTER;
            fv_frame_stats rs;
            fv_pipeline_render(ref, eye, &head, smp.gaze_x, smp.gaze_y, &rs);
            fv_pipeline_to_rgb8(ref, eye, full, (ptrdiff_t)W * 3);
            fv_region fov = fv_region_disc(gpx, gpy, sm->r0_px, 0), per = fv_region_disc(gpx, gpy, sm->r1_px, 1);
            p_all = fv_luma_psnr(full, cur, W, H, (ptrdiff_t)W * 3, NULL);
            p_fov = fv_luma_psnr(full, cur, W, H, (ptrdiff_t)W * 3, &fov);
            p_per = fv_luma_psnr(full, cur, W, H, (ptrdiff_t)W * 3, &per);
            /* flicker: how much the error against full sampling changes between frames */
            fv_luma_error(full, cur, W, H, (ptrdiff_t)W * 3, err_cur);
            if (f > 0) {
                fv_region both = {gpx, gpy, sm->r1_px, prev_gx, prev_gy, 1};
                fl = fv_mean_abs_diff(err_prev, err_cur, W, H, &both);
            }
            float *t = err_prev;
            err_prev = err_cur;
            err_cur = t;
        }
        uint8_t *t8 = prev;
        prev = cur;
        cur = t8;
        prev_gx = gpx;
        prev_gy = gpy;
        mean_add(&m_dl, dl);
        mean_add(&m_all, p_all);
        mean_add(&m_fov, p_fov);
        mean_add(&m_per, p_per);
        mean_add(&m_fl, fl);
        snprintf(path, sizeof path, "%s/frame_%05ld.png", out_dir, f);
        if (fv_write_png(path, rgb, outw, H, (ptrdiff_t)outw * 3, err, sizeof err) ||
            (y4m_open && fv_y4m_write_rgb(&y4m, rgb, (ptrdiff_t)outw * 3, err, sizeof err))) {
            fprintf(stderr, "%s: %s\n", prog, err);
            goto done;
        }
        fprintf(csv.f, "%ld,%.3f,%.5f,%.5f,%ld", f, t_ms, (double)smp.gaze_x, (double)smp.gaze_y, sum.samples);
        for (int s = 0; s < FV_STAGE_COUNT; s++) {
            if (isnan(sum.stage_ms[s]))
                fputs(",", csv.f); /* stage not built: empty field */
            else
                fprintf(csv.f, ",%.3f", sum.stage_ms[s]);
        }
        fprintf(csv.f, ",%.3f", sum.total_ms);
        csv_num(csv.f, dl, "%.4f");
        csv_num(csv.f, p_all, "%.3f");
        csv_num(csv.f, p_fov, "%.3f");
        csv_num(csv.f, p_per, "%.3f");
        csv_num(csv.f, fl, "%.4f");
        csv_num(csv.f, refp.spp ? (double)refp.focus_m : (double)st[0].focus_m, "%.4f");
        fputc('\n', csv.f);
        if (!quiet && !refp.spp)
            fv_progress_update(&prog_bar, f + 1);
    }
    fv_progress_end(&prog_bar);
    if (fv_afile_commit(&csv, err, sizeof err) || (y4m_open && (y4m_open = 0, fv_y4m_close(&y4m, err, sizeof err)))) {
        fprintf(stderr, "%s: %s\n", prog, err);
        goto done;
    }
    if (!quiet) {
        printf("%s: %ld frame%s of %dx%d%s in %s/ (stats.csv)\n", prog, frames, frames == 1 ? "" : "s", W, H,
               stereo ? " x 2 eyes" : "", out_dir);
        if (frames > 1)
            printf("%s: mean periphery luma change between frames %.3f (of 255)\n", prog, mean_get(&m_dl));
        if (vs_full)
            printf("%s: luma PSNR against full sampling, mean over frames: all %.2f dB, fovea %.2f dB, periphery "
                   "%.2f dB; periphery flicker (change of the error between frames) %.3f\n",
                   prog, mean_get(&m_all), mean_get(&m_fov), mean_get(&m_per), mean_get(&m_fl));
    }
    status = FV_EXIT_OK;
    if (prof) {
        char label[600];
        snprintf(label, sizeof label, "fovea-replay %s", scene_path);
        fv_pipeline_set_prof(pl, NULL);
        if (fv_prof_write_json(prof, prof_path, label, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", prog, err);
            status = FV_EXIT_FAIL;
        }
    }
done:
    fv_afile_abort(&csv);
    if (y4m_open)
        fv_y4m_abort(&y4m);
    free(rgb);
    free(prev);
    free(cur);
    free(full);
    free(err_prev);
    free(err_cur);
    free(refbuf);
    fv_pipeline_destroy(ref);
    fv_pipeline_destroy(pl);
    fv_prof_destroy(prof);
    fv_scene_free(scene);
    fv_trace_free(&tr);
    return status;
}
