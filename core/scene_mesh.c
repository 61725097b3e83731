/* fovea: scene meshes: validated, flattened to world space (positions in double), with
 * normals (given ones through the inverse transpose, otherwise smooth area-weighted) and
 * per-triangle texel density for mip selection, attached to the Embree scene. */
#include "scene_impl.h"
#include "base/err.h"
#include "brdf.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define FV_MAX_VERTICES ((size_t)1 << 28)
#define FV_MAX_TRIANGLES ((size_t)1 << 28)

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
    const int map[FV_MAPS] = {m->maps ? m->maps->metallic_roughness : -1, m->maps ? m->maps->occlusion : -1,
                              m->maps ? m->maps->emissive : -1, m->maps ? m->maps->normal : -1};
    int tex_ref = m->texture;
    for (int j = 0; j < FV_MAPS; j++) {
        if (map[j] < -1 || map[j] >= s->texture_count) {
            fv_err(err, err_len, "material map texture %d does not exist", map[j]);
            return -1;
        }
        if (tex_ref < 0) tex_ref = map[j];
    }
    if (tex_ref >= 0 && !m->uvs) {
        fv_err(err, err_len, "texture without uvs");
        return -1;
    }
    if (!(m->alpha_cutoff >= 0.0f && m->alpha_cutoff <= 1.0f)) {
        fv_err(err, err_len, "alpha cutoff %g is outside [0, 1]", (double)m->alpha_cutoff);
        return -1;
    }
    if (map[FV_MAP_NRM] >= 0 && !isfinite(m->maps->normal_scale)) {
        fv_err(err, err_len, "normal scale is not finite");
        return -1;
    }
    if (m->maps && !(m->maps->occlusion_strength >= 0.0f && m->maps->occlusion_strength <= 1.0f)) {
        fv_err(err, err_len, "occlusion strength %g is outside [0, 1]", (double)m->maps->occlusion_strength);
        return -1;
    }
    for (int c = 0; c < 4; c++)
        if (!isfinite(m->base_color[c])) {
            fv_err(err, err_len, "base colour is not finite");
            return -1;
        }
    const float unit[3] = {m->metallic, m->roughness, m->specular};
    for (int c = 0; c < 3; c++)
        if (!(unit[c] >= 0.0f && unit[c] <= 1.0f)) { /* also NaN */
            fv_err(err, err_len, "%s %g is outside [0, 1]", c == 0 ? "metallic" : c == 1 ? "roughness" : "specular",
                   (double)unit[c]);
            return -1;
        }
    for (int c = 0; c < 3; c++)
        if (!(m->emissive[c] >= 0.0f) || !isfinite(m->emissive[c])) {
            fv_err(err, err_len, "emissive is negative or not finite");
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

    if (fv_scene_grow((void **)&s->meshes, &s->mesh_cap, s->mesh_count + 1, sizeof *s->meshes)) {
        fv_err(err, err_len, "out of memory");
        return -1;
    }
    fv_mesh_rec r;
    memset(&r, 0, sizeof r);
    r.vertex_count = nv, r.tri_count = nt, r.texture = m->texture;
    memcpy(r.base_color, m->base_color, sizeof r.base_color);
    r.metallic = m->metallic, r.a2 = fv_ggx_a2(m->roughness), r.specular = m->specular, r.roughness = m->roughness;
    r.tex_ref = tex_ref;
    r.alpha_cutoff = m->alpha_cutoff;
    r.single_sided = m->single_sided != 0;
    r.blend = m->alpha_blend != 0 && !(m->alpha_cutoff > 0.0f);
    s->has_blend |= r.blend;
    if (m->maps && m->maps->has_uv_transform) {
        for (int j = 0; j < 4; j++)
            for (int k = 0; k < 6; k++)
                if (!isfinite(m->maps->uv_transform[j][k])) {
                    fv_err(err, err_len, "uv transform is not finite");
                    return -1;
                }
        r.has_uvx = 1;
        memcpy(r.uvx, m->maps->uv_transform, sizeof r.uvx);
    }
    r.occlusion_strength = m->maps ? m->maps->occlusion_strength : 0.0f;
    r.normal_scale = map[FV_MAP_NRM] >= 0 ? m->maps->normal_scale : 0.0f;
    for (int j = 0; j < FV_SLOTS; j++) { /* a map with 4x the texels of tex_ref is one mip level further down at the same footprint */
        const int tx = j == 0 ? m->texture : map[j - 1];
        if (j > 0) r.map[j - 1] = tx;
        r.lod_bias[j] = 0.0f;
        if (tx >= 0 && tx != tex_ref) {
            const fv_texture *a = &s->textures[tx], *b = &s->textures[tex_ref];
            r.lod_bias[j] = (float)(0.5 * log2(((double)a->w[0] * a->h[0]) / ((double)b->w[0] * b->h[0])));
        }
    }
    /* maps that cannot change the result are not sampled */
    if (r.occlusion_strength == 0.0f) r.map[FV_MAP_OCC] = -1;
    if (m->emissive[0] == 0.0f && m->emissive[1] == 0.0f && m->emissive[2] == 0.0f) r.map[FV_MAP_EMIS] = -1;
    for (int j = 0; j < FV_SLOTS; j++) { /* slots that would fetch the same texels: the packet path fetches them once */
        const int tj = j == 0 ? r.texture : r.map[j - 1];
        r.slot_src[j] = (signed char)j;
        for (int i = 0; i < j && tj >= 0; i++)
            if ((i == 0 ? r.texture : r.map[i - 1]) == tj && (!r.has_uvx || !memcmp(r.uvx[i], r.uvx[j], sizeof r.uvx[i]))) {
                r.slot_src[j] = (signed char)i;
                break;
            }
    }
    memcpy(r.emissive, m->emissive, sizeof r.emissive);
    float *pos = malloc(nv * 3 * sizeof(float));
    uint32_t *tri = malloc(nt * 3 * sizeof(uint32_t));
    float *normals = calloc(nv * 3, sizeof(float));
    float *uvs = m->uvs ? malloc(nv * 2 * sizeof(float)) : NULL;
    float *density = tex_ref >= 0 ? malloc(nt * sizeof(float)) : NULL;
    r.attr = aligned_alloc(64, nt * sizeof *r.attr);
    r.face = tex_ref >= 0 ? malloc(nt * sizeof *r.face) : NULL;
    RTCGeometry g = NULL;
    if (!pos || !tri || !normals || !r.attr || (tex_ref >= 0 && !r.face) || (m->uvs && !uvs) || (tex_ref >= 0 && !density)) {
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
            float *o = normals + 3 * i;
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
                for (int k = 0; k < 3; k++) normals[3 * (size_t)tri[3 * t + (size_t)j] + (size_t)k] += fn[k];
        }
        for (size_t i = 0; i < nv; i++) {
            float *o = normals + 3 * i;
            const float l = len3(o);
            if (l > 0.0f && isfinite(l))
                for (int k = 0; k < 3; k++) o[k] /= l;
            else
                o[0] = o[1] = o[2] = 0.0f; /* shading falls back to the geometric normal */
        }
    }
    if (m->colors) {
        r.col = malloc(nt * 9 * sizeof(float));
        if (!r.col) {
            fv_err(err, err_len, "out of memory");
            goto fail;
        }
        for (size_t i = 0; i < 3 * nv; i++)
            if (!isfinite(m->colors[i])) {
                fv_err(err, err_len, "vertex %zu colour is not finite", i / 3);
                goto fail;
            }
        for (size_t t = 0; t < nt; t++)
            for (int c = 0; c < 3; c++)
                memcpy(r.col + 9 * t + 3 * c, m->colors + 3 * (size_t)tri[3 * t + (size_t)c], 3 * sizeof(float));
    }
    if (m->uvs) {
        for (size_t i = 0; i < 2 * nv; i++)
            if (!isfinite(m->uvs[i])) {
                fv_err(err, err_len, "vertex %zu uv is not finite", i / 2);
                goto fail;
            }
        memcpy(uvs, m->uvs, nv * 2 * sizeof(float));
    }
    if (r.map[FV_MAP_NRM] >= 0) {
        r.tan = malloc(nt * 12 * sizeof(float));
        if (!r.tan) {
            fv_err(err, err_len, "out of memory");
            goto fail;
        }
        if (fv_scene_mesh_tangents(pos, tri, nv, nt, normals, uvs, m->tangents, M, r.tan, err, err_len))
            goto fail;
    }
    if (density) {
        const fv_texture *tx = &s->textures[tex_ref];
        const double texels = (double)tx->w[0] * (double)tx->h[0];
        for (size_t t = 0; t < nt; t++) {
            float e1[3], e2[3], fn[3];
            tri_edges(pos, tri + 3 * t, e1, e2);
            cross3(e1, e2, fn);
            const uint32_t *v = tri + 3 * t;
            const float *u0 = uvs + 2 * (size_t)v[0], *u1 = uvs + 2 * (size_t)v[1], *u2 = uvs + 2 * (size_t)v[2];
            const double uv_area2 = fabs((double)(u1[0] - u0[0]) * (u2[1] - u0[1]) - (double)(u1[1] - u0[1]) * (u2[0] - u0[0]));
            const double world_area2 = len3(fn);
            const double d = world_area2 > 0.0 ? sqrt(uv_area2 * texels / world_area2) : 0.0;
            density[t] = isfinite(d) && d < FLT_MAX ? (float)d : 0.0f;
            for (int k = 0; k < 3; k++) r.face[t].ng[k] = fn[k];
            r.face[t].ng_len = len3(fn);
        }
    }

    /* shading reads one cache line per hit, not the index buffer and three vertices */
    for (size_t t = 0; t < nt; t++) {
        fv_tri_attr *a = &r.attr[t];
        for (int c = 0; c < 3; c++) {
            const size_t v = tri[3 * t + (size_t)c];
            for (int k = 0; k < 3; k++) a->n[3 * c + k] = normals[3 * v + (size_t)k];
            for (int k = 0; k < 2; k++) a->uv[2 * c + k] = uvs ? uvs[2 * v + (size_t)k] : 0.0f;
        }
        a->texel_density = density ? density[t] : 0.0f;
    }
    free(normals);
    free(uvs);
    free(density);
    normals = uvs = density = NULL;

    g = rtcNewGeometry(s->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *vb = g ? rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv) : NULL;
    uint32_t *ib = g ? rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), nt) : NULL;
    if (!vb || !ib) {
        if (!fv_scene_take_rtc_error(s, err, err_len)) fv_err(err, err_len, "embree geometry allocation failed");
        goto fail;
    }
    memcpy(vb, pos, nv * 3 * sizeof(float));
    memcpy(ib, tri, nt * 3 * sizeof(uint32_t));
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(s->rtc, g, (unsigned)s->mesh_count);
    rtcReleaseGeometry(g); /* the scene keeps its reference */
    g = NULL;
    if (fv_scene_take_rtc_error(s, err, err_len)) {
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
    free(normals);
    free(uvs);
    free(density);
    free(r.attr);
    free(r.face);
    free(r.col);
    free(r.tan);
    return -1;
}
