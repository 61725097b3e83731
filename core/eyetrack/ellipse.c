/* fovea eye tracker: direct least-squares ellipse fit (Fitzgibbon, Pilu & Fisher 1999) in the
 * numerically stable form of Halir & Flusser 1998. The points are centred and scaled first so
 * the scatter matrices are well conditioned whatever the image coordinates. */
#include <math.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#include "eyetrack/eyetrack.h"

static int inv3(const double m[3][3], double r[3][3])
{
    const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                       m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                       m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if (!(fabs(det) > 1e-300))
        return -1;
    const double id = 1.0 / det;
    r[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * id;
    r[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * id;
    r[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * id;
    r[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * id;
    r[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * id;
    r[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * id;
    r[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * id;
    r[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * id;
    r[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * id;
    return 0;
}

/* Real roots of the monic cubic x^3 + a x^2 + b x + c; returns how many (1 or 3). */
static int cubic_roots(double a, double b, double c, double x[3])
{
    const double q = (a * a - 3.0 * b) / 9.0, r = (2.0 * a * a * a - 9.0 * a * b + 27.0 * c) / 54.0;
    const double q3 = q * q * q;
    if (r * r < q3) {
        const double th = acos(r / sqrt(q3)), s = -2.0 * sqrt(q);
        x[0] = s * cos(th / 3.0) - a / 3.0;
        x[1] = s * cos((th + 2.0 * M_PI) / 3.0) - a / 3.0;
        x[2] = s * cos((th - 2.0 * M_PI) / 3.0) - a / 3.0;
        return 3;
    }
    double A = -cbrt(fabs(r) + sqrt(r * r - q3));
    if (r < 0)
        A = -A;
    const double B = A != 0.0 ? q / A : 0.0;
    x[0] = (A + B) - a / 3.0;
    return 1;
}

/* Null vector of (M - l I) from the largest cross product of two of its rows. */
static void null_vector(const double m[3][3], double l, double v[3])
{
    double r[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            r[i][j] = m[i][j] - (i == j ? l : 0.0);
    double best = -1.0;
    for (int p = 0; p < 3; p++) {
        const double *u = r[p], *w = r[(p + 1) % 3];
        const double c[3] = { u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0] };
        const double n = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
        if (n > best) {
            best = n;
            v[0] = c[0], v[1] = c[1], v[2] = c[2];
        }
    }
}

int fv_ellipse_fit(const float *px, const float *py, int n, fv_ellipse *e)
{
    if (n < 5)
        return -1;
    double mx = 0, my = 0;
    for (int i = 0; i < n; i++)
        mx += px[i], my += py[i];
    mx /= n, my /= n;
    double s = 0;
    for (int i = 0; i < n; i++)
        s += fabs(px[i] - mx) + fabs(py[i] - my);
    s = s / (2.0 * n);
    if (!(s > 1e-9))
        return -1;
    /* scatter matrices of D1 = [x^2 xy y^2], D2 = [x y 1] */
    double S1[3][3] = { { 0 } }, S2[3][3] = { { 0 } }, S3[3][3] = { { 0 } };
    for (int i = 0; i < n; i++) {
        const double x = (px[i] - mx) / s, y = (py[i] - my) / s;
        const double d1[3] = { x * x, x * y, y * y }, d2[3] = { x, y, 1.0 };
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) {
                S1[a][b] += d1[a] * d1[b];
                S2[a][b] += d1[a] * d2[b];
                S3[a][b] += d2[a] * d2[b];
            }
    }
    double S3i[3][3], T[3][3], M[3][3];
    if (inv3(S3, S3i))
        return -1;
    for (int a = 0; a < 3; a++) /* T = -S3^-1 S2^T */
        for (int b = 0; b < 3; b++) {
            double t = 0;
            for (int k = 0; k < 3; k++)
                t += S3i[a][k] * S2[b][k];
            T[a][b] = -t;
        }
    double Mr[3][3];
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            double t = S1[a][b];
            for (int k = 0; k < 3; k++)
                t += S2[a][k] * T[k][b];
            Mr[a][b] = t;
        }
    for (int b = 0; b < 3; b++) { /* M = C1^-1 Mr, C1 = [0 0 2; 0 -1 0; 2 0 0] */
        M[0][b] = Mr[2][b] / 2.0;
        M[1][b] = -Mr[1][b];
        M[2][b] = Mr[0][b] / 2.0;
    }
    /* characteristic polynomial of M */
    const double tr = M[0][0] + M[1][1] + M[2][2];
    const double c2 = M[0][0] * M[1][1] - M[0][1] * M[1][0] + M[0][0] * M[2][2] - M[0][2] * M[2][0] +
                      M[1][1] * M[2][2] - M[1][2] * M[2][1];
    const double det = M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) -
                       M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
                       M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]);
    double roots[3];
    const int nr = cubic_roots(-tr, c2, -det, roots);
    double a1[3] = { 0 }, bestc = 0;
    int ok = 0;
    for (int k = 0; k < nr; k++) {
        double v[3] = { 0, 0, 0 };
        null_vector(M, roots[k], v);
        const double cond = 4.0 * v[0] * v[2] - v[1] * v[1];
        if (cond > 0 && (!ok || cond > bestc)) { /* the one ellipse-specific eigenvector */
            ok = 1;
            bestc = cond;
            a1[0] = v[0], a1[1] = v[1], a1[2] = v[2];
        }
    }
    if (!ok)
        return -1;
    double a2[3];
    for (int a = 0; a < 3; a++)
        a2[a] = T[a][0] * a1[0] + T[a][1] * a1[1] + T[a][2] * a1[2];
    const double A = a1[0], B = a1[1], C = a1[2], D = a2[0], E = a2[1], F = a2[2];
    const double den = B * B - 4.0 * A * C;
    if (!(den < 0))
        return -1;
    const double x0 = (2.0 * C * D - B * E) / den, y0 = (2.0 * A * E - B * D) / den;
    const double f0 = A * x0 * x0 + B * x0 * y0 + C * y0 * y0 + D * x0 + E * y0 + F;
    /* eigenvalues of [A B/2; B/2 C] */
    const double m = 0.5 * (A + C), d = sqrt(0.25 * (A - C) * (A - C) + 0.25 * B * B);
    const double l1 = m - d, l2 = m + d; /* |l1| <= |l2| when A, C > 0 */
    const double q1 = -f0 / l1, q2 = -f0 / l2;
    if (!(q1 > 0 && q2 > 0))
        return -1;
    double ax1 = sqrt(q1), ax2 = sqrt(q2);
    /* direction of the eigenvector for l1 */
    double ang = 0.5 * atan2(B, A - C) + M_PI / 2.0;
    if (ax2 > ax1) {
        const double t = ax1;
        ax1 = ax2, ax2 = t;
        ang -= M_PI / 2.0;
    }
    ang = fmod(ang + 2.0 * M_PI, M_PI);
    e->cx = x0 * s + mx;
    e->cy = y0 * s + my;
    e->a = ax1 * s;
    e->b = ax2 * s;
    e->angle = ang;
    return isfinite(e->cx) && isfinite(e->cy) && isfinite(e->a) && isfinite(e->b) ? 0 : -1;
}

double fv_ellipse_distance(const fv_ellipse *e, double x, double y)
{
    const double c = cos(e->angle), s = sin(e->angle);
    const double u = (x - e->cx) * c + (y - e->cy) * s, v = -(x - e->cx) * s + (y - e->cy) * c;
    const double rho = sqrt((u / e->a) * (u / e->a) + (v / e->b) * (v / e->b));
    if (rho < 1e-12)
        return e->b;
    return fabs(rho - 1.0) * sqrt(u * u + v * v) / rho;
}
