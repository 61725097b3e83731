#include "posepred.h"

#include <math.h>
#include <string.h>

void fv_posepred_init(fv_posepred *p, int64_t vel_span_ns, int64_t max_horizon_ns)
{
    memset(p, 0, sizeof *p);
    p->vel_span_ns = vel_span_ns > 0 ? vel_span_ns : 1;
    p->max_horizon_ns = max_horizon_ns > 0 ? max_horizon_ns : 0;
}

void fv_posepred_push(fv_posepred *p, int64_t t_ns, const fv_pose *pose)
{
    if (p->n > 0 && t_ns <= p->t_ns[(p->n - 1) % FV_POSEPRED_RING])
        return;
    p->t_ns[p->n % FV_POSEPRED_RING] = t_ns;
    p->pose[p->n % FV_POSEPRED_RING] = *pose;
    p->n++;
}

int fv_posepred_predict(const fv_posepred *p, int64_t t_ns, fv_pose *out, int64_t *sample_t_ns)
{
    if (p->n == 0)
        return 0;
    const long i1 = (p->n - 1) % FV_POSEPRED_RING;
    const int64_t t1 = p->t_ns[i1];
    const fv_pose *s1 = &p->pose[i1];
    *out = *s1;
    if (sample_t_ns)
        *sample_t_ns = t1;
    /* the velocity's older end: the newest sample at least vel_span older, else the oldest kept */
    const long oldest = p->n > FV_POSEPRED_RING ? p->n - FV_POSEPRED_RING : 0;
    long j = -1;
    for (long k = p->n - 2; k >= oldest; k--) {
        j = k;
        if (t1 - p->t_ns[k % FV_POSEPRED_RING] >= p->vel_span_ns)
            break;
    }
    int64_t dt_ns = t_ns - t1;
    if (j < 0 || dt_ns <= 0)
        return 1;
    if (dt_ns > p->max_horizon_ns)
        dt_ns = p->max_horizon_ns;
    const fv_pose *s0 = &p->pose[j % FV_POSEPRED_RING];
    const double span = (double)(t1 - p->t_ns[j % FV_POSEPRED_RING]), f = (double)dt_ns / span;
    for (int k = 0; k < 3; k++)
        out->pos[k] = (float)((double)s1->pos[k] + ((double)s1->pos[k] - s0->pos[k]) * f);
    /* world-frame rotation from s0 to s1: d = q1 conj(q0); extrapolated: d^f q1 */
    const double a[4] = {s1->quat[0], s1->quat[1], s1->quat[2], s1->quat[3]};
    const double b[4] = {-s0->quat[0], -s0->quat[1], -s0->quat[2], s0->quat[3]};
    double d[4] = {a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
                   a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
                   a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
                   a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2]};
    if (d[3] < 0)
        for (int k = 0; k < 4; k++)
            d[k] = -d[k]; /* the short way round */
    const double sn = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (sn < 1e-12)
        return 1;
    const double ang = 2.0 * atan2(sn, d[3]) * f;
    const double e[4] = {d[0] / sn * sin(ang / 2), d[1] / sn * sin(ang / 2), d[2] / sn * sin(ang / 2), cos(ang / 2)};
    double q[4] = {e[3] * a[0] + e[0] * a[3] + e[1] * a[2] - e[2] * a[1],
                   e[3] * a[1] - e[0] * a[2] + e[1] * a[3] + e[2] * a[0],
                   e[3] * a[2] + e[0] * a[1] - e[1] * a[0] + e[2] * a[3],
                   e[3] * a[3] - e[0] * a[0] - e[1] * a[1] - e[2] * a[2]};
    const double qn = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int k = 0; k < 4; k++)
        out->quat[k] = (float)(q[k] / qn);
    return 1;
}

double fv_pose_angle_deg(const fv_pose *a, const fv_pose *b)
{
    /* r = conj(a) b; the angle from its vector part and its w (atan2: exact for small angles,
     * where acos of the dot product loses them to rounding) */
    const double x = a->quat[0], y = a->quat[1], z = a->quat[2], w = a->quat[3];
    const double X = b->quat[0], Y = b->quat[1], Z = b->quat[2], W = b->quat[3];
    const double rx = w * X - x * W - y * Z + z * Y, ry = w * Y + x * Z - y * W - z * X;
    const double rz = w * Z - x * Y + y * X - z * W, rw = w * W + x * X + y * Y + z * Z;
    return 2.0 * atan2(sqrt(rx * rx + ry * ry + rz * rz), fabs(rw)) * 180.0 / 3.14159265358979323846;
}

double fv_pose_dist_m(const fv_pose *a, const fv_pose *b)
{
    double s = 0;
    for (int k = 0; k < 3; k++)
        s += ((double)a->pos[k] - b->pos[k]) * ((double)a->pos[k] - b->pos[k]);
    return sqrt(s);
}
