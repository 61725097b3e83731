/* fovea: shading hits (fv_scene_shade, one; fv_scene_shade_packet, an Embree packet): the
 * material's inputs gathered here, the BRDF and lights in core/shade_lane.h / the kernels. */
#include "scene_impl.h"
#include "shade_lane.h"
#include "shadow.h"
#include "texture_tap.h"
#include "base/util.h"

#include <math.h>
#include <string.h>

_Static_assert(FV_SHADE_LANES == 16, "fv_hit_packet (scene.h) holds 16 lanes");

/* A textured hit's texture coordinates and mip level (from the ray footprint: footprint_rad is
 * the pixel's angle along the ray). */
static void tex_coords(const fv_mesh_rec *m, unsigned prim, float u, float v, float w, const float dir[3], float t,
                       float footprint_rad, float *tu, float *tv, float *lod)
{
    const fv_tri_attr *at = &m->attr[prim];
    const float *a = at->uv, *b = at->uv + 2, *c = at->uv + 4;
    *tu = w * a[0] + u * b[0] + v * c[0], *tv = w * a[1] + u * b[1] + v * c[1];
    const float density = at->texel_density;
    *lod = 0.0f;
    if (footprint_rad > 0.0f && t > 0.0f && density > 0.0f) {
        const fv_tri_face *f = &m->face[prim];
        const float ng_len = f->ng_len, dir_len = len3(dir);
        const float cos_theta = ng_len > 0.0f && dir_len > 0.0f ? fabsf(dot3(f->ng, dir)) / (ng_len * dir_len) : 1.0f;
        const float width_m = t * dir_len * footprint_rad / fmaxf(cos_theta, 0.1f);
        *lod = log2f(width_m * density);
    }
}

/* The material's inputs at a hit from the texels of its maps (NULL: no such map); the one
 * definition both paths use. glTF: metallic in B, roughness in G, occlusion in R. */
static void material_at(const fv_mesh_rec *m, unsigned prim, float u, float v, float w, const float *base_tx,
                        const float *mr, const float *oc, const float *em, fv_brdf_mat *mat, float *occ, float emit[3])
{
    for (int k = 0; k < 3; k++) mat->base[k] = base_tx ? m->base_color[k] * base_tx[k] : m->base_color[k];
    if (m->col) { /* vertex colours (glTF COLOR_0), interpolated */
        const float *c = m->col + 9 * (size_t)prim;
        for (int k = 0; k < 3; k++) mat->base[k] *= w * c[k] + u * c[3 + k] + v * c[6 + k];
    }
    mat->metallic = m->metallic, mat->a2 = m->a2, mat->specular = m->specular;
    if (mr) {
        mat->metallic = m->metallic * mr[2];
        mat->a2 = fv_ggx_a2(m->roughness * mr[1]);
    }
    *occ = oc ? 1.0f + m->occlusion_strength * (oc[0] - 1.0f) : 1.0f;
    for (int k = 0; k < 3; k++) emit[k] = em ? m->emissive[k] * em[k] : m->emissive[k];
}

/* Slot j's texture: 0 base colour, 1 + FV_MAP_*. */
static int slot_texture(const fv_mesh_rec *m, int j) { return j == 0 ? m->texture : m->map[j - 1]; }

/* Slot j's texture coordinates: the mesh's, through its KHR_texture_transform if any. */
static void slot_uv(const fv_mesh_rec *m, int j, float tu, float tv, float *su, float *sv)
{
    if (!m->has_uvx) {
        *su = tu, *sv = tv;
        return;
    }
    const float *x = m->uvx[j];
    *su = x[0] * tu + x[1] * tv + x[2];
    *sv = x[3] * tu + x[4] * tv + x[5];
}

/* The material at the hit, every map sampled trilinearly at the footprint's mip level; the
 * normal map's texel into ntex (returns 1 if there is one). */
static int material(const fv_scene *s, const fv_mesh_rec *m, unsigned prim, float u, float v, float w,
                    const float dir[3], float t, float footprint_rad, fv_brdf_mat *mat, float *occ, float emit[3],
                    float ntex[4])
{
    float texel[FV_SLOTS][4];
    const float *tx[FV_SLOTS] = {NULL, NULL, NULL, NULL, NULL};
    if (m->tex_ref >= 0) {
        float tu, tv, lod;
        tex_coords(m, prim, u, v, w, dir, t, footprint_rad, &tu, &tv, &lod);
        for (int j = 0; j < FV_SLOTS; j++) {
            const int id = slot_texture(m, j);
            if (id < 0) continue;
            float su, sv;
            slot_uv(m, j, tu, tv, &su, &sv);
            fv_texture_sample(&s->textures[id], su, sv, lod + m->lod_bias[j], texel[j]);
            tx[j] = texel[j];
        }
    }
    material_at(m, prim, u, v, w, tx[0], tx[1], tx[2], tx[3], mat, occ, emit);
    if (!tx[1 + FV_MAP_NRM]) return 0;
    memcpy(ntex, tx[1 + FV_MAP_NRM], 4 * sizeof(float));
    return 1;
}

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

    float n[3];
    const fv_tri_attr *at = &m->attr[prim_id];
    const float *n0 = at->n, *n1 = at->n + 3, *n2 = at->n + 6;
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
    fv_brdf_mat mat;
    float occ, emit[3], ntex[4];
    if (material(s, m, prim_id, u, v, w, dir, t, footprint_rad, &mat, &occ, emit, ntex))
        fv_shade_normal_mapped(m, prim_id, u, v, w, ntex, n, &nn); /* core/shade_normal.c */
    float lit[FV_SHADOW_MAX_LIGHTS];
    const int shadows = s->shadows && s->light_count > 0 && nn > 1e-24f;
    if (shadows) { /* core/shadow.c */
        const float hit[3] = {org[0] + t * dir[0], org[1] + t * dir[1], org[2] + t * dir[2]};
        fv_shadow_scalar(s, hit, n, nn, dir, lit);
    }
    fv_shade_lane(&mat, occ, emit, n, nn, org, dir, t, eye_pos, s->lights, s->light_count, s->light_exposure,
                  shadows ? lit : NULL, 1, rgb);
}

/* A textured mesh's slots as the packet gather walks them, looked up once per run of lanes on
 * the mesh: the slots sampled here (a texture, and not the same texels as an earlier slot) in
 * order, each slot's texture (NULL: none) and, per sampled slot j, bit i set where slot i's
 * texture has the same layout (fv_tex_same_layout). */
typedef struct {
    const fv_mesh_rec *m;
    int n, slot[FV_SLOTS];
    const fv_texture *tex[FV_SLOTS];
    unsigned same_layout[FV_SLOTS];
} slot_plan_t;

static void slot_plan(const fv_scene *s, const fv_mesh_rec *m, slot_plan_t *p)
{
    p->m = m, p->n = 0;
    for (int j = 0; j < FV_SLOTS; j++) {
        const int id = slot_texture(m, j);
        p->tex[j] = id >= 0 ? &s->textures[id] : NULL;
        p->same_layout[j] = 0;
        if (id < 0 || m->slot_src[j] != j) continue; /* none, or the same texels as an earlier slot */
        p->slot[p->n++] = j;
        for (int i = 0; i < j; i++)
            if (p->tex[i] && fv_tex_same_layout(p->tex[i], p->tex[j])) p->same_layout[j] |= 1u << i;
    }
}

void fv_scene_shade_prefetch(const fv_scene *s, const unsigned *geom, const unsigned *prim, int n)
{
    /* the mesh's arrays looked up once per run of lanes on it (a packet mostly hits one or two) */
    const fv_tri_attr *attr = NULL;
    const fv_tri_face *face = NULL;
    const float *tan = NULL;
    size_t tris = 0;
    unsigned mg = RTC_INVALID_GEOMETRY_ID;
    for (int q = 0; q < n; q++) {
        const unsigned g = geom[q], p = prim[q];
        if (g >= s->mesh_count) continue; /* a miss */
        if (g != mg) {
            const fv_mesh_rec *m = &s->meshes[g];
            attr = m->attr, face = m->face, tan = m->tan, tris = m->tri_count, mg = g;
        }
        if (p >= tris) continue;
        __builtin_prefetch(&attr[p]);
        if (face)
            __builtin_prefetch(&face[p]);
        if (tan) /* a normal map's corner tangents (48 bytes) */
            __builtin_prefetch(&tan[12 * (size_t)p]), __builtin_prefetch(&tan[12 * (size_t)p + 11]);
    }
}

void fv_scene_shade_packet(const fv_scene *s, const fv_shade_dsp *dsp, const fv_hit_packet *h, int n,
                           float px_tan, const float eye_pos[3], float rgb[3][FV_SHADE_LANES])
{
    /* Per thread, zero at start: lanes of misses keep whatever an earlier packet left there
     * (finite, initialised: their results are not used), so a miss costs no stores. */
    static _Thread_local _Alignas(64) fv_shade_packet pk;
    /* the geometry of short packets and of normal-mapped lanes (a full packet's is read in place) */
    static _Thread_local _Alignas(64) fv_shade_lanes own;
    /* the corner normals of lanes without a hit (their results are not used): finite, not degenerate */
    static const float nrm_none[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    /* pk's material rows (base, emit, metal, a2, spec, occl) hold mesh pk_geom of scene pk_scene in
     * every lane (0: not known): a one-mesh packet on the same mesh as the last one skips the
     * broadcast (208 stores; consecutive packets of a tile mostly hit the same mesh) */
    static _Thread_local unsigned long pk_scene;
    static _Thread_local unsigned pk_geom;
    fv_tex_taps taps[FV_SLOTS][FV_SHADE_LANES]; /* slot (base colour, maps), lane */
    unsigned hits = 0, black = 0, textured = 0;
    const unsigned *geom = h->geom, *primv = h->prim; /* locals: the stores to pk would make the compiler reload h */
    /* g0: the first hit lane's mesh; mixed: a hit on another mesh. A packet of misses only (most of
     * a small object's frame: FlightHelmet, DepthOfFieldExample) has nothing to shade and no lane to
     * blacken; pk is left as it is (its material rows still hold what pk_scene / pk_geom say). A
     * full packet's tests are passes without a branch per lane (vectorised). */
    unsigned g0 = RTC_INVALID_GEOMETRY_ID, mixed = 0;
    if (n == FV_SHADE_LANES) {
        unsigned any = 0;
        for (int q = 0; q < FV_SHADE_LANES; q++)
            any |= geom[q] != RTC_INVALID_GEOMETRY_ID;
        if (!any)
            return;
    }
    for (int q = 0; q < n; q++)
        if (geom[q] != RTC_INVALID_GEOMETRY_ID) {
            g0 = geom[q];
            break;
        }
    if (g0 == RTC_INVALID_GEOMETRY_ID)
        return;
    if (n == FV_SHADE_LANES)
        for (int q = 0; q < FV_SHADE_LANES; q++)
            mixed |= (geom[q] != RTC_INVALID_GEOMETRY_ID) & (geom[q] != g0);
    else
        for (int q = 0; q < n; q++)
            mixed |= (geom[q] != RTC_INVALID_GEOMETRY_ID) & (geom[q] != g0);
    /* the lanes' ray data: a full packet's read in place by the kernel, a short one's copied (the
     * lanes past n keep an earlier packet's values: finite, unused) */
    if (n == FV_SHADE_LANES) {
        pk.u = h->u, pk.v = h->v, pk.t = h->t;
        for (int k = 0; k < 3; k++) pk.dir[k] = h->dir[k];
    } else {
        const float *hu = h->u, *hv = h->v, *ht = h->t, *d0 = h->dir[0], *d1 = h->dir[1], *d2 = h->dir[2];
        for (int q = 0; q < n; q++) {
            own.u[q] = hu[q], own.v[q] = hv[q], own.t[q] = ht[q];
            own.dir[0][q] = d0[q], own.dir[1][q] = d1[q], own.dir[2][q] = d2[q];
        }
        pk.u = own.u, pk.v = own.v, pk.t = own.t;
        for (int k = 0; k < 3; k++) pk.dir[k] = own.dir[k];
        for (int q = n; q < FV_SHADE_LANES; q++)
            pk.nrm_at[q] = nrm_none;
    }
    /* A packet usually hits one mesh: an untextured mesh without vertex colours then has one
     * material for every lane, broadcast to all 16 (material_at's values, computed once), and
     * each lane only needs its corner normals. */
    const fv_mesh_rec *um = !mixed && g0 < s->mesh_count ? &s->meshes[g0] : NULL;
    if (um && (um->tex_ref >= 0 || um->col)) um = NULL;
    if (um && (pk_scene != s->serial || pk_geom != g0)) {
        fv_brdf_mat mat;
        float occ, emit[3];
        material_at(um, 0, 0.0f, 0.0f, 1.0f, NULL, NULL, NULL, NULL, &mat, &occ, emit);
        for (int q = 0; q < FV_SHADE_LANES; q++) {
            for (int k = 0; k < 3; k++) pk.base[k][q] = mat.base[k], pk.emit[k][q] = emit[k];
            pk.metal[q] = mat.metallic, pk.a2[q] = mat.a2, pk.spec[q] = mat.specular, pk.occl[q] = occ;
        }
        pk_scene = s->serial, pk_geom = g0;
    } else if (!um) { /* the lanes' own materials follow */
        pk_scene = 0;
    }
    if (um) {
        const fv_tri_attr *attr = um->attr;
        const size_t tris = um->tri_count;
        for (int q = 0; q < n; q++) {
            const unsigned prim = primv[q];
            pk.nrm_at[q] = nrm_none;
            if (geom[q] == RTC_INVALID_GEOMETRY_ID)
                continue;
            if (prim >= tris) { /* no such triangle: black */
                black |= 1u << q;
                continue;
            }
            hits |= 1u << q;
            pk.nrm_at[q] = attr[prim].n; /* read by the kernel (NRM9) */
        }
    }
    slot_plan_t plan; /* the textured mesh of the last textured lane */
    plan.m = NULL;
    const fv_mesh_rec *plain_m = NULL; /* the mesh whose material plain holds */
    fv_brdf_mat plain = {{0, 0, 0}, 0, 0, 0};
    float plain_occ = 1.0f, plain_emit[3] = {0, 0, 0};
    for (int q = 0; q < n && !um; q++) {
        const unsigned g = geom[q], prim = primv[q];
        const fv_mesh_rec *m = g < s->mesh_count ? &s->meshes[g] : NULL;
        pk.nrm_at[q] = nrm_none;
        if (!m || prim >= m->tri_count) { /* a miss, or no such triangle (black) */
            if (g != RTC_INVALID_GEOMETRY_ID)
                black |= 1u << q;
            continue;
        }
        hits |= 1u << q;
        const fv_tri_attr *at = &m->attr[prim];
        pk.nrm_at[q] = at->n;
        const float u = h->u[q], v = h->v[q], t = h->t[q];
        if (m->tex_ref >= 0) { /* the texel fetches of all lanes are asked for before any is used */
            const float dir[3] = {h->dir[0][q], h->dir[1][q], h->dir[2][q]};
            const float fp = px_tan / sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
            float tu, tv, lod;
            tex_coords(m, prim, u, v, 1.0f - u - v, dir, t, fp, &tu, &tv, &lod);
            if (m != plan.m)
                slot_plan(s, m, &plan);
            int jp = -1; /* the last slot whose taps were computed here */
            float psu = 0.0f, psv = 0.0f, plod = 0.0f;
            for (int k = 0; k < plan.n; k++) {
                const int j = plan.slot[k];
                float su, sv;
                slot_uv(m, j, tu, tv, &su, &sv);
                const float lj = lod + m->lod_bias[j];
                const fv_texture *tj = plan.tex[j];
                /* maps of one size sampled at the same point (no own texture transform): the
                 * same texel offsets and weights in another texture */
                if (jp >= 0 && su == psu && sv == psv && lj == plod && (plan.same_layout[j] >> jp & 1))
                    fv_tex_taps_rebase(plan.tex[jp], tj, &taps[jp][q], &taps[j][q]);
                else
                    fv_tex_taps_at(tj, su, sv, lj, &taps[j][q]), jp = j, psu = su, psv = sv, plod = lj;
                fv_tex_taps_prefetch(&taps[j][q]);
            }
            textured |= 1u << q;
            if (slot_texture(m, 1 + FV_MAP_NRM) >= 0 && pk.u != own.u) {
                /* a normal-mapped lane gets u = v = 0 below: copy a full packet's u, v now, so
                 * the stores are done long before the kernel's vector loads read them */
                memcpy(own.u, h->u, sizeof own.u), memcpy(own.v, h->v, sizeof own.v);
                pk.u = own.u, pk.v = own.v;
            }
        } else {
            /* without vertex colours the material is the mesh's: computed once per run of lanes
             * on one mesh */
            if (m != plain_m || m->col) {
                material_at(m, prim, u, v, 1.0f - u - v, NULL, NULL, NULL, NULL, &plain, &plain_occ, plain_emit);
                plain_m = m;
            }
            for (int k = 0; k < 3; k++) pk.base[k][q] = plain.base[k], pk.emit[k][q] = plain_emit[k];
            pk.metal[q] = plain.metallic, pk.a2[q] = plain.a2, pk.spec[q] = plain.specular, pk.occl[q] = plain_occ;
        }
    }
    for (unsigned r = textured; r; r &= r - 1) {
        const int q = __builtin_ctz(r);
        const fv_mesh_rec *m = &s->meshes[h->geom[q]];
        float texel[FV_SLOTS][4];
        const float *tx[FV_SLOTS] = {NULL, NULL, NULL, NULL, NULL};
        if (m != plan.m)
            slot_plan(s, m, &plan);
        for (int k = 0; k < plan.n; k++)
            fv_tex_blend(&taps[plan.slot[k]][q], texel[plan.slot[k]]);
        for (int j = 0; j < FV_SLOTS; j++)
            if (plan.tex[j])
                tx[j] = texel[m->slot_src[j]];
        fv_brdf_mat mat;
        float occ, emit[3];
        const float u = h->u[q], v = h->v[q];
        material_at(m, h->prim[q], u, v, 1.0f - u - v, tx[0], tx[1], tx[2], tx[3], &mat, &occ, emit);
        for (int k = 0; k < 3; k++) pk.base[k][q] = mat.base[k], pk.emit[k][q] = emit[k];
        pk.metal[q] = mat.metallic, pk.a2[q] = mat.a2, pk.spec[q] = mat.specular, pk.occl[q] = occ;
        if (tx[1 + FV_MAP_NRM]) { /* normal map: the kernel gets the mapped normal as corner 0 at u = v = 0 */
            float nm[3], nn;
            fv_shade_normal_mapped(m, h->prim[q], u, v, 1.0f - u - v, tx[1 + FV_MAP_NRM], nm, &nn);
            for (int k = 0; k < 3; k++) own.nrm[q][k] = nm[k], own.nrm[q][3 + k] = 0.0f, own.nrm[q][6 + k] = 0.0f;
            pk.nrm_at[q] = own.nrm[q];
            if (pk.u != own.u) { /* a full packet's u, v were read in place */
                memcpy(own.u, h->u, sizeof own.u), memcpy(own.v, h->v, sizeof own.v);
                pk.u = own.u, pk.v = own.v;
            }
            own.u[q] = 0.0f, own.v[q] = 0.0f;
        }
    }
    if (!hits) { /* all misses: nothing to shade */
        for (; black; black &= black - 1)
            for (int k = 0; k < 3; k++) rgb[k][__builtin_ctz(black)] = 0.0f;
        return;
    }
    fv_shade_env env = {.lights = s->lights, .nlights = s->light_count, .exposure = s->light_exposure,
                        .eye = {eye_pos[0], eye_pos[1], eye_pos[2]}};
    if (s->shadows && s->light_count > 0) { /* occlusion rays towards the lights: core/shadow.c */
        static _Thread_local _Alignas(64) float lit[FV_SHADOW_MAX_LIGHTS][FV_SHADE_LANES];
        fv_shadow_packet(s, &pk, hits, eye_pos, lit);
        env.lit = &lit[0][0];
    }
    unsigned rest = dsp->brdf(&pk, &env, rgb) & hits;
    while (rest) { /* degenerate smooth normals: the scalar path's face normal */
        const int q = __builtin_ctz(rest);
        rest &= rest - 1;
        const float dir[3] = {h->dir[0][q], h->dir[1][q], h->dir[2][q]};
        const float len = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
        float c[3];
        fv_scene_shade(s, h->geom[q], h->prim[q], h->u[q], h->v[q], eye_pos, dir, h->t[q], px_tan / len, eye_pos, c);
        for (int k = 0; k < 3; k++) rgb[k][q] = c[k];
    }
    for (; black; black &= black - 1)
        for (int k = 0; k < 3; k++) rgb[k][__builtin_ctz(black)] = 0.0f;
}
