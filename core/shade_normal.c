/* fovea: the shading normal of a hit on a normal-mapped mesh (glTF normalTexture), the one
 * definition fv_scene_shade and the packet gather (core/shade.c) both use, so they agree bit for
 * bit: the packet path hands the kernel this normal in place of the corner normals.
 *
 *   n = interpolated vertex normal (the face normal where that is degenerate), unit
 *   t = interpolated corner tangents, made perpendicular to n (Gram-Schmidt), unit
 *   b = sign(interpolated w) n x t                          (glTF: bitangent = w (n x t))
 *   m = ((2 R - 1) scale, (2 G - 1) scale, 2 B - 1)         (the map's texel, linear)
 *   shading normal = m.x t + m.y b + m.z n
 * falling back to n where t or the result is degenerate (computed without normalising n, t
 * and b first: see the body). */
#include "scene_impl.h"

void fv_shade_normal_mapped(const fv_mesh_rec *m, unsigned prim, float u, float v, float w, const float texel[4],
                            float n[3], float *nn)
{
    const fv_tri_attr *at = &m->attr[prim];
    const float *n0 = at->n, *n1 = at->n + 3, *n2 = at->n + 6;
    /* scalars, not arrays: arrays stayed on the stack and their reloads stalled (as in
     * fv_scene_shade) */
    float nx = w * n0[0] + u * n1[0] + v * n2[0];
    float ny = w * n0[1] + u * n1[1] + v * n2[1];
    float nz = w * n0[2] + u * n1[2] + v * n2[2];
    float q = nx * nx + ny * ny + nz * nz;
    if (!(q > 1e-24f)) { /* degenerate smooth normal: the face's, as fv_scene_shade */
        float e1[3], e2[3], f[3];
        tri_edges(m->pos, m->tri + 3 * (size_t)prim, e1, e2);
        cross3(e1, e2, f);
        nx = f[0], ny = f[1], nz = f[2];
        q = nx * nx + ny * ny + nz * nz;
    }
    n[0] = nx, n[1] = ny, n[2] = nz, *nn = q;
    if (!(q > 1e-24f)) return;
    const float *tc = m->tan + 12 * (size_t)prim; /* corners: x y z w */
    float tx = w * tc[0] + u * tc[4] + v * tc[8];
    float ty = w * tc[1] + u * tc[5] + v * tc[9];
    float tz = w * tc[2] + u * tc[6] + v * tc[10];
    const float tw = w * tc[3] + u * tc[7] + v * tc[11];
    /* With n unnormalised: t' = t - n (n.t) / |n|^2, b' = n x t' (length |n| |t'|), and
     * |n| |t'| (mx t'/|t'| + my b'/(|n| |t'|) + mz n/|n|) = mx |n| t' + my b' + mz |t'| n: the
     * same direction with one division and two independent square roots. */
    const float d = (nx * tx + ny * ty + nz * tz) / q;
    tx -= d * nx, ty -= d * ny, tz -= d * nz;
    const float tt = tx * tx + ty * ty + tz * tz;
    if (!(tt > 1e-24f)) return; /* no tangent plane direction: the unmapped normal */
    const float ln = sqrtf(q), lt = sqrtf(tt);
    const float sgn = tw < 0.0f ? -1.0f : 1.0f;
    const float bx = sgn * (ny * tz - nz * ty), by = sgn * (nz * tx - nx * tz), bz = sgn * (nx * ty - ny * tx);
    const float mx = (2.0f * texel[0] - 1.0f) * m->normal_scale * ln, my = (2.0f * texel[1] - 1.0f) * m->normal_scale;
    const float mz = (2.0f * texel[2] - 1.0f) * lt;
    const float px = mx * tx + my * bx + mz * nx, py = mx * ty + my * by + mz * ny, pz = mx * tz + my * bz + mz * nz;
    const float pp = px * px + py * py + pz * pz;
    if (!(pp > 1e-24f) || !isfinite(pp)) return;
    n[0] = px, n[1] = py, n[2] = pz, *nn = pp;
}
