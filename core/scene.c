/* fovea: the scene object: Embree device and scene, lifecycle, lights and their exposure,
 * commit, queries and the default view. Meshes: scene_mesh.c; textures: texture.c; shading:
 * shade.c; glTF: gltf_import.c (a client of the builder API). */
#include "scene_impl.h"
#include "blend.h"
#include "base/err.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void on_rtc_error(void *user, enum RTCError code, const char *str)
{
    fv_scene *s = user;
    pthread_mutex_lock(&s->rtc_err_lock);
    if (!s->rtc_err[0]) snprintf(s->rtc_err, sizeof s->rtc_err, "embree error %d: %s", (int)code, str ? str : "");
    pthread_mutex_unlock(&s->rtc_err_lock);
}

/* Returns 1 and copies the first recorded Embree error, or 0 if none. */
int fv_scene_take_rtc_error(fv_scene *s, char *err, size_t err_len)
{
    pthread_mutex_lock(&s->rtc_err_lock);
    int have = s->rtc_err[0] != 0;
    if (have) fv_err(err, err_len, "%s", s->rtc_err);
    pthread_mutex_unlock(&s->rtc_err_lock);
    if (!have) {
        enum RTCError e = rtcGetDeviceError(s->device);
        if (e != RTC_ERROR_NONE) {
            fv_err(err, err_len, "embree error %d", (int)e);
            have = 1;
        }
    }
    return have;
}

/* Grows *p (of *cap elements) to hold n; 0 on success. */
int fv_scene_grow(void **p, size_t *cap, size_t n, size_t elem)
{
    if (n <= *cap) return 0;
    size_t c = *cap ? *cap * 2 : 8;
    while (c < n) c *= 2;
    void *q = realloc(*p, c * elem);
    if (!q) return -1;
    *p = q;
    *cap = c;
    return 0;
}

fv_scene *fv_scene_create(void)
{
    static atomic_ulong scenes;
    fv_scene *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->serial = atomic_fetch_add_explicit(&scenes, 1, memory_order_relaxed) + 1;
    if (pthread_mutex_init(&s->rtc_err_lock, NULL) != 0) {
        free(s);
        return NULL;
    }
    s->device = rtcNewDevice(NULL);
    if (!s->device) {
        pthread_mutex_destroy(&s->rtc_err_lock);
        free(s);
        return NULL;
    }
    rtcSetDeviceErrorFunction(s->device, on_rtc_error, s);
    s->rtc = rtcNewScene(s->device);
    if (!s->rtc) {
        rtcReleaseDevice(s->device);
        pthread_mutex_destroy(&s->rtc_err_lock);
        free(s);
        return NULL;
    }
    /* static; ROBUST makes shared edges watertight (no background specks through cracks) */
    rtcSetSceneFlags(s->rtc, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(s->rtc, RTC_BUILD_QUALITY_HIGH);
    for (int i = 0; i < 3; i++) s->lo[i] = FLT_MAX, s->hi[i] = -FLT_MAX;
    s->light_exposure = 1.0f;
    return s;
}

void fv_scene_free(fv_scene *s)
{
    if (!s) return;
    for (size_t i = 0; i < s->mesh_count; i++) {
        free(s->meshes[i].attr);
        free(s->meshes[i].face);
        free(s->meshes[i].col);
        free(s->meshes[i].tan);
    }
    free(s->meshes);
    for (int i = 0; i < s->texture_count; i++) free(s->textures[i].data);
    free(s->textures);
    free(s->lights);
    if (s->rtc) rtcReleaseScene(s->rtc); /* releases the geometries and their buffers */
    if (s->device) rtcReleaseDevice(s->device);
    pthread_mutex_destroy(&s->rtc_err_lock);
    free(s);
}

/* ---- lights -------------------------------------------------------------------------- */

static void bounds_sphere(const fv_scene *s, float c[3], float *radius)
{
    if (s->triangle_count == 0) {
        c[0] = c[1] = c[2] = 0.0f;
        *radius = 1.0f;
        return;
    }
    float half[3];
    for (int k = 0; k < 3; k++) c[k] = 0.5f * (s->lo[k] + s->hi[k]), half[k] = 0.5f * (s->hi[k] - s->lo[k]);
    *radius = len3(half);
}

/* The exposure: 1 / (peak irradiance of the brightest light at the bounds' centre), where
 * a light's peak is intensity * its largest colour channel, point/spot lights fall off as
 * range_window/d^2 and spot cones are ignored (an aimed spot should still count). */
static void update_exposure(fv_scene *s)
{
    float c[3], r;
    bounds_sphere(s, c, &r);
    const float dmin = fmaxf(1e-3f * r, 1e-6f);
    float best = 0.0f, best_peak = 0.0f;
    for (int i = 0; i < s->light_count; i++) {
        const fv_light *l = &s->lights[i].l;
        const float peak = l->intensity * fmaxf(l->color[0], fmaxf(l->color[1], l->color[2]));
        if (!(peak > 0.0f) || !isfinite(peak)) continue;
        float e = peak;
        if (l->type != FV_LIGHT_DIRECTIONAL) {
            const float d3[3] = {l->pos[0] - c[0], l->pos[1] - c[1], l->pos[2] - c[2]};
            const float d = fmaxf(len3(d3), dmin);
            e = peak * range_window(d, l->range) / (d * d);
        }
        if (isfinite(e) && e > best) best = e;
        if (peak > best_peak) best_peak = peak;
    }
    s->light_exposure = best > 0.0f ? 1.0f / best : best_peak > 0.0f ? 1.0f / best_peak : 1.0f;
}

void fv_scene_add_light(fv_scene *s, const fv_light *l)
{
    if (!s || !l) return;
    size_t cap = (size_t)s->light_cap;
    if (fv_scene_grow((void **)&s->lights, &cap, (size_t)s->light_count + 1, sizeof *s->lights)) return;
    s->light_cap = (int)cap;
    fv_light_rec r;
    r.l = *l;
    const float dl = len3(r.l.dir);
    for (int k = 0; k < 3; k++) r.l.dir[k] = dl > 0.0f && isfinite(dl) ? r.l.dir[k] / dl : 0.0f;
    r.cos_inner = cosf(r.l.inner_cone);
    r.cos_outer = cosf(r.l.outer_cone);
    s->lights[s->light_count++] = r;
    if (s->committed) update_exposure(s);
}

int fv_scene_get_light(const fv_scene *s, int i, fv_light *out)
{
    if (!s || !out || i < 0 || i >= s->light_count) return -1;
    *out = s->lights[i].l;
    return 0;
}

/* The Embree intersect filter of single-sided (glTF doubleSided false) and alpha-MASK meshes:
 * a hit on a back face, or where the base colour's alpha (factor x texture, bilinear at mip 0:
 * the filter does not know the ray's footprint) is below the cutoff, is rejected, so the ray
 * goes on to whatever lies behind. Embree's Ng is cross(p1 - p0, p2 - p0), glTF's front side
 * (counter-clockwise corners), so a back face is Ng . dir > 0; grazing hits (0) are kept. */
/* base alpha at a hit (factor x texture, bilinear at mip 0) */
static float mesh_alpha(const fv_mesh_rec *m, unsigned prim, float u, float v)
{
    float alpha = m->base_color[3];
    if (m->mask_tex) {
        const float w = 1.0f - u - v;
        const float *uv = m->attr[prim].uv;
        float tu = w * uv[0] + u * uv[2] + v * uv[4], tv = w * uv[1] + u * uv[3] + v * uv[5], texel[4];
        if (m->has_uvx) { /* the base colour's KHR_texture_transform */
            const float *x = m->uvx[0], su = x[0] * tu + x[1] * tv + x[2];
            tv = x[3] * tu + x[4] * tv + x[5], tu = su;
        }
        fv_texture_sample(m->mask_tex, tu, tv, 0.0f, texel);
        alpha *= texel[3];
    }
    return alpha;
}

float fv_scene_alpha(const fv_scene *s, unsigned geom_id, unsigned prim_id, float u, float v)
{
    if (!s || geom_id >= s->mesh_count || prim_id >= s->meshes[geom_id].tri_count) return 1.0f;
    const float a = mesh_alpha(&s->meshes[geom_id], prim_id, u, v);
    return a > 0.0f ? (a < 1.0f ? a : 1.0f) : 0.0f;
}

static void filter(const struct RTCFilterFunctionNArguments *a, int cull)
{
    const fv_mesh_rec *m = a->geometryUserPtr;
    const unsigned n = a->N;
    /* RTCHitN is N-wide SoA: Ng x y z, u, v, primID, ...; RTCRayN: org x y z, tnear, dir x y z,
     * ... (the C++-only RTCHitN_* / RTCRayN_* accessors) */
    const float *ng = (const float *)a->hit, *dir = (const float *)a->ray + 4 * n;
    const float *hu = (const float *)a->hit + 3 * n, *hv = (const float *)a->hit + 4 * n;
    const unsigned *hprim = (const unsigned *)a->hit + 5 * n;
    for (unsigned i = 0; i < n; i++) {
        if (a->valid[i] != -1) continue;
        if (cull && m->single_sided && ng[i] * dir[i] + ng[n + i] * dir[n + i] + ng[2 * n + i] * dir[2 * n + i] > 0.0f) {
            a->valid[i] = 0;
            continue;
        }
        if (m->blend) { /* recorded (camera rays in the ray stage) and passed: core/blend.c */
            if (cull) /* RTCRayN: tfar (the hit's distance here) at 8, id at 10; RTCHitN: geomID at 6 */
                fv_blend_record(((const unsigned *)a->ray)[10 * n + i], ((const unsigned *)a->hit)[6 * n + i], hprim[i],
                                hu[i], hv[i], ((const float *)a->ray)[8 * n + i]);
            a->valid[i] = 0;
            continue;
        }
        if (!(m->alpha_cutoff > 0.0f)) continue;
        const unsigned prim = hprim[i];
        if (prim >= m->tri_count) continue;
        const float alpha = mesh_alpha(m, prim, hu[i], hv[i]);
        if (!(alpha >= m->alpha_cutoff)) a->valid[i] = 0;
    }
}

static void surface_filter(const struct RTCFilterFunctionNArguments *a) { filter(a, 1); }
/* Occlusion rays (shadows, core/shadow.c) see MASK cut-outs but every side: a single-sided
 * surface blocks light from behind too. */
static void occluded_filter(const struct RTCFilterFunctionNArguments *a) { filter(a, 0); }

/* The second trace's context filter: back faces of single-sided meshes rejected (Embree calls it
 * for every mesh, after a mesh's own filter). */
static void cull_filter(const struct RTCFilterFunctionNArguments *a)
{
    const fv_mesh_rec *m = a->geometryUserPtr;
    if (!m || !m->single_sided) return;
    const unsigned n = a->N;
    const float *ng = (const float *)a->hit, *dir = (const float *)a->ray + 4 * n;
    for (unsigned i = 0; i < n; i++)
        if (a->valid[i] == -1 && ng[i] * dir[i] + ng[n + i] * dir[n + i] + ng[2 * n + i] * dir[2 * n + i] > 0.0f)
            a->valid[i] = 0;
}

/* A closest hit on the back face of a single-sided mesh (only plain ones report such hits). */
static inline int back_face(const fv_scene *s, unsigned g, float nx, float ny, float nz, float dx, float dy, float dz)
{
    return g != RTC_INVALID_GEOMETRY_ID && s->meshes[g].single_sided && nx * dx + ny * dy + nz * dz > 0.0f;
}

void fv_scene_intersect1(const fv_scene *s, struct RTCIntersectContext *ictx, struct RTCRayHit *rh)
{
    const float tfar0 = rh->ray.tfar;
    rtcIntersect1(s->rtc, ictx, rh);
    if (!s->cull_retrace || !back_face(s, rh->hit.geomID, rh->hit.Ng_x, rh->hit.Ng_y, rh->hit.Ng_z, rh->ray.dir_x,
                                       rh->ray.dir_y, rh->ray.dir_z))
        return;
    struct RTCIntersectContext c = *ictx;
    c.filter = cull_filter;
    rh->ray.tfar = tfar0;
    rh->hit.geomID = rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(s->rtc, &c, rh);
}

/* The closest hits are checked for back faces of single-sided meshes in two passes: a branch-free
 * one over all lanes (valid, a hit, Ng . dir > 0: the compiler vectorises it), which usually finds
 * none, then the mesh's single_sided flag only for the lanes it found (one load per candidate
 * instead of per hit; was a branchy per-lane loop, ~2 % of a full frame's CPU on range). */
#define DEF_INTERSECT_N(N)                                                                                       \
    void fv_scene_intersect##N(const fv_scene *s, const int *valid, struct RTCIntersectContext *ictx,            \
                               struct RTCRayHit##N *rh)                                                          \
    {                                                                                                            \
        _Alignas(4 * N) float tfar0[N];                                                                          \
        if (s->cull_retrace)                                                                                     \
            memcpy(tfar0, rh->ray.tfar, sizeof tfar0);                                                           \
        rtcIntersect##N(valid, s->rtc, ictx, rh);                                                                \
        if (!s->cull_retrace)                                                                                    \
            return;                                                                                              \
        _Alignas(4 * N) int again[N];                                                                            \
        int any = 0;                                                                                             \
        for (int i = 0; i < N; i++) {                                                                            \
            const float d = rh->hit.Ng_x[i] * rh->ray.dir_x[i] + rh->hit.Ng_y[i] * rh->ray.dir_y[i] +            \
                            rh->hit.Ng_z[i] * rh->ray.dir_z[i];                                                  \
            again[i] = -((valid[i] == -1) & (rh->hit.geomID[i] != RTC_INVALID_GEOMETRY_ID) & (d > 0.0f));        \
            any |= again[i];                                                                                     \
        }                                                                                                        \
        if (!any)                                                                                                \
            return;                                                                                              \
        any = 0;                                                                                                 \
        for (int i = 0; i < N; i++) {                                                                            \
            if (!again[i])                                                                                       \
                continue;                                                                                        \
            if (!s->meshes[rh->hit.geomID[i]].single_sided) {                                                    \
                again[i] = 0;                                                                                    \
                continue;                                                                                        \
            }                                                                                                    \
            any = 1;                                                                                             \
            rh->ray.tfar[i] = tfar0[i];                                                                          \
            rh->hit.geomID[i] = rh->hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;                                  \
        }                                                                                                        \
        if (!any)                                                                                                \
            return;                                                                                              \
        struct RTCIntersectContext c = *ictx;                                                                    \
        c.filter = cull_filter;                                                                                  \
        rtcIntersect##N(again, s->rtc, &c, rh);                                                                  \
    }
DEF_INTERSECT_N(8)
DEF_INTERSECT_N(16)

int fv_scene_commit(fv_scene *s, char *err, size_t err_len)
{
    if (!s) {
        fv_err(err, err_len, "no scene");
        return -1;
    }
    if (s->committed) return 0;
    if (fv_scene_take_rtc_error(s, err, err_len)) return -1;
    for (size_t i = 0; i < s->mesh_count; i++) { /* the arrays no longer move: hand out pointers */
        fv_mesh_rec *m = &s->meshes[i];
        RTCGeometry g = rtcGetGeometry(s->rtc, (unsigned)i);
        rtcSetGeometryUserData(g, m); /* the culling context filter reads it on every mesh */
        if (!(m->alpha_cutoff > 0.0f) && !m->blend) {
            s->cull_retrace |= m->single_sided;
            rtcCommitGeometry(g);
            continue;
        }
        m->mask_tex = m->texture >= 0 ? &s->textures[m->texture] : NULL;
        rtcSetGeometryIntersectFilterFunction(g, surface_filter);
        if (m->alpha_cutoff > 0.0f || m->blend) /* shadows: cut-outs and blended surfaces let light through */
            rtcSetGeometryOccludedFilterFunction(g, occluded_filter);
        rtcCommitGeometry(g);
    }
    if (s->cull_retrace)
        rtcSetSceneFlags(s->rtc, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    rtcCommitScene(s->rtc);
    if (fv_scene_take_rtc_error(s, err, err_len)) return -1;
    update_exposure(s);
    s->committed = 1;
    return 0;
}

int fv_scene_set_shadows(fv_scene *s, int on)
{
    if (!s) return -1;
    if (on && s->light_count > 16) { /* FV_SHADOW_MAX_LIGHTS (core/shadow.h) */
        s->shadows = 0;
        return -1;
    }
    s->shadows = on != 0;
    return 0;
}

/* ---- queries ------------------------------------------------------------------------- */

RTCScene fv_scene_rtc(const fv_scene *s) { return s ? s->rtc : NULL; }
size_t fv_scene_triangle_count(const fv_scene *s) { return s ? s->triangle_count : 0; }
int fv_scene_light_count(const fv_scene *s) { return s ? s->light_count : 0; }

void fv_scene_bounds(const fv_scene *s, float lo[3], float hi[3])
{
    for (int k = 0; k < 3; k++) {
        const int empty = !s || s->triangle_count == 0;
        lo[k] = empty ? 0.0f : s->lo[k];
        hi[k] = empty ? 0.0f : s->hi[k];
    }
}

void fv_scene_set_default_view(fv_scene *s, const float pos[3], const float quat[4])
{
    if (!s || !pos || !quat) return;
    const float n = sqrtf(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
    if (!(n > 0.0f) || !isfinite(n)) return;
    for (int k = 0; k < 3; k++) s->view_pos[k] = pos[k];
    for (int k = 0; k < 4; k++) s->view_quat[k] = quat[k] / n;
    s->has_view = 1;
}

int fv_scene_default_view(const fv_scene *s, float fov_y_deg, float aspect, float pos[3], float quat[4])
{
    if (s && s->has_view) {
        memcpy(pos, s->view_pos, sizeof s->view_pos);
        memcpy(quat, s->view_quat, sizeof s->view_quat);
        return 1;
    }
    float c[3] = {0, 0, 0}, r = 1.0f;
    if (s) bounds_sphere(s, c, &r);
    float half_v = fov_y_deg * (float)(3.14159265358979323846 / 360.0);
    if (!(half_v > 1e-4f && half_v < 1.5f)) half_v = 0.5235988f; /* nonsense fov: use 60 deg */
    if (!(aspect > 0.0f) || !isfinite(aspect)) aspect = 1.0f;
    const float half_h = atanf(tanf(half_v) * aspect);
    const float half = fminf(half_v, half_h);
    /* The bounding sphere is tangent to the narrower frustum side at this distance. */
    const float d = r / sinf(half);
    pos[0] = c[0], pos[1] = c[1], pos[2] = c[2] + d;
    quat[0] = quat[1] = quat[2] = 0.0f, quat[3] = 1.0f;
    return 0;
}

void fv_scene_set_warning(fv_scene *s, const char *w)
{
    snprintf(s->warning, sizeof s->warning, "%s", w ? w : "");
}

const char *fv_scene_warning(const fv_scene *s)
{
    return s->warning;
}
