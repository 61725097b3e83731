#include "camera.h"

#include <math.h>

#define FV_PI_F 3.14159265358979323846f

void fv_camera_desc_default(fv_camera_desc *d)
{
    d->width = 1280;
    d->height = 1440;
    d->fov_y_deg = 100.0f;
    d->ipd_m = 0.063f;
    d->eye = FV_EYE_CENTER;
    d->axis_shift = 0.0f;
    d->lens = NULL;
}

void fv_quat_rotate(const float q[4], const float v[3], float out[3])
{
    /* v' = v + 2w (u x v) + 2 u x (u x v) */
    float ux = q[0], uy = q[1], uz = q[2], w = q[3];
    float cx = uy * v[2] - uz * v[1], cy = uz * v[0] - ux * v[2], cz = ux * v[1] - uy * v[0];
    float ccx = uy * cz - uz * cy, ccy = uz * cx - ux * cz, ccz = ux * cy - uy * cx;
    out[0] = v[0] + 2.0f * (w * cx + ccx);
    out[1] = v[1] + 2.0f * (w * cy + ccy);
    out[2] = v[2] + 2.0f * (w * cz + ccz);
}

void fv_quat_mul(const float a[4], const float b[4], float out[4])
{
    const float x = a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1];
    const float y = a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0];
    const float z = a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3];
    const float w = a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2];
    out[0] = x;
    out[1] = y;
    out[2] = z;
    out[3] = w;
}

void fv_quat_normalize(float q[4])
{
    float n = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(n > 1e-12f)) {
        q[0] = q[1] = q[2] = 0.0f;
        q[3] = 1.0f;
        return;
    }
    for (int i = 0; i < 4; i++)
        q[i] /= n;
}

void fv_quat_slerp(const float a[4], const float b[4], float t, float out[4])
{
    float d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    float s = 1.0f;
    if (d < 0.0f) { /* shortest arc */
        d = -d;
        s = -1.0f;
    }
    float wa, wb;
    if (d > 0.9995f) { /* nearly parallel: lerp is exact enough and avoids 0/0 */
        wa = 1.0f - t;
        wb = t;
    } else {
        float th = acosf(d), sn = sinf(th);
        wa = sinf((1.0f - t) * th) / sn;
        wb = sinf(t * th) / sn;
    }
    for (int i = 0; i < 4; i++)
        out[i] = wa * a[i] + wb * s * b[i];
    fv_quat_normalize(out);
}

int fv_camera_setup(fv_camera *c, const fv_camera_desc *d, const fv_pose *head)
{
    if (d->width < 1 || d->height < 1 || d->width > 16384 || d->height > 16384)
        return -1;
    if (!(d->fov_y_deg > 1.0f && d->fov_y_deg < 170.0f))
        return -1;
    c->width = d->width;
    c->height = d->height;
    float ty = tanf(d->fov_y_deg * FV_PI_F / 360.0f);
    float tx = ty * (float)d->width / (float)d->height;
    /* The left eye's optical axis sits toward the nose (+x): its frustum extends further
     * to the left. Mirror for the right eye. */
    float shift = d->axis_shift * tx, vshift = 0.0f;
    if (d->eye == FV_EYE_RIGHT)
        shift = -shift;
    if (d->lens) {
        /* With a lens the eye looks straight ahead through the lens centre: the frustum is the
         * asymmetric one that puts the optical axis (tangent 0) on this eye's lens centre, from
         * the profile (axis_shift is not used). A centre left of the panel's middle widens the
         * frustum to the right, and so on. */
        const float *ctr = d->lens->center[d->eye == FV_EYE_RIGHT ? 1 : 0];
        shift = (2.0f * ctr[0] - 1.0f) * tx;
        vshift = (2.0f * ctr[1] - 1.0f) * ty;
    }
    c->tan_left = -tx - shift;
    c->tan_right = tx - shift;
    c->tan_bottom = -ty + vshift;
    c->tan_top = ty + vshift;
    c->px_tan = 2.0f * ty / (float)d->height;
    c->focal_px = 1.0f / c->px_tan;
    /* every field set, lens or not: reprojection compares whole cameras (memcmp) */
    c->lens_on = d->lens != NULL;
    c->lens_k1 = c->lens_k2 = c->lens_cx = c->lens_cy = 0.0f;
    c->lens_scale = 1.0f;
    c->lens_scale_rgb[0] = c->lens_scale_rgb[1] = c->lens_scale_rgb[2] = 1.0f;
    if (d->lens) {
        for (int i = 0; i < 3; i++)
            c->lens_scale_rgb[i] = d->lens->scale[i];
        const float *ctr = d->lens->center[d->eye == FV_EYE_RIGHT ? 1 : 0];
        c->lens_k1 = d->lens->k1;
        c->lens_k2 = d->lens->k2;
        c->lens_scale = d->lens->scale[FV_LENS_G];
        c->lens_cx = c->tan_left + ctr[0] * (float)d->width * c->px_tan; /* ~0: on the axis, above */
        c->lens_cy = c->tan_top - ctr[1] * (float)d->height * c->px_tan;
    }

    float q[4] = {head->quat[0], head->quat[1], head->quat[2], head->quat[3]};
    fv_quat_normalize(q);
    static const float ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1};
    fv_quat_rotate(q, ex, c->right);
    fv_quat_rotate(q, ey, c->up);
    fv_quat_rotate(q, ez, c->back);
    float off = 0.0f;
    if (d->eye == FV_EYE_LEFT)
        off = -0.5f * d->ipd_m;
    else if (d->eye == FV_EYE_RIGHT)
        off = 0.5f * d->ipd_m;
    for (int i = 0; i < 3; i++)
        c->eye_pos[i] = head->pos[i] + off * c->right[i];
    return 0;
}

float fv_camera_project(const fv_camera *c, const float p[3], float *px, float *py)
{
    float v[3] = {p[0] - c->eye_pos[0], p[1] - c->eye_pos[1], p[2] - c->eye_pos[2]};
    float x = v[0] * c->right[0] + v[1] * c->right[1] + v[2] * c->right[2];
    float y = v[0] * c->up[0] + v[1] * c->up[1] + v[2] * c->up[2];
    float z = -(v[0] * c->back[0] + v[1] * c->back[1] + v[2] * c->back[2]);
    if (z > 0.0f) {
        float tx = x / z, ty = y / z;
        if (c->lens_on && fv_lens_undistort(c->lens_k1, c->lens_k2, c->lens_scale, c->lens_cx, c->lens_cy, tx, ty, &tx, &ty))
            return 0.0f; /* beyond what the lens shows */
        *px = (tx - c->tan_left) / c->px_tan;
        *py = (c->tan_top - ty) / c->px_tan;
    }
    return z;
}
