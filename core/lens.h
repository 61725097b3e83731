/* fovea: HMD lens distortion model. A panel point at tangent-space offset u from the lens centre
 * (tangent units of the camera's undistorted frustum, r = |u|) is seen through the lens along
 *     centre + u * scale_c * (1 + k1 r^2 + k2 r^4)
 * (radial polynomial; scale_c per colour channel c models lateral chromatic aberration).
 * Rendering rays along that direction pre-distorts the image, so no resampling pass is needed.
 * Rays are cast for the green channel (one ray per pixel). Red and blue go along their own
 * directions: where green's image shows direction D at panel point Q, red at panel point P must
 * show D_r(P), so red at P is read from the rendered image at Q = D_g^-1(D_r(P)) (radial, so a
 * 1-D table of |Q - c| / |P - c| against |P - c|), fused into the conversion to display bytes
 * (fv_lens_lca_*): no extra pass over the image. */
#ifndef FOVEA_LENS_H
#define FOVEA_LENS_H

#include <math.h>
#include <stddef.h>

enum { FV_LENS_R = 0, FV_LENS_G = 1, FV_LENS_B = 2 };

typedef struct fv_lens {
    float k1, k2;
    float scale[3];        /* per channel, R G B */
    float center[2][2];    /* lens centre per eye [left, right][x, y], normalised image coordinates */
} fv_lens;

/* No distortion: k = 0, scales 1, centres at the image centre. */
void fv_lens_default(fv_lens *l);

/* Lens profile text (the files: platform/lensfile.h). One `key values` per line, '#' comments
 * and blank lines skipped, every key optional (defaults: fv_lens_default):
 *   k1 0.10                  radial coefficients
 *   k2 0.02
 *   chroma 0.994 1.0 1.008   per-channel scale R G B (lateral chromatic aberration)
 *   left_center 0.53 0.5     lens centre per eye, normalised image coordinates
 *   right_center 0.47 0.5
 * Unknown keys, missing or extra values, lines of 512 bytes or more, NUL bytes and a mapping that
 * folds over within r_max (fv_lens_validate) are errors. text holds text_len bytes (no terminator
 * needed); name is used in messages ("NAME:LINE: reason" or "NAME: reason"). 0, or -1. */
int fv_lens_parse(fv_lens *l, const char *text, size_t text_len, const char *name, float r_max, char *err,
                  size_t err_len);
/* 0 when the radial mapping is monotonic (invertible) out to r_max tangent units and the
 * numbers are sane; -1 with a reason otherwise. */
int fv_lens_validate(const fv_lens *l, float r_max, char *err, size_t err_len);

/* The direction (tangent space) seen through the lens for panel point (tx, ty); (cx, cy) = lens
 * centre in tangent units. */
static inline void fv_lens_distort(float k1, float k2, float scale, float cx, float cy, float tx, float ty, float *ox,
                                   float *oy)
{
    const float ux = tx - cx, uy = ty - cy;
    const float r2 = ux * ux + uy * uy;
    const float f = scale * (1.0f + r2 * (k1 + k2 * r2));
    *ox = cx + ux * f;
    *oy = cy + uy * f;
}
/* The inverse: the panel point that is seen along (dx, dy). 0, or -1 when Newton's method did
 * not converge (outside the invertible range). */
int fv_lens_undistort(float k1, float k2, float scale, float cx, float cy, float dx, float dy, float *tx, float *ty);

/* Lateral chromatic aberration: per channel (R, B) the ratio |Q - c| / |P - c| against
 * r = |P - c| in FV_LENS_LCA_STEPS steps up to r_max (tangent units). */
#define FV_LENS_LCA_STEPS 1024
typedef struct fv_lens_lca {
    int on;                                   /* red or blue scale differs from green's */
    float r_max, inv_step;
    float ratio[2][FV_LENS_LCA_STEPS + 1];    /* [0] red, [1] blue */
} fv_lens_lca;
/* Builds the tables for radii up to r_max; on = 0 when there is nothing to correct. */
void fv_lens_lca_init(fv_lens_lca *t, float k1, float k2, const float scale[3], float r_max);
/* The panel point (tangent units) whose green ray carries channel ch's (0 red, 1 blue) direction
 * at panel point (tx, ty); (cx, cy) = lens centre. */
static inline void fv_lens_lca_source(const fv_lens_lca *t, int ch, float cx, float cy, float tx, float ty, float *qx,
                                      float *qy)
{
    const float ux = tx - cx, uy = ty - cy;
    float f = sqrtf(ux * ux + uy * uy) * t->inv_step;
    f = f < (float)FV_LENS_LCA_STEPS ? f : (float)FV_LENS_LCA_STEPS;
    int i = (int)f;
    i = i < FV_LENS_LCA_STEPS ? i : FV_LENS_LCA_STEPS - 1;
    const float a = f - (float)i, s = t->ratio[ch][i] + a * (t->ratio[ch][i + 1] - t->ratio[ch][i]);
    *qx = cx + ux * s;
    *qy = cy + uy * s;
}

/* ---- the lens in pixel units, for the reprojection and the timewarp ----
 * A camera with a lens renders pixel p (continuous pixel coordinates, centre x + 0.5) along the
 * direction of the pinhole camera's pixel q = F(p) (its "pinhole coordinates"):
 *     q = c + (p - c) s (1 + k1' |p - c|^2 + k2' |p - c|^4),  k1' = k1 px_tan^2, k2' = k2 px_tan^4,
 * c the lens centre in pixels (fv_camera_ray's mapping in pixel units; radial, so the y flip between
 * pixels and tangents does not matter). The inverse p = F^-1(q) = c + (q - c) rho(|q - c|^2): rho
 * from a table over |q - c|^2 (linear interpolation; rho is even in |q - c|, so smooth in its square),
 * then one Newton step on s rho (1 + k1' rho^2 R + k2' rho^4 R^2) = 1 (R = |q - c|^2; no square root).
 * Round trip |F^-1(F(p)) - p| <= FV_LENS_MAP_ERR_PX over a 1280 x 1440 image with the example profile
 * (tests/test_lens.c checks every pixel). Built once per camera: the lens does not change. */
#define FV_LENS_MAP_STEPS 1024
#define FV_LENS_MAP_ERR_PX 2e-3f
typedef struct fv_lens_map {
    float cx, cy;        /* lens centre, pixels */
    float s, k1, k2;     /* the green channel's scale and coefficients in pixel units (k1', k2') */
    float r2_max;        /* the table's range in |q - c|^2 (pinhole pixels squared) */
    float inv_step;      /* FV_LENS_MAP_STEPS / r2_max */
    float rho[FV_LENS_MAP_STEPS + 2];
} fv_lens_map;

struct fv_camera;
/* The map of camera c (c->lens_on): the table covers the image's corners with a margin (1.5 x their
 * radius, or up to where the lens folds over). 0, or -1 when the camera has no lens. */
int fv_lens_map_init(fv_lens_map *m, const struct fv_camera *c);

static inline void fv_lens_map_fwd(const fv_lens_map *m, float px, float py, float *qx, float *qy)
{
    const float ux = px - m->cx, uy = py - m->cy, r2 = ux * ux + uy * uy;
    const float f = m->s * (1.0f + r2 * (m->k1 + m->k2 * r2));
    *qx = m->cx + ux * f;
    *qy = m->cy + uy * f;
}
/* The Jacobian of F at p: J = f I + f' u u^T with f' = 2 s (k1' + 2 k2' r^2); j = {Jxx, Jxy, Jyy}
 * (symmetric). */
static inline void fv_lens_map_jac(const fv_lens_map *m, float px, float py, float j[3])
{
    const float ux = px - m->cx, uy = py - m->cy, r2 = ux * ux + uy * uy;
    const float f = m->s * (1.0f + r2 * (m->k1 + m->k2 * r2)), g = 2.0f * m->s * (m->k1 + 2.0f * m->k2 * r2);
    j[0] = f + g * ux * ux;
    j[1] = g * ux * uy;
    j[2] = f + g * uy * uy;
}
/* A map between two cameras with this lens in the form the reprojection and timewarp kernels use,
 * (U, V, Z) = T + d (M0 + qx MX + qy MY) at depth d from pinhole coordinates q to the other camera's
 * pinhole point (U / Z, V / Z), made a map between lensed pixels near pixel p0: F linearised at p0
 * (q = F(p0) + J_F(p0) (p - p0)) and F^-1 linearised at Q1, p0's image at inverse depth w0
 * (p' = F^-1(Q1) + J_F(F^-1(Q1))^-1 (Q - Q1)). Both are affine, one before the rows and one after
 * the division, so they fold into new rows (oT, oM0, oMX, oMY) of the same form: the kernels run
 * unchanged. Exact for an identity motion; otherwise second order in |p - p0| (and in the depth
 * difference from w0). The outputs may not alias the inputs. */
void fv_lens_map_fold(const fv_lens_map *m, const float T[3], const float M0[3], const float MX[3], const float MY[3],
                      float p0x, float p0y, float w0, float oT[3], float oM0[3], float oMX[3], float oMY[3]);
/* F^-1; returns 0, or 1 when q lies beyond the table (p is then along the same ray at the table's
 * last ratio: outside the image, in the right direction). */
static inline int fv_lens_map_inv(const fv_lens_map *m, float qx, float qy, float *px, float *py)
{
    const float vx = qx - m->cx, vy = qy - m->cy, R = vx * vx + vy * vy;
    float t = R * m->inv_step;
    const int out = !(t < (float)FV_LENS_MAP_STEPS); /* also NaN */
    t = out ? (float)FV_LENS_MAP_STEPS : t;
    const int i = (int)t;
    float rho = m->rho[i] + (t - (float)i) * (m->rho[i + 1] - m->rho[i]);
    if (!out) {
        const float a = rho * rho * R;
        const float g = m->s * rho * (1.0f + a * (m->k1 + m->k2 * a)) - 1.0f;
        const float dg = m->s * (1.0f + a * (3.0f * m->k1 + 5.0f * m->k2 * a));
        rho -= g / dg;
    }
    *px = m->cx + vx * rho;
    *py = m->cy + vy * rho;
    return out;
}

#endif
