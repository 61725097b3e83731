/* fovea: the body of the packet shading kernel (shade_dsp.h: brdf) that every ISA shares. The
 * includer defines a vector of SW floats and its operations, then includes this once:
 *   V, M                      float vector, lane mask
 *   VLD(p) VST(p, v) VS(x)    load, store (unaligned), broadcast
 *   VADD VSUB VMUL VDIV VSQRT IEEE, exactly rounded
 *   VNEG(a)                   sign flipped
 *   VGT VGE VLT (a, b)        ordered comparisons (false for NaN)
 *   MAND(a, b)                both
 *   VSEL(m, a, b)             m ? a : b per lane
 *   MBITS(m)                  the lanes of m as the low SW bits
 *   NRM9(at, n)               n[k] lane j = at[j][k] for k < 9, j < SW: the corner normals of SW
 *                             lanes from their records (a transpose; at[j][0..8] readable)
 *   SHADE_FN                  the kernel's name
 * Each line does what core/shade_lane.h (fv_shade_lane, core/brdf.h) does for one lane, in the same
 * order, so the bits agree. */
#include <math.h> /* INFINITY */

#include "brdf.h"  /* the constants */
#include "scene.h" /* FV_SCENE_AMBIENT */

/* inlined whatever the compiler estimates: out of line, the vectors go through memory (and the
 * AVX2 helpers returned without clearing the upper halves, which slowed SSE code after them 2x) */
#define SH_INLINE static inline __attribute__((always_inline))

static inline V dot3v(const V a[3], const V b[3]) { return VADD(VADD(VMUL(a[0], b[0]), VMUL(a[1], b[1])), VMUL(a[2], b[2])); }

/* fv_scene_shade's smoothstepf(e0, e1, x) */
static inline V smoothstepv(float e0, float e1, V x)
{
    if (e1 <= e0)
        return VSEL(VGE(x, VS(e1)), VS(1.0f), VS(0.0f));
    V t = VDIV(VSUB(x, VS(e0)), VS(e1 - e0));
    t = VSEL(VLT(t, VS(0.0f)), VS(0.0f), VSEL(VGT(t, VS(1.0f)), VS(1.0f), t));
    return VMUL(VMUL(t, t), VSUB(VS(3.0f), VMUL(VS(2.0f), t)));
}

/* fv_clamp01: NaN gives 0 */
static inline V clamp01v(V x) { return VSEL(VGT(x, VS(0.0f)), VSEL(VLT(x, VS(1.0f)), x, VS(1.0f)), VS(0.0f)); }

/* fv_brdf_cos (core/brdf.h) */
static inline void brdf_cosv(const V base[3], V metal, V a2, V specw, V nl, V nv, V nh, V vh, V out[3])
{
    nv = clamp01v(nv), nh = clamp01v(nh);
    const V one = VS(1.0f);
    const V gv = VMUL(nl, VSQRT(VADD(VMUL(VMUL(nv, nv), VSUB(one, a2)), a2)));
    const V gl = VMUL(nv, VSQRT(VADD(VMUL(VMUL(nl, nl), VSUB(one, a2)), a2)));
    const V s = VADD(gv, gl);
    const V vis = VSEL(VGT(s, VS(0.0f)), VDIV(VS(0.5f), s), VS(0.0f));
    const V dd = VADD(VMUL(VSUB(one, nh), VADD(one, nh)), VMUL(VMUL(nh, nh), a2));
    const V dist = VDIV(a2, VMUL(VS(FV_PI_F), VMUL(dd, dd)));
    const V spec = VMUL(VS(FV_PI_F), VMUL(vis, dist));
    const V x = VSUB(one, clamp01v(vh)), x2 = VMUL(x, x);
    const V w = VMUL(VMUL(x2, x2), x);
    const V fd = VMUL(specw, VADD(VS(FV_DIELECTRIC_F0), VMUL(VS(1.0f - FV_DIELECTRIC_F0), w)));
    for (int k = 0; k < 3; k++) {
        const V diel = VADD(VMUL(VSUB(one, fd), base[k]), VMUL(fd, spec));
        const V met = VMUL(spec, VADD(base[k], VMUL(VSUB(one, base[k]), w)));
        out[k] = VMUL(VADD(VMUL(VSUB(one, metal), diel), VMUL(metal, met)), nl);
    }
}

/* fv_brdf_cos_head (core/brdf.h) */
static inline void brdf_cos_headv(const V base[3], V metal, V a2, V specw, V nv, V out[3])
{
    nv = clamp01v(nv);
    const V one = VS(1.0f);
    const V g = VMUL(nv, VSQRT(VADD(VMUL(VMUL(nv, nv), VSUB(one, a2)), a2)));
    const V s = VADD(g, g);
    const V vis = VSEL(VGT(s, VS(0.0f)), VDIV(VS(0.5f), s), VS(0.0f));
    const V dd = VADD(VMUL(VSUB(one, nv), VADD(one, nv)), VMUL(VMUL(nv, nv), a2));
    const V dist = VDIV(a2, VMUL(VS(FV_PI_F), VMUL(dd, dd)));
    const V spec = VMUL(VS(FV_PI_F), VMUL(vis, dist));
    const V fd = VMUL(specw, VS(FV_DIELECTRIC_F0));
    for (int k = 0; k < 3; k++) {
        const V diel = VADD(VMUL(VSUB(one, fd), base[k]), VMUL(fd, spec));
        const V met = VMUL(spec, base[k]);
        out[k] = VMUL(VADD(VMUL(VSUB(one, metal), diel), VMUL(metal, met)), nv);
    }
}

/* fv_lane_add_light (core/shade_lane.h), on the lanes of ok only */
static inline void add_lightv(const V base[3], V metal, V a2, V specw, const V n[3], const V v[3], V nv,
                              const V L[3], V nl, const V col_e[3], M ok, V rgb[3])
{
    V h[3] = {VADD(L[0], v[0]), VADD(L[1], v[1]), VADD(L[2], v[2])};
    const V hl = VSQRT(dot3v(h, h));
    const V ih = VSEL(VGT(hl, VS(0.0f)), VDIV(VS(1.0f), hl), VS(0.0f));
    for (int k = 0; k < 3; k++)
        h[k] = VMUL(h[k], ih);
    V f[3];
    brdf_cosv(base, metal, a2, specw, nl, nv, dot3v(n, h), dot3v(v, h), f);
    for (int k = 0; k < 3; k++)
        rgb[k] = VSEL(ok, VADD(rgb[k], VMUL(f[k], col_e[k])), rgb[k]);
}

/* The geometry of lanes i .. i + SW: the oriented unit normal n, the unit view vector vw, n . vw;
 * the lanes whose interpolated normal is degenerate as bits (bit 0: lane i). */
SH_INLINE unsigned lane_geomv(const fv_shade_packet *p, int i, V n[3], V d[3], V vw[3], V *nv)
{
    const V one = VS(1.0f);
    const V u = VLD(p->u + i), v = VLD(p->v + i);
    const V w = VSUB(VSUB(one, u), v);
    V c[9];
    NRM9(p->nrm_at + i, c);
    for (int k = 0; k < 3; k++)
        n[k] = VADD(VADD(VMUL(w, c[k]), VMUL(u, c[3 + k])), VMUL(v, c[6 + k]));
    const V nn = dot3v(n, n);
    const unsigned degenerate = ~(unsigned)MBITS(VGT(nn, VS(1e-24f))) & ((1u << SW) - 1u);
    for (int k = 0; k < 3; k++)
        d[k] = VLD(p->dir[k] + i);
    const M flip = VGT(dot3v(n, d), VS(0.0f));
    for (int k = 0; k < 3; k++)
        n[k] = VSEL(flip, VNEG(n[k]), n[k]);
    const V inv_n = VDIV(one, VSQRT(nn));
    for (int k = 0; k < 3; k++)
        n[k] = VMUL(n[k], inv_n);
    const V inv_d = VDIV(one, VSQRT(dot3v(d, d)));
    for (int k = 0; k < 3; k++)
        vw[k] = VMUL(VNEG(d[k]), inv_d);
    *nv = dot3v(n, vw);
    return degenerate;
}

/* fv_brdf_ambient of lanes i .. i + SW into out */
SH_INLINE void ambientv(const fv_shade_packet *p, int i, const V base[3], V metal, V specw, V out[3])
{
    const V one = VS(1.0f);
    const V f0 = VMUL(specw, VS(FV_DIELECTRIC_F0));
    const V amb = VMUL(VS(FV_SCENE_AMBIENT), VLD(p->occl + i));
    for (int k = 0; k < 3; k++) {
        const V diel = VADD(VMUL(VSUB(one, f0), base[k]), f0);
        out[k] = VMUL(amb, VADD(VMUL(VSUB(one, metal), diel), VMUL(metal, base[k])));
    }
}

/* The head light at the eye (no KHR lights): l = v, fv_brdf_cos_head. Two groups of SW lanes
 * side by side, each step for both: one group is a chain of ~140 cycles (two square roots and
 * three divisions in series) of ~250 instructions, so the out-of-order window overlapped a
 * group with little of the next one. */
SH_INLINE void head_outv(const fv_shade_packet *p, int i, V nv, float rgb[3][FV_SHADE_LANES])
{
    const V t = VLD(p->t + i);
    const V base[3] = {VLD(p->base[0] + i), VLD(p->base[1] + i), VLD(p->base[2] + i)};
    const V metal = VLD(p->metal + i), a2 = VLD(p->a2 + i), specw = VLD(p->spec + i);
    V out[3], f[3];
    ambientv(p, i, base, metal, specw, out);
    brdf_cos_headv(base, metal, a2, specw, nv, f);
    const M ok = MAND(VGT(t, VS(0.0f)), VGT(nv, VS(0.0f)));
    for (int k = 0; k < 3; k++)
        VST(rgb[k] + i, VADD(VSEL(ok, VADD(out[k], f[k]), out[k]), VLD(p->emit[k] + i)));
}

SH_INLINE unsigned shade_headv(const fv_shade_packet *p, float rgb[3][FV_SHADE_LANES])
{
    _Static_assert(FV_SHADE_LANES % (2 * SW) == 0, "pairs of groups");
    unsigned degenerate = 0;
    for (int i = 0; i < FV_SHADE_LANES; i += 2 * SW) {
        V n0[3], d0[3], vw0[3], nv0, n1[3], d1[3], vw1[3], nv1;
        degenerate |= lane_geomv(p, i, n0, d0, vw0, &nv0) << i;
        degenerate |= lane_geomv(p, i + SW, n1, d1, vw1, &nv1) << (i + SW);
        head_outv(p, i, nv0, rgb);
        head_outv(p, i + SW, nv1, rgb);
    }
    return degenerate;
}

/* KHR lights: the loop as it was (pairs of groups as in shade_headv measured slower here, 17.8 ->
 * 19.3 ms a frame on AVX2: the lights' chains already overlap). Its geometry is lane_geomv's, written
 * out: through the helper GCC 12 allocated the light loop's registers worse (brdf_lights +3.2 %
 * instructions on AVX2, +3.1 % on SSE4.1, more stack traffic; docs/raystage.md) */
static unsigned SHADE_FN(const fv_shade_packet *p, const fv_shade_env *env, float rgb[3][FV_SHADE_LANES])
{
    if (env->nlights == 0)
        return shade_headv(p, rgb);
    unsigned degenerate = 0;
    const V one = VS(1.0f);
    for (int i = 0; i < FV_SHADE_LANES; i += SW) {
        const V u = VLD(p->u + i), v = VLD(p->v + i);
        const V w = VSUB(VSUB(one, u), v);
        V c[9];
        NRM9(p->nrm_at + i, c);
        V n[3];
        for (int k = 0; k < 3; k++)
            n[k] = VADD(VADD(VMUL(w, c[k]), VMUL(u, c[3 + k])), VMUL(v, c[6 + k]));
        const V nn = dot3v(n, n);
        degenerate |= (~(unsigned)MBITS(VGT(nn, VS(1e-24f))) & ((1u << SW) - 1u)) << i;
        const V d[3] = {VLD(p->dir[0] + i), VLD(p->dir[1] + i), VLD(p->dir[2] + i)};
        const M flip = VGT(dot3v(n, d), VS(0.0f));
        for (int k = 0; k < 3; k++)
            n[k] = VSEL(flip, VNEG(n[k]), n[k]);
        const V inv_n = VDIV(one, VSQRT(nn));
        for (int k = 0; k < 3; k++)
            n[k] = VMUL(n[k], inv_n);
        const V inv_d = VDIV(one, VSQRT(dot3v(d, d)));
        const V vw[3] = {VMUL(VNEG(d[0]), inv_d), VMUL(VNEG(d[1]), inv_d), VMUL(VNEG(d[2]), inv_d)};
        const V nv = dot3v(n, vw);
        const V t = VLD(p->t + i);
        const V hit[3] = {VADD(VS(env->eye[0]), VMUL(t, d[0])), VADD(VS(env->eye[1]), VMUL(t, d[1])),
                          VADD(VS(env->eye[2]), VMUL(t, d[2]))};
        const V base[3] = {VLD(p->base[0] + i), VLD(p->base[1] + i), VLD(p->base[2] + i)};
        const V metal = VLD(p->metal + i), a2 = VLD(p->a2 + i), specw = VLD(p->spec + i);
        V out[3];
        ambientv(p, i, base, metal, specw, out);
        for (int j = 0; j < env->nlights; j++) {
            const fv_light_rec *lr = &env->lights[j];
            const fv_light *l = &lr->l;
            V L[3], atten = one;
            M ok = VGE(one, VS(0.0f)); /* every lane */
            if (l->type == FV_LIGHT_DIRECTIONAL) {
                for (int k = 0; k < 3; k++)
                    L[k] = VS(-l->dir[k]);
            } else {
                for (int k = 0; k < 3; k++)
                    L[k] = VSUB(VS(l->pos[k]), hit[k]);
                const V dist = VSQRT(dot3v(L, L));
                ok = VGT(dist, VS(0.0f));
                for (int k = 0; k < 3; k++)
                    L[k] = VDIV(L[k], dist);
                V win = one; /* fv_lane_window */
                if (l->range > 0.0f) {
                    const V x = VDIV(dist, VS(l->range));
                    const V x4 = VMUL(VMUL(VMUL(x, x), x), x);
                    win = VSEL(VGE(x4, one), VS(0.0f), VSUB(one, x4));
                }
                atten = VDIV(win, VMUL(dist, dist));
                if (l->type == FV_LIGHT_SPOT) {
                    const V ld[3] = {VS(l->dir[0]), VS(l->dir[1]), VS(l->dir[2])};
                    atten = VMUL(atten, smoothstepv(lr->cos_outer, lr->cos_inner, VNEG(dot3v(ld, L))));
                }
            }
            const V nl = dot3v(n, L);
            const V e = VMUL(VMUL(atten, VS(l->intensity)), VS(env->exposure));
            ok = MAND(ok, MAND(VGT(nl, VS(0.0f)), MAND(VGT(e, VS(0.0f)), VLT(e, VS(INFINITY)))));
            if (env->lit) /* shadows: light j occluded on some lanes */
                ok = MAND(ok, VGT(VLD(env->lit + j * FV_SHADE_LANES + i), VS(0.0f)));
            const V col_e[3] = {VMUL(VS(l->color[0]), e), VMUL(VS(l->color[1]), e), VMUL(VS(l->color[2]), e)};
            add_lightv(base, metal, a2, specw, n, vw, nv, L, nl, col_e, ok, out);
        }
        for (int k = 0; k < 3; k++)
            VST(rgb[k] + i, VADD(out[k], VLD(p->emit[k] + i)));
    }
    return degenerate;
}
