#include "cli.h"

#include <getopt.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/parse.h"
#include "lensfile.h"

static _Noreturn void vexit(const char *prog, int status, const char *fmt, va_list ap)
{
    fprintf(stderr, "%s: ", prog);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    exit(status);
}

_Noreturn void fv_usage_error(const char *prog, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vexit(prog, FV_EXIT_USAGE, fmt, ap);
}

_Noreturn void fv_fail(const char *prog, int status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vexit(prog, status, fmt, ap);
}

_Noreturn void fv_bad_option(const char *prog, char **argv)
{
    /* getopt_long leaves optind past the offending word; optopt is the short option (or the
     * long option's value, not printable here) that lacked its argument, 0 for an unknown one */
    const char *word = argv[optind - 1];
    if (optopt && strncmp(word, "--", 2))
        fv_usage_error(prog, "option -%c is unknown or lacks its argument (see --help)", optopt);
    if (optopt)
        fv_usage_error(prog, "%s needs an argument (see --help)", word);
    fv_usage_error(prog, "%s: unknown option (see --help)", word);
}

long fv_arg_long(const char *prog, const char *flag, const char *s, long lo, long hi)
{
    char err[4400]; /* the message quotes the argument whole */
    long v;
    if (fv_parse_long(flag, s, lo, hi, &v, err, sizeof err))
        fv_usage_error(prog, "%s", err);
    return v;
}

float fv_arg_float(const char *prog, const char *flag, const char *s, float lo, float hi)
{
    char err[4400];
    float v;
    if (fv_parse_float(flag, s, lo, hi, &v, err, sizeof err))
        fv_usage_error(prog, "%s", err);
    return v;
}

void fv_arg_size(const char *prog, const char *flag, const char *s, int *w, int *h)
{
    char err[4400];
    if (fv_parse_size(flag, s, w, h, err, sizeof err))
        fv_usage_error(prog, "%s", err);
}

int fv_arg_onoff(const char *prog, const char *flag, const char *s)
{
    if (!strcmp(s, "on"))
        return 1;
    if (!strcmp(s, "off"))
        return 0;
    fv_usage_error(prog, "%s: '%s' is not one of on, off", flag, s);
}

int fv_common_option(const char *prog, int opt, const char *arg, fv_pipeline_config *cfg)
{
    switch (opt) {
    case FV_OPT_SIZE:
        fv_arg_size(prog, "--size", arg, &cfg->cam.width, &cfg->cam.height);
        return 1;
    case FV_OPT_THREADS:
        cfg->threads = (int)fv_arg_long(prog, "--threads", arg, 1, 256);
        return 1;
    case FV_OPT_FOV:
        cfg->cam.fov_y_deg = fv_arg_float(prog, "--fov", arg, 10.0f, 160.0f);
        return 1;
    case FV_OPT_IPD:
        cfg->cam.ipd_m = fv_arg_float(prog, "--ipd", arg, 0.0f, 0.1f);
        return 1;
    case FV_OPT_R0:
        cfg->samp.r0_deg = fv_arg_float(prog, "--r0", arg, 0.5f, 90.0f);
        return 1;
    case FV_OPT_R1:
        cfg->samp.r1_deg = fv_arg_float(prog, "--r1", arg, 0.5f, 90.0f);
        return 1;
    case FV_OPT_PMIN:
        cfg->samp.p_min = fv_arg_float(prog, "--pmin", arg, 0.01f, 1.0f);
        return 1;
    case FV_OPT_ISA:
        if (fv_isa_mask_parse(arg, &cfg->isa_mask))
            fv_usage_error(prog, "--isa: '%s' is not one of c, sse41, avx2, neon", arg);
        return 1;
    case FV_OPT_REPROJECT:
        cfg->taa.enabled = fv_arg_onoff(prog, "--reproject", arg);
        return 1;
    case FV_OPT_FOVEA_AA:
        cfg->taa.fovea_aa = fv_arg_onoff(prog, "--fovea-aa", arg);
        return 1;
    case FV_OPT_TAA_FILL:
        cfg->taa.fill = fv_arg_onoff(prog, "--taa-fill", arg);
        return 1;
    case FV_OPT_TAA_ALPHA:
        cfg->taa.alpha_min = fv_arg_float(prog, "--taa-alpha", arg, 0.001f, 1.0f);
        return 1;
    case FV_OPT_TAA_TOL:
        cfg->taa.depth_tol = fv_arg_float(prog, "--taa-depth-tol", arg, 0.0001f, 10.0f);
        return 1;
    case FV_OPT_PATTERN:
        if (!strcmp(arg, "rotate") || !strcmp(arg, "static"))
            cfg->samp.rotate = !strcmp(arg, "rotate");
        else
            fv_usage_error(prog, "--pattern: '%s' is not one of rotate, static", arg);
        return 1;
    case FV_OPT_DOF:
        if (fv_dof_preset_parse(arg, &cfg->dof.preset))
            fv_usage_error(prog, "--dof: '%s' is not one of none, weak, medium, strong", arg);
        return 1;
    case FV_OPT_DOF_MODEL:
        if (fv_dof_model_parse(arg, &cfg->dof.model))
            fv_usage_error(prog, "--dof-model: '%s' is not one of weier, hussain, mantiuk, konrad, liu", arg);
        if (!fv_dof_models[cfg->dof.model].run)
            fv_usage_error(prog, "--dof-model %s: this model is not built yet", arg);
        return 1;
    case FV_OPT_FOCUS_M:
        cfg->dof.focus.fixed_m = fv_arg_float(prog, "--focus-m", arg, 0.05f, 1000.0f);
        return 1;
    case FV_OPT_PUPIL_MM:
        cfg->dof.pupil_mm = fv_arg_float(prog, "--pupil-mm", arg, 0.0f, 20.0f);
        return 1;
    case FV_OPT_GAZE_ERR:
        cfg->dof.focus.error_deg = fv_arg_float(prog, "--gaze-error-deg", arg, 0.0f, 10.0f);
        return 1;
    case FV_OPT_DOF_TOL:
        cfg->dof.tolerance_m = fv_arg_float(prog, "--dof-tolerance-m", arg, 0.0f, 10.0f);
        return 1;
    case FV_OPT_ACCOMMODATION:
        cfg->dof.focus.tau_ms = fv_arg_float(prog, "--accommodation-ms", arg, 0.0f, 10000.0f);
        return 1;
    case FV_OPT_CONTRAST:
        cfg->dof.contrast_gain = fv_arg_float(prog, "--contrast-gain", arg, 0.0f, 4.0f);
        return 1;
    case FV_OPT_CHROMA:
        cfg->dof.chroma = fv_arg_onoff(prog, "--chroma", arg);
        return 1;
    case FV_OPT_SAMPLING: /* issue 15 item 3: Liu's polar sampler */
        if (fv_sampler_kind_parse(arg, &cfg->samp.kind))
            fv_usage_error(prog, "--sampling: '%s' is not one of weier, liu", arg);
        return 1;
    case FV_OPT_LIU_DENSITY:
        cfg->samp.liu_density = fv_arg_float(prog, "--liu-density", arg, 0.0f, 1e4f);
        if (cfg->samp.liu_density > 0.0f && cfg->samp.liu_density < 1.0f)
            fv_usage_error(prog, "--liu-density %s: must be 0 (Weier's ray count) or at least 1 (a full fovea)", arg);
        return 1;
    case FV_OPT_DOF_SAMPLING: /* depth-of-field-driven sampling (core/sampling_dof.h) */
        cfg->dofsamp.enabled = fv_arg_onoff(prog, "--dof-sampling", arg);
        return 1;
    case FV_OPT_DOF_SAMPLING_KAPPA:
        cfg->dofsamp.kappa = fv_arg_float(prog, "--dof-sampling-kappa", arg, 0.25f, 32.0f);
        return 1;
    }
    return 0;
}

void fv_common_validate(const char *prog, int argc, char **argv, const char *scene_path, const fv_pipeline_config *cfg)
{
    if (optind < argc)
        fv_usage_error(prog, "unexpected argument '%s' (see --help)", argv[optind]);
    if (!scene_path)
        fv_usage_error(prog, "--scene FILE is required (see --help)");
    if (cfg->samp.r0_deg > cfg->samp.r1_deg)
        fv_usage_error(prog, "--r0 %g must not exceed --r1 %g", (double)cfg->samp.r0_deg, (double)cfg->samp.r1_deg);
}

void fv_cli_lens(const char *prog, const char *path, struct fv_lens *lens, fv_pipeline_config *cfg)
{
    char err[512];
    const float r_max = 3.0f * tanf(cfg->cam.fov_y_deg * 3.14159265f / 360.0f); /* beyond any corner */
    if (fv_lens_load(lens, path, r_max, err, sizeof err))
        fv_usage_error(prog, "--lens %s", err);
    cfg->cam.lens = lens;
}
