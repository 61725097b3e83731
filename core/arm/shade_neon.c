/* fovea: the packet shading kernel, NEON: 4 lanes a vector, core/shade_tmpl.h's body for the head light (and
 * over 8 KHR lights), its own light loop below.
 * Bit-identical to the C reference (IEEE operations in its order: vdivq / vsqrtq, no FMA). */
/* the template's loops over x, y, z peeled (as -O3 would): at -O2 gcc kept them as loops over
 * arrays of vectors on the stack (brdf_lights 2720 -> 2196 instructions a packet, brdf 1372 -> 890) */
#if defined(__GNUC__) && !defined(__clang__) /* clang -O2 unrolls them already */
#pragma GCC optimize("peel-loops")
#endif
#include <arm_neon.h>

#include "shade_dsp.h"

#define SW 4
typedef float32x4_t V;
typedef uint32x4_t M;
#define VLD(p) vld1q_f32(p)
#define VST(p, v) vst1q_f32(p, v)
#define VS(x) vdupq_n_f32(x)
#define VADD vaddq_f32
#define VSUB vsubq_f32
#define VMUL vmulq_f32
#define VDIV vdivq_f32
#define VSQRT vsqrtq_f32
#define VNEG vnegq_f32
#define VGT vcgtq_f32
#define VGE vcgeq_f32
#define VLT vcltq_f32
#define MAND vandq_u32
#define VSEL(m, a, b) vbslq_f32(m, a, b)
static inline int mbits(uint32x4_t m)
{
    static const uint32_t bit[4] = {1, 2, 4, 8};
    return (int)vaddvq_u32(vandq_u32(m, vld1q_u32(bit)));
}
#define MBITS mbits
/* the corner normals of 4 lanes from their records: 4x4 transposes of elements 0-3 and 4-7, then
 * element 8 on its own (only 9 floats of a record are read) */
static inline void nrm9(const float *const *at, V c[9])
{
    for (int j = 0; j < 8; j += 4) {
        const float32x4x2_t p01 = vtrnq_f32(vld1q_f32(at[0] + j), vld1q_f32(at[1] + j));
        const float32x4x2_t p23 = vtrnq_f32(vld1q_f32(at[2] + j), vld1q_f32(at[3] + j));
        c[j] = vcombine_f32(vget_low_f32(p01.val[0]), vget_low_f32(p23.val[0]));
        c[j + 1] = vcombine_f32(vget_low_f32(p01.val[1]), vget_low_f32(p23.val[1]));
        c[j + 2] = vcombine_f32(vget_high_f32(p01.val[0]), vget_high_f32(p23.val[0]));
        c[j + 3] = vcombine_f32(vget_high_f32(p01.val[1]), vget_high_f32(p23.val[1]));
    }
    const float e8[4] = {at[0][8], at[1][8], at[2][8], at[3][8]};
    c[8] = vld1q_f32(e8);
}
#define NRM9 nrm9
#define SHADE_FN brdf_neon_tmpl
#include "shade_tmpl.h"

/* KHR lights, NEON: the template's light loop with what is the same for every lane group made
 * once a call (broadcasts, and a directional light's direction, exposure test and colour
 * times exposure, which are constants): the template redid them for each group of 4 lanes and
 * spilled more. Same operations on each lane in the same order: the same bits. */
#define NL_MAX 8
typedef struct light_v {
    int type, ranged, skip;
    V a[3];     /* directional: L = -dir; point, spot: the position */
    V col[3];   /* directional: colour x exposed intensity; else colour */
    V inten, exposure, range, ld[3];
    float cos_outer, cos_inner;
} light_v;

static unsigned brdf_neon(const fv_shade_packet *p, const fv_shade_env *env, float rgb[3][FV_SHADE_LANES])
{
    if (env->nlights == 0 || env->nlights > NL_MAX)
        return brdf_neon_tmpl(p, env, rgb);
    light_v lv[NL_MAX];
    const int nl_n = env->nlights;
    for (int j = 0; j < nl_n; j++) {
        const fv_light_rec *lr = &env->lights[j];
        const fv_light *l = &lr->l;
        light_v *o = &lv[j];
        o->type = l->type, o->ranged = l->range > 0.0f, o->skip = 0;
        o->inten = VS(l->intensity), o->exposure = VS(env->exposure), o->range = VS(l->range);
        o->cos_outer = lr->cos_outer, o->cos_inner = lr->cos_inner;
        for (int k = 0; k < 3; k++)
            o->ld[k] = VS(l->dir[k]);
        if (l->type == FV_LIGHT_DIRECTIONAL) {
            const float e = 1.0f * l->intensity * env->exposure; /* atten = 1 */
            o->skip = !(e > 0.0f && e < INFINITY);
            for (int k = 0; k < 3; k++)
                o->a[k] = VS(-l->dir[k]), o->col[k] = VS(l->color[k] * e);
        } else {
            for (int k = 0; k < 3; k++)
                o->a[k] = VS(l->pos[k]), o->col[k] = VS(l->color[k]);
        }
    }
    unsigned degenerate = 0;
    const V one = VS(1.0f);
    for (int i = 0; i < FV_SHADE_LANES; i += SW) {
        V n[3], d[3], vw[3], nv;
        degenerate |= lane_geomv(p, i, n, d, vw, &nv) << i;
        const V t = VLD(p->t + i);
        const V hit[3] = {VADD(VS(env->eye[0]), VMUL(t, d[0])), VADD(VS(env->eye[1]), VMUL(t, d[1])),
                          VADD(VS(env->eye[2]), VMUL(t, d[2]))};
        const V base[3] = {VLD(p->base[0] + i), VLD(p->base[1] + i), VLD(p->base[2] + i)};
        const V metal = VLD(p->metal + i), a2 = VLD(p->a2 + i), specw = VLD(p->spec + i);
        V out[3];
        ambientv(p, i, base, metal, specw, out);
        for (int j = 0; j < nl_n; j++) {
            const light_v *o = &lv[j];
            if (o->skip)
                continue;
            V L[3], col_e[3], nl;
            M ok;
            if (o->type == FV_LIGHT_DIRECTIONAL) {
                for (int k = 0; k < 3; k++)
                    L[k] = o->a[k], col_e[k] = o->col[k];
                nl = dot3v(n, L);
                ok = VGT(nl, VS(0.0f));
            } else {
                for (int k = 0; k < 3; k++)
                    L[k] = VSUB(o->a[k], hit[k]);
                const V dist = VSQRT(dot3v(L, L));
                ok = VGT(dist, VS(0.0f));
                for (int k = 0; k < 3; k++)
                    L[k] = VDIV(L[k], dist);
                V win = one; /* fv_lane_window */
                if (o->ranged) {
                    const V x = VDIV(dist, o->range);
                    const V x4 = VMUL(VMUL(VMUL(x, x), x), x);
                    win = VSEL(VGE(x4, one), VS(0.0f), VSUB(one, x4));
                }
                V atten = VDIV(win, VMUL(dist, dist));
                if (o->type == FV_LIGHT_SPOT)
                    atten = VMUL(atten, smoothstepv(o->cos_outer, o->cos_inner, VNEG(dot3v(o->ld, L))));
                nl = dot3v(n, L);
                const V e = VMUL(VMUL(atten, o->inten), o->exposure);
                ok = MAND(ok, MAND(VGT(nl, VS(0.0f)), MAND(VGT(e, VS(0.0f)), VLT(e, VS(INFINITY)))));
                for (int k = 0; k < 3; k++)
                    col_e[k] = VMUL(o->col[k], e);
            }
            if (env->lit) /* shadows: light j occluded on some lanes */
                ok = MAND(ok, VGT(VLD(env->lit + j * FV_SHADE_LANES + i), VS(0.0f)));
            add_lightv(base, metal, a2, specw, n, vw, nv, L, nl, col_e, ok, out);
        }
        for (int k = 0; k < 3; k++)
            VST(rgb[k] + i, VADD(out[k], VLD(p->emit[k] + i)));
    }
    return degenerate;
}

void fv_shade_dsp_init_neon(fv_shade_dsp *d) { d->brdf = brdf_neon; }
