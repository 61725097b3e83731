/* fovea eye tracker: gaze filter (see gazefilter.h). */
#include "eyetrack/gazefilter.h"

#include <math.h>
#include <string.h>

#include "eyetrack/calib.h"

void fv_gaze_filter_default_params(fv_gaze_filter_params *p)
{
    p->saccade_deg_s = 50.0f;
    p->outlier_deg_s = 1000.0f;
    p->confirm_samples = 2;
    p->min_cutoff_hz = 1.0f;
    p->beta = 0.02f;
    p->d_cutoff_hz = 1.0f;
    p->hold_ms = 300.0f;
    p->velocity_window_ms = 30.0f;
}

void fv_gaze_filter_init(fv_gaze_filter *f, const fv_gaze_filter_params *p)
{
    memset(f, 0, sizeof *f);
    if (p)
        f->p = *p;
    else
        fv_gaze_filter_default_params(&f->p);
}

static float alpha(float cutoff_hz, float dt_s)
{
    const float tau = 1.0f / (2.0f * 3.14159265f * cutoff_hz);
    return 1.0f / (1.0f + tau / dt_s);
}

float fv_fovea_radius_scale(float confidence)
{
    if (!(confidence > 0.2f))
        return 2.0f;
    if (confidence >= 0.8f)
        return 1.0f;
    return 1.0f + (0.8f - confidence) / 0.6f;
}

static void push_hist(fv_gaze_filter *f, double t, float x, float y)
{
    if (f->nhist == 8) {
        memmove(f->hist_t, f->hist_t + 1, 7 * sizeof *f->hist_t);
        memmove(f->hist_x, f->hist_x + 1, 7 * sizeof *f->hist_x);
        memmove(f->hist_y, f->hist_y + 1, 7 * sizeof *f->hist_y);
        f->nhist = 7;
    }
    f->hist_t[f->nhist] = t, f->hist_x[f->nhist] = x, f->hist_y[f->nhist] = y;
    f->nhist++;
}

/* Angular velocity from the newest kept sample at least velocity_window_ms older than t (or the
 * oldest one). */
static float window_velocity(const fv_gaze_filter *f, double t, float x, float y)
{
    if (!f->nhist)
        return 0;
    int k = f->nhist - 1;
    while (k > 0 && t - f->hist_t[k] < f->p.velocity_window_ms)
        k--;
    const double dt_s = fmax(1e-4, (t - f->hist_t[k]) / 1000.0);
    return (float)(fv_gaze_angle_deg(f->hist_x[k], f->hist_y[k], x, y) / dt_s);
}

static void hold(fv_gaze_filter *f, double t_ms, fv_gaze_out *out)
{
    const double since = t_ms - f->last_good_ms;
    out->yaw_deg = f->fx;
    out->pitch_deg = f->fy;
    out->velocity_deg_s = 0;
    if (!f->have || since > f->p.hold_ms) {
        out->state = f->have ? FV_GAZE_LOST : FV_GAZE_NONE;
        out->confidence = 0;
    } else {
        out->state = FV_GAZE_HOLD;
        out->confidence = f->last_conf * (float)(1.0 - since / f->p.hold_ms);
    }
}

void fv_gaze_filter_update(fv_gaze_filter *f, double t_ms, int valid, float yaw, float pitch, float conf,
                           fv_gaze_out *out)
{
    const double dt_ms = f->have ? t_ms - f->last_t_ms : 0;
    f->last_t_ms = t_ms;
    if (!valid || !isfinite(yaw) || !isfinite(pitch)) {
        f->pending = 0;
        hold(f, t_ms, out);
        f->out = *out;
        return;
    }
    if (!f->have) {
        f->have = 1;
        f->raw_x = f->fx = yaw;
        f->raw_y = f->fy = pitch;
        f->dfx = f->dfy = 0;
        f->last_good_ms = t_ms;
        f->last_conf = conf;
        f->nhist = 0;
        push_hist(f, t_ms, yaw, pitch);
        *out = (fv_gaze_out){ yaw, pitch, conf, 0, FV_GAZE_FIXATION };
        f->out = *out;
        return;
    }
    /* velocity against the last accepted sample (over the time since it) */
    const double gap_s = fmax(1e-4, (t_ms - f->last_good_ms) / 1000.0);
    const float vel = (float)(fv_gaze_angle_deg(f->raw_x, f->raw_y, yaw, pitch) / gap_s);
    if (vel > f->p.outlier_deg_s) {
        /* too fast for an eye: drop it, unless it is where the eye now stays */
        if (f->pending && fv_gaze_angle_deg(f->cand_x, f->cand_y, yaw, pitch) < 1.0)
            f->pending++;
        else
            f->pending = 1, f->cand_x = yaw, f->cand_y = pitch;
        if (f->pending <= f->p.confirm_samples) {
            hold(f, t_ms, out);
            f->out = *out;
            return;
        }
        /* confirmed: jump there without smoothing */
        f->pending = 0;
        f->raw_x = f->fx = yaw, f->raw_y = f->fy = pitch;
        f->dfx = f->dfy = 0;
        f->last_good_ms = t_ms;
        f->last_conf = conf;
        f->nhist = 0;
        push_hist(f, t_ms, yaw, pitch);
        *out = (fv_gaze_out){ yaw, pitch, conf, vel, FV_GAZE_SACCADE };
        f->out = *out;
        return;
    }
    f->pending = 0;
    const float dt_s = (float)fmax(1e-4, dt_ms / 1000.0);
    const float wvel = window_velocity(f, t_ms, yaw, pitch);
    push_hist(f, t_ms, yaw, pitch);
    int state;
    if (wvel > f->p.saccade_deg_s) {
        state = FV_GAZE_SACCADE; /* follow the raw signal; reset the smoother onto it */
        f->dfx = (yaw - f->fx) / dt_s;
        f->dfy = (pitch - f->fy) / dt_s;
        f->fx = yaw, f->fy = pitch;
    } else {
        state = FV_GAZE_FIXATION;
        /* 1-euro per axis: derivative smoothed at d_cutoff, cutoff grows with speed */
        const float ad = alpha(f->p.d_cutoff_hz, dt_s);
        f->dfx += ad * ((yaw - f->fx) / dt_s - f->dfx);
        f->dfy += ad * ((pitch - f->fy) / dt_s - f->dfy);
        const float ax = alpha(f->p.min_cutoff_hz + f->p.beta * fabsf(f->dfx), dt_s);
        const float ay = alpha(f->p.min_cutoff_hz + f->p.beta * fabsf(f->dfy), dt_s);
        f->fx += ax * (yaw - f->fx);
        f->fy += ay * (pitch - f->fy);
    }
    f->raw_x = yaw, f->raw_y = pitch;
    f->last_good_ms = t_ms;
    f->last_conf = conf;
    *out = (fv_gaze_out){ f->fx, f->fy, conf, wvel, state };
    f->out = *out;
}
