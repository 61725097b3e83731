#include "lens.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/err.h"
#include "camera.h"

void fv_lens_default(fv_lens *l)
{
    l->k1 = l->k2 = 0.0f;
    for (int c = 0; c < 3; c++)
        l->scale[c] = 1.0f;
    for (int e = 0; e < 2; e++)
        l->center[e][0] = l->center[e][1] = 0.5f;
}

int fv_lens_validate(const fv_lens *l, float r_max, char *err, size_t err_len)
{
    if (!isfinite(l->k1) || !isfinite(l->k2) || fabsf(l->k1) > 10.0f || fabsf(l->k2) > 10.0f)
        return fv_err(err, err_len, "lens: k1 and k2 must be in [-10, 10]");
    for (int c = 0; c < 3; c++)
        if (!(l->scale[c] > 0.5f && l->scale[c] < 2.0f))
            return fv_err(err, err_len, "lens: channel scales must be in (0.5, 2)");
    for (int e = 0; e < 2; e++)
        for (int i = 0; i < 2; i++)
            if (!(l->center[e][i] >= 0.0f && l->center[e][i] <= 1.0f))
                return fv_err(err, err_len, "lens: centres must be in [0, 1] (normalised image coordinates)");
    /* d/dr [r (1 + k1 r^2 + k2 r^4)] = 1 + 3 k1 r^2 + 5 k2 r^4 must stay positive */
    for (int i = 0; i <= 1000; i++) {
        const float r = r_max * (float)i / 1000.0f, r2 = r * r;
        if (1.0f + 3.0f * l->k1 * r2 + 5.0f * l->k2 * r2 * r2 <= 0.0f)
            return fv_err(err, err_len, "lens: k1 %g, k2 %g fold the image over at r = %.3f (not invertible)",
                          (double)l->k1, (double)l->k2, (double)r);
    }
    return 0;
}

int fv_lens_undistort(float k1, float k2, float scale, float cx, float cy, float dx, float dy, float *tx, float *ty)
{
    /* radial only: solve g(r) = scale r (1 + k1 r^2 + k2 r^4) = |d - c| for r, in double */
    const double vx = (double)dx - cx, vy = (double)dy - cy;
    const double rd = sqrt(vx * vx + vy * vy);
    if (rd == 0.0) {
        *tx = cx;
        *ty = cy;
        return 0;
    }
    double r = rd / scale;
    for (int it = 0; it < 30; it++) {
        const double r2 = r * r;
        const double g = scale * r * (1.0 + k1 * r2 + k2 * r2 * r2) - rd;
        const double dg = scale * (1.0 + 3.0 * k1 * r2 + 5.0 * k2 * r2 * r2);
        if (!(dg > 0.0))
            return -1;
        const double step = g / dg;
        r -= step;
        if (fabs(step) < 1e-12 * (1.0 + r))
            break;
    }
    if (!(r >= 0.0) || !isfinite(r))
        return -1;
    const double s = r / rd;
    *tx = (float)(cx + vx * s);
    *ty = (float)(cy + vy * s);
    return 0;
}

void fv_lens_lca_init(fv_lens_lca *t, float k1, float k2, const float scale[3], float r_max)
{
    t->on = scale[FV_LENS_R] != scale[FV_LENS_G] || scale[FV_LENS_B] != scale[FV_LENS_G];
    t->r_max = r_max > 0.0f ? r_max : 1.0f;
    t->inv_step = (float)FV_LENS_LCA_STEPS / t->r_max;
    for (int ch = 0; ch < 2; ch++) {
        const float sc = scale[ch == 0 ? FV_LENS_R : FV_LENS_B];
        for (int i = 0; i <= FV_LENS_LCA_STEPS; i++) {
            /* r = 0: the limit of the ratio is sc / scale_g (the radial functions' slopes) */
            const double r = i ? (double)t->r_max * i / FV_LENS_LCA_STEPS : 1e-6;
            const double r2 = r * r, d = sc * r * (1.0 + k1 * r2 + k2 * r2 * r2); /* |D_c(P) - c| */
            float qx = 0.0f, qy = 0.0f;
            /* Q on the same ray from c: solve green's radial function for |d| */
            if (fv_lens_undistort(k1, k2, scale[FV_LENS_G], 0.0f, 0.0f, (float)d, 0.0f, &qx, &qy))
                qx = (float)r; /* beyond the invertible range: no correction */
            t->ratio[ch][i] = (float)((double)qx / r);
        }
    }
}

/* ---- the lens in pixel units (lens.h: fv_lens_map) ---------------------------------- */

int fv_lens_map_init(fv_lens_map *m, const fv_camera *c)
{
    memset(m, 0, sizeof *m);
    if (!c->lens_on)
        return -1;
    const double pt = c->px_tan;
    m->cx = (float)((c->lens_cx - c->tan_left) / pt);
    m->cy = (float)((c->tan_top - c->lens_cy) / pt);
    m->s = c->lens_scale;
    m->k1 = (float)(c->lens_k1 * pt * pt);
    m->k2 = (float)(c->lens_k2 * pt * pt * pt * pt);
    const double s = m->s, k1 = m->k1, k2 = m->k2;
    /* the corners' largest radius, 1.5 x, or less where g(r) = s r (1 + k1 r^2 + k2 r^4) folds over */
    double rc = 0.0;
    for (int i = 0; i < 4; i++) {
        const double dx = (i & 1 ? c->width : 0) - (double)m->cx, dy = (i & 2 ? c->height : 0) - (double)m->cy;
        rc = fmax(rc, sqrt(dx * dx + dy * dy));
    }
    double r_lim = 1.5 * rc;
    for (int i = 1; i <= 4096; i++) {
        const double r = 1.5 * rc * i / 4096.0, r2 = r * r;
        if (!(1.0 + 3.0 * k1 * r2 + 5.0 * k2 * r2 * r2 > 0.05)) {
            r_lim = 1.5 * rc * (i - 1) / 4096.0;
            break;
        }
    }
    const double gl = s * r_lim * (1.0 + k1 * r_lim * r_lim + k2 * r_lim * r_lim * r_lim * r_lim);
    m->r2_max = (float)(gl * gl);
    m->inv_step = (float)FV_LENS_MAP_STEPS / m->r2_max;
    double r = 0.0;
    for (int i = 0; i <= FV_LENS_MAP_STEPS; i++) {
        /* solve g(r) = sqrt(R_i) by Newton from the previous entry's root (g is increasing) */
        const double rq = sqrt((double)m->r2_max * i / FV_LENS_MAP_STEPS);
        for (int it = 0; it < 50 && i; it++) {
            const double r2 = r * r, g = s * r * (1.0 + k1 * r2 + k2 * r2 * r2) - rq;
            const double dg = s * (1.0 + 3.0 * k1 * r2 + 5.0 * k2 * r2 * r2);
            const double st = g / dg;
            r -= st;
            if (fabs(st) < 1e-12 * (1.0 + r))
                break;
        }
        m->rho[i] = i ? (float)(r / rq) : (float)(1.0 / s);
    }
    m->rho[FV_LENS_MAP_STEPS + 1] = m->rho[FV_LENS_MAP_STEPS];
    return 0;
}

void fv_lens_map_fold(const fv_lens_map *m, const float T[3], const float M0[3], const float MX[3], const float MY[3],
                      float p0x, float p0y, float w0, float oT[3], float oM0[3], float oMX[3], float oMY[3])
{
    float q0x, q0y, j[3];
    fv_lens_map_fwd(m, p0x, p0y, &q0x, &q0y);
    fv_lens_map_jac(m, p0x, p0y, j);
    /* q = q0 + J (p - p0): the rows in p */
    const double ax = (double)q0x - j[0] * (double)p0x - j[1] * (double)p0y;
    const double ay = (double)q0y - j[1] * (double)p0x - j[2] * (double)p0y;
    double R[4][3]; /* T, M0, MX, MY */
    for (int k = 0; k < 3; k++) {
        R[0][k] = T[k];
        R[1][k] = (double)M0[k] + ax * MX[k] + ay * MY[k];
        R[2][k] = (double)j[0] * MX[k] + (double)j[1] * MY[k];
        R[3][k] = (double)j[1] * MX[k] + (double)j[2] * MY[k];
    }
    /* Q1 and P1 = F^-1(Q1); K = J_F(P1)^-1 */
    double P[3];
    for (int k = 0; k < 3; k++)
        P[k] = w0 * R[0][k] + (R[1][k] + p0x * R[2][k] + p0y * R[3][k]); /* (T + M / w0) w0 */
    if (!(P[2] > 1e-6)) { /* p0 behind B's eye: any point will do (none of its samples has history) */
        P[0] = p0x, P[1] = p0y, P[2] = 1.0;
    }
    const float Q1x = (float)(P[0] / P[2]), Q1y = (float)(P[1] / P[2]);
    float P1x, P1y, k[3];
    fv_lens_map_inv(m, Q1x, Q1y, &P1x, &P1y);
    fv_lens_map_jac(m, P1x, P1y, k);
    const double det = (double)k[0] * k[2] - (double)k[1] * k[1];
    const double K00 = k[2] / det, K01 = -k[1] / det, K11 = k[0] / det;
    /* p' = P1 + K (Q - Q1): U' = bx Z + K00 U + K01 V, V' = by Z + K01 U + K11 V */
    const double bx = P1x - (K00 * Q1x + K01 * Q1y), by = P1y - (K01 * Q1x + K11 * Q1y);
    float *out[4] = {oT, oM0, oMX, oMY};
    for (int r = 0; r < 4; r++) {
        const double U = R[r][0], V = R[r][1], Z = R[r][2];
        out[r][0] = (float)(bx * Z + K00 * U + K01 * V);
        out[r][1] = (float)(by * Z + K01 * U + K11 * V);
        out[r][2] = (float)Z;
    }
}

/* ---- profile text (see lens.h) ------------------------------------------------------ */

/* Reads exactly n numbers from s; 0 or -1. */
static int numbers(const char *s, float *v, int n)
{
    for (int i = 0; i < n; i++) {
        char *end;
        errno = 0;
        double d = strtod(s, &end);
        if (end == s || errno || !isfinite(d))
            return -1;
        v[i] = (float)d;
        s = end;
    }
    while (*s == ' ' || *s == '\t' || *s == '\r')
        s++;
    return *s ? -1 : 0;
}

int fv_lens_parse(fv_lens *l, const char *text, size_t text_len, const char *name, float r_max, char *err,
                  size_t err_len)
{
    fv_lens_default(l);
    if (memchr(text, '\0', text_len))
        return fv_err(err, err_len, "%s: not a text file (NUL byte)", name);
    int lineno = 0;
    const char *p = text, *const end = text + text_len;
    while (p < end) {
        const char *nl = memchr(p, '\n', (size_t)(end - p));
        size_t len = nl ? (size_t)(nl - p) : (size_t)(end - p);
        lineno++;
        char line[512];
        if (len >= sizeof line)
            return fv_err(err, err_len, "%s:%d: line too long", name, lineno);
        memcpy(line, p, len);
        line[len] = 0;
        p += len + (nl ? 1 : 0);
        char *hash = strchr(line, '#');
        if (hash)
            *hash = 0;
        char *s = line;
        while (*s == ' ' || *s == '\t' || *s == '\r')
            s++;
        if (!*s)
            continue;
        char *key = s;
        while (*s && *s != ' ' && *s != '\t')
            s++;
        if (*s)
            *s++ = 0;
        float v[3];
        int want, rc;
        if (!strcmp(key, "k1") || !strcmp(key, "k2"))
            want = 1;
        else if (!strcmp(key, "chroma"))
            want = 3;
        else if (!strcmp(key, "left_center") || !strcmp(key, "right_center"))
            want = 2;
        else
            return fv_err(err, err_len, "%s:%d: unknown key '%s' (k1, k2, chroma, left_center, right_center)", name,
                          lineno, key);
        rc = numbers(s, v, want);
        if (rc)
            return fv_err(err, err_len, "%s:%d: %s wants %d number%s", name, lineno, key, want, want > 1 ? "s" : "");
        if (!strcmp(key, "k1"))
            l->k1 = v[0];
        else if (!strcmp(key, "k2"))
            l->k2 = v[0];
        else if (!strcmp(key, "chroma"))
            memcpy(l->scale, v, sizeof l->scale);
        else
            memcpy(l->center[key[0] == 'r'], v, 2 * sizeof(float));
    }
    char why[200];
    if (fv_lens_validate(l, r_max, why, sizeof why))
        return fv_err(err, err_len, "%s: %s", name, why);
    return 0;
}
