/* fovea: the texel taps and blends of core/texture.c as inline functions, so the packet shading
 * (core/shade.c) runs them without five calls per lane and slot; texture.c's fv_texture_taps /
 * fv_texture_blend / fv_texture_sample are these, so both give the same bits. Texels are linear
 * float RGBA: a blend works on whole texels (4 floats), which the compiler keeps in one vector
 * register (the copies into locals tell it the output cannot alias the texels). */
#ifndef FOVEA_TEXTURE_TAP_H
#define FOVEA_TEXTURE_TAP_H

#include "scene_impl.h"

#include <math.h>
#include <string.h>

/* A coordinate folded into [0, 1] by the wrap mode (glTF samplers; NaN and infinities give 0). */
static inline float fv_tex_wrap_coord(float u, fv_wrap mode)
{
    if (!isfinite(u)) return 0.0f;
    if (mode == FV_WRAP_CLAMP) return u < 0.0f ? 0.0f : u > 1.0f ? 1.0f : u;
    if (mode == FV_WRAP_MIRROR) {
        const float f = u - 2.0f * floorf(0.5f * u); /* [0, 2] */
        return f > 1.0f ? 2.0f - f : f;
    }
    return u - floorf(u); /* [0,1] (1 only by rounding) */
}

/* A bilinear tap's neighbour index on one axis, i in [-1, side]: wrapped for REPEAT, the edge
 * texel for CLAMP and MIRROR (a mirror repeats the edge texel across the edge). */
static inline int fv_tex_wrap_index(int i, int side, fv_wrap mode)
{
    if (mode == FV_WRAP_REPEAT) return i < 0 ? i + side : i >= side ? i - side : i;
    return i < 0 ? 0 : i >= side ? side - 1 : i;
}

/* Bilinear with the texture's wrap modes; uv (0,0) is the first texel of the first row (glTF),
 * u and v already folded by fv_tex_wrap_coord (in [0, 1]). A bilinear tap: the four texels (00, 10, 01, 11) and the fractions. nearest: the texel holding
 * the point, as all four with fractions 0 (the blend then gives its bits exactly). */
static inline void fv_tex_tap_wrapped(const fv_texture *t, int l, float u, float v, fv_tex_tap *tp, int nearest)
{
    const int w = t->w[l], h = t->h[l];
    const float *px = t->level[l];
    const float x = u * (float)w - 0.5f, y = v * (float)h - 0.5f;
    const float xf = floorf(x), yf = floorf(y);
    tp->fx = x - xf, tp->fy = y - yf;
    if (nearest) { /* x - xf >= 0.5: the point lies in texel xf + 1 */
        const int xn = fv_tex_wrap_index((int)xf + (tp->fx >= 0.5f), w, t->wrap_s);
        const int yn = fv_tex_wrap_index((int)yf + (tp->fy >= 0.5f), h, t->wrap_t);
        tp->p[0] = tp->p[1] = tp->p[2] = tp->p[3] = px + ((size_t)yn * (size_t)w + (size_t)xn) * 4;
        tp->fx = tp->fy = 0.0f;
        return;
    }
    const int x0 = fv_tex_wrap_index((int)xf, w, t->wrap_s), y0 = fv_tex_wrap_index((int)yf, h, t->wrap_t);
    const int x1 = fv_tex_wrap_index((int)xf + 1, w, t->wrap_s), y1 = fv_tex_wrap_index((int)yf + 1, h, t->wrap_t);
    tp->p[0] = px + ((size_t)y0 * (size_t)w + (size_t)x0) * 4, tp->p[1] = px + ((size_t)y0 * (size_t)w + (size_t)x1) * 4;
    tp->p[2] = px + ((size_t)y1 * (size_t)w + (size_t)x0) * 4, tp->p[3] = px + ((size_t)y1 * (size_t)w + (size_t)x1) * 4;
}

/* One level's bilinear blend of whole texels. */
static inline void fv_tex_blend1(const fv_tex_tap *tp, float out[4])
{
    float a[4], b[4], c[4], d[4], o[4];
    memcpy(a, tp->p[0], sizeof a), memcpy(b, tp->p[1], sizeof b);
    memcpy(c, tp->p[2], sizeof c), memcpy(d, tp->p[3], sizeof d);
    const float fx = tp->fx, fy = tp->fy;
    for (int k = 0; k < 4; k++) {
        const float top = a[k] + (b[k] - a[k]) * fx, bot = c[k] + (d[k] - c[k]) * fx;
        o[k] = top + (bot - top) * fy;
    }
    memcpy(out, o, sizeof o);
}

/* fv_texture_taps (scene_impl.h): the taps of the one or two mip levels around lod, as the
 * texture's filters say (lod <= 0 magnifies: level 0, mag_nearest; else min_nearest and mip). */
static inline void fv_tex_taps_at(const fv_texture *t, float u, float v, float lod, fv_tex_taps *tp)
{
    if (!(lod > 0.0f)) lod = 0.0f; /* also NaN */
    const int nearest = lod > 0.0f ? t->min_nearest : t->mag_nearest;
    const float top = (float)(t->levels - 1);
    tp->f = 0.0f;
    if (t->mip == FV_MIP_NONE) lod = 0.0f;
    else if (t->mip == FV_MIP_NEAREST) lod = floorf(lod + 0.5f);
    /* the wrap does not depend on the level: folded once for both */
    u = fv_tex_wrap_coord(u, t->wrap_s), v = fv_tex_wrap_coord(v, t->wrap_t);
    if (lod >= top) {
        fv_tex_tap_wrapped(t, t->levels - 1, u, v, &tp->tap[0], nearest);
        return;
    }
    const int l0 = (int)lod;
    tp->f = lod - (float)l0;
    fv_tex_tap_wrapped(t, l0, u, v, &tp->tap[0], nearest);
    if (tp->f > 0.0f)
        fv_tex_tap_wrapped(t, l0 + 1, u, v, &tp->tap[1], nearest);
}

/* Textures of the same size, wrap modes and filters: fv_tex_taps_at of one at (u, v, lod) is the
 * other's at the same coordinates moved to its texels (fv_tex_taps_rebase). */
static inline int fv_tex_same_layout(const fv_texture *a, const fv_texture *b)
{
    return a->w[0] == b->w[0] && a->h[0] == b->h[0] && a->wrap_s == b->wrap_s && a->wrap_t == b->wrap_t &&
           a->mag_nearest == b->mag_nearest && a->min_nearest == b->min_nearest && a->mip == b->mip;
}

/* The taps fv_tex_taps_at(to, u, v, lod) gives, from src = fv_tex_taps_at(from, u, v, lod) with
 * fv_tex_same_layout(from, to): the same weights and texel offsets. A texture's levels lie in one
 * block (data) at offsets that depend on its size only, so an offset from level 0 carries over
 * whatever the level. */
static inline void fv_tex_taps_rebase(const fv_texture *from, const fv_texture *to, const fv_tex_taps *src,
                                      fv_tex_taps *dst)
{
    /* the bases in locals: a store of a texel pointer could alias the textures' level pointers,
     * which the compiler then reloaded for every tap */
    const float *const from0 = from->level[0], *const to0 = to->level[0];
    const int levels = src->f > 0.0f ? 2 : 1;
    dst->f = src->f;
    for (int l = 0; l < levels; l++) {
        const fv_tex_tap *a = &src->tap[l];
        fv_tex_tap *b = &dst->tap[l];
        b->fx = a->fx, b->fy = a->fy;
        const float *const p0 = to0 + (a->p[0] - from0), *const p1 = to0 + (a->p[1] - from0);
        const float *const p2 = to0 + (a->p[2] - from0), *const p3 = to0 + (a->p[3] - from0);
        b->p[0] = p0, b->p[1] = p1, b->p[2] = p2, b->p[3] = p3;
    }
}

static inline void fv_tex_taps_prefetch(const fv_tex_taps *tp)
{
    for (int i = 0; i < 4; i++)
        __builtin_prefetch(tp->tap[0].p[i]);
    if (tp->f > 0.0f)
        for (int i = 0; i < 4; i++)
            __builtin_prefetch(tp->tap[1].p[i]);
}

/* fv_texture_blend: trilinear between the taps' levels. */
static inline void fv_tex_blend(const fv_tex_taps *tp, float out[4])
{
    float o[4];
    fv_tex_blend1(&tp->tap[0], o);
    if (tp->f > 0.0f) {
        float o1[4];
        fv_tex_blend1(&tp->tap[1], o1);
        const float f = tp->f;
        for (int k = 0; k < 4; k++) o[k] += (o1[k] - o[k]) * f;
    }
    memcpy(out, o, sizeof o);
}

#endif
