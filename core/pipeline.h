/* fovea: the per-eye frame pipeline (Weier et al. 2018): sample -> ray cast -> reproject (TAA)
 * -> pull-push reconstruction -> focus depth, CoC, DoF filter, combine (core/dof/dof.h; with
 * --dof none those stages do not run and their times are NAN: "-" in tables, null in JSON). */
#ifndef FOVEA_PIPELINE_H
#define FOVEA_PIPELINE_H

#include <stddef.h>
#include <stdint.h>
#include "camera.h"
#include "dof/dof.h"
#include "render_dsp.h"
#include "pool.h"
#include "pullpush.h"
#include "reproject.h"
#include "sampling.h"
#include "sampling_dof.h"
#include "scene.h"
#include "stage.h"

typedef struct fv_pipeline_config {
    fv_camera_desc cam;      /* size, vertical FOV, IPD, frustum shift */
    fv_sampling_params samp; /* r0, r1, p_min, full; rotate (default 1) with reprojection */
    fv_taa_params taa;       /* temporal reprojection (foveated only; full sampling needs none) */
    fv_dof_params dof;       /* depth of field (preset none: off) */
    fv_dofsamp_params dofsamp; /* DoF-driven sampling (with DoF and reprojection; default on) */
    int keep_image;          /* keep the final float image for fv_pipeline_image (tests, tools).
                              * 0 (default): with the layered DoF the combine's rows go straight to
                              * the display format and never to memory as floats (29.5 MB a
                              * 1280x1440 eye a frame saved) */
    int time_shading;        /* 1: time the shading inside the ray stage (fv_frame_stats.shade_ms,
                              * two clock reads a tile); 0 (default): not timed, shade_ms NAN */
    int threads;             /* 0 = online CPUs */
    unsigned isa_mask;       /* kernels allowed (FV_ISA_* bits); ~0u = the best this CPU runs */
} fv_pipeline_config;

typedef struct fv_frame_stats {
    double stage_ms[FV_STAGE_COUNT]; /* NAN for a stage that is not built */
    double total_ms;                 /* wall time of the whole frame */
    long samples;                    /* rays cast */
    double shade_ms;                 /* with cfg.time_shading: the workers' time shading hits inside
                                      * the ray stage over their count (comparable with its wall
                                      * time); else NAN */
    float focus_m;                   /* the accommodated focus distance (NAN without DoF) */
} fv_frame_stats;

typedef struct fv_pipeline fv_pipeline;

void fv_pipeline_config_default(fv_pipeline_config *c);
/* The scene must outlive the pipeline. NULL with a reason in err on bad configuration. */
fv_pipeline *fv_pipeline_create(const fv_scene *scene, const fv_pipeline_config *cfg, char *err, size_t err_len);
void fv_pipeline_destroy(fv_pipeline *p);

/* Renders one eye (FV_EYE_CENTER and FV_EYE_LEFT share slot 0, FV_EYE_RIGHT has its own state)
 * from head pose `head` with the point of regard at normalised image coordinates (gaze_x, gaze_y). */
int fv_pipeline_render(fv_pipeline *p, fv_eye eye, const fv_pose *head, float gaze_x, float gaze_y,
                       fv_frame_stats *stats);
/* Renders both eyes (st[0] left, st[1] right) from one head pose and gaze, the same bytes as
 * fv_pipeline_render of FV_EYE_LEFT then FV_EYE_RIGHT. Both eyes' set-ups run first (camera,
 * reprojection, the DoF-driven sampling's defocus map: each eye its own), then the right eye's
 * ray-casting tiles go to the pool as its background job (fv_pool_post) while the left eye's
 * tiles, pull-push, depth of field and output run as usual: idle workers take right-eye tiles
 * wherever the left eye's passes leave them nothing to do, with no barrier between the eyes.
 * Then the right eye's remaining tiles, then its stages. Barriers left: each pass of an eye
 * (the per-eye stage order); the right eye's stages wait for its tiles; the two eyes' pull-push,
 * DoF and output passes run one eye after the other (they share the DoF scratch).
 * Stats: the left eye's as fv_pipeline_render's; the right eye's ray stage is the workers' time
 * in its tiles over the threads (it ran beside the left eye's stages); total_ms: left from the
 * pair's start to its output, right from there to the end (the two add up to the pair). Stage
 * spans: the pair's frame span carries arg FV_PIPELINE_PAIR. 0, or -1 (camera or memory). */
#define FV_PIPELINE_PAIR 3
int fv_pipeline_render_stereo(fv_pipeline *p, const fv_pose *head, float gaze_x, float gaze_y, fv_frame_stats st[2]);
/* The time of the frames rendered next (CLOCK_MONOTONIC or a trace's clock), for the focus
 * filter's accommodation. Without it every frame counts as 1/90 s after the last. */
void fv_pipeline_set_time_ns(fv_pipeline *p, int64_t t_ns);
/* Forgets both eyes' history (a cut, a teleport): the next frame starts afresh. */
void fv_pipeline_reset_history(fv_pipeline *p);
/* The eye's reconstruction pyramid after its last render (level 0 = the image). */
const fv_pyramid *fv_pipeline_pyramid(const fv_pipeline *p, fv_eye eye);
const fv_camera *fv_pipeline_camera(const fv_pipeline *p, fv_eye eye);
/* The sampling pattern in force (it changes with fv_pipeline_set_fovea_scale). */
const fv_sampler *fv_pipeline_sampler(const fv_pipeline *p);
/* The sampling phase the eye's last frame used (0 before its first frame, and without
 * reprojection): with fv_pipeline_sampler and the camera, the exact pixel set that frame traced
 * (the bench's ceiling retraces it). */
int fv_pipeline_last_phase(const fv_pipeline *p, fv_eye eye);
/* The sample bits the eye's last frame traced when DoF-driven sampling thinned them (tile i's
 * FV_TILE rows at [FV_TILE * i], tiles row-major; core/tile.h), else NULL: then the sampler and
 * the phase give them. */
const uint32_t *fv_pipeline_last_rows(const fv_pipeline *p, fv_eye eye);
/* Widens the fovea for the following frames (both eyes) when the gaze is doubtful: r0 and r1
 * times `scale` (r1 capped at 90 deg), the scale rounded to a step of 0.25 in [1, 2] (below 1:
 * 1; NaN: 2), as fv_fovea_radius_scale (eyetrack/gazefilter.h) gives it for the gaze filter's
 * confidence. Each step's sampling tables are built on its first use, here and not during a
 * frame, and kept until fv_pipeline_destroy: calling this every frame allocates nothing once
 * each step has been visited, and a step always gives the same pattern. No effect with full
 * sampling. 0 on success, -1 when there is no memory for the step's tables (the scale in force
 * stays). */
int fv_pipeline_set_fovea_scale(fv_pipeline *p, float scale);
float fv_pipeline_fovea_scale(const fv_pipeline *p); /* the step in force: 1 .. 2 */
fv_pool *fv_pipeline_pool(fv_pipeline *p);
/* Trace recorder (core/prof.h) for the following frames, NULL = off (the default): stage spans
 * (frame, trace, reconstruct, dof) on the stage tracks, pool jobs and ray-casting tiles on the
 * workers' tracks; its stage hook runs at every stage boundary. prof needs a slot per pool
 * thread (fv_pool_threads(fv_pipeline_pool(p))) and must outlive its use. */
struct fv_prof;
void fv_pipeline_set_prof(fv_pipeline *p, struct fv_prof *prof);
const fv_render_dsp *fv_pipeline_dsp(const fv_pipeline *p);

/* The bytes the pipeline keeps between frames (allocated; large planes the frame touches only in
 * part, such as the DoF centre's, become resident only there). */
typedef struct fv_pipeline_memory {
    size_t pyramids; /* per eye: the reconstruction pyramid and, with reprojection, its history
                      * (r, g, b, depth and a weight a texel, every level) */
    size_t image;    /* per eye: the final float image (fv_pipeline_config.keep_image; 0 without) */
    size_t display;  /* per eye: the display-format image */
    size_t other;    /* per eye: the last frame's sample bits (DoF-driven sampling), the fovea
                      * anti-aliasing's two sample-count planes (a byte a pixel each) */
    size_t shared;   /* both eyes together: DoF scratch planes, tables and row buffers, the
                      * DoF-driven sampling map */
} fv_pipeline_memory;
/* For the eye (its buffers exist from fv_pipeline_create or its first frame on). */
void fv_pipeline_memory_bytes(const fv_pipeline *p, fv_eye eye, fv_pipeline_memory *m);

/* The eye's last image (after depth of field, if on): 4 floats a pixel (linear r, g, b,
 * depth_m), rows *stride pixels apart. NULL when depth of field ran without a float image
 * (fv_pipeline_config.keep_image 0: the display format only). */
const float *fv_pipeline_image(const fv_pipeline *p, fv_eye eye, ptrdiff_t *stride);
/* The eye's last depth: level 0 of its reconstruction, 4 floats a pixel with depth_m in the
 * fourth (the final image's depth is the same), rows *stride pixels apart. Always there. */
const float *fv_pipeline_depth(const fv_pipeline *p, fv_eye eye, ptrdiff_t *stride);
/* The eye's last frame in the display format (the output stage: sRGB-encoded 8-bit RGB, the
 * lens's chromatic aberration resampled where set), rows *stride bytes apart; valid until the
 * eye's next render. */
const uint8_t *fv_pipeline_rgb8(const fv_pipeline *p, fv_eye eye, ptrdiff_t *stride);
/* A copy of it, rows of dst_stride bytes. */
void fv_pipeline_to_rgb8(const fv_pipeline *p, fv_eye eye, uint8_t *dst, ptrdiff_t dst_stride);

#endif
