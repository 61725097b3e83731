/* fovea: alpha BLEND along the camera rays (core/blend.h). Each ray keeps the FV_BLEND_LAYERS
 * nearest blended surfaces the intersect filter reported (Embree may report a primitive more
 * than once with a high-quality BVH: duplicates are dropped), sorted by (t, geometry,
 * primitive) when composited, so the result does not depend on the order Embree found them in:
 *
 *   rgb = sum_i a_i c_i prod_{k<i} (1 - a_k)  +  prod_k (1 - a_k) c_opaque
 *
 * over the layers nearer than the opaque hit (c_opaque: the shaded hit, or the background), a_i
 * the layer's alpha (base colour factor x texture, bilinear at mip 0 as the MASK filter reads
 * it) and c_i its colour shaded as an opaque surface (fv_scene_shade). */
#include "blend.h"
#include "scene_impl.h"

#include <math.h>
#include <string.h>

static _Thread_local fv_blend_packet *rec; /* the packet being traced, or NULL */

int fv_scene_has_blend(const fv_scene *s) { return s && s->has_blend; }

void fv_blend_begin(fv_blend_packet *p)
{
    p->used = 0;
    rec = p;
}

void fv_blend_end(void) { rec = NULL; }

/* a before b in depth order (ties by geometry, then primitive: deterministic) */
static int nearer(float ta, unsigned ga, unsigned pa, float tb, unsigned gb, unsigned pb)
{
    return ta < tb || (ta == tb && (ga < gb || (ga == gb && pa < pb)));
}

void fv_blend_record(unsigned ray_id, unsigned geom, unsigned prim, float u, float v, float t)
{
    if (!rec || ray_id >= 16) return;
    fv_blend_lane *l = &rec->lane[ray_id];
    if (!(rec->used >> ray_id & 1u)) /* the ray's first layer */
        rec->used |= 1u << ray_id, l->n = 0;
    for (unsigned k = 0; k < l->n; k++)
        if (l->geom[k] == geom && l->prim[k] == prim) return; /* the same primitive again */
    unsigned slot = l->n;
    if (slot == FV_BLEND_LAYERS) { /* full: replace the farthest if this one is nearer */
        slot = 0;
        for (unsigned k = 1; k < FV_BLEND_LAYERS; k++)
            if (nearer(l->t[slot], l->geom[slot], l->prim[slot], l->t[k], l->geom[k], l->prim[k])) slot = k;
        if (!nearer(t, geom, prim, l->t[slot], l->geom[slot], l->prim[slot])) return;
    } else {
        l->n++;
    }
    l->geom[slot] = geom, l->prim[slot] = prim, l->u[slot] = u, l->v[slot] = v, l->t[slot] = t;
}

void fv_blend_composite(const fv_scene *s, const fv_blend_packet *p, unsigned *geom, float *tfar,
                        const float *const org[3], const float *const dir[3], int n, float px_tan, const float eye[3],
                        const float background[3], float rgb[3][16])
{
    for (unsigned r = p->used & (n >= 16 ? 0xffffu : (1u << n) - 1u); r; r &= r - 1) {
        const int q = __builtin_ctz(r);
        const fv_blend_lane *l = &p->lane[q];
        if (!l->n) continue;
        const int miss = geom[q] == RTC_INVALID_GEOMETRY_ID;
        const float t_opaque = miss ? INFINITY : tfar[q];
        unsigned order[FV_BLEND_LAYERS], m = 0;
        for (unsigned k = 0; k < l->n; k++) {
            if (!(l->t[k] < t_opaque)) continue;
            unsigned j = m++; /* insertion sort, nearest first */
            while (j > 0 && nearer(l->t[k], l->geom[k], l->prim[k], l->t[order[j - 1]], l->geom[order[j - 1]],
                                   l->prim[order[j - 1]])) {
                order[j] = order[j - 1];
                j--;
            }
            order[j] = k;
        }
        if (!m) continue;
        const float d[3] = {dir[0][q], dir[1][q], dir[2][q]};
        const float o[3] = {org ? org[0][q] : eye[0], org ? org[1][q] : eye[1], org ? org[2][q] : eye[2]};
        const float fp = px_tan / sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        float acc[3] = {0, 0, 0}, trans = 1.0f;
        for (unsigned i = 0; i < m; i++) {
            const unsigned k = order[i];
            const float a = fv_scene_alpha(s, l->geom[k], l->prim[k], l->u[k], l->v[k]);
            float c[3];
            fv_scene_shade(s, l->geom[k], l->prim[k], l->u[k], l->v[k], o, d, l->t[k], fp, eye, c);
            for (int ch = 0; ch < 3; ch++) acc[ch] += trans * a * c[ch];
            trans *= 1.0f - a;
        }
        for (int ch = 0; ch < 3; ch++) rgb[ch][q] = acc[ch] + trans * (miss ? background[ch] : rgb[ch][q]);
        if (miss) { /* the nearest layer stands for the ray's depth */
            geom[q] = l->geom[order[0]];
            tfar[q] = l->t[order[0]];
        }
    }
}
