/* fovea: shadows from the KHR punctual lights (fv_scene_set_shadows): one occlusion ray per hit
 * and light, in packets of 16 (rtcOccluded16) for the packet shading path, one at a time
 * (rtcOccluded1) for fv_scene_shade; both build their rays with shadow_ray, so a hit gets the
 * same ray, and the same answer, on either path.
 *
 * The ray leaves the hit towards the light from a point lifted off the surface along the
 * shading normal turned to the light's side: hit + eps n, eps = 1e-4 (1 + max |hit_k|) metres
 * (0.1 mm near the origin, growing with the coordinates as their rounding does), so the surface
 * the ray starts on is not hit again (self-shadowing acne). A point or spot light's ray stops
 * 1e-4 of the way short of the light (the light has no geometry, but a surface exactly at it
 * should not count). Only hits facing the light get a ray: where n.l <= 0 the light adds
 * nothing anyway. The head light (no KHR lights) sits at the eye, so every hit sees it: no
 * rays. Occlusion rays see alpha MASK cut-outs (the occluded filter) but not back-face culling:
 * a single-sided surface casts a shadow from both sides, as light blocked by a wall's back is
 * still blocked. */
#include "shadow.h"
#include "scene_impl.h"

#include <math.h>
#include <string.h>

/* The occlusion ray from hit (unit shading normal n, facing the ray) towards light l; returns 0
 * where no ray is needed (the light is behind the surface, or at the hit). */
static int shadow_ray(const float hit[3], const float n[3], const fv_light *l, float org[3], float dir[3], float *tfar)
{
    float L[3];
    if (l->type == FV_LIGHT_DIRECTIONAL) {
        for (int k = 0; k < 3; k++) L[k] = -l->dir[k];
    } else {
        for (int k = 0; k < 3; k++) L[k] = l->pos[k] - hit[k];
    }
    if (!(n[0] * L[0] + n[1] * L[1] + n[2] * L[2] > 0.0f)) return 0;
    const float eps = 1e-4f * (1.0f + fmaxf(fabsf(hit[0]), fmaxf(fabsf(hit[1]), fabsf(hit[2]))));
    for (int k = 0; k < 3; k++) org[k] = hit[k] + eps * n[k];
    if (l->type == FV_LIGHT_DIRECTIONAL) {
        for (int k = 0; k < 3; k++) dir[k] = L[k];
        *tfar = INFINITY;
    } else {
        for (int k = 0; k < 3; k++) dir[k] = l->pos[k] - org[k];
        *tfar = 1.0f - 1e-4f;
    }
    return 1;
}

/* n (unnormalised, nn = |n|^2 > 0) made unit and turned to face against dir, as shading does. */
static void facing_unit(const float n_in[3], float nn, const float dir[3], float n[3])
{
    const float s = (n_in[0] * dir[0] + n_in[1] * dir[1] + n_in[2] * dir[2] > 0.0f ? -1.0f : 1.0f) / sqrtf(nn);
    for (int k = 0; k < 3; k++) n[k] = n_in[k] * s;
}

void fv_shadow_scalar(const fv_scene *s, const float hit[3], const float n_in[3], float nn, const float dir[3],
                      float lit[FV_SHADOW_MAX_LIGHTS])
{
    const int nl = s->light_count < FV_SHADOW_MAX_LIGHTS ? s->light_count : FV_SHADOW_MAX_LIGHTS;
    float n[3];
    facing_unit(n_in, nn, dir, n);
    for (int j = 0; j < FV_SHADOW_MAX_LIGHTS; j++) lit[j] = 1.0f;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (int j = 0; j < nl; j++) {
        struct RTCRay r;
        memset(&r, 0, sizeof r);
        float o[3], d[3], tf;
        if (!shadow_ray(hit, n, &s->lights[j].l, o, d, &tf)) continue;
        r.org_x = o[0], r.org_y = o[1], r.org_z = o[2];
        r.dir_x = d[0], r.dir_y = d[1], r.dir_z = d[2];
        r.tnear = 0.0f, r.tfar = tf, r.mask = ~0u;
        rtcOccluded1(s->rtc, &ctx, &r);
        if (r.tfar == -INFINITY) lit[j] = 0.0f;
    }
}

void fv_shadow_packet(const fv_scene *s, const fv_shade_packet *pk, unsigned lanes, const float eye[3],
                      float lit[FV_SHADOW_MAX_LIGHTS][FV_SHADE_LANES])
{
    const int nl = s->light_count < FV_SHADOW_MAX_LIGHTS ? s->light_count : FV_SHADOW_MAX_LIGHTS;
    float hit[FV_SHADE_LANES][3], n[FV_SHADE_LANES][3];
    unsigned ok = 0;
    for (unsigned r = lanes; r; r &= r - 1) { /* the kernel's hit point and normal, in its operations */
        const int q = __builtin_ctz(r);
        const float u = pk->u[q], v = pk->v[q], w = 1.0f - u - v;
        float m[3];
        const float *nq = pk->nrm_at[q];
        for (int k = 0; k < 3; k++) m[k] = w * nq[k] + u * nq[3 + k] + v * nq[6 + k];
        const float mm = m[0] * m[0] + m[1] * m[1] + m[2] * m[2];
        if (!(mm > 1e-24f)) continue; /* degenerate: the scalar path shades this lane */
        const float d[3] = {pk->dir[0][q], pk->dir[1][q], pk->dir[2][q]};
        facing_unit(m, mm, d, n[q]);
        for (int k = 0; k < 3; k++) hit[q][k] = eye[k] + pk->t[q] * d[k];
        ok |= 1u << q;
    }
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (int j = 0; j < nl; j++) {
        _Alignas(64) struct RTCRay16 r;
        _Alignas(64) int valid[16];
        int any = 0;
        for (int q = 0; q < 16; q++) {
            lit[j][q] = 1.0f;
            valid[q] = 0;
            float o[3], d[3], tf;
            if (!(ok >> q & 1u) || !shadow_ray(hit[q], n[q], &s->lights[j].l, o, d, &tf)) {
                r.org_x[q] = r.org_y[q] = r.org_z[q] = 0.0f, r.dir_x[q] = r.dir_y[q] = 0.0f, r.dir_z[q] = 1.0f;
                r.tnear[q] = 0.0f, r.tfar[q] = 0.0f;
            } else {
                r.org_x[q] = o[0], r.org_y[q] = o[1], r.org_z[q] = o[2];
                r.dir_x[q] = d[0], r.dir_y[q] = d[1], r.dir_z[q] = d[2];
                r.tnear[q] = 0.0f, r.tfar[q] = tf;
                valid[q] = -1, any = 1;
            }
            r.time[q] = 0.0f, r.mask[q] = ~0u, r.id[q] = (unsigned)q, r.flags[q] = 0;
        }
        if (!any) continue;
        rtcOccluded16(valid, s->rtc, &ctx, &r);
        for (int q = 0; q < 16; q++)
            if (valid[q] && r.tfar[q] == -INFINITY) lit[j][q] = 0.0f;
    }
    for (int j = nl; j < FV_SHADOW_MAX_LIGHTS; j++)
        for (int q = 0; q < 16; q++) lit[j][q] = 1.0f;
}
