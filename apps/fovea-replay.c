/* fovea-replay: renders a scene along a recorded gaze / head trace, frame by frame, into PNGs
 * and a per-frame stats CSV. The development and evaluation loop on a PC without a headset. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "bench.h"
#include "benchio.h"
#include "cli.h"
#include "display.h"
#include "lens.h"
#include "output.h"
#include "pipeline.h"
#include "prof.h"
#include "proftrace.h"
#include "quality.h"
#include "reference.h"
#include "scene.h"
#include "tracefile.h"
#include "prof.h"
#include "proftrace.h"

static const char *prog = "fovea-replay";

static void usage(FILE *f)
{
    fprintf(f,
            "usage: fovea-replay --scene FILE --out DIR [--trace FILE] [--frames N] [options]\n"
            "Renders the scene along a gaze/head trace; writes DIR/frame_NNNNN.png (left eye, or\n"
            "both eyes side by side with --stereo) and DIR/stats.csv (per-stage ms and samples).\n"
            "  --scene FILE       glTF 2.0 scene (.gltf or .glb)\n"
            FV_ASSET_ROOT_HELP FV_SHADOWS_HELP FV_LENS_HELP
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
            "                     is the view depth at the point of regard); with --dof none given:\n"
            "                     SPP pinhole rays spread over each pixel's area instead, the\n"
            "                     supersampled (anti-aliased) image\n"
            "  --trace-out FILE   write a Chrome trace-event JSON of the run (Perfetto,\n"
            "                     chrome://tracing): worker, stage and ray-tile tracks, frame markers\n"
            "  --window           also show each frame in a window (SDL2) as it is rendered; closing\n"
            "                     it (or Esc) ends the run early\n"
            "  --quiet            no progress output\n"
            "  --png on|off       write the frame PNGs (default on; off: stats.csv only, e.g. a soak)\n" FV_COMMON_HELP "  --help             this text\n");
}

enum { OPT_LENS = 500, OPT_SCENE = 1, OPT_TRACE, OPT_FRAMES, OPT_OUT, OPT_FULL, OPT_STEREO, OPT_Y4M, OPT_REF, OPT_WINDOW, OPT_HZ,
       OPT_QUIET, OPT_VS_FULL, OPT_TRACE_OUT, OPT_HELP, OPT_PNG };

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
                             fv_pool *pool, float *rgbd, uint8_t *rgb8, ptrdiff_t stride, unsigned isa_mask,
                             ref_progress *rp, fv_frame_stats *st)
{
    const int64_t t0 = fv_time_ns();
    st->samples = fv_reference_render(scene, cam, prm, pool, rgbd, on_ref_progress, rp);
    fv_reference_to_rgb8(rgbd, cam->width, cam->height, rgb8, stride, isa_mask);
    for (int s = 0; s < FV_STAGE_COUNT; s++)
        st->stage_ms[s] = NAN; /* none of the pipeline's stages ran */
    st->total_ms = (double)(fv_time_ns() - t0) * 1e-6;
    rp->base += ref_tiles(cam->width, cam->height);
}

/* The eye's name in messages: "" for the single centre eye. */
static const char *eye_name(fv_eye e) { return e == FV_EYE_LEFT ? " (left eye)" : e == FV_EYE_RIGHT ? " (right eye)" : ""; }

int main(int argc, char **argv)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    const char *asset_root = NULL; /* --asset-root */
    int shadows = 0;               /* --shadows */
    const char *lens_path = NULL;  /* --lens */
    int dof_given = 0, pupil_given = 0;
    const char *scene_path = NULL, *trace_path = NULL, *out_dir = NULL, *y4m_path = NULL, *prof_path = NULL;
    long frames = -1;
    int stereo = 0, quiet = 0, vs_full = 0, window = 0, png = 1;
    fv_reference_params refp = {.spp = 0, .pupil_mm = 4.49f, .focus_m = 0.0f}; /* spp 0: no --reference */
    float hz = 90.0f;
    static const struct option opts[] = {
        {"scene", required_argument, 0, OPT_SCENE}, FV_ASSET_ROOT_LONGOPT, FV_SHADOWS_LONGOPT, {"lens", required_argument, 0, OPT_LENS}, {"trace", required_argument, 0, OPT_TRACE},
        {"frames", required_argument, 0, OPT_FRAMES}, {"out", required_argument, 0, OPT_OUT},
        {"full", no_argument, 0, OPT_FULL}, {"stereo", no_argument, 0, OPT_STEREO},
        {"y4m", required_argument, 0, OPT_Y4M}, {"reference", required_argument, 0, OPT_REF},
        {"window", no_argument, 0, OPT_WINDOW}, {"hz", required_argument, 0, OPT_HZ},
        {"quiet", no_argument, 0, OPT_QUIET}, {"png", required_argument, 0, OPT_PNG}, {"vs-full", no_argument, 0, OPT_VS_FULL},
        {"trace-out", required_argument, 0, OPT_TRACE_OUT},
        {"help", no_argument, 0, OPT_HELP}, FV_COMMON_LONGOPTS, {0, 0, 0, 0}};
    opterr = 0;
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case OPT_SCENE: scene_path = optarg; break;
        case FV_OPT_ASSET_ROOT: asset_root = optarg; break;
        case FV_OPT_SHADOWS: shadows = fv_arg_onoff(prog, "--shadows", optarg); break;
        case OPT_LENS: lens_path = optarg; break;
        case OPT_TRACE: trace_path = optarg; break;
        case OPT_FRAMES: frames = fv_arg_long(prog, "--frames", optarg, 1, 10000000); break;
        case OPT_OUT: out_dir = optarg; break;
        case OPT_FULL: cfg.samp.full = 1; break;
        case OPT_STEREO: stereo = 1; break;
        case OPT_Y4M: y4m_path = optarg; break;
        case OPT_HZ: hz = fv_arg_float(prog, "--hz", optarg, 1.0f, 1000.0f); break;
        case OPT_QUIET: quiet = 1; break;
        case OPT_PNG: png = fv_arg_onoff(prog, "--png", optarg); break;
        case OPT_VS_FULL: vs_full = 1; break;
        case OPT_TRACE_OUT: prof_path = optarg; break;
        case OPT_REF: refp.spp = (int)fv_arg_long(prog, "--reference", optarg, 1, 65536); break;
        case OPT_WINDOW: window = 1; break;
        case OPT_HELP: usage(stdout); return FV_EXIT_OK;
        case '?': fv_bad_option(prog, argv);
        default:
            dof_given |= o == FV_OPT_DOF;
            pupil_given |= o == FV_OPT_PUPIL_MM;
            if (!fv_common_option(prog, o, optarg, &cfg))
                fv_usage_error(prog, "unhandled option (see --help)");
        }
    }
    fv_common_validate(prog, argc, argv, scene_path, &cfg);
    fv_lens lens; /* --lens: outlives the pipeline (its cameras point at it) */
    if (lens_path)
        fv_cli_lens(prog, lens_path, &lens, &cfg);
    if (!out_dir)
        fv_usage_error(prog, "--out DIR is required (see --help)");
    /* the reference's lens is the pipeline's eye: same pupil, same fixed focus if one is given */
    const int focus_given = cfg.dof.focus.fixed_m > 0.0f;
    refp.pupil_mm = cfg.dof.pupil_mm;
    refp.focus_m = cfg.dof.focus.fixed_m;
    /* --dof none given: the pinhole supersampling reference (rays spread over each pixel), the
     * anti-aliased image the pipeline without depth of field is compared with */
    if (refp.spp && dof_given && cfg.dof.preset == FV_DOF_NONE) {
        if (pupil_given)
            fv_usage_error(prog, "--pupil-mm: --reference with --dof none is a pinhole (no lens)");
        refp.pupil_mm = 0.0f;
        refp.pixel_aa = 1;
    }
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

    fv_scene *scene = fv_scene_load_in(scene_path, asset_root, err, sizeof err);
    if (!scene) {
        fv_trace_free(&tr);
        fv_usage_error(prog, "%s", err);
    }
    if (fv_scene_warning(scene)[0]) /* once, before any output */
        fprintf(stderr, "%s: %s: warning: %s\n", prog, scene_path, fv_scene_warning(scene));
    if (shadows && fv_scene_set_shadows(scene, 1))
        fprintf(stderr, "%s: %s: warning: more than 16 KHR lights, shadows off\n", prog, scene_path);
    const int W = cfg.cam.width, H = cfg.cam.height, outw = stereo ? 2 * W : W;
    fv_pose view;
    fv_scene_default_view(scene, cfg.cam.fov_y_deg, (float)W / (float)H, view.pos, view.quat);
    fv_pipeline *pl = fv_pipeline_create(scene, &cfg, err, sizeof err), *ref = NULL;
    if (pl && vs_full) {
        fv_pipeline_config rc = cfg;
        rc.samp.full = 1;
        ref = fv_pipeline_create(scene, &rc, err, sizeof err);
    }
    /* --window: no display (or no SDL2 in this build) is bad input, caught before any output */
    fv_display *disp = NULL;
    char werr[512];
    const int no_window = pl && (!vs_full || ref) && window &&
                          fv_display_open(&disp, "window", outw, H, (int)lrintf(hz), werr, sizeof werr);
    if (!pl || (vs_full && !ref) || no_window) {
        fv_pipeline_destroy(ref);
        fv_pipeline_destroy(pl);
        fv_scene_free(scene);
        fv_trace_free(&tr);
        if (no_window) /* (the display's "window: " prefix would say it twice) */
            fv_usage_error(prog, "--window: %s", strncmp(werr, "window: ", 8) ? werr : werr + 8);
        fv_usage_error(prog, "%s", err);
    }

    int status = FV_EXIT_FAIL;
    /* the trace recorder: one slot per worker of the (rendering) pipeline's pool */
    fv_prof *prof = NULL;
    if (prof_path) {
        if (!(prof = fv_prof_create(fv_pool_threads(fv_pipeline_pool(pl)), (size_t)1 << 18))) {
            fv_display_close(disp, NULL, 0);
            fv_pipeline_destroy(ref);
            fv_pipeline_destroy(pl);
            fv_scene_free(scene);
            fv_trace_free(&tr);
            fv_fail(prog, FV_EXIT_FAIL, "out of memory for the trace recorder");
        }
        fv_pipeline_set_prof(pl, prof);
    }
    uint8_t *rgb = malloc((size_t)outw * H * 3), *full = vs_full ? malloc((size_t)W * H * 3) : NULL;
    float *refbuf = refp.spp ? malloc(sizeof(float) * 4 * (size_t)W * H) : NULL;
    fv_quality q; /* measured on the (left) eye's image */
    const int q_ok = !fv_quality_init(&q, W, H, vs_full);
    fv_afile csv = {0};
    fv_y4m_writer y4m = {0};
    int y4m_open = 0;
    char path[4200];
    if (!rgb || !q_ok || (refp.spp && !refbuf) || (vs_full && !full)) {
        fprintf(stderr, "%s: out of memory\n", prog);
        goto done;
    }
    /* The outputs, opened once every input has been accepted and before any frame: one that cannot
     * be written is bad usage (exit 2), found now rather than after the run. */
    snprintf(path, sizeof path, "%s/stats.csv", out_dir);
    if (fv_output_probe_dir(out_dir, err, sizeof err) || fv_afile_open(&csv, path, err, sizeof err) ||
        (prof_path && fv_output_probe(prof_path, err, sizeof err))) {
        fprintf(stderr, "%s: %s\n", prog, err);
        status = FV_EXIT_USAGE;
        goto done;
    }
    if (y4m_path) {
        if (fv_y4m_open(&y4m, y4m_path, outw, H, (int)lrintf(hz), err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", prog, err);
            status = FV_EXIT_USAGE;
            goto done;
        }
        y4m_open = 1;
    }
    fv_stats_csv_header(csv.f);

    fv_progress prog_bar;
    const int neyes = stereo ? 2 : 1;
    if (refp.spp)
        fv_progress_begin(&prog_bar, "reference: tile", frames * neyes * ref_tiles(W, H));
    else
        fv_progress_begin(&prog_bar, "rendering frame", frames);
    ref_progress rprog = {&prog_bar, 0, quiet};
    double t_first = trace_path ? tr.s[0].t_ms : 0.0;
    for (long f = 0; f < frames; f++) {
        if (disp && fv_display_quit_requested(disp)) {
            frames = f; /* the window was closed: the frames so far are the run */
            break;
        }
        fv_trace_sample smp;
        double t_ms = t_first + (double)f * 1000.0 / hz;
        fv_trace_at(&tr, t_ms, &smp);
        fv_pipeline_set_time_ns(pl, (int64_t)llround(t_ms * 1e6)); /* the focus filter's clock */
        if (ref)
            fv_pipeline_set_time_ns(ref, (int64_t)llround(t_ms * 1e6));
        fv_pose head = tr.has_head ? smp.head : view;
        fv_prof_instant(prof, 0, FV_PROF_TRACK_MARKERS, "frame", fv_time_ns(), (int)f);
        fv_frame_stats st[2], sum;
        /* both eyes' tiles in one pool job: the bytes of one eye after the other */
        if (stereo && !refp.spp && fv_pipeline_render_stereo(pl, &head, smp.gaze_x, smp.gaze_y, st)) {
            fprintf(stderr, "%s: frame %ld (stereo pair): rendering failed\n", prog, f);
            goto done;
        }
        for (int e = 0; e < neyes; e++) {
            fv_eye eye = stereo ? (e == 0 ? FV_EYE_LEFT : FV_EYE_RIGHT) : FV_EYE_CENTER;
            if (refp.spp) {
                fv_camera_desc cd = cfg.cam;
                fv_camera cam;
                cd.eye = eye;
                if (fv_camera_setup(&cam, &cd, &head)) { /* (the size and FOV passed fv_pipeline_create) */
                    fprintf(stderr, "%s: frame %ld%s: the reference's camera setup failed\n", prog, f, eye_name(eye));
                    goto done;
                }
                if (e == 0 && !focus_given) { /* the first eye's depth at the point of regard, for both */
                    refp.focus_m = fv_reference_depth_at(scene, &cam, fv_gaze_px(smp.gaze_x, W),
                                                         fv_gaze_px(smp.gaze_y, H));
                    refp.focus_m = refp.focus_m > 0.05f ? refp.focus_m : 0.05f; /* as --focus-m's minimum */
                }
                render_reference(scene, &cam, &refp, fv_pipeline_pool(pl), refbuf, rgb + (size_t)e * W * 3,
                                 (ptrdiff_t)outw * 3, cfg.isa_mask, &rprog, &st[e]);
            } else {
                if (!stereo && fv_pipeline_render(pl, eye, &head, smp.gaze_x, smp.gaze_y, &st[e])) {
                    fprintf(stderr, "%s: frame %ld%s: rendering failed\n", prog, f, eye_name(eye));
                    goto done;
                }
                fv_pipeline_to_rgb8(pl, eye, rgb + (size_t)e * W * 3, (ptrdiff_t)outw * 3);
            }
            fv_frame_stats_sum(&sum, &st[e], e == 0);
        }
        const float gpx = fv_gaze_px(smp.gaze_x, W), gpy = fv_gaze_px(smp.gaze_y, H);
        const fv_sampler *sm = fv_pipeline_sampler(pl);
        if (vs_full) {
            fv_eye eye = stereo ? FV_EYE_LEFT : FV_EYE_CENTER;
            fv_frame_stats rs;
            if (fv_pipeline_render(ref, eye, &head, smp.gaze_x, smp.gaze_y, &rs)) {
                fprintf(stderr, "%s: frame %ld%s: the full-sampling render of --vs-full failed\n", prog, f,
                        eye_name(eye));
                goto done;
            }
            fv_pipeline_to_rgb8(ref, eye, full, (ptrdiff_t)W * 3);
        }
        fv_quality_row qr;
        fv_quality_frame(&q, rgb, (ptrdiff_t)outw * 3, full, gpx, gpy, sm->r0_px, sm->r1_px, &qr);
        snprintf(path, sizeof path, "%s/frame_%05ld.png", out_dir, f);
        if ((png && fv_write_png(path, rgb, outw, H, (ptrdiff_t)outw * 3, err, sizeof err)) ||
            (y4m_open && fv_y4m_write_rgb(&y4m, rgb, (ptrdiff_t)outw * 3, err, sizeof err))) {
            fprintf(stderr, "%s: %s\n", prog, err);
            goto done;
        }
        fv_stats_csv_row(csv.f, f, t_ms, smp.gaze_x, smp.gaze_y, &sum, &qr,
                         refp.spp ? (double)refp.focus_m : (double)st[0].focus_m);
        if (disp && fv_display_present(disp, rgb, outw, H, (ptrdiff_t)outw * 3, err, sizeof err)) {
            fprintf(stderr, "%s: --window: %s\n", prog, err);
            goto done;
        }
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
            printf("%s: mean periphery luma change between frames %.3f (of 255)\n", prog, fv_mean_get(&q.dluma));
        if (vs_full)
            printf("%s: luma PSNR against full sampling, mean over frames: all %.2f dB, fovea %.2f dB, periphery "
                   "%.2f dB; periphery flicker (change of the error between frames) %.3f\n",
                   prog, fv_mean_get(&q.psnr_all), fv_mean_get(&q.psnr_fovea), fv_mean_get(&q.psnr_periph),
                   fv_mean_get(&q.flicker));
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
    fv_display_close(disp, NULL, 0);
    free(rgb);
    free(full);
    free(refbuf);
    fv_quality_free(&q);
    fv_pipeline_destroy(ref);
    fv_pipeline_destroy(pl);
    fv_prof_destroy(prof);
    fv_scene_free(scene);
    fv_trace_free(&tr);
    return status;
}
