/* fovea: shading one hit from its gathered inputs, in plain C: the single definition that
 * fv_scene_shade (core/shade.c) and the packet kernel's C reference (core/shade_ref.c) share,
 * so both give the same bits. core/shade_tmpl.h is the same sequence of operations per vector.
 *
 *   rgb = ambient term + sum over lights of pi f(l, v) n.l x colour x irradiance + emissive
 *
 * with the BRDF of core/brdf.h. Without KHR lights a head light of irradiance 1 at eye. */
#ifndef FOVEA_SHADE_LANE_H
#define FOVEA_SHADE_LANE_H

#include "brdf.h"
#include "shade_dsp.h"

#include <math.h>

static inline float fv_lane_dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static inline float fv_lane_smoothstep(float e0, float e1, float x)
{
    if (e1 <= e0) return x >= e1 ? 1.0f : 0.0f;
    float t = (x - e0) / (e1 - e0);
    t = t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
    return t * t * (3.0f - 2.0f * t);
}

/* glTF's range window (as range_window in scene_impl.h). */
static inline float fv_lane_window(float d, float range)
{
    if (range <= 0.0f) return 1.0f;
    const float x = d / range, x4 = x * x * x * x;
    return x4 >= 1.0f ? 0.0f : 1.0f - x4;
}

/* Adds pi f n.l x colour x e for unit n, v, l (nl > 0). */
static inline void fv_lane_add_light(const fv_brdf_mat *m, const float n[3], const float v[3], float nv,
                                     const float L[3], float nl, const float color[3], float e, float rgb[3])
{
    float h[3] = {L[0] + v[0], L[1] + v[1], L[2] + v[2]};
    const float hl = sqrtf(fv_lane_dot3(h, h));
    const float ih = hl > 0.0f ? 1.0f / hl : 0.0f; /* l = -v: no half vector, h = 0 */
    for (int k = 0; k < 3; k++) h[k] *= ih;
    float f[3];
    fv_brdf_cos(m, nl, nv, fv_lane_dot3(n, h), fv_lane_dot3(v, h), f);
    for (int k = 0; k < 3; k++) rgb[k] += f[k] * (color[k] * e);
}

/* occlusion: the material's ambient occlusion (1 none) at the hit.
 * n: the interpolated (or face) normal, unnormalised, nn = |n|^2 > 0; the hit is org + t dir.
 * Normals are turned to face the ray (every material is shaded two-sided).
 * lit: NULL, or light j reaches the hit where lit[j * lit_stride] > 0 (shadows, core/shadow.c). */
static inline void fv_shade_lane(const fv_brdf_mat *m, float occlusion, const float emit[3], const float n_in[3], float nn,
                                 const float org[3], const float dir[3], float t, const float eye[3],
                                 const fv_light_rec *lights, int nlights, float exposure, const float *lit, int lit_stride,
                                 float rgb[3])
{
    float n[3] = {n_in[0], n_in[1], n_in[2]};
    if (fv_lane_dot3(n, dir) > 0.0f)
        for (int k = 0; k < 3; k++) n[k] = -n[k];
    const float inv_n = 1.0f / sqrtf(nn);
    for (int k = 0; k < 3; k++) n[k] *= inv_n;
    const float inv_d = 1.0f / sqrtf(fv_lane_dot3(dir, dir));
    const float v[3] = {-dir[0] * inv_d, -dir[1] * inv_d, -dir[2] * inv_d};
    const float nv = fv_lane_dot3(n, v);
    const float hit[3] = {org[0] + t * dir[0], org[1] + t * dir[1], org[2] + t * dir[2]};
    fv_brdf_ambient(m, FV_SCENE_AMBIENT * occlusion, rgb); /* occlusion darkens the surround only */
    if (nlights == 0 && org[0] == eye[0] && org[1] == eye[1] && org[2] == eye[2]) {
        /* head light (irradiance 1, white, no falloff) at the ray's origin: the hit at
         * eye + t dir (t > 0) sees it along l = v (fv_brdf_cos_head); the packet kernels' case */
        if (t > 0.0f && nv > 0.0f) {
            float f[3];
            fv_brdf_cos_head(m, nv, f);
            for (int k = 0; k < 3; k++) rgb[k] += f[k];
        }
    } else if (nlights == 0) { /* head light elsewhere (a lens point's ray, core/reference.c) */
        float L[3] = {eye[0] - hit[0], eye[1] - hit[1], eye[2] - hit[2]};
        const float ll = fv_lane_dot3(L, L);
        if (ll > 0.0f) {
            const float il = 1.0f / sqrtf(ll);
            for (int k = 0; k < 3; k++) L[k] *= il;
            const float nl = fv_lane_dot3(n, L);
            static const float white[3] = {1.0f, 1.0f, 1.0f};
            if (nl > 0.0f) fv_lane_add_light(m, n, v, nv, L, nl, white, 1.0f, rgb);
        }
    } else {
        for (int j = 0; j < nlights; j++) {
            const fv_light_rec *lr = &lights[j];
            const fv_light *l = &lr->l;
            float L[3], atten = 1.0f;
            if (l->type == FV_LIGHT_DIRECTIONAL) {
                for (int k = 0; k < 3; k++) L[k] = -l->dir[k];
            } else {
                for (int k = 0; k < 3; k++) L[k] = l->pos[k] - hit[k];
                const float dist = sqrtf(fv_lane_dot3(L, L));
                if (!(dist > 0.0f)) continue;
                for (int k = 0; k < 3; k++) L[k] /= dist;
                atten = fv_lane_window(dist, l->range) / (dist * dist);
                if (l->type == FV_LIGHT_SPOT)
                    atten *= fv_lane_smoothstep(lr->cos_outer, lr->cos_inner, -fv_lane_dot3(l->dir, L));
            }
            const float nl = fv_lane_dot3(n, L);
            const float e = atten * l->intensity * exposure;
            if (!(nl > 0.0f) || !(e > 0.0f) || !isfinite(e)) continue;
            if (lit && !(lit[j * lit_stride] > 0.0f)) continue; /* in the shadow of light j */
            fv_lane_add_light(m, n, v, nv, L, nl, l->color, e, rgb);
        }
    }
    for (int k = 0; k < 3; k++) rgb[k] += emit[k];
}

#endif
