#include "pipeline.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "raycast.h"
#include "err.h"

const char *const fv_stage_names[FV_STAGE_COUNT] = {"trace", "reproject", "reconstruct", "coc", "dof_filter", "combine"};

#define SRGB_LUT 4096

typedef struct {
    fv_camera cam;
    fv_pyramid pyr;
} eye_state;

struct fv_pipeline {
    const fv_scene *scene;
    fv_pipeline_config cfg;
    fv_pool *pool;
    fv_dsp dsp;
    fv_sampler smp;
    eye_state eyes[2];
    uint8_t srgb[SRGB_LUT + 1]; /* linear [0,1] -> sRGB 8-bit */
};

int64_t fv_time_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

void fv_pipeline_config_default(fv_pipeline_config *c)
{
    memset(c, 0, sizeof *c);
    fv_camera_desc_default(&c->cam);
    fv_sampling_params_default(&c->samp);
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
    if (fv_sampler_init(&p->smp, cfg->cam.width, cfg->cam.height, p->eyes[0].cam.focal_px, &cfg->samp)) {
        fv_err(err, err_len, "sampling parameters out of range: need 0 < r0 <= r1 <= 90 deg, 0 < p_min <= 1");
        goto bad;
    }
    for (int e = 0; e < 2; e++)
        if (fv_pyramid_init(&p->eyes[e].pyr, cfg->cam.width, cfg->cam.height)) {
            fv_err(err, err_len, "out of memory for a %dx%d pyramid", cfg->cam.width, cfg->cam.height);
            goto bad;
        }
    p->pool = fv_pool_create(cfg->threads);
    if (!p->pool) {
        fv_err(err, err_len, "cannot start %d worker threads", cfg->threads);
        goto bad;
    }
    fv_dsp_init(&p->dsp, cfg->isa_mask);
    for (int i = 0; i <= SRGB_LUT; i++) {
        double v = (double)i / SRGB_LUT;
        double s = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
        p->srgb[i] = (uint8_t)(s * 255.0 + 0.5);
    }
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
    fv_sampler_free(&p->smp);
    for (int e = 0; e < 2; e++)
        fv_pyramid_free(&p->eyes[e].pyr);
    free(p);
}

static inline int slot(fv_eye eye) { return eye == FV_EYE_RIGHT ? 1 : 0; }

int fv_pipeline_render(fv_pipeline *p, fv_eye eye, const fv_pose *head, float gaze_x, float gaze_y,
                       fv_frame_stats *st)
{
    eye_state *es = &p->eyes[slot(eye)];
    fv_camera_desc d = p->cfg.cam;
    d.eye = eye;
    if (fv_camera_setup(&es->cam, &d, head))
        return -1;
    for (int i = 0; i < FV_STAGE_COUNT; i++)
        st->stage_ms[i] = NAN;
    int64_t t0 = fv_time_ns();
    /* The S_in pattern moves by whole pixels with the point of regard. */
    int gx = (int)floorf(gaze_x * (float)d.width), gy = (int)floorf(gaze_y * (float)d.height);
    st->samples = fv_raycast(p->scene, &es->cam, &p->smp, gx, gy, &es->pyr, &p->dsp, p->pool);
    int64_t t1 = fv_time_ns();
    /* the first levels were pulled by the ray-casting tiles (their cost is in the trace time) */
    fv_pullpush_from(&es->pyr, &p->dsp, p->pool, fv_raycast_pulled_levels(&es->pyr));
    int64_t t2 = fv_time_ns();
    st->stage_ms[FV_STAGE_TRACE] = (double)(t1 - t0) * 1e-6;
    st->stage_ms[FV_STAGE_RECONSTRUCT] = (double)(t2 - t1) * 1e-6;
    st->total_ms = (double)(t2 - t0) * 1e-6;
    return 0;
}

const fv_pyramid *fv_pipeline_pyramid(const fv_pipeline *p, fv_eye eye) { return &p->eyes[slot(eye)].pyr; }
const fv_camera *fv_pipeline_camera(const fv_pipeline *p, fv_eye eye) { return &p->eyes[slot(eye)].cam; }
const fv_sampler *fv_pipeline_sampler(const fv_pipeline *p) { return &p->smp; }
fv_pool *fv_pipeline_pool(fv_pipeline *p) { return p->pool; }
const fv_dsp *fv_pipeline_dsp(const fv_pipeline *p) { return &p->dsp; }

void fv_pipeline_to_rgb8(const fv_pipeline *p, fv_eye eye, uint8_t *dst, ptrdiff_t dst_stride)
{
    const fv_pyr_level *l0 = &p->eyes[slot(eye)].pyr.lv[0];
    for (int y = 0; y < l0->h; y++) {
        const float *s = l0->rgbd + 4 * y * l0->stride;
        uint8_t *o = dst + y * dst_stride;
        for (int x = 0; x < l0->w; x++)
            for (int c = 0; c < 3; c++) {
                float v = s[4 * x + c];
                /* clamp before converting: NaN-free by construction, but never index out of range */
                int i = v > 0.0f ? (v < 1.0f ? (int)(v * SRGB_LUT + 0.5f) : SRGB_LUT) : 0;
                o[3 * x + c] = p->srgb[i];
            }
    }
}
