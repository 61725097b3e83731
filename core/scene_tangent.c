/* fovea: tangent frames for normal maps (glTF normalTexture): the TANGENT attribute of the
 * file, else tangents generated from the uv gradients in the MikkTSpace way (per-face tangent
 * and bitangent from the uv gradients, projected into each corner's normal plane, normalised,
 * summed per vertex weighted by the corner's angle; handedness from the summed bitangent).
 * What MikkTSpace does beyond that, and this does not: it welds vertices with equal position,
 * normal and uv before summing (here: per vertex index, so a non-indexed mesh gets per-face
 * tangents) and splits a vertex whose faces disagree in handedness (a mirrored uv chart meeting
 * itself at one index; glTF exporters duplicate seam vertices, so this is rare). On a vertex
 * whose faces agree the two give the same frame up to rounding, and the map only needs the
 * frame the artist baked with where it is smooth: docs/materials.md. */
#include "scene_impl.h"
#include "base/err.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int unit3d(double v[3])
{
    const double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(l > 1e-30) || !isfinite(l)) return 0;
    for (int k = 0; k < 3; k++) v[k] /= l;
    return 1;
}

/* v minus its component along unit n (n zero: v unchanged) */
static void project_out(double v[3], const float n[3])
{
    const double d = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
    for (int k = 0; k < 3; k++) v[k] -= d * n[k];
}

/* Any unit vector perpendicular to unit n (a tangent for a vertex without uv gradient). */
static void any_perpendicular(const float n[3], double t[3])
{
    const double a[3] = {fabs(n[0]) < 0.9f ? 1.0 : 0.0, fabs(n[0]) < 0.9f ? 0.0 : 1.0, 0.0};
    t[0] = a[0], t[1] = a[1], t[2] = a[2];
    project_out(t, n);
    if (!unit3d(t)) t[0] = 1.0, t[1] = t[2] = 0.0;
}

int fv_scene_mesh_tangents(const float *pos, const uint32_t *tri, size_t nv, size_t nt, const float *normals,
                           const float *uvs, const float *file_tan, const double M[16], float *out, char *err,
                           size_t err_len)
{
    double *acc = calloc(nv * 6, sizeof *acc); /* per vertex: tangent sum, bitangent sum */
    if (!acc) {
        fv_err(err, err_len, "out of memory");
        return -1;
    }
    if (file_tan) { /* tangents are directions: M's linear part; a mirroring M flips the handedness */
        const double det = M[0] * (M[5] * M[10] - M[9] * M[6]) - M[4] * (M[1] * M[10] - M[9] * M[2]) +
                           M[8] * (M[1] * M[6] - M[5] * M[2]);
        for (size_t i = 0; i < nv; i++) {
            const float *t = file_tan + 4 * i;
            for (int k = 0; k < 4; k++)
                if (!isfinite(t[k])) {
                    fv_err(err, err_len, "vertex %zu tangent is not finite", i);
                    free(acc);
                    return -1;
                }
            double *o = acc + 6 * i;
            for (int k = 0; k < 3; k++) o[k] = M[k] * t[0] + M[4 + k] * t[1] + M[8 + k] * t[2];
            if (!unit3d(o)) any_perpendicular(normals + 3 * i, o);
            o[3] = (t[3] < 0.0f) != (det < 0.0) ? -1.0 : 1.0; /* w, kept in the bitangent slot */
        }
    } else {
        for (size_t f = 0; f < nt; f++) {
            const uint32_t *v = tri + 3 * f;
            const float *p[3] = {pos + 3 * (size_t)v[0], pos + 3 * (size_t)v[1], pos + 3 * (size_t)v[2]};
            const float *uv[3] = {uvs + 2 * (size_t)v[0], uvs + 2 * (size_t)v[1], uvs + 2 * (size_t)v[2]};
            double e1[3], e2[3];
            for (int k = 0; k < 3; k++) e1[k] = (double)p[1][k] - p[0][k], e2[k] = (double)p[2][k] - p[0][k];
            const double du1 = (double)uv[1][0] - uv[0][0], dv1 = (double)uv[1][1] - uv[0][1];
            const double du2 = (double)uv[2][0] - uv[0][0], dv2 = (double)uv[2][1] - uv[0][1];
            const double r = du1 * dv2 - du2 * dv1;
            if (!(fabs(r) > 1e-20) || !isfinite(r)) continue; /* no uv gradient: this face adds nothing */
            double T[3], B[3]; /* dp/du, dp/dv */
            for (int k = 0; k < 3; k++) T[k] = (e1[k] * dv2 - e2[k] * dv1) / r, B[k] = (e2[k] * du1 - e1[k] * du2) / r;
            for (int c = 0; c < 3; c++) {
                double a[3], b[3]; /* the corner's two edges */
                const float *q0 = p[c], *q1 = p[(c + 1) % 3], *q2 = p[(c + 2) % 3];
                for (int k = 0; k < 3; k++) a[k] = (double)q1[k] - q0[k], b[k] = (double)q2[k] - q0[k];
                if (!unit3d(a) || !unit3d(b)) continue;
                double cosang = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
                cosang = cosang < -1.0 ? -1.0 : cosang > 1.0 ? 1.0 : cosang;
                const double angle = acos(cosang);
                const float *n = normals + 3 * (size_t)v[c];
                double tp[3] = {T[0], T[1], T[2]}, bp[3] = {B[0], B[1], B[2]};
                project_out(tp, n), project_out(bp, n);
                double *o = acc + 6 * (size_t)v[c];
                if (unit3d(tp))
                    for (int k = 0; k < 3; k++) o[k] += angle * tp[k];
                if (unit3d(bp))
                    for (int k = 0; k < 3; k++) o[3 + k] += angle * bp[k];
            }
        }
        for (size_t i = 0; i < nv; i++) {
            double *o = acc + 6 * i;
            const float *n = normals + 3 * i;
            project_out(o, n);
            if (!unit3d(o)) any_perpendicular(n, o);
            const double nxt[3] = {n[1] * o[2] - n[2] * o[1], n[2] * o[0] - n[0] * o[2], n[0] * o[1] - n[1] * o[0]};
            o[3] = nxt[0] * o[3] + nxt[1] * o[4] + nxt[2] * o[5] < 0.0 ? -1.0 : 1.0;
        }
    }
    for (size_t f = 0; f < nt; f++)
        for (int c = 0; c < 3; c++) {
            const double *o = acc + 6 * (size_t)tri[3 * f + (size_t)c];
            for (int k = 0; k < 4; k++) out[12 * f + 4 * (size_t)c + (size_t)k] = (float)o[k];
        }
    free(acc);
    return 0;
}
