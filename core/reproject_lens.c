/* fovea: temporal reprojection with a lens (reproject.h, "with a lens"): the lens folded into the
 * per-frame rows around each tile, so the kernels (reproject_dsp.h) run as they are. */
#include <math.h>
#include <string.h>

#include "reproject.h"

void fv_taa_frame_set_lens(fv_taa_frame *f, const fv_lens_map *m)
{
    f->lens = f->identity ? NULL : m; /* pixel to the same pixel: no lens to undo */
}

/* rows (T, M0, MX, MY) of a pinhole map from camera A to camera B, A's pixel p, lens m on both
 * sides, linearised around A's pixel p0 (F at p0) and the B pinhole point Q1 that p0 at A depth
 * d0 maps to (F^-1 at Q1) */
static void fold(const fv_lens_map *m, const float T[3], const float M0[3], const float MX[3], const float MY[3],
                 float p0x, float p0y, float d0, float oT[3], float oM0[3], float oMX[3], float oMY[3])
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
        P[k] = R[0][k] + d0 * (R[1][k] + p0x * R[2][k] + p0y * R[3][k]);
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

void fv_taa_lens_tile_blend(const fv_taa_frame *f, fv_taa_frame *t, float cx, float cy, float d_m)
{
    *t = *f;
    t->lens = NULL;
    fold(f->lens, f->T, f->M0, f->MX, f->MY, cx, cy, d_m, t->T, t->M0, t->MX, t->MY);
}

void fv_taa_lens_tile_fill(const fv_taa_frame *f, fv_taa_frame *t, float hx, float hy, float d_m)
{
    fold(f->lens, f->T2, f->N0, f->NX, f->NY, hx, hy, d_m, t->T2, t->N0, t->NX, t->NY);
}

float fv_taa_project_lens(const fv_taa_frame *f, float px, float py, float d, float *u, float *v)
{
    float qx, qy;
    fv_lens_map_fwd(f->lens, px, py, &qx, &qy);
    const float U = f->T[0] + d * ((f->M0[0] + qy * f->MY[0]) + qx * f->MX[0]);
    const float V = f->T[1] + d * ((f->M0[1] + qy * f->MY[1]) + qx * f->MX[1]);
    const float Z = f->T[2] + d * ((f->M0[2] + qy * f->MY[2]) + qx * f->MX[2]);
    if (Z > 0.0f)
        fv_lens_map_inv(f->lens, U / Z, V / Z, u, v);
    return Z;
}
