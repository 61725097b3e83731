/* fovea: the shading normal of a hit on a normal-mapped mesh (glTF normalTexture), the one
 * definition fv_scene_shade and the packet gather (core/shade.c) both use, so they agree bit for
 * bit: the packet path hands the kernel this normal in place of the corner normals.
 *
 *   n = interpolated vertex normal (the face normal where that is degenerate), unit
 *   t = interpolated corner tangents, made perpendicular to n (Gram-Schmidt), unit
 *   b = sign(interpolated w) n x t                          (glTF: bitangent = w (n x t))
 *   m = ((2 R - 1) scale, (2 G - 1) scale, 2 B - 1)         (the map's texel, linear)
 *   shading normal = m.x t + m.y b + m.z n
 * falling back to n where t or the result is degenerate. */
#include "scene_impl.h"

void fv_shade_normal_mapped(const fv_mesh_rec *m, unsigned prim, float u, float v, float w, const float texel[4],
                            float n[3], float *nn)
{
    const fv_tri_attr *at = &m->attr[prim];
    const float *n0 = at->n, *n1 = at->n + 3, *n2 = at->n + 6;
    n[0] = w * n0[0] + u * n1[0] + v * n2[0];
    n[1] = w * n0[1] + u * n1[1] + v * n2[1];
    n[2] = w * n0[2] + u * n1[2] + v * n2[2];
    *nn = dot3(n, n);
    if (!(*nn > 1e-24f)) { /* degenerate smooth normal: the face's, as fv_scene_shade */
        float e1[3], e2[3];
        tri_edges(m->pos, m->tri + 3 * (size_t)prim, e1, e2);
        cross3(e1, e2, n);
        *nn = dot3(n, n);
        if (!(*nn > 1e-24f)) return;
    }
    const float inv_n = 1.0f / sqrtf(*nn);
    const float nh[3] = {n[0] * inv_n, n[1] * inv_n, n[2] * inv_n};
    const float *tc = m->tan + 12 * (size_t)prim; /* corners: x y z w */
    float t[3];
    for (int k = 0; k < 3; k++) t[k] = w * tc[k] + u * tc[4 + k] + v * tc[8 + k];
    const float tw = w * tc[3] + u * tc[7] + v * tc[11];
    const float d = dot3(nh, t);
    for (int k = 0; k < 3; k++) t[k] -= d * nh[k];
    const float tt = dot3(t, t);
    if (!(tt > 1e-24f)) return; /* no tangent plane direction: the unmapped normal */
    const float inv_t = 1.0f / sqrtf(tt);
    for (int k = 0; k < 3; k++) t[k] *= inv_t;
    float b[3];
    cross3(nh, t, b);
    if (tw < 0.0f)
        for (int k = 0; k < 3; k++) b[k] = -b[k];
    const float mx = (2.0f * texel[0] - 1.0f) * m->normal_scale, my = (2.0f * texel[1] - 1.0f) * m->normal_scale;
    const float mz = 2.0f * texel[2] - 1.0f;
    float p[3];
    for (int k = 0; k < 3; k++) p[k] = mx * t[k] + my * b[k] + mz * nh[k];
    const float pp = dot3(p, p);
    if (!(pp > 1e-24f) || !isfinite(pp)) return;
    for (int k = 0; k < 3; k++) n[k] = p[k];
    *nn = pp;
}
