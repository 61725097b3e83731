/* fovea platform: shared command-line helpers for the thin apps (number parsing with range
 * checks, the one-line usage error, the scene/eye/sampling options every renderer takes). */
#ifndef FOVEA_CLI_H
#define FOVEA_CLI_H

#include "camera.h"
#include "pipeline.h"

#define FV_EXIT_OK 0
#define FV_EXIT_FAIL 1
#define FV_EXIT_USAGE 2

/* Prints "PROG: message" and exits with status 2 (bad usage or bad input). */
_Noreturn void fv_usage_error(const char *prog, const char *fmt, ...);
_Noreturn void fv_fail(const char *prog, int status, const char *fmt, ...);
/* For getopt_long's '?': names the unknown option, or the one missing its argument; exits 2. */
_Noreturn void fv_bad_option(const char *prog, char **argv);

/* Strict parsers: the whole string must be a number in [lo, hi]; exit 2 naming the flag otherwise. */
long fv_arg_long(const char *prog, const char *flag, const char *s, long lo, long hi);
float fv_arg_float(const char *prog, const char *flag, const char *s, float lo, float hi);
int fv_arg_onoff(const char *prog, const char *flag, const char *s); /* "on" 1, "off" 0 */
void fv_arg_size(const char *prog, const char *flag, const char *s, int *w, int *h); /* WxH */

/* Options shared by fovea-replay and fovea-bench, parsed into a pipeline config.
 * Returns 1 if opt was one of them. */
enum {
    FV_OPT_SIZE = 1000, FV_OPT_THREADS, FV_OPT_FOV, FV_OPT_IPD, FV_OPT_R0, FV_OPT_R1, FV_OPT_PMIN, FV_OPT_ISA,
    FV_OPT_DOF, FV_OPT_DOF_MODEL, FV_OPT_REPROJECT, FV_OPT_TAA_ALPHA, FV_OPT_TAA_TOL, FV_OPT_TAA_FILL,
    FV_OPT_PATTERN, FV_OPT_FOCUS_M, FV_OPT_PUPIL_MM, FV_OPT_GAZE_ERR, FV_OPT_DOF_TOL, FV_OPT_ACCOMMODATION,
    FV_OPT_CONTRAST, FV_OPT_CHROMA,
    FV_OPT_SAMPLING, FV_OPT_LIU_DENSITY,
    FV_OPT_DOF_SAMPLING, FV_OPT_DOF_SAMPLING_KAPPA, /* depth-of-field-driven sampling */
    FV_OPT_FOVEA_AA, /* anti-aliasing in the fovea */
};
#define FV_COMMON_LONGOPTS                                                                     \
    {"size", required_argument, 0, FV_OPT_SIZE}, {"threads", required_argument, 0, FV_OPT_THREADS}, \
    {"fov", required_argument, 0, FV_OPT_FOV}, {"ipd", required_argument, 0, FV_OPT_IPD},         \
    {"r0", required_argument, 0, FV_OPT_R0}, {"r1", required_argument, 0, FV_OPT_R1},             \
    {"pmin", required_argument, 0, FV_OPT_PMIN}, {"isa", required_argument, 0, FV_OPT_ISA},        \
    {"dof", required_argument, 0, FV_OPT_DOF}, {"dof-model", required_argument, 0, FV_OPT_DOF_MODEL},   \
    {"reproject", required_argument, 0, FV_OPT_REPROJECT}, {"taa-alpha", required_argument, 0, FV_OPT_TAA_ALPHA}, \
    {"taa-depth-tol", required_argument, 0, FV_OPT_TAA_TOL}, {"taa-fill", required_argument, 0, FV_OPT_TAA_FILL}, \
    {"pattern", required_argument, 0, FV_OPT_PATTERN}, {"focus-m", required_argument, 0, FV_OPT_FOCUS_M}, \
    {"pupil-mm", required_argument, 0, FV_OPT_PUPIL_MM}, {"gaze-error-deg", required_argument, 0, FV_OPT_GAZE_ERR}, \
    {"dof-tolerance-m", required_argument, 0, FV_OPT_DOF_TOL},                                   \
    {"accommodation-ms", required_argument, 0, FV_OPT_ACCOMMODATION},                            \
    {"contrast-gain", required_argument, 0, FV_OPT_CONTRAST}, {"chroma", required_argument, 0, FV_OPT_CHROMA}, \
    {"sampling", required_argument, 0, FV_OPT_SAMPLING}, {"liu-density", required_argument, 0, FV_OPT_LIU_DENSITY}, \
    {"dof-sampling", required_argument, 0, FV_OPT_DOF_SAMPLING},                                 \
    {"dof-sampling-kappa", required_argument, 0, FV_OPT_DOF_SAMPLING_KAPPA},                     \
    {"fovea-aa", required_argument, 0, FV_OPT_FOVEA_AA}
#define FV_COMMON_HELP                                                                             \
    "  --size WxH         eye image size in pixels (default 1280x1440)\n"                          \
    "  --fov DEG          vertical field of view (default 100)\n"                                  \
    "  --ipd M            inter-pupillary distance in metres (default 0.063)\n"                    \
    "  --r0 DEG           fully sampled fovea radius (default 10)\n"                               \
    "  --r1 DEG           end of the transition region (default 20)\n"                             \
    "  --pmin P           peripheral sampling probability (default 0.2)\n"                         \
    "  --reproject on|off temporal reprojection (TAA) of the previous frame (default on;\n"       \
    "                     foveated only)\n"                                                     \
    "  --taa-alpha A      minimum weight of a new sample per frame of history (default 0.3)\n"  \
    "  --taa-depth-tol F  relative depth difference that rejects history (default 0.03)\n"     \
    "  --taa-fill on|off  fill pixels without a sample from valid history (default on)\n"      \
    "  --fovea-aa on|off  anti-aliasing in the fovea: its rays jittered inside the pixels\n"    \
    "                     over frames and accumulated by the reprojection (default on;\n"     \
    "                     needs reprojection)\n"                                              \
    "  --sampling weier|liu  sampling pattern: Weier's S_in/S_out (default) or Liu's polar\n"  \
    "                     acuity grid (eq. 1-3), at Weier's ray count for r0, r1, pmin\n"     \
    "  --liu-density L    liu: samples per pixel where eq. 1 is flat (>= 1; default 0 =\n"      \
    "                     Weier's ray count for the gaze at the centre)\n"                      \
    "  --pattern rotate|static   sampling pattern over frames (default rotate with\n"          \
    "                     reprojection; static always without it)\n"                           \
    "  --threads N        worker threads (default: online CPUs)\n"                                 \
    "  --isa c|sse41|avx2|neon  cap the SIMD kernels (default: best available)\n"                  \
    "  --dof none|weak|medium|strong   gaze-contingent depth of field (default none; weak is\n"  \
    "                     the eye's own blur, medium x2, strong x4: docs/dof.md)\n"                \
    "  --dof-model weier|hussain|mantiuk|konrad|liu   the filter (default weier, layered)\n"      \
    "  --focus-m D        fixed focus distance in metres (default: estimated from the gaze)\n"   \
    "  --pupil-mm P       pupil (lens aperture) diameter (default 4.49)\n"                         \
    "  --gaze-error-deg E tracker's angular error: focus sampling radius (default 1)\n"          \
    "  --accommodation-ms T  focus time constant (default 370; 0 = instant)\n"                   \
    "  --dof-tolerance-m T   depth range kept sharp around the focus, +-T (default 0.2)\n"      \
    "  --contrast-gain G  peripheral contrast enhancement (Patney 2016; default 0 = off)\n" \
    "  --chroma on|off    liu: longitudinal chromatic aberration (default off)\n" \
    "  --dof-sampling on|off   fewer rays where the depth of field blurs (density falls\n" \
    "                     with the CoC's area; needs --dof and reprojection; default on)\n" \
    "  --dof-sampling-kappa K  the density's CoC scale (default 2: one ray per texel\n" \
    "                     of the pyramid level the filter reads; density\n" \
    "                     1 / ((CoC_px / K)^2 + 1/3) where below the acuity model's)\n"
int fv_common_option(const char *prog, int opt, const char *arg, fv_pipeline_config *cfg);
/* --lens FILE (replay, bench, headset): loads the HMD lens profile into *lens (which must outlive
 * the pipeline) and points cfg->cam.lens at it; the lens also places each eye's optical axis (an
 * asymmetric frustum, core/camera.h). Reprojection stays as configured: it models the lens
 * (core/reproject.h, "with a lens"). Exits 2 naming the problem. */
struct fv_lens;
void fv_cli_lens(const char *prog, const char *path, struct fv_lens *lens, fv_pipeline_config *cfg);
#define FV_LENS_HELP                                                                               \
    "  --lens FILE        HMD lens profile (distortion, chromatic aberration, per-eye centres\n"  \
    "                     that place each eye's optical axis); works with reprojection\n"

/* --asset-root DIR, in every program that loads a scene: the folder tree the scene's external
 * files (buffers, textures) may come from; default the scene file's own folder (fv_scene_load_in). */
#define FV_OPT_ASSET_ROOT 1100
#define FV_ASSET_ROOT_LONGOPT {"asset-root", required_argument, 0, FV_OPT_ASSET_ROOT}
#define FV_ASSET_ROOT_HELP                                                                         \
    "  --asset-root DIR   folder tree the scene's buffers and textures may come from (default:\n" \
    "                     the scene file's folder; a URI leading elsewhere is refused)\n"
/* --shadows on|off (replay, bench, headset): shadows from the scene's KHR punctual lights
 * (fv_scene_set_shadows, docs/materials.md); default off. */
#define FV_OPT_SHADOWS 1101
#define FV_SHADOWS_LONGOPT {"shadows", required_argument, 0, FV_OPT_SHADOWS}
#define FV_SHADOWS_HELP                                                                            \
    "  --shadows on|off   shadows from the scene's KHR lights, an occlusion ray per hit and\n"   \
    "                     light (default off; the head light at the eye casts none)\n"
/* After getopt_long: no stray words, a scene was given, option combinations agree (r0 <= r1);
 * exits 2 with a reason otherwise. */
void fv_common_validate(const char *prog, int argc, char **argv, const char *scene_path, const fv_pipeline_config *cfg);

#endif
