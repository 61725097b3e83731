/* fovea eye tracker: polynomial gaze calibration (see calib.h). */
#include "eyetrack/calib.h"
#include "eyetrack/eyetrack.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/err.h"

#define DEG (3.14159265358979323846 / 180.0)

void fv_calib_targets_3x3(float span_x_deg, float span_y_deg, float yaw_deg[9], float pitch_deg[9])
{
    for (int i = 0; i < 9; i++) {
        yaw_deg[i] = (float)(i % 3 - 1) * span_x_deg;
        pitch_deg[i] = (float)(1 - i / 3) * span_y_deg;
    }
}

static void terms(const fv_calib *c, double x, double y, double t[6])
{
    const double u = (x - c->u0) / c->s, v = (y - c->v0) / c->s;
    t[0] = 1, t[1] = u, t[2] = v, t[3] = u * v, t[4] = u * u, t[5] = v * v;
}

void fv_calib_apply(const fv_calib *c, float in_x, float in_y, float *yaw_deg, float *pitch_deg)
{
    double t[6], gx = 0, gy = 0;
    terms(c, in_x, in_y, t);
    for (int k = 0; k < 6; k++)
        gx += c->a[k] * t[k], gy += c->b[k] * t[k];
    *yaw_deg = (float)gx;
    *pitch_deg = (float)gy;
}

double fv_calib_slip_gain(double d_led_mm)
{
    return 1.0 / (1.0 - 7.8 / (2.0 * d_led_mm));
}

int fv_calib_feature(const fv_calib *c, const fv_eye_result *r, float *fx, float *fy)
{
    if (r->status != FV_EYE_OK || !r->found)
        return 0;
    if (c->input == FV_CALIB_PUPIL) {
        *fx = r->pupil_x, *fy = r->pupil_y;
    } else {
        if (!r->has_pg)
            return 0;
        const double k = c->slip_gain > 0 ? c->slip_gain : 1.0;
        *fx = (float)(k * r->pg_x - (k - 1.0) * r->pupil_x);
        *fy = (float)(k * r->pg_y - (k - 1.0) * r->pupil_y);
    }
    return isfinite(*fx) && isfinite(*fy);
}

double fv_gaze_angle_deg(double yaw1, double pitch1, double yaw2, double pitch2)
{
    const double y1 = yaw1 * DEG, p1 = pitch1 * DEG, y2 = yaw2 * DEG, p2 = pitch2 * DEG;
    const double ax = sin(y1) * cos(p1), ay = sin(p1), az = cos(y1) * cos(p1);
    const double bx = sin(y2) * cos(p2), by = sin(p2), bz = cos(y2) * cos(p2);
    /* atan2 of |a x b| and a . b: accurate for small angles too */
    const double cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
    return atan2(sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz) / DEG;
}

/* Solve the 6x6 system m x = r (Gaussian elimination, partial pivoting). */
static int solve6(double m[6][6], double r[2][6], double x[2][6])
{
    double scale = 0;
    for (int i = 0; i < 6; i++)
        scale = fmax(scale, fabs(m[i][i]));
    for (int col = 0; col < 6; col++) {
        int best = col;
        for (int i = col + 1; i < 6; i++)
            if (fabs(m[i][col]) > fabs(m[best][col]))
                best = i;
        if (!(fabs(m[best][col]) > 1e-10 * scale))
            return -1;
        if (best != col) {
            for (int j = 0; j < 6; j++) {
                const double t = m[col][j];
                m[col][j] = m[best][j], m[best][j] = t;
            }
            for (int k = 0; k < 2; k++) {
                const double t = r[k][col];
                r[k][col] = r[k][best], r[k][best] = t;
            }
        }
        for (int i = col + 1; i < 6; i++) {
            const double f = m[i][col] / m[col][col];
            for (int j = col; j < 6; j++)
                m[i][j] -= f * m[col][j];
            for (int k = 0; k < 2; k++)
                r[k][i] -= f * r[k][col];
        }
    }
    for (int k = 0; k < 2; k++)
        for (int i = 5; i >= 0; i--) {
            double s = r[k][i];
            for (int j = i + 1; j < 6; j++)
                s -= m[i][j] * x[k][j];
            x[k][i] = s / m[i][i];
        }
    return 0;
}

static int fit_once(fv_calib *c, const float *ix, const float *iy, const float *yaw, const float *pitch, int n,
                    const unsigned char *use)
{
    double m[6][6] = { { 0 } }, r[2][6] = { { 0 } }, x[2][6];
    int used = 0;
    for (int i = 0; i < n; i++) {
        if (!use[i])
            continue;
        double t[6];
        terms(c, ix[i], iy[i], t);
        for (int a = 0; a < 6; a++) {
            for (int b = 0; b < 6; b++)
                m[a][b] += t[a] * t[b];
            r[0][a] += t[a] * yaw[i];
            r[1][a] += t[a] * pitch[i];
        }
        used++;
    }
    if (used < 6 || solve6(m, r, x))
        return -1;
    memcpy(c->a, x[0], sizeof c->a);
    memcpy(c->b, x[1], sizeof c->b);
    c->n_used = used;
    return 0;
}

static int cmp_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

int fv_calib_fit(fv_calib *c, int input, const float *in_x, const float *in_y, const float *yaw_deg,
                 const float *pitch_deg, int n, float *resid_deg)
{
    memset(c, 0, sizeof *c);
    c->input = input;
    c->slip_gain = 1.0; /* the caller sets the gain its features were made with */
    if (n < 6)
        return -1;
    double mx = 0, my = 0;
    for (int i = 0; i < n; i++)
        mx += in_x[i], my += in_y[i];
    mx /= n, my /= n;
    double s = 0;
    for (int i = 0; i < n; i++)
        s = fmax(s, fmax(fabs(in_x[i] - mx), fabs(in_y[i] - my)));
    if (!(s > 0))
        return -1;
    c->u0 = mx, c->v0 = my, c->s = s;
    unsigned char *use = malloc((size_t)n);
    float *res = malloc((size_t)n * sizeof *res), *sorted = malloc((size_t)n * sizeof *sorted);
    int rc = -1;
    if (!use || !res || !sorted)
        goto out;
    memset(use, 1, (size_t)n);
    if (fit_once(c, in_x, in_y, yaw_deg, pitch_deg, n, use))
        goto out;
    for (int round = 0; round < 2; round++) {
        for (int i = 0; i < n; i++) {
            float gx, gy;
            fv_calib_apply(c, in_x[i], in_y[i], &gx, &gy);
            res[i] = (float)fv_gaze_angle_deg(gx, gy, yaw_deg[i], pitch_deg[i]);
        }
        if (round == 1)
            break;
        memcpy(sorted, res, (size_t)n * sizeof *res);
        qsort(sorted, (size_t)n, sizeof *sorted, cmp_float);
        const float lim = fmaxf(1.0f, 3.0f * sorted[n / 2]);
        int drop = 0;
        for (int i = 0; i < n; i++)
            if (res[i] > lim)
                use[i] = 0, drop++;
        if (!drop)
            break;
        fv_calib tmp = *c;
        if (fit_once(&tmp, in_x, in_y, yaw_deg, pitch_deg, n, use)) { /* too few left: keep all */
            memset(use, 1, (size_t)n);
            break;
        }
        *c = tmp;
    }
    double ss = 0, mx_res = 0;
    int k = 0;
    for (int i = 0; i < n; i++) {
        if (resid_deg)
            resid_deg[i] = res[i];
        if (use[i]) {
            ss += (double)res[i] * res[i], k++;
            mx_res = fmax(mx_res, res[i]);
        }
    }
    c->rms_deg = k ? sqrt(ss / k) : 0;
    c->max_deg = mx_res;
    c->n_used = k;
    rc = 0;
out:
    free(use), free(res), free(sorted);
    return rc;
}

int fv_calib_format(const fv_calib *c, char *buf, size_t len)
{
    return snprintf(buf, len,
                    "# fovea eye calibration: yaw_deg / pitch_deg = coefficients . [1, u, v, u*v, u^2, v^2],\n"
                    "# u = (in_x - u0) / s, v = (in_y - v0) / s; in = pupil minus glint centroid (pupil_glint)\n"
                    "# or the pupil centre (pupil), in pixels of the eye image; pupil_glint with slip_gain k:\n"
                    "# in = k (pupil - glints) - (k - 1) pupil\n"
                    "fovea-calibration 1\n"
                    "input %s\n"
                    "norm %.17g %.17g %.17g\n"
                    "yaw_deg %.17g %.17g %.17g %.17g %.17g %.17g\n"
                    "pitch_deg %.17g %.17g %.17g %.17g %.17g %.17g\n"
                    "rms_deg %.6g\n"
                    "max_deg %.6g\n"
                    "samples %d\n"
                    "slip_gain %.17g\n",
                    c->input == FV_CALIB_PUPIL ? "pupil" : "pupil_glint", c->u0, c->v0, c->s, c->a[0], c->a[1],
                    c->a[2], c->a[3], c->a[4], c->a[5], c->b[0], c->b[1], c->b[2], c->b[3], c->b[4], c->b[5],
                    c->rms_deg, c->max_deg, c->n_used, c->slip_gain > 0 ? c->slip_gain : 1.0);
}

static int numbers(const char *s, double *v, int n)
{
    for (int i = 0; i < n; i++) {
        char *end;
        v[i] = strtod(s, &end);
        if (end == s || !isfinite(v[i]))
            return -1;
        s = end;
    }
    while (*s == ' ' || *s == '\t' || *s == '\r')
        s++;
    return *s ? -1 : 0;
}

int fv_calib_parse(fv_calib *c, const char *text, char *err, size_t err_len)
{
    memset(c, 0, sizeof *c);
    c->slip_gain = 1.0; /* files from before the key: the plain pupil-glint vector */
    int have = 0, ln = 0;
    const char *p = text;
    while (*p) {
        const char *e = strchr(p, '\n');
        const size_t l = e ? (size_t)(e - p) : strlen(p);
        char line[512];
        ln++;
        if (l >= sizeof line)
            return fv_err(err, err_len, "line %d: too long", ln);
        memcpy(line, p, l);
        line[l] = '\0';
        p += l + (e ? 1 : 0);
        char *q = line;
        while (*q == ' ' || *q == '\t')
            q++;
        if (!*q || *q == '#' || *q == '\r')
            continue;
        char key[32];
        int kl = 0;
        while (q[kl] && q[kl] != ' ' && q[kl] != '\t' && kl < 31)
            key[kl] = q[kl], kl++;
        key[kl] = '\0';
        const char *rest = q + kl;
        double v[6];
        if (!(have & 1)) {
            if (strcmp(key, "fovea-calibration") || numbers(rest, v, 1) || v[0] != 1)
                return fv_err(err, err_len, "line %d: expected 'fovea-calibration 1'", ln);
            have |= 1;
        } else if (!strcmp(key, "input")) {
            while (*rest == ' ' || *rest == '\t')
                rest++;
            if (!strncmp(rest, "pupil_glint", 11) && (!rest[11] || rest[11] == '\r'))
                c->input = FV_CALIB_PUPIL_GLINT;
            else if (!strncmp(rest, "pupil", 5) && (!rest[5] || rest[5] == '\r'))
                c->input = FV_CALIB_PUPIL;
            else
                return fv_err(err, err_len, "line %d: input must be pupil_glint or pupil", ln);
            have |= 2;
        } else if (!strcmp(key, "norm")) {
            if (numbers(rest, v, 3) || !(v[2] > 0))
                return fv_err(err, err_len, "line %d: norm needs u0 v0 s (s > 0)", ln);
            /* pupil positions are pixels of a camera image: beyond 1e6 is not a camera */
            if (fabs(v[0]) > 1e6 || fabs(v[1]) > 1e6 || v[2] > 1e6 || v[2] < 1e-6)
                return fv_err(err, err_len, "line %d: norm %g %g %g out of range (|u0|, |v0| <= 1e6, 1e-6 <= s <= 1e6)",
                              ln, v[0], v[1], v[2]);
            c->u0 = v[0], c->v0 = v[1], c->s = v[2];
            have |= 4;
        } else if (!strcmp(key, "yaw_deg") || !strcmp(key, "pitch_deg")) {
            if (numbers(rest, v, 6))
                return fv_err(err, err_len, "line %d: %s needs 6 numbers", ln, key);
            for (int k = 0; k < 6; k++) /* degrees per normalised unit: a gaze in degrees stays a float */
                if (fabs(v[k]) > 1e6)
                    return fv_err(err, err_len, "line %d: %s coefficient %d (%g) out of range (|c| <= 1e6)", ln, key,
                                  k + 1, v[k]);
            memcpy(key[0] == 'y' ? c->a : c->b, v, sizeof v);
            have |= key[0] == 'y' ? 8 : 16;
        } else if (!strcmp(key, "rms_deg") || !strcmp(key, "max_deg") || !strcmp(key, "samples")) {
            if (numbers(rest, v, 1))
                return fv_err(err, err_len, "line %d: %s needs a number", ln, key);
            /* checked at the type and range they are used in: a count is a whole number an int
             * holds, an angular residual lies within a half turn */
            if (key[0] == 's' ? !(v[0] >= 0 && v[0] <= FV_CALIB_MAX_SAMPLES && v[0] == floor(v[0]))
                              : !(v[0] >= 0 && v[0] <= 180))
                return fv_err(err, err_len, "line %d: %s %g out of range (%s)", ln, key, v[0],
                              key[0] == 's' ? "a whole number 0..1000000" : "0..180 degrees");
            if (key[0] == 'r')
                c->rms_deg = v[0];
            else if (key[0] == 'm')
                c->max_deg = v[0];
            else
                c->n_used = (int)v[0];
        } else if (!strcmp(key, "slip_gain")) {
            if (numbers(rest, v, 1) || !(v[0] >= 1.0 && v[0] <= 2.0))
                return fv_err(err, err_len, "line %d: slip_gain needs a number in [1, 2]", ln);
            c->slip_gain = v[0];
        } else {
            return fv_err(err, err_len, "line %d: unknown key '%s'", ln, key);
        }
    }
    if (have != 31)
        return fv_err(err, err_len, "missing %s", !(have & 1) ? "'fovea-calibration 1'" : !(have & 2) ? "input"
                                                  : !(have & 4) ? "norm" : !(have & 8) ? "yaw_deg" : "pitch_deg");
    return 0;
}
