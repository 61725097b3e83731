#include "pipeline.h"
#include "base/clock.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "prof.h"
#include "output_convert.h"
#include "tile.h"
#include "base/err.h"

#define FOVEA_STEPS 4 /* fovea scales 1, 1.25, 1.5, 1.75, 2 */

typedef struct {
    fv_camera cam, prev_cam;
    fv_pyramid pyr[2]; /* with reprojection: the current image and the previous one (history) */
    int cur;           /* pyr[cur] holds the last rendered frame */
    int hist_valid;    /* pyr[cur] and prev_cam may be reprojected */
    long frame;        /* frames rendered: the sampling pattern's phase */
    fv_focus focus;    /* depth of field: this eye's accommodation */
    float *out;        /* depth of field: the final image (level 0's layout); NULL where the
                        * layered model converts its rows straight to the display format */
    int64_t last_t_ns; /* the time of its last frame (focus filter) */
    fv_lens_lca *lca;  /* lateral chromatic aberration tables (a lens with per-channel scales) */
    fv_lens_map *lmap; /* the lens in pixel units, for the reprojection (NULL: no lens) */
    uint8_t *rgb8;     /* the last frame in the display format: sRGB 8-bit RGB, rows 3 w bytes */
    uint32_t *rows;    /* DoF-driven sampling: the last frame's sample bits per tile (ceiling) */
    int rows_valid;    /* the last frame was thinned: rows holds its bits */
    uint8_t *aa_n[2];  /* fovea anti-aliasing: per-pixel sample counts, aa_n[cur] the last frame's */
    float *aa_snap;    /* the still head in place: the AA tiles' history (fv_taa_aa_snapshot) */
    size_t aa_snap_cap; /* its floats */
} eye_state;

struct fv_pipeline {
    const fv_scene *scene;
    fv_pipeline_config cfg;
    fv_pool *pool;
    fv_render_dsp dsp;
    fv_sampler smp;
    /* fovea widened (fv_pipeline_set_fovea_scale): step k of FOVEA_STEPS scales r0, r1 by
     * 1 + k / FOVEA_STEPS; wide[k - 1] is built on the step's first use and kept */
    fv_sampler wide[FOVEA_STEPS];
    const fv_sampler *smp_cur; /* the sampler in force: smp or one of wide */
    int fovea_step;
    int taa;           /* reprojection runs (enabled and foveated) */
    int aa;            /* anti-aliasing in the fovea (with reprojection; core/reproject_aa.c) */
    int dof;           /* the depth-of-field stages run */
    int dofsamp;       /* DoF-driven sampling thins the rays (DoF and reprojection on) */
    float *dofsamp_map; /* its defocus map (shared by the eyes, rendered one after the other) */
    float *dofsamp_map_r; /* the right eye's in fv_pipeline_render_stereo (its tiles run beside the left eye) */
    fv_dof_model_fn dof_fn;
    fv_dof_work dof_work;    /* scratch shared by the eyes (rendered one after the other) */
    float *enh_fp;           /* contrast enhancement footprint per eccentricity step */
    int enh_n;
    const fv_sampler *enh_for; /* the sampler enh_fp was computed for (the fovea may widen) */
    int64_t t_ns;            /* the frame time set by fv_pipeline_set_time_ns; INT64_MIN: none */
    eye_state eyes[2];
    fv_prof *prof;           /* trace recorder (fv_pipeline_set_prof); NULL: off */
    fv_output_conv conv;     /* the display format conversion (sRGB LUT) */
};


/* Bytes of an eye's float image (level 0's layout) and of its sample bits (one row word per tile row). */
static size_t image_bytes(const fv_pyr_level *l0) { return (size_t)l0->stride * (size_t)l0->h * 4 * sizeof(float); }
static size_t rows_bytes(const fv_camera_desc *c)
{
    return (size_t)((c->width + FV_TILE - 1) / FV_TILE) * (size_t)((c->height + FV_TILE - 1) / FV_TILE) * FV_TILE *
           sizeof(uint32_t);
}

void fv_pipeline_config_default(fv_pipeline_config *c)
{
    memset(c, 0, sizeof *c);
    fv_camera_desc_default(&c->cam);
    fv_sampling_params_default(&c->samp);
    c->samp.rotate = 1;
    fv_taa_params_default(&c->taa);
    fv_dof_params_default(&c->dof);
    fv_dofsamp_params_default(&c->dofsamp);
    c->threads = 0;
    c->isa_mask = ~0u;
}

fv_pipeline *fv_pipeline_create(const fv_scene *scene, const fv_pipeline_config *cfg, char *err, size_t err_len)
{
    fv_pipeline *p = calloc(1, sizeof *p);
    if (!p) {
        fv_err(err, err_len, "out of memory");
        return NULL;
    }
    p->scene = scene;
    p->cfg = *cfg;
    static const fv_pose origin = {{0, 0, 0}, {0, 0, 0, 1}};
    if (fv_camera_setup(&p->eyes[0].cam, &cfg->cam, &origin)) {
        fv_err(err, err_len, "eye size %dx%d or vertical FOV %g deg out of range", cfg->cam.width, cfg->cam.height,
             (double)cfg->cam.fov_y_deg);
        goto bad;
    }
    if (!(cfg->taa.alpha_min > 0.0f && cfg->taa.alpha_min <= 1.0f && cfg->taa.depth_tol > 0.0f)) {
        fv_err(err, err_len, "reprojection parameters out of range: need 0 < alpha_min <= 1, depth_tol > 0");
        goto bad;
    }
    p->taa = cfg->taa.enabled && !cfg->samp.full;
    fv_sampling_params sp = cfg->samp;
    /* a rotating pattern without history filling its holes would only flicker */
    sp.rotate = sp.rotate && p->taa && cfg->taa.fill;
    if (fv_sampler_init(&p->smp, cfg->cam.width, cfg->cam.height, p->eyes[0].cam.focal_px, &sp)) {
        fv_err(err, err_len, "sampling parameters out of range: need 0 < r0 <= r1 <= 90 deg, 0 < p_min <= 1");
        goto bad;
    }
    p->smp_cur = &p->smp;
    for (int e = 0; e < 2; e++)
        for (int b = 0; b < (p->taa ? 2 : 1); b++)
            if (fv_pyramid_init(&p->eyes[e].pyr[b], cfg->cam.width, cfg->cam.height)) {
                fv_err(err, err_len, "out of memory for a %dx%d pyramid", cfg->cam.width, cfg->cam.height);
                goto bad;
            }
    p->aa = p->taa && cfg->taa.fovea_aa;
    for (int e = 0; e < 2 && p->aa; e++)
        for (int b = 0; b < 2; b++)
            if (!(p->eyes[e].aa_n[b] = calloc((size_t)cfg->cam.width * (size_t)cfg->cam.height, 1))) {
                fv_err(err, err_len, "out of memory");
                goto bad;
            }
    for (int e = 0; e < 2; e++)
        if (!(p->eyes[e].rgb8 = calloc((size_t)cfg->cam.width * (size_t)cfg->cam.height, 3))) {
            fv_err(err, err_len, "out of memory for a %dx%d output image", cfg->cam.width, cfg->cam.height);
            goto bad;
        }
    p->t_ns = INT64_MIN;
    p->eyes[0].last_t_ns = p->eyes[1].last_t_ns = INT64_MIN;
    p->dof = cfg->dof.preset != FV_DOF_NONE;
    if (p->dof) {
        const fv_dof_params *dp = &cfg->dof;
        if ((unsigned)dp->model >= FV_DOF_MODEL_COUNT || (unsigned)dp->preset >= FV_DOF_PRESET_COUNT ||
            !(dp->pupil_mm > 0.0f && dp->pupil_mm <= 20.0f) || !(dp->tolerance_m >= 0.0f) ||
            !(dp->contrast_gain >= 0.0f && dp->contrast_gain <= 4.0f) || !(dp->focus.error_deg >= 0.0f) ||
            !(dp->focus.tau_ms >= 0.0f) || !(dp->focus.fixed_m >= 0.0f)) {
            fv_err(err, err_len, "depth-of-field parameters out of range");
            goto bad;
        }
        p->dof_fn = fv_dof_models[dp->model].run;
        if (!p->dof_fn) {
            fv_err(err, err_len, "depth-of-field model '%s' is not built", fv_dof_models[dp->model].name);
            goto bad;
        }
        const fv_pyr_level *l0 = &p->eyes[0].pyr[0].lv[0];
        if (fv_dof_work_init(&p->dof_work, l0->w, l0->h, l0->stride)) {
            fv_err(err, err_len, "out of memory for depth-of-field buffers");
            goto bad;
        }
        /* the float image: asked for, or a model without the fused output (a lens's chromatic
         * aberration, which reads other rows, adds it at the first frame with the lens) */
        const int need_out = cfg->keep_image || dp->model != FV_DOF_MODEL_WEIER;
        for (int e = 0; e < 2; e++) {
            fv_focus_init(&p->eyes[e].focus, &dp->focus);
            if (need_out && !(p->eyes[e].out = malloc(image_bytes(l0)))) {
                fv_err(err, err_len, "out of memory for depth-of-field buffers");
                goto bad;
            }
        }
        /* DoF-driven sampling needs the history's depth, so reprojection */
        p->dofsamp = cfg->dofsamp.enabled && p->taa;
        if (p->dofsamp && !(cfg->dofsamp.kappa > 0.0f && cfg->dofsamp.coc_cap_px >= cfg->dofsamp.kappa)) {
            fv_err(err, err_len, "DoF sampling parameters out of range: need kappa > 0, CoC cap >= kappa");
            goto bad;
        }
        for (int e = 0; e < 2 && p->dofsamp; e++)
            if (!(p->eyes[e].rows = malloc(rows_bytes(&cfg->cam)))) {
                fv_err(err, err_len, "out of memory");
                goto bad;
            }
        if (p->dofsamp && !(p->dofsamp_map = malloc(fv_dofsamp_map_len(&p->eyes[0].pyr[0]) * sizeof(float)))) {
            fv_err(err, err_len, "out of memory");
            goto bad;
        }
        if (!cfg->samp.full) {
            /* Patney's enhancement kernel: the footprint of one sample, 1 / sqrt(density), per 4 px */
            const float diag = sqrtf((float)cfg->cam.width * cfg->cam.width + (float)cfg->cam.height * cfg->cam.height);
            p->enh_n = (int)(diag / 4.0f) + 2;
            if (!(p->enh_fp = malloc((size_t)p->enh_n * sizeof(float)))) {
                fv_err(err, err_len, "out of memory");
                goto bad;
            }
            p->enh_for = NULL; /* filled for the sampler in force at the first frame */
        }
    }
    p->pool = fv_pool_create(cfg->threads);
    if (!p->pool) {
        fv_err(err, err_len, "cannot start %d worker threads", cfg->threads);
        goto bad;
    }
    fv_render_dsp_init(&p->dsp, cfg->isa_mask);
    fv_output_conv_init(&p->conv, cfg->isa_mask);
    return p;
bad:
    fv_pipeline_destroy(p);
    return NULL;
}

void fv_pipeline_destroy(fv_pipeline *p)
{
    if (!p)
        return;
    fv_pool_destroy(p->pool);
    for (int k = 0; k < FOVEA_STEPS; k++)
        fv_sampler_free(&p->wide[k]);
    fv_sampler_free(&p->smp);
    for (int e = 0; e < 2; e++) {
        for (int b = 0; b < 2; b++)
            fv_pyramid_free(&p->eyes[e].pyr[b]);
        free(p->eyes[e].out);
        free(p->eyes[e].lca);
        free(p->eyes[e].lmap);
        free(p->eyes[e].rgb8);
        free(p->eyes[e].rows);
        free(p->eyes[e].aa_n[0]);
        free(p->eyes[e].aa_n[1]);
        free(p->eyes[e].aa_snap);
    }
    fv_dof_work_free(&p->dof_work);
    free(p->dofsamp_map);
    free(p->dofsamp_map_r);
    free(p->enh_fp);
    free(p);
}

static inline int slot(fv_eye eye) { return eye == FV_EYE_RIGHT ? 1 : 0; }

void fv_pipeline_reset_history(fv_pipeline *p)
{
    for (int e = 0; e < 2; e++) {
        p->eyes[e].hist_valid = 0;
        if (p->dof)
            fv_focus_init(&p->eyes[e].focus, &p->cfg.dof.focus);
    }
}

void fv_pipeline_set_time_ns(fv_pipeline *p, int64_t t_ns) { p->t_ns = t_ns; }

/* DoF-driven sampling's defocus map, in row bands over the pool (each band its own rows) */
#define DOFSAMP_BANDS 16
static void dofsamp_map_band(void *ctx, int band, int thread_id)
{
    (void)thread_id;
    const fv_dofsamp_frame *f = ctx;
    fv_dofsamp_map_rows(f, f->map_h * band / DOFSAMP_BANDS, f->map_h * (band + 1) / DOFSAMP_BANDS);
}

/* The focus estimator's view of the reconstruction: level 0's depth at the nearest pixel. */
static float pyr_depth(void *ctx, float x, float y)
{
    const fv_pyr_level *l0 = ctx;
    const int i = (int)floorf(x), j = (int)floorf(y);
    if (i < 0 || j < 0 || i >= l0->w || j >= l0->h)
        return NAN;
    return l0->rgbd[4 * ((ptrdiff_t)j * l0->stride + i) + 3];
}

/* Focus depth, CoC, filter, combine of one eye into es->out. 1 when the model also wrote the
 * display format (the output stage fused into its last pass), else 0. */
static int render_dof(fv_pipeline *p, eye_state *es, fv_eye eye, const fv_pyramid *pyr, float gaze_x,
                       float gaze_y, fv_frame_stats *st)
{
    const fv_pyr_level *l0 = &pyr->lv[0];
    const fv_dof_params *dp = &p->cfg.dof;
    /* elapsed time since this eye's last frame */
    float dt_ms = 1000.0f / 90.0f;
    if (p->t_ns != INT64_MIN) {
        if (es->last_t_ns != INT64_MIN && p->t_ns > es->last_t_ns)
            dt_ms = (float)((double)(p->t_ns - es->last_t_ns) * 1e-6);
        es->last_t_ns = p->t_ns;
    }
    const float gx = gaze_x * (float)l0->w, gy = gaze_y * (float)l0->h;
    const float ppd = es->cam.focal_px * 0.017453292f;
    /* the focus estimate is part of the CoC stage (Weier's Table 1 has no row of its own) */
    const int64_t t0 = fv_prof_stage_begin(p->prof, FV_STAGE_COC);
    const float focus_m = fv_focus_update(&es->focus, pyr_depth, (void *)l0, gx, gy, ppd, dt_ms);
    st->focus_m = focus_m;
    const double focus_ms = (double)(fv_prof_stage_end(p->prof, FV_STAGE_COC, t0, (int)eye) - t0) * 1e-6;
    if (!(focus_m > 0.0f)) { /* no depth under the gaze yet: nothing to focus on, show it sharp */
        if (!es->out) { /* the pipeline converts level 0 itself */
            st->stage_ms[FV_STAGE_COC] = focus_ms;
            return 0;
        }
        for (int y = 0; y < l0->h; y++)
            memcpy(es->out + 4 * (ptrdiff_t)y * l0->stride, l0->rgbd + 4 * (ptrdiff_t)y * l0->stride,
                   (size_t)l0->w * 4 * sizeof(float));
        st->stage_ms[FV_STAGE_COC] = focus_ms;
        return 0;
    }
    if (p->enh_fp && p->enh_for != p->smp_cur) {
        for (int i = 0; i < p->enh_n; i++) {
            const float pr = fv_sampler_probability(p->smp_cur, 4.0f * (float)i, 0.0f);
            p->enh_fp[i] = pr > 0.0f ? 1.0f / sqrtf(pr) : 1.0f;
        }
        p->enh_for = p->smp_cur;
    }
    fv_dof_view v = {
        .pyr = pyr,
        .focus_m = focus_m,
        .focal_px = es->cam.focal_px,
        .blur_scale = fv_dof_presets[dp->preset].e_scale,
        .gaze_x = gx,
        .gaze_y = gy,
        .r0_px = p->smp_cur->r0_px, /* the fovea in force (widened when the gaze is doubtful) */
        .r1_px = p->smp_cur->r1_px,
        .prm = dp,
        .enh_fp = p->enh_fp,
        .enh_n = p->enh_n,
        .enh_step = 4.0f,
        .prof = p->prof,
        .prof_arg = (int)eye,
        /* the lens's chromatic aberration reads other rows: then the output is a pass of its own */
        .conv = es->lca && es->lca->on ? NULL : &p->conv,
        .rgb8 = es->rgb8,
        .rgb8_stride = (ptrdiff_t)l0->w * 3,
    };
    v.e_px_per_mm = fv_retina_px_per_mm(v.focal_px, FV_EYE_IMAGE_DIST_MM) * v.blur_scale;
    fv_dof_times t = {NAN, NAN, NAN, NAN};
    p->dof_fn(&v, &p->dof_work, es->out, l0->stride, p->pool, &p->dsp.dof, &t);
    st->stage_ms[FV_STAGE_COC] = (isnan(t.coc_ms) ? 0.0 : t.coc_ms) + focus_ms;
    st->stage_ms[FV_STAGE_DOF_FILTER] = t.filter_ms;
    st->stage_ms[FV_STAGE_COMBINE] = t.combine_ms;
    st->stage_ms[FV_STAGE_OUTPUT] = t.output_ms;
    return !isnan(t.output_ms);
}

void fv_pipeline_set_prof(fv_pipeline *p, fv_prof *prof)
{
    p->prof = prof;
    fv_pool_set_prof(p->pool, prof);
}

/* One eye's frame between its set-up and its tile pass (the stereo path runs both eyes' set-ups,
 * then their tiles as one pool job, then each eye's remaining stages). */
typedef struct {
    eye_state *es;
    fv_eye eye;
    int dst; /* the pyramid rendered into */
    fv_pyramid *pyr;
    float gaze_x, gaze_y;
    int gx, gy;
    fv_taa_frame tf;
    fv_dofsamp_frame dsf;
    fv_taa_aa_frame aaf;
    fv_tile_opts opt; /* points into tf, dsf, aaf and shade_ns */
    int64_t shade_ns; /* the workers' time shading, when the config asks (time_shading) */
    int64_t t0, tc0;  /* the frame's and the ray stage's span starts (single-eye path) */
    double snap_ms;   /* the still head's AA snapshot (reprojection time before the tiles) */
} eye_frame;

/* The eye's camera, reprojection and DoF-sampling set-up (its defocus map into map). */
static int eye_begin(fv_pipeline *p, eye_frame *f, fv_eye eye, const fv_pose *head, float gaze_x, float gaze_y,
                     float *map, int spans, fv_frame_stats *st)
{
    eye_state *es = &p->eyes[slot(eye)];
    memset(f, 0, sizeof *f);
    f->es = es, f->eye = eye, f->gaze_x = gaze_x, f->gaze_y = gaze_y;
    fv_camera_desc d = p->cfg.cam;
    d.eye = eye;
    if (fv_camera_setup(&es->cam, &d, head))
        return -1;
    if (es->cam.lens_on && !es->lca) /* built once: the lens does not change */
        es->lca = fv_output_lca_create(&es->cam);
    if (p->dof && !es->out && es->lca && es->lca->on && !(es->out = malloc(image_bytes(&es->pyr[0].lv[0]))))
        return -1; /* the lens's output is a pass of its own, from the float image */
    if (p->taa && es->cam.lens_on && !es->lmap) { /* built once: the lens does not change */
        if (!(es->lmap = malloc(sizeof *es->lmap)))
            return -1;
        fv_lens_map_init(es->lmap, &es->cam);
    }
    for (int i = 0; i < FV_STAGE_COUNT; i++)
        st->stage_ms[i] = NAN;
    st->shade_ms = NAN;
    /* with reprojection, render into the other pyramid and read this one as history */
    f->dst = p->taa ? es->cur ^ 1 : 0;
    f->pyr = &es->pyr[f->dst];
    f->opt = (fv_tile_opts){.phase = p->taa ? (int)(es->frame % p->smp_cur->phases) : 0, .taa_prm = &p->cfg.taa,
                            .prof = p->prof, .shade_ns = p->cfg.time_shading ? &f->shade_ns : NULL};
    if (spans) /* the DoF-sampling map counts in the ray stage's time */
        f->t0 = fv_prof_stage_begin(p->prof, FV_PROF_FRAME), f->tc0 = fv_prof_stage_begin(p->prof, FV_STAGE_TRACE);
    /* The S_in pattern moves by whole pixels with the point of regard. */
    f->gx = (int)floorf(gaze_x * (float)d.width), f->gy = (int)floorf(gaze_y * (float)d.height);
    if (p->taa && es->hist_valid) {
        fv_taa_frame_setup(&f->tf, &es->cam, &es->prev_cam, &es->pyr[es->cur], p->cfg.taa.depth_tol);
        if (es->lmap)
            fv_taa_frame_set_lens(&f->tf, es->lmap);
        f->opt.taa = &f->tf;
        /* The focus this frame is not estimated yet (it needs this frame's depth): the eye
         * accommodates from last frame's focus towards last frame's target, so the frame's focus
         * lies between them unless the target jumps (a saccade to another depth, then the focus
         * moves 1 - exp(-dt / tau) of the way: 3 % at 90 Hz). */
        if (p->dofsamp && es->focus.valid) {
            const fv_dof_params *dp = &p->cfg.dof;
            const float fa = 1.0f / fmaxf(es->focus.focus_dpt, 1e-6f), fb = 1.0f / fmaxf(es->focus.target_dpt, 1e-6f);
            fv_dofsamp_frame_setup(&f->dsf, &p->cfg.dofsamp, &f->tf, p->smp_cur, f->gx, f->gy, fa, fb, dp->tolerance_m,
                                   dp->pupil_mm * 1e-3f * es->cam.focal_px * fv_dof_presets[dp->preset].e_scale,
                                   (uint32_t)es->frame, f->opt.phase);
            fv_dofsamp_map_attach(&f->dsf, map);
            fv_pool_run(p->pool, DOFSAMP_BANDS, dofsamp_map_band, &f->dsf);
            f->opt.dofs = &f->dsf;
            f->opt.rows_out = es->rows;
        }
    }
    es->rows_valid = f->opt.dofs != NULL;
    /* fovea anti-aliasing: this frame's point in the pixels, the counts next to the pyramids */
    if (p->aa) {
        f->aaf.n_prev = es->hist_valid ? es->aa_n[es->cur] : NULL;
        f->aaf.n_cur = es->aa_n[f->dst];
        f->aaf.stride = d.width;
        fv_sampling_jitter((uint32_t)es->frame, &f->aaf.ox, &f->aaf.oy);
        f->opt.aa = &f->aaf;
    }
    /* The head still (identical cameras): render over the history's level 0 in place instead of
     * copying it into the other pyramid (core/reproject.h, fv_taa_still_*). The pyramids swap
     * their level-0 planes, so pyr[dst] gets the history's; their coarser levels stay apart (the
     * still blend reads the history's). The AA tiles read a copy of theirs. */
    if (p->taa && es->hist_valid && f->tf.identity && p->cfg.taa.in_place && p->cfg.taa.fill) {
        const int64_t ts0 = fv_time_ns();
        if (p->aa && fv_taa_aa_snapshot(&f->aaf, &es->pyr[es->cur].lv[0], p->smp_cur, f->gx, f->gy, FV_TILE,
                                        &es->aa_snap, &es->aa_snap_cap))
            return -1;
        const fv_pyr_level l0 = es->pyr[es->cur].lv[0];
        es->pyr[es->cur].lv[0] = es->pyr[f->dst].lv[0];
        es->pyr[f->dst].lv[0] = l0;
        f->opt.still = 1;
        f->snap_ms = (double)(fv_time_ns() - ts0) * 1e-6; /* reprojection's, though outside the tiles */
    }
    return 0;
}

/* The eye's stages after its tiles: pull-push, depth of field, output; its history advanced. */
static void eye_finish(fv_pipeline *p, eye_frame *f, fv_frame_stats *st)
{
    eye_state *es = f->es;
    const fv_eye eye = f->eye;
    fv_pyramid *pyr = f->pyr;
    const int64_t tr0 = fv_prof_stage_begin(p->prof, FV_STAGE_RECONSTRUCT);
    /* the first levels were pulled by the ray-casting tiles (their cost is in the trace time) */
    fv_pullpush_from(pyr, &p->dsp.pp, p->pool, fv_tile_pulled_levels(pyr));
    const int64_t t2 = fv_prof_stage_end(p->prof, FV_STAGE_RECONSTRUCT, tr0, (int)eye);
    st->stage_ms[FV_STAGE_RECONSTRUCT] = (double)(t2 - tr0) * 1e-6;
    st->focus_m = NAN;
    const int converted = p->dof && render_dof(p, es, eye, pyr, f->gaze_x, f->gaze_y, st);
    /* output: the display format, every frame (a headset pays for it each refresh), unless the
     * depth of field wrote it row by row in its last pass */
    if (!converted) {
        const int64_t to0 = fv_prof_stage_begin(p->prof, FV_STAGE_OUTPUT);
        const fv_pyr_level *l0 = &pyr->lv[0];
        const float *img = p->dof && es->out ? es->out : l0->rgbd;
        fv_output_convert_pool(&p->conv, img, l0->stride, l0->w, l0->h, &es->cam, es->lca, es->rgb8,
                               (ptrdiff_t)l0->w * 3, p->pool);
        st->stage_ms[FV_STAGE_OUTPUT] =
            (double)(fv_prof_stage_end(p->prof, FV_STAGE_OUTPUT, to0, (int)eye) - to0) * 1e-6;
    }
    es->cur = f->dst;
    es->prev_cam = es->cam;
    es->hist_valid = 1;
    es->frame++;
}

/* The ray stage's time (cast_ms, its reprojection share taa_ms, the workers' shading time
 * shade_ns) into the stats */
static void trace_stats(const fv_pipeline *p, fv_frame_stats *st, double cast_ms, double taa_ms, int64_t shade_ns)
{
    st->shade_ms = p->cfg.time_shading ? (double)shade_ns * 1e-6 / fv_pool_threads(p->pool) : NAN;
    /* reprojection runs inside the ray-casting tiles: its share is the workers' time in it */
    if (p->taa) {
        if (isnan(taa_ms))
            taa_ms = 0.0; /* first frame: no history yet */
        st->stage_ms[FV_STAGE_REPROJECT] = taa_ms;
        st->stage_ms[FV_STAGE_TRACE] = cast_ms - taa_ms;
    } else {
        st->stage_ms[FV_STAGE_TRACE] = cast_ms;
    }
}

int fv_pipeline_render(fv_pipeline *p, fv_eye eye, const fv_pose *head, float gaze_x, float gaze_y,
                       fv_frame_stats *st)
{
    eye_frame f;
    if (eye_begin(p, &f, eye, head, gaze_x, gaze_y, p->dofsamp_map, 1, st))
        return -1;
    const int64_t t0 = f.t0, tc0 = f.tc0;
    double taa_ms = NAN;
    st->samples = fv_tile_pass(p->scene, &f.es->cam, p->smp_cur, f.gx, f.gy, f.pyr, &p->dsp, p->pool, &f.opt, &taa_ms);
    const int64_t t1 = fv_prof_stage_end(p->prof, FV_STAGE_TRACE, tc0, (int)eye);
    eye_finish(p, &f, st);
    const int64_t t3 = fv_prof_stage_end(p->prof, FV_PROF_FRAME, t0, (int)eye);
    trace_stats(p, st, (double)(t1 - tc0) * 1e-6, taa_ms + f.snap_ms, f.shade_ns); /* the snapshot is inside */
    st->total_ms = (double)(t3 - t0) * 1e-6;
    return 0;
}

int fv_pipeline_render_stereo(fv_pipeline *p, const fv_pose *head, float gaze_x, float gaze_y, fv_frame_stats st[2])
{
    /* the right eye's defocus map: its own, as its tiles read it while the left eye's stages run */
    if (p->dofsamp && !p->dofsamp_map_r &&
        !(p->dofsamp_map_r = malloc(fv_dofsamp_map_len(&p->eyes[1].pyr[0]) * sizeof(float))))
        return -1;
    eye_frame f[2];
    const int64_t t0 = fv_prof_stage_begin(p->prof, FV_PROF_FRAME); /* the pair's (arg FV_PIPELINE_PAIR) */
    for (int e = 0; e < 2; e++)
        if (eye_begin(p, &f[e], e ? FV_EYE_RIGHT : FV_EYE_LEFT, head, gaze_x, gaze_y,
                      e ? p->dofsamp_map_r : p->dofsamp_map, 0, &st[e]))
            return -1;
    fv_tile_eye te[2];
    for (int e = 0; e < 2; e++)
        te[e] = (fv_tile_eye){.cam = &f[e].es->cam, .gx = f[e].gx, .gy = f[e].gy, .pyr = f[e].pyr, .opt = f[e].opt};
    /* The right eye's tiles are the pool's background job: workers take them whenever the left
     * eye's passes leave them nothing to do (its tile pass's tail, the serial and barrier parts
     * of its pull-push, DoF and output). They touch only the right eye's pyramids, sample bits
     * and defocus map; the left eye's stages touch none of those. */
    fv_tile_async *bg = fv_tile_pass_post(p->scene, p->smp_cur, &p->dsp, p->pool, &te[1]);
    if (!bg)
        return -1;
    const int64_t tc0 = fv_prof_stage_begin(p->prof, FV_STAGE_TRACE);
    double taa_ms = NAN;
    st[0].samples = fv_tile_pass(p->scene, te[0].cam, p->smp_cur, te[0].gx, te[0].gy, te[0].pyr, &p->dsp, p->pool,
                                 &te[0].opt, &taa_ms);
    const int64_t t1 = fv_prof_stage_end(p->prof, FV_STAGE_TRACE, tc0, FV_EYE_LEFT);
    trace_stats(p, &st[0], (double)(t1 - tc0) * 1e-6 + f[0].snap_ms, taa_ms + f[0].snap_ms, f[0].shade_ns);
    eye_finish(p, &f[0], &st[0]);
    const int64_t tl = fv_time_ns();
    st[0].total_ms = (double)(tl - t0) * 1e-6;
    /* the right eye's tiles left (the caller takes them too), then its stages */
    const int64_t tw0 = fv_prof_stage_begin(p->prof, FV_STAGE_TRACE);
    fv_tile_pass_wait(bg, p->pool, &te[1]);
    fv_prof_stage_end(p->prof, FV_STAGE_TRACE, tw0, FV_EYE_RIGHT);
    st[1].samples = te[1].rays;
    /* its ray stage ran beside the left eye's stages: the workers' time in its tiles over the threads */
    trace_stats(p, &st[1], te[1].tile_ms / fv_pool_threads(p->pool) + f[1].snap_ms, te[1].taa_ms + f[1].snap_ms,
                f[1].shade_ns);
    eye_finish(p, &f[1], &st[1]);
    const int64_t t3 = fv_prof_stage_end(p->prof, FV_PROF_FRAME, t0, FV_PIPELINE_PAIR);
    st[1].total_ms = (double)(t3 - tl) * 1e-6;
    return 0;
}

const fv_pyramid *fv_pipeline_pyramid(const fv_pipeline *p, fv_eye eye)
{
    const eye_state *es = &p->eyes[slot(eye)];
    return &es->pyr[es->cur];
}
const fv_camera *fv_pipeline_camera(const fv_pipeline *p, fv_eye eye) { return &p->eyes[slot(eye)].cam; }
const fv_sampler *fv_pipeline_sampler(const fv_pipeline *p) { return p->smp_cur; }
const uint32_t *fv_pipeline_last_rows(const fv_pipeline *p, fv_eye eye)
{
    const eye_state *es = &p->eyes[slot(eye)];
    return es->rows_valid ? es->rows : NULL;
}
int fv_pipeline_last_phase(const fv_pipeline *p, fv_eye eye)
{
    const eye_state *es = &p->eyes[slot(eye)];
    return p->taa && es->frame > 0 ? (int)((es->frame - 1) % p->smp_cur->phases) : 0;
}

int fv_pipeline_set_fovea_scale(fv_pipeline *p, float scale)
{
    /* NaN: as doubtful as it gets (fv_fovea_radius_scale's convention) */
    const float s = scale == scale ? scale : 2.0f;
    const int k = s <= 1.0f ? 0 : s >= 2.0f ? FOVEA_STEPS : (int)lrintf((s - 1.0f) * FOVEA_STEPS);
    if (k == 0 || p->cfg.samp.full) { /* full sampling has no fovea to widen */
        p->smp_cur = &p->smp;
        p->fovea_step = 0;
        return 0;
    }
    fv_sampler *w = &p->wide[k - 1];
    if (!w->s_in) {
        fv_sampling_params sp = p->smp.prm; /* as created (rotation decided there) */
        const float f = 1.0f + (float)k / FOVEA_STEPS;
        sp.r1_deg = fminf(90.0f, sp.r1_deg * f);
        sp.r0_deg = fminf(sp.r1_deg, sp.r0_deg * f);
        if (fv_sampler_init(w, p->smp.width, p->smp.height, p->eyes[0].cam.focal_px, &sp))
            return -1; /* the scale in force stays */
    }
    p->smp_cur = w;
    p->fovea_step = k;
    return 0;
}

float fv_pipeline_fovea_scale(const fv_pipeline *p) { return 1.0f + (float)p->fovea_step / FOVEA_STEPS; }
fv_pool *fv_pipeline_pool(fv_pipeline *p) { return p->pool; }
const fv_render_dsp *fv_pipeline_dsp(const fv_pipeline *p) { return &p->dsp; }

const float *fv_pipeline_image(const fv_pipeline *p, fv_eye eye, ptrdiff_t *stride)
{
    const fv_pyr_level *l0 = &fv_pipeline_pyramid(p, eye)->lv[0];
    *stride = l0->stride;
    return p->dof ? p->eyes[slot(eye)].out : l0->rgbd;
}

static size_t pyramid_bytes(const fv_pyramid *p)
{
    size_t n = 0;
    for (int l = 0; p->mem && l < p->levels; l++)
        n += (size_t)p->lv[l].stride * (size_t)p->lv[l].h * 5 * sizeof(float); /* rgbd + weight */
    return n;
}

void fv_pipeline_memory_bytes(const fv_pipeline *p, fv_eye eye, fv_pipeline_memory *m)
{
    const eye_state *es = &p->eyes[slot(eye)];
    memset(m, 0, sizeof *m);
    m->pyramids = pyramid_bytes(&es->pyr[0]) + pyramid_bytes(&es->pyr[1]);
    m->image = es->out ? image_bytes(&es->pyr[0].lv[0]) : 0;
    m->display = (size_t)p->cfg.cam.width * (size_t)p->cfg.cam.height * 3;
    m->other = (es->rows ? rows_bytes(&p->cfg.cam) : 0) +
               (es->aa_n[0] ? 2 * (size_t)p->cfg.cam.width * (size_t)p->cfg.cam.height : 0) +
               es->aa_snap_cap * sizeof(float);
    if (p->dof) {
        const fv_dof_work *wk = &p->dof_work;
        m->shared = (size_t)wk->stride * (size_t)wk->h * (4 * FV_DOF_PLANES4 + FV_DOF_PLANES1) * sizeof(float) +
                    (wk->aux_len + wk->rows_len) * sizeof(float) +
                    (p->dofsamp_map ? fv_dofsamp_map_len(&es->pyr[0]) * sizeof(float) : 0) +
                    (p->dofsamp_map_r ? fv_dofsamp_map_len(&es->pyr[0]) * sizeof(float) : 0);
    }
}

const float *fv_pipeline_depth(const fv_pipeline *p, fv_eye eye, ptrdiff_t *stride)
{
    const fv_pyr_level *l0 = &fv_pipeline_pyramid(p, eye)->lv[0];
    *stride = l0->stride;
    return l0->rgbd;
}

const uint8_t *fv_pipeline_rgb8(const fv_pipeline *p, fv_eye eye, ptrdiff_t *stride)
{
    *stride = (ptrdiff_t)p->cfg.cam.width * 3;
    return p->eyes[slot(eye)].rgb8;
}

void fv_pipeline_to_rgb8(const fv_pipeline *p, fv_eye eye, uint8_t *dst, ptrdiff_t dst_stride)
{
    ptrdiff_t stride;
    const uint8_t *src = fv_pipeline_rgb8(p, eye, &stride);
    for (int y = 0; y < p->cfg.cam.height; y++)
        memcpy(dst + y * dst_stride, src + y * stride, (size_t)stride);
}
