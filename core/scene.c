/* fovea: the scene. Meshes are flattened to world space into one static Embree scene; the
 * mesh records (normals, uvs, material, per-triangle texel density) stay here for shading,
 * indexed by Embree geometry ID. The glTF loader is a client of the builder API. */
#include "scene.h"
#include "base/err.h"

#include "gltf_shim.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FV_TEX_MAX_SIDE 16384
#define FV_TEX_MAX_LEVELS 15 /* 16384 -> 1 */
#define FV_TEX_MAX_TEXELS ((size_t)1 << 26) /* 8192^2: about 1.4 GB as float RGBA with mips */
#define FV_MAX_VERTICES ((size_t)1 << 28)
#define FV_MAX_TRIANGLES ((size_t)1 << 28)

typedef struct fv_texture {
    int levels;
    int w[FV_TEX_MAX_LEVELS], h[FV_TEX_MAX_LEVELS];
    const float *level[FV_TEX_MAX_LEVELS]; /* linear RGBA, rows top to bottom, into data */
    float *data;
} fv_texture;

typedef struct fv_mesh_rec {
    const float *pos;      /* world positions, 3 per vertex: Embree's vertex buffer */
    const uint32_t *tri;   /* 3 per triangle: Embree's index buffer */
    float *normals;        /* world, unit (or zero if degenerate), 3 per vertex */
    float *uvs;            /* 2 per vertex, or NULL */
    float *texel_density;  /* per triangle, mip-0 texels per metre; NULL without texture */
    size_t vertex_count, tri_count;
    float base_color[4];
    int texture;
} fv_mesh_rec;

typedef struct fv_light_rec {
    fv_light l;
    float cos_inner, cos_outer; /* spot only */
} fv_light_rec;

struct fv_scene {
    RTCDevice device;
    RTCScene rtc;
    fv_mesh_rec *meshes;
    size_t mesh_count, mesh_cap;
    fv_texture *textures;
    int texture_count, texture_cap;
    fv_light_rec *lights;
    int light_count, light_cap;
    size_t triangle_count;
    float lo[3], hi[3];
    int committed;
    float light_exposure; /* multiplies every KHR light contribution, see update_exposure */
    int has_view;
    float view_pos[3], view_quat[4];
    pthread_mutex_t rtc_err_lock; /* Embree may report from its own threads */
    char rtc_err[192];
};

static void on_rtc_error(void *user, enum RTCError code, const char *str)
{
    fv_scene *s = user;
    pthread_mutex_lock(&s->rtc_err_lock);
    if (!s->rtc_err[0]) snprintf(s->rtc_err, sizeof s->rtc_err, "embree error %d: %s", (int)code, str ? str : "");
    pthread_mutex_unlock(&s->rtc_err_lock);
}

/* Returns 1 and copies the first recorded Embree error, or 0 if none. */
static int take_rtc_error(fv_scene *s, char *err, size_t err_len)
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
static int grow(void **p, size_t *cap, size_t n, size_t elem)
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
    fv_scene *s = calloc(1, sizeof *s);
    if (!s) return NULL;
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
        free(s->meshes[i].normals);
        free(s->meshes[i].uvs);
        free(s->meshes[i].texel_density);
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

/* ---- textures ------------------------------------------------------------------------ */

/* 2x2 box filter; an odd source side folds its last texel into the last output texel
 * (3 taps), so every source texel contributes and 1-texel sides pass through. */
static void downsample(const float *src, int sw, int sh, float *dst, int dw, int dh)
{
    for (int y = 0; y < dh; y++) {
        int ty[3], nty = 0;
        ty[nty++] = 2 * y;
        if (2 * y + 1 < sh) ty[nty++] = 2 * y + 1;
        if ((sh & 1) && sh > 1 && y == dh - 1) ty[nty++] = 2 * y + 2;
        for (int x = 0; x < dw; x++) {
            int tx[3], ntx = 0;
            tx[ntx++] = 2 * x;
            if (2 * x + 1 < sw) tx[ntx++] = 2 * x + 1;
            if ((sw & 1) && sw > 1 && x == dw - 1) tx[ntx++] = 2 * x + 2;
            float acc[4] = {0, 0, 0, 0};
            for (int j = 0; j < nty; j++)
                for (int i = 0; i < ntx; i++) {
                    const float *p = src + ((size_t)ty[j] * (size_t)sw + (size_t)tx[i]) * 4;
                    for (int c = 0; c < 4; c++) acc[c] += p[c];
                }
            const float inv = 1.0f / (float)(nty * ntx);
            float *d = dst + ((size_t)y * (size_t)dw + (size_t)x) * 4;
            for (int c = 0; c < 4; c++) d[c] = acc[c] * inv;
        }
    }
}

int fv_scene_add_texture(fv_scene *s, const uint8_t *rgba8, int w, int h)
{
    if (!s || !rgba8 || w < 1 || h < 1 || w > FV_TEX_MAX_SIDE || h > FV_TEX_MAX_SIDE ||
        (size_t)w * (size_t)h > FV_TEX_MAX_TEXELS)
        return -1;
    size_t cap = (size_t)s->texture_cap;
    if (grow((void **)&s->textures, &cap, (size_t)s->texture_count + 1, sizeof *s->textures)) return -1;
    s->texture_cap = (int)cap;

    fv_texture t;
    memset(&t, 0, sizeof t);
    size_t total = 0, offs[FV_TEX_MAX_LEVELS];
    for (int lw = w, lh = h;; lw = lw > 1 ? lw / 2 : 1, lh = lh > 1 ? lh / 2 : 1) {
        t.w[t.levels] = lw, t.h[t.levels] = lh;
        offs[t.levels++] = total;
        total += (size_t)lw * (size_t)lh * 4;
        if (lw == 1 && lh == 1) break;
    }
    t.data = malloc(total * sizeof(float));
    if (!t.data) return -1;

    float lut[256]; /* sRGB -> linear */
    for (int i = 0; i < 256; i++) {
        float c = (float)i / 255.0f;
        lut[i] = c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
    }
    const size_t n = (size_t)w * (size_t)h;
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++) t.data[i * 4 + (size_t)c] = lut[rgba8[i * 4 + (size_t)c]];
        t.data[i * 4 + 3] = (float)rgba8[i * 4 + 3] / 255.0f;
    }
    for (int l = 0; l < t.levels; l++) t.level[l] = t.data + offs[l];
    for (int l = 1; l < t.levels; l++)
        downsample(t.data + offs[l - 1], t.w[l - 1], t.h[l - 1], t.data + offs[l], t.w[l], t.h[l]);
    s->textures[s->texture_count] = t;
    return s->texture_count++;
}

/* Bilinear, REPEAT addressing; uv (0,0) is the first texel of the first row (glTF). */
static void tex_bilinear(const fv_texture *t, int l, float u, float v, float out[4])
{
    const int w = t->w[l], h = t->h[l];
    const float *px = t->level[l];
    u = isfinite(u) ? u - floorf(u) : 0.0f; /* [0,1] (1 only by rounding) */
    v = isfinite(v) ? v - floorf(v) : 0.0f;
    const float x = u * (float)w - 0.5f, y = v * (float)h - 0.5f;
    const float xf = floorf(x), yf = floorf(y);
    const float fx = x - xf, fy = y - yf;
    int x0 = (int)xf, y0 = (int)yf, x1 = x0 + 1, y1 = y0 + 1; /* in [-1, side] */
    if (x0 < 0) x0 += w;
    if (y0 < 0) y0 += h;
    if (x1 >= w) x1 -= w;
    if (y1 >= h) y1 -= h;
    const float *a = px + ((size_t)y0 * (size_t)w + (size_t)x0) * 4, *b = px + ((size_t)y0 * (size_t)w + (size_t)x1) * 4;
    const float *c = px + ((size_t)y1 * (size_t)w + (size_t)x0) * 4, *d = px + ((size_t)y1 * (size_t)w + (size_t)x1) * 4;
    for (int k = 0; k < 4; k++) {
        const float top = a[k] + (b[k] - a[k]) * fx, bot = c[k] + (d[k] - c[k]) * fx;
        out[k] = top + (bot - top) * fy;
    }
}

/* Trilinear between the two mip levels around lod (lod 0 = full resolution). */
static void tex_sample(const fv_texture *t, float u, float v, float lod, float out[4])
{
    if (!(lod > 0.0f)) lod = 0.0f; /* also NaN */
    const float top = (float)(t->levels - 1);
    if (lod >= top) {
        tex_bilinear(t, t->levels - 1, u, v, out);
        return;
    }
    const int l0 = (int)lod;
    const float f = lod - (float)l0;
    tex_bilinear(t, l0, u, v, out);
    if (f > 0.0f) {
        float o1[4];
        tex_bilinear(t, l0 + 1, u, v, o1);
        for (int k = 0; k < 4; k++) out[k] += (o1[k] - out[k]) * f;
    }
}

/* ---- meshes -------------------------------------------------------------------------- */

static void cross3(const float a[3], const float b[3], float o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}
static float dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static float len3(const float a[3]) { return sqrtf(dot3(a, a)); }

static void tri_edges(const float *pos, const uint32_t *tri, float e1[3], float e2[3])
{
    const float *p0 = pos + 3 * (size_t)tri[0], *p1 = pos + 3 * (size_t)tri[1], *p2 = pos + 3 * (size_t)tri[2];
    for (int k = 0; k < 3; k++) e1[k] = p1[k] - p0[k], e2[k] = p2[k] - p0[k];
}

int fv_scene_add_mesh(fv_scene *s, const fv_mesh_desc *m, char *err, size_t err_len)
{
    if (!s || !m) {
        fv_err(err, err_len, "no scene or mesh");
        return -1;
    }
    if (s->committed) {
        fv_err(err, err_len, "scene already committed");
        return -1;
    }
    if (!m->positions || m->vertex_count == 0 || m->vertex_count > FV_MAX_VERTICES) {
        fv_err(err, err_len, "mesh needs 1..%zu vertices", FV_MAX_VERTICES);
        return -1;
    }
    const size_t nv = m->vertex_count;
    if (m->indices ? m->index_count % 3 != 0 : nv % 3 != 0) {
        fv_err(err, err_len, "%s count %zu is not a multiple of 3", m->indices ? "index" : "vertex",
                m->indices ? m->index_count : nv);
        return -1;
    }
    const size_t nt = m->indices ? m->index_count / 3 : nv / 3;
    if (nt == 0 || nt > FV_MAX_TRIANGLES) {
        fv_err(err, err_len, "mesh needs 1..%zu triangles", FV_MAX_TRIANGLES);
        return -1;
    }
    if (m->indices)
        for (size_t i = 0; i < m->index_count; i++)
            if (m->indices[i] >= nv) {
                fv_err(err, err_len, "index %u at %zu out of range (vertex count %zu)", m->indices[i], i, nv);
                return -1;
            }
    if (m->texture < -1 || m->texture >= s->texture_count) {
        fv_err(err, err_len, "texture %d does not exist", m->texture);
        return -1;
    }
    if (m->texture >= 0 && !m->uvs) {
        fv_err(err, err_len, "texture without uvs");
        return -1;
    }
    for (int c = 0; c < 4; c++)
        if (!isfinite(m->base_color[c])) {
            fv_err(err, err_len, "base colour is not finite");
            return -1;
        }
    double M[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    int all_zero = 1;
    for (int i = 0; i < 16; i++) {
        if (!isfinite(m->transform[i])) {
            fv_err(err, err_len, "transform is not finite");
            return -1;
        }
        if (m->transform[i] != 0.0f) all_zero = 0;
    }
    if (!all_zero)
        for (int i = 0; i < 16; i++) M[i] = m->transform[i];

    if (grow((void **)&s->meshes, &s->mesh_cap, s->mesh_count + 1, sizeof *s->meshes)) {
        fv_err(err, err_len, "out of memory");
        return -1;
    }
    fv_mesh_rec r;
    memset(&r, 0, sizeof r);
    r.vertex_count = nv, r.tri_count = nt, r.texture = m->texture;
    memcpy(r.base_color, m->base_color, sizeof r.base_color);
    float *pos = malloc(nv * 3 * sizeof(float));
    uint32_t *tri = malloc(nt * 3 * sizeof(uint32_t));
    r.normals = calloc(nv * 3, sizeof(float));
    r.uvs = m->uvs ? malloc(nv * 2 * sizeof(float)) : NULL;
    r.texel_density = m->texture >= 0 ? malloc(nt * sizeof(float)) : NULL;
    RTCGeometry g = NULL;
    if (!pos || !tri || !r.normals || (m->uvs && !r.uvs) || (m->texture >= 0 && !r.texel_density)) {
        fv_err(err, err_len, "out of memory");
        goto fail;
    }

    for (size_t i = 0; i < nv; i++) { /* world positions, computed in double */
        const float *p = m->positions + 3 * i;
        for (int k = 0; k < 3; k++) {
            double w = M[k] * p[0] + M[4 + k] * p[1] + M[8 + k] * p[2] + M[12 + k];
            if (!isfinite(w) || fabs(w) > FLT_MAX) {
                fv_err(err, err_len, "vertex %zu position is not finite", i);
                goto fail;
            }
            pos[3 * i + (size_t)k] = (float)w;
        }
    }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++)
            tri[3 * t + (size_t)k] = m->indices ? m->indices[3 * t + (size_t)k] : (uint32_t)(3 * t + (size_t)k);

    if (m->normals) {
        /* Inverse-transpose via the cofactor matrix (columns c1xc2, c2xc0, c0xc1): defined even
         * for singular transforms; the sign of the determinant keeps the orientation. */
        float c0[3] = {(float)M[0], (float)M[1], (float)M[2]}, c1[3] = {(float)M[4], (float)M[5], (float)M[6]},
              c2[3] = {(float)M[8], (float)M[9], (float)M[10]}, k0[3], k1[3], k2[3];
        cross3(c1, c2, k0), cross3(c2, c0, k1), cross3(c0, c1, k2);
        const float sgn = dot3(c0, k0) < 0.0f ? -1.0f : 1.0f;
        for (size_t i = 0; i < nv; i++) {
            const float *n = m->normals + 3 * i;
            float *o = r.normals + 3 * i;
            for (int k = 0; k < 3; k++) o[k] = sgn * (k0[k] * n[0] + k1[k] * n[1] + k2[k] * n[2]);
            const float l = len3(o);
            if (!isfinite(l)) {
                fv_err(err, err_len, "vertex %zu normal is not finite", i);
                goto fail;
            }
            if (l > 0.0f)
                for (int k = 0; k < 3; k++) o[k] /= l;
        }
    } else { /* smooth, area-weighted: |e1 x e2| is twice the area */
        for (size_t t = 0; t < nt; t++) {
            float e1[3], e2[3], fn[3];
            tri_edges(pos, tri + 3 * t, e1, e2);
            cross3(e1, e2, fn);
            for (int j = 0; j < 3; j++)
                for (int k = 0; k < 3; k++) r.normals[3 * (size_t)tri[3 * t + (size_t)j] + (size_t)k] += fn[k];
        }
        for (size_t i = 0; i < nv; i++) {
            float *o = r.normals + 3 * i;
            const float l = len3(o);
            if (l > 0.0f && isfinite(l))
                for (int k = 0; k < 3; k++) o[k] /= l;
            else
                o[0] = o[1] = o[2] = 0.0f; /* shading falls back to the geometric normal */
        }
    }
    if (m->uvs) {
        for (size_t i = 0; i < 2 * nv; i++)
            if (!isfinite(m->uvs[i])) {
                fv_err(err, err_len, "vertex %zu uv is not finite", i / 2);
                goto fail;
            }
        memcpy(r.uvs, m->uvs, nv * 2 * sizeof(float));
    }
    if (r.texel_density) {
        const fv_texture *tx = &s->textures[m->texture];
        const double texels = (double)tx->w[0] * (double)tx->h[0];
        for (size_t t = 0; t < nt; t++) {
            float e1[3], e2[3], fn[3];
            tri_edges(pos, tri + 3 * t, e1, e2);
            cross3(e1, e2, fn);
            const uint32_t *v = tri + 3 * t;
            const float *u0 = r.uvs + 2 * (size_t)v[0], *u1 = r.uvs + 2 * (size_t)v[1], *u2 = r.uvs + 2 * (size_t)v[2];
            const double uv_area2 = fabs((double)(u1[0] - u0[0]) * (u2[1] - u0[1]) - (double)(u1[1] - u0[1]) * (u2[0] - u0[0]));
            const double world_area2 = len3(fn);
            const double d = world_area2 > 0.0 ? sqrt(uv_area2 * texels / world_area2) : 0.0;
            r.texel_density[t] = isfinite(d) && d < FLT_MAX ? (float)d : 0.0f;
        }
    }

    g = rtcNewGeometry(s->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *vb = g ? rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv) : NULL;
    uint32_t *ib = g ? rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), nt) : NULL;
    if (!vb || !ib) {
        if (!take_rtc_error(s, err, err_len)) fv_err(err, err_len, "embree geometry allocation failed");
        goto fail;
    }
    memcpy(vb, pos, nv * 3 * sizeof(float));
    memcpy(ib, tri, nt * 3 * sizeof(uint32_t));
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(s->rtc, g, (unsigned)s->mesh_count);
    rtcReleaseGeometry(g); /* the scene keeps its reference */
    g = NULL;
    if (take_rtc_error(s, err, err_len)) {
        rtcDetachGeometry(s->rtc, (unsigned)s->mesh_count);
        goto fail;
    }
    free(pos);
    free(tri);
    r.pos = vb;
    r.tri = ib;
    for (size_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) {
            if (vb[3 * i + (size_t)k] < s->lo[k]) s->lo[k] = vb[3 * i + (size_t)k];
            if (vb[3 * i + (size_t)k] > s->hi[k]) s->hi[k] = vb[3 * i + (size_t)k];
        }
    s->meshes[s->mesh_count++] = r;
    s->triangle_count += nt;
    return 0;

fail:
    if (g) rtcReleaseGeometry(g);
    free(pos);
    free(tri);
    free(r.normals);
    free(r.uvs);
    free(r.texel_density);
    return -1;
}

/* ---- lights -------------------------------------------------------------------------- */

/* glTF's recommended range window: smooth falloff to zero at range (0 = infinite). */
static float range_window(float d, float range)
{
    if (range <= 0.0f) return 1.0f;
    const float x = d / range, x4 = x * x * x * x;
    return x4 >= 1.0f ? 0.0f : 1.0f - x4;
}

static float smoothstepf(float e0, float e1, float x)
{
    if (e1 <= e0) return x >= e1 ? 1.0f : 0.0f;
    float t = (x - e0) / (e1 - e0);
    t = t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
    return t * t * (3.0f - 2.0f * t);
}

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
    if (grow((void **)&s->lights, &cap, (size_t)s->light_count + 1, sizeof *s->lights)) return;
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

int fv_scene_commit(fv_scene *s, char *err, size_t err_len)
{
    if (!s) {
        fv_err(err, err_len, "no scene");
        return -1;
    }
    if (s->committed) return 0;
    if (take_rtc_error(s, err, err_len)) return -1;
    rtcCommitScene(s->rtc);
    if (take_rtc_error(s, err, err_len)) return -1;
    update_exposure(s);
    s->committed = 1;
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

/* ---- shading ------------------------------------------------------------------------- */

void fv_scene_shade(const fv_scene *s, unsigned geom_id, unsigned prim_id, float u, float v,
                    const float org[3], const float dir[3], float t, float footprint_rad,
                    const float eye_pos[3], float rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (!s || geom_id >= s->mesh_count) return;
    const fv_mesh_rec *m = &s->meshes[geom_id];
    if (prim_id >= m->tri_count) return;
    const uint32_t *tri = m->tri + 3 * (size_t)prim_id;
    const float w = 1.0f - u - v; /* Embree: u weights vertex 1, v vertex 2 */

    /* The hot path (untextured, head light) costs one sqrt and one divide: the normal stays
     * unnormalised and the Lambert term divides by |n||L| once. Scalar sqrt/div chains were
     * most of the shading time. */
    float n[3];
    const float *n0 = m->normals + 3 * (size_t)tri[0], *n1 = m->normals + 3 * (size_t)tri[1],
                *n2 = m->normals + 3 * (size_t)tri[2];
    /* written out: a 3-iteration loop left n[] on the stack and the 8-byte reload of two
     * 4-byte stores stalled store forwarding on every call */
    n[0] = w * n0[0] + u * n1[0] + v * n2[0];
    n[1] = w * n0[1] + u * n1[1] + v * n2[1];
    n[2] = w * n0[2] + u * n1[2] + v * n2[2];
    float nn = dot3(n, n);
    if (!(nn > 1e-24f)) { /* degenerate smooth normal: use the face */
        float e1[3], e2[3];
        tri_edges(m->pos, tri, e1, e2);
        cross3(e1, e2, n);
        nn = dot3(n, n);
    }
    if (dot3(n, dir) > 0.0f)
        for (int k = 0; k < 3; k++) n[k] = -n[k];

    float base[3] = {m->base_color[0], m->base_color[1], m->base_color[2]};
    if (m->texture >= 0) {
        const float *a = m->uvs + 2 * (size_t)tri[0], *b = m->uvs + 2 * (size_t)tri[1], *c = m->uvs + 2 * (size_t)tri[2];
        const float tu = w * a[0] + u * b[0] + v * c[0], tv = w * a[1] + u * b[1] + v * c[1];
        const float density = m->texel_density[prim_id];
        float lod = 0.0f;
        if (footprint_rad > 0.0f && t > 0.0f && density > 0.0f) {
            float e1[3], e2[3], ng[3];
            tri_edges(m->pos, tri, e1, e2);
            cross3(e1, e2, ng);
            const float ng_len = len3(ng), dir_len = len3(dir);
            const float cos_theta = ng_len > 0.0f && dir_len > 0.0f ? fabsf(dot3(ng, dir)) / (ng_len * dir_len) : 1.0f;
            const float width_m = t * dir_len * footprint_rad / fmaxf(cos_theta, 0.1f);
            lod = log2f(width_m * density);
        }
        float texel[4];
        tex_sample(&s->textures[m->texture], tu, tv, lod, texel);
        for (int k = 0; k < 3; k++) base[k] *= texel[k];
    }

    const float p[3] = {org[0] + t * dir[0], org[1] + t * dir[1], org[2] + t * dir[2]};
    float light[3] = {FV_SCENE_AMBIENT, FV_SCENE_AMBIENT, FV_SCENE_AMBIENT};
    if (s->light_count == 0) { /* head light: unit intensity, no falloff */
        float L[3] = {eye_pos[0] - p[0], eye_pos[1] - p[1], eye_pos[2] - p[2]};
        const float nl = dot3(n, L), ll = dot3(L, L);
        if (nl > 0.0f && ll > 0.0f) {
            const float lam = nl / sqrtf(nn * ll);
            for (int k = 0; k < 3; k++) light[k] += lam;
        }
    } else {
        const float inv_n = nn > 0.0f ? 1.0f / sqrtf(nn) : 0.0f;
        for (int k = 0; k < 3; k++) n[k] *= inv_n;
        for (int i = 0; i < s->light_count; i++) {
            const fv_light_rec *lr = &s->lights[i];
            const fv_light *l = &lr->l;
            float L[3], atten = 1.0f;
            if (l->type == FV_LIGHT_DIRECTIONAL) {
                for (int k = 0; k < 3; k++) L[k] = -l->dir[k];
            } else {
                for (int k = 0; k < 3; k++) L[k] = l->pos[k] - p[k];
                const float d = len3(L);
                if (!(d > 0.0f)) continue;
                for (int k = 0; k < 3; k++) L[k] /= d;
                atten = range_window(d, l->range) / (d * d);
                if (l->type == FV_LIGHT_SPOT)
                    atten *= smoothstepf(lr->cos_outer, lr->cos_inner, -dot3(l->dir, L));
            }
            const float lam = fmaxf(0.0f, dot3(n, L));
            const float e = lam * atten * l->intensity * s->light_exposure;
            if (!(e > 0.0f) || !isfinite(e)) continue;
            for (int k = 0; k < 3; k++) light[k] += l->color[k] * e;
        }
    }
    for (int k = 0; k < 3; k++) rgb[k] = base[k] * light[k];
}

/* ---- glTF ---------------------------------------------------------------------------- */

/* Rotation of a column-major matrix (scale divided out) as a quaternion x,y,z,w. */
static void matrix_quat(const double wm[16], float q[4])
{
    double c[3][3];
    for (int j = 0; j < 3; j++) {
        const double l = sqrt(wm[j * 4] * wm[j * 4] + wm[j * 4 + 1] * wm[j * 4 + 1] + wm[j * 4 + 2] * wm[j * 4 + 2]);
        for (int i = 0; i < 3; i++) c[j][i] = l > 0.0 ? wm[j * 4 + i] / l : (i == j);
    }
#define R(row, col) c[col][row]
    double x, y, z, w;
    const double tr = R(0, 0) + R(1, 1) + R(2, 2);
    if (tr > 0.0) {
        const double S = sqrt(tr + 1.0) * 2.0;
        w = 0.25 * S, x = (R(2, 1) - R(1, 2)) / S, y = (R(0, 2) - R(2, 0)) / S, z = (R(1, 0) - R(0, 1)) / S;
    } else if (R(0, 0) > R(1, 1) && R(0, 0) > R(2, 2)) {
        const double S = sqrt(1.0 + R(0, 0) - R(1, 1) - R(2, 2)) * 2.0;
        w = (R(2, 1) - R(1, 2)) / S, x = 0.25 * S, y = (R(0, 1) + R(1, 0)) / S, z = (R(0, 2) + R(2, 0)) / S;
    } else if (R(1, 1) > R(2, 2)) {
        const double S = sqrt(1.0 + R(1, 1) - R(0, 0) - R(2, 2)) * 2.0;
        w = (R(0, 2) - R(2, 0)) / S, x = (R(0, 1) + R(1, 0)) / S, y = 0.25 * S, z = (R(1, 2) + R(2, 1)) / S;
    } else {
        const double S = sqrt(1.0 + R(2, 2) - R(0, 0) - R(1, 1)) * 2.0;
        w = (R(1, 0) - R(0, 1)) / S, x = (R(0, 2) + R(2, 0)) / S, y = (R(1, 2) + R(2, 1)) / S, z = 0.25 * S;
    }
#undef R
    const double n = sqrt(x * x + y * y + z * z + w * w);
    if (!(n > 0.0) || !isfinite(n)) x = y = z = 0.0, w = 1.0;
    else x /= n, y /= n, z /= n, w /= n;
    q[0] = (float)x, q[1] = (float)y, q[2] = (float)z, q[3] = (float)w;
}

/* Adds the glTF's meshes, lights and first camera through the builder. 0 on success. */
static int add_gltf(fv_scene *s, const fv_gltf_model *g, char *err, size_t err_len)
{
    int *tex_of_image = NULL;
    if (g->image_count) {
        tex_of_image = malloc(g->image_count * sizeof *tex_of_image);
        if (!tex_of_image) {
            fv_err(err, err_len, "out of memory");
            return -1;
        }
        for (size_t i = 0; i < g->image_count; i++) tex_of_image[i] = -1;
    }
    int have_camera = 0, rc = 0;
    for (size_t ni = 0; ni < g->node_count && rc == 0; ni++) {
        const fv_gltf_node *nd = &g->nodes[ni];
        if (nd->mesh >= 0) {
            const fv_gltf_mesh *gm = &g->meshes[nd->mesh];
            for (size_t pi = 0; pi < gm->prim_count; pi++) {
                const fv_gltf_prim *p = &gm->prims[pi];
                fv_mesh_desc d;
                memset(&d, 0, sizeof d);
                d.positions = p->positions, d.normals = p->normals, d.uvs = p->uvs, d.indices = p->indices;
                d.vertex_count = p->vertex_count, d.index_count = p->index_count;
                d.base_color[0] = d.base_color[1] = d.base_color[2] = d.base_color[3] = 1.0f;
                d.texture = -1;
                if (p->material >= 0) {
                    const fv_gltf_material *mat = &g->materials[p->material];
                    memcpy(d.base_color, mat->base_color, sizeof d.base_color);
                    const int img = mat->image;
                    if (img >= 0 && p->uvs && g->images[img].rgba8) { /* no uvs: factor only */
                        if (tex_of_image[img] < 0)
                            tex_of_image[img] = fv_scene_add_texture(s, g->images[img].rgba8, g->images[img].width,
                                                                     g->images[img].height);
                        if (tex_of_image[img] < 0) {
                            fv_err(err, err_len, "image %d: cannot add texture", img);
                            rc = -1;
                            break;
                        }
                        d.texture = tex_of_image[img];
                    }
                }
                for (int k = 0; k < 16; k++) d.transform[k] = (float)nd->world[k];
                char e[192];
                if (fv_scene_add_mesh(s, &d, e, sizeof e) < 0) {
                    fv_err(err, err_len, "mesh %d (node %zu in traversal order): %s", nd->mesh, ni, e);
                    rc = -1;
                    break;
                }
            }
        }
        if (nd->light >= 0) {
            const fv_gltf_light *gl = &g->lights[nd->light];
            fv_light l;
            memset(&l, 0, sizeof l);
            l.type = gl->type == 0 ? FV_LIGHT_DIRECTIONAL : gl->type == 1 ? FV_LIGHT_POINT : FV_LIGHT_SPOT;
            memcpy(l.color, gl->color, sizeof l.color);
            l.intensity = gl->intensity, l.range = gl->range;
            l.inner_cone = gl->inner_cone_rad, l.outer_cone = gl->outer_cone_rad;
            for (int k = 0; k < 3; k++) {
                l.pos[k] = (float)nd->world[12 + k];
                l.dir[k] = -(float)nd->world[8 + k]; /* lights point down the node's -Z */
            }
            fv_scene_add_light(s, &l);
        }
        if (nd->camera >= 0 && !have_camera) {
            const float pos[3] = {(float)nd->world[12], (float)nd->world[13], (float)nd->world[14]};
            float q[4];
            matrix_quat(nd->world, q);
            fv_scene_set_default_view(s, pos, q);
            have_camera = 1;
        }
    }
    free(tex_of_image);
    return rc;
}

fv_scene *fv_scene_load(const char *path, char *err, size_t err_len)
{
    char e[256] = "";
    if (!path) {
        fv_err(err, err_len, "no path");
        return NULL;
    }
    fv_gltf_model *g = fv_gltf_load(path, e, sizeof e);
    if (!g) {
        fv_err(err, err_len, "%s: %s", path, e);
        return NULL;
    }
    fv_scene *s = fv_scene_create();
    if (!s) {
        fv_gltf_free(g);
        fv_err(err, err_len, "%s: cannot create the Embree device/scene", path);
        return NULL;
    }
    int rc = add_gltf(s, g, e, sizeof e);
    fv_gltf_free(g);
    if (rc == 0 && s->triangle_count == 0) { /* nothing to render: most likely not a real scene */
        fv_err(e, sizeof e, "no triangles reachable from the scene's root nodes");
        rc = -1;
    }
    if (rc == 0) rc = fv_scene_commit(s, e, sizeof e);
    if (rc != 0) {
        fv_err(err, err_len, "%s: %s", path, e);
        fv_scene_free(s);
        return NULL;
    }
    fv_err(err, err_len, "%s", "");
    return s;
}
