/* fovea eye tracker: the calibration procedure (calibproc.h). */
#include "eyetrack/calibproc.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/err.h"

typedef struct sample {
    int64_t t_ns;
    float fx, fy;
    int usable;
} sample;

typedef struct slot_buf {
    sample *s;
    int n, cap;
} slot_buf;

struct fv_calproc {
    fv_calproc_params p;
    int64_t t0_ns;
    int n_main;                          /* 9 grid + n_valid */
    float yaw[9 + FV_CALPROC_MAX_VALID], pitch[9 + FV_CALPROC_MAX_VALID];
    int repeat_of[9];                    /* the grid point of each repeat slot */
    float px_per_deg;                    /* the feature's scale (set when the main schedule ends) */
    int n_repeat, repeats_decided;
    slot_buf buf[FV_CALPROC_MAX_SLOTS];
};

void fv_calproc_default_params(fv_calproc_params *p)
{
    p->span_x_deg = 15.0f;
    p->span_y_deg = 10.0f;
    p->n_valid = 4;
    p->dwell_ms = 1500;
    p->settle_ms = 400;
    p->fix_ms = 300;
    p->fix_disp_deg = 1.0f;
    p->input = FV_CALIB_PUPIL_GLINT;
    p->slip_gain = (float)fv_calib_slip_gain(35.0);
    p->valid_mean_max_deg = 1.5f;
    p->valid_max_max_deg = 3.0f;
}

fv_calproc *fv_calproc_create(const fv_calproc_params *p)
{
    if (!p || !(p->span_x_deg > 0 && p->span_x_deg <= 40) || !(p->span_y_deg > 0 && p->span_y_deg <= 40) ||
        p->n_valid < 0 || p->n_valid > FV_CALPROC_MAX_VALID || p->dwell_ms < 100 || p->dwell_ms > 10000 ||
        p->settle_ms < 0 || p->fix_ms < 30 || p->settle_ms + p->fix_ms > p->dwell_ms || !(p->fix_disp_deg > 0) ||
        (p->input != FV_CALIB_PUPIL_GLINT && p->input != FV_CALIB_PUPIL) || !(p->slip_gain >= 1 && p->slip_gain <= 2) || !(p->valid_mean_max_deg > 0) ||
        !(p->valid_max_max_deg > 0))
        return NULL;
    fv_calproc *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    c->p = *p;
    fv_calib_targets_3x3(p->span_x_deg, p->span_y_deg, c->yaw, c->pitch);
    /* validation points between the grid's rows and columns, where the fit was not anchored */
    static const float vx[FV_CALPROC_MAX_VALID] = {-0.5f, 0.5f, 0.5f, -0.5f, 0.0f, 0.5f, 0.0f, -0.5f};
    static const float vy[FV_CALPROC_MAX_VALID] = {0.5f, 0.5f, -0.5f, -0.5f, 0.5f, 0.0f, -0.5f, 0.0f};
    for (int k = 0; k < p->n_valid; k++) {
        c->yaw[9 + k] = vx[k] * p->span_x_deg;
        c->pitch[9 + k] = vy[k] * p->span_y_deg;
    }
    c->n_main = 9 + p->n_valid;
    return c;
}

void fv_calproc_destroy(fv_calproc *c)
{
    if (!c)
        return;
    for (int k = 0; k < FV_CALPROC_MAX_SLOTS; k++)
        free(c->buf[k].s);
    free(c);
}

void fv_calproc_start(fv_calproc *c, int64_t t0_ns)
{
    c->t0_ns = t0_ns;
    c->n_repeat = 0;
    c->repeats_decided = 0;
    for (int k = 0; k < FV_CALPROC_MAX_SLOTS; k++)
        c->buf[k].n = 0;
}

int fv_calproc_slots(const fv_calproc *c)
{
    return c->n_main;
}

void fv_calproc_slot_target(const fv_calproc *c, int k, float *yaw_deg, float *pitch_deg)
{
    k = k < 0 ? 0 : k >= c->n_main ? c->n_main - 1 : k;
    *yaw_deg = c->yaw[k];
    *pitch_deg = c->pitch[k];
}

static int64_t dwell_ns(const fv_calproc *c)
{
    return (int64_t)c->p.dwell_ms * 1000000;
}

/* The most stable window of slot k: 1 with its median feature and spread when one exists with
 * enough usable frames and a spread within max_disp, else 0 (with the best spread found). */
static int fixation(const fv_calproc *c, int k, float max_disp, float *fx, float *fy, float *disp, int *usable_frames)
{
    const slot_buf *b = &c->buf[k];
    const int64_t onset = c->t0_ns + (int64_t)k * dwell_ns(c), from = onset + (int64_t)c->p.settle_ms * 1000000,
                  win = (int64_t)c->p.fix_ms * 1000000, end = onset + dwell_ns(c);
    int best = 0, usable_total = 0;
    float best_d = INFINITY;
    float *xs = malloc(sizeof(float) * (size_t)(b->n + 1)), *ys = malloc(sizeof(float) * (size_t)(b->n + 1));
    if (!xs || !ys) {
        free(xs), free(ys);
        return 0;
    }
    for (int i = 0; i < b->n; i++)
        usable_total += b->s[i].usable;
    for (int i = 0; i < b->n; i++) {
        if (b->s[i].t_ns < from || b->s[i].t_ns + win > end)
            continue;
        int n = 0, m = 0;
        for (int j = i; j < b->n && b->s[j].t_ns < b->s[i].t_ns + win; j++, n++)
            if (b->s[j].usable)
                xs[m] = b->s[j].fx, ys[m] = b->s[j].fy, m++;
        if (m < 3 || m * 10 < n * 6)
            continue;
        /* median per axis (insertion sort: windows hold tens of frames) */
        float sx[256], sy[256];
        const int q = m < 256 ? m : 256;
        memcpy(sx, xs, sizeof(float) * (size_t)q);
        memcpy(sy, ys, sizeof(float) * (size_t)q);
        for (int a = 1; a < q; a++)
            for (int z = a; z > 0 && sx[z - 1] > sx[z]; z--) {
                const float t = sx[z];
                sx[z] = sx[z - 1], sx[z - 1] = t;
            }
        for (int a = 1; a < q; a++)
            for (int z = a; z > 0 && sy[z - 1] > sy[z]; z--) {
                const float t = sy[z];
                sy[z] = sy[z - 1], sy[z - 1] = t;
            }
        const float mx = q & 1 ? sx[q / 2] : 0.5f * (sx[q / 2 - 1] + sx[q / 2]);
        const float my = q & 1 ? sy[q / 2] : 0.5f * (sy[q / 2 - 1] + sy[q / 2]);
        float d = 0;
        for (int a = 0; a < q; a++)
            d = fmaxf(d, hypotf(xs[a] - mx, ys[a] - my));
        if (d < best_d) {
            best_d = d, best = 1;
            *fx = mx, *fy = my;
        }
    }
    free(xs), free(ys);
    *disp = best ? best_d : NAN;
    *usable_frames = usable_total;
    return best && best_d <= max_disp;
}

/* The feature's pixels per degree: the median over neighbouring grid points (a row or column
 * apart) of |feature difference| / angle, from each slot's steadiest window; 0 if fewer than 3
 * pairs are known. */
static float grid_scale(const fv_calproc *c)
{
    float fx[9], fy[9], ratio[12];
    int have[9], n = 0;
    for (int k = 0; k < 9; k++) {
        float d;
        int u;
        have[k] = fixation(c, k, INFINITY, &fx[k], &fy[k], &d, &u);
    }
    for (int k = 0; k < 9; k++)
        for (int step = 1; step <= 3; step += 2) { /* right neighbour, neighbour below */
            const int j = k + step;
            if ((step == 1 && k % 3 == 2) || j >= 9 || !have[k] || !have[j])
                continue;
            const double ang = fv_gaze_angle_deg(c->yaw[k], c->pitch[k], c->yaw[j], c->pitch[j]);
            ratio[n++] = (float)(hypot(fx[k] - fx[j], fy[k] - fy[j]) / ang);
        }
    if (n < 3)
        return 0.0f;
    for (int a = 1; a < n; a++)
        for (int z = a; z > 0 && ratio[z - 1] > ratio[z]; z--) {
            const float t = ratio[z];
            ratio[z] = ratio[z - 1], ratio[z - 1] = t;
        }
    return n & 1 ? ratio[n / 2] : 0.5f * (ratio[n / 2 - 1] + ratio[n / 2]);
}

static float max_disp(const fv_calproc *c)
{
    return c->px_per_deg > 0 ? c->p.fix_disp_deg * c->px_per_deg : 0.0f; /* no scale: nothing passes */
}

static void decide_repeats(fv_calproc *c)
{
    if (c->repeats_decided)
        return;
    c->repeats_decided = 1;
    c->px_per_deg = grid_scale(c);
    for (int k = 0; k < 9; k++) {
        float fx, fy, d;
        int u;
        if (!fixation(c, k, max_disp(c), &fx, &fy, &d, &u))
            c->repeat_of[c->n_repeat++] = k;
    }
}

int fv_calproc_target(fv_calproc *c, int64_t t_ns, int *slot, float *yaw_deg, float *pitch_deg)
{
    const int64_t dt = t_ns - c->t0_ns;
    const int k = dt < 0 ? 0 : (int)(dt / dwell_ns(c));
    if (k >= c->n_main)
        decide_repeats(c);
    if (k >= c->n_main + c->n_repeat)
        return 0;
    *slot = k;
    const int src = k < c->n_main ? k : c->repeat_of[k - c->n_main];
    *yaw_deg = c->yaw[src];
    *pitch_deg = c->pitch[src];
    return 1;
}

void fv_calproc_feed(fv_calproc *c, int64_t t_ns, const fv_eye_result *r)
{
    const int64_t dt = t_ns - c->t0_ns;
    if (dt < 0)
        return;
    const int k = (int)(dt / dwell_ns(c));
    if (k >= c->n_main)
        decide_repeats(c);
    if (k >= c->n_main + c->n_repeat || k >= FV_CALPROC_MAX_SLOTS)
        return;
    slot_buf *b = &c->buf[k];
    if (b->n == b->cap) {
        const int cap = b->cap ? 2 * b->cap : 256;
        if (cap > 1 << 16) /* a camera far above any real rate: keep what we have */
            return;
        sample *ns = realloc(b->s, sizeof(sample) * (size_t)cap);
        if (!ns)
            return;
        b->s = ns, b->cap = cap;
    }
    sample *s = &b->s[b->n++];
    s->t_ns = t_ns;
    fv_calib kind = {.input = c->p.input, .slip_gain = c->p.slip_gain};
    s->usable = fv_calib_feature(&kind, r, &s->fx, &s->fy);
}

int fv_calproc_finish(fv_calproc *c, fv_calib *out, fv_calproc_report *rep, char *err, size_t err_len)
{
    memset(rep, 0, sizeof *rep);
    decide_repeats(c);
    rep->n_repeated = c->n_repeat;
    rep->px_per_deg = c->px_per_deg;
    rep->n_points = c->n_main;
    float gx[9], gy[9], gyaw[9], gpitch[9];
    int ng = 0;
    for (int k = 0; k < c->n_main; k++) {
        fv_calproc_point *pt = &rep->points[k];
        pt->kind = k < 9 ? FV_CALPROC_GRID : FV_CALPROC_VALID;
        pt->yaw_deg = c->yaw[k], pt->pitch_deg = c->pitch[k];
        pt->err_deg = NAN;
        int u;
        pt->ok = fixation(c, k, max_disp(c), &pt->fx, &pt->fy, &pt->disp_px, &u);
        pt->frames = u;
        if (k < 9 && !pt->ok) /* its repeat, if that found one */
            for (int r = 0; r < c->n_repeat; r++)
                if (c->repeat_of[r] == k) {
                    int u2;
                    pt->ok = fixation(c, c->n_main + r, max_disp(c), &pt->fx, &pt->fy, &pt->disp_px, &u2);
                    pt->frames += u2;
                }
        if (k < 9 && pt->ok)
            gx[ng] = pt->fx, gy[ng] = pt->fy, gyaw[ng] = pt->yaw_deg, gpitch[ng] = pt->pitch_deg, ng++;
        if (pt->ok && k < 9)
            rep->n_grid_ok++;
        else if (pt->ok)
            rep->n_valid_ok++;
    }
    char failed[160] = "";
    for (int k = 0, len = 0; k < c->n_main && len < (int)sizeof failed - 8; k++)
        if (!rep->points[k].ok)
            len += snprintf(failed + len, sizeof failed - (size_t)len, "%s%d", len ? ", " : "", k + 1);
    if (ng < 6)
        return fv_err(err, err_len,
                      "only %d of the 9 grid points had a stable fixation (no fixation at point%s %s): blinks, "
                      "saccades or a lost pupil; repeat those points",
                      ng, strchr(failed, ',') ? "s" : "", failed);
    if (fv_calib_fit(out, c->p.input, gx, gy, gyaw, gpitch, ng, NULL))
        return fv_err(err, err_len, "the %d grid fixations do not determine a mapping (points %s missing); repeat them",
                      ng, failed[0] ? failed : "none");
    out->slip_gain = c->p.input == FV_CALIB_PUPIL_GLINT ? c->p.slip_gain : 1.0;
    double sum = 0, mx = 0;
    for (int k = 9; k < c->n_main; k++) {
        fv_calproc_point *pt = &rep->points[k];
        if (!pt->ok)
            continue;
        float yaw, pitch;
        fv_calib_apply(out, pt->fx, pt->fy, &yaw, &pitch);
        pt->err_deg = (float)fv_gaze_angle_deg(yaw, pitch, pt->yaw_deg, pt->pitch_deg);
        sum += pt->err_deg;
        mx = fmax(mx, pt->err_deg);
    }
    rep->valid_mean_deg = rep->n_valid_ok ? (float)(sum / rep->n_valid_ok) : NAN;
    rep->valid_max_deg = rep->n_valid_ok ? (float)mx : NAN;
    if (c->p.n_valid > 0 && rep->n_valid_ok == 0)
        return fv_err(err, err_len, "no validation point had a stable fixation: the mapping is unchecked; repeat");
    if (rep->n_valid_ok && (rep->valid_mean_deg > c->p.valid_mean_max_deg || rep->valid_max_deg > c->p.valid_max_max_deg)) {
        int worst = 9;
        for (int k = 9; k < c->n_main; k++)
            if (rep->points[k].ok && !(rep->points[k].err_deg <= rep->points[worst].err_deg))
                worst = k;
        return fv_err(err, err_len,
                      "the mapping does not reach the validation points: mean %.2f deg, max %.2f deg at point %d "
                      "(limits %.2f, %.2f); repeat the calibration",
                      (double)rep->valid_mean_deg, (double)rep->valid_max_deg, worst + 1,
                      (double)c->p.valid_mean_max_deg, (double)c->p.valid_max_max_deg);
    }
    return 0;
}
