/* fovea: the body of the packet shading kernel (shade_dsp.h: lambert) that every ISA shares. The
 * includer defines a vector of SW floats and its operations, then includes this once:
 *   V, M                      float vector, lane mask
 *   VLD(p) VST(p, v) VS(x)    load, store (unaligned), broadcast
 *   VADD VSUB VMUL VDIV VSQRT IEEE, exactly rounded
 *   VNEG(a)                   sign flipped
 *   VMAX0(a)                  max(a, 0) (a NaN lane may give 0 or NaN: both add no light)
 *   VGT VGE VLT (a, b)        ordered comparisons (false for NaN)
 *   MAND(a, b)                both
 *   VSEL(m, a, b)             m ? a : b per lane
 *   MBITS(m)                  the lanes of m as the low SW bits
 *   SHADE_FN                  the kernel's name
 * Each line does what core/shade_ref.c does for one lane, in the same order, so the bits agree. */
#include <math.h> /* INFINITY */

#include "scene.h" /* FV_SCENE_AMBIENT */

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

static unsigned SHADE_FN(const fv_shade_packet *p, const fv_shade_env *env, float rgb[3][FV_SHADE_LANES])
{
    unsigned degenerate = 0;
    for (int i = 0; i < FV_SHADE_LANES; i += SW) {
        const V u = VLD(p->u + i), v = VLD(p->v + i);
        const V w = VSUB(VSUB(VS(1.0f), u), v);
        V n[3];
        for (int k = 0; k < 3; k++)
            n[k] = VADD(VADD(VMUL(w, VLD(p->nrm[k] + i)), VMUL(u, VLD(p->nrm[3 + k] + i))),
                        VMUL(v, VLD(p->nrm[6 + k] + i)));
        const V nn = dot3v(n, n);
        degenerate |= (~(unsigned)MBITS(VGT(nn, VS(1e-24f))) & ((1u << SW) - 1u)) << i;
        const V d[3] = {VLD(p->dir[0] + i), VLD(p->dir[1] + i), VLD(p->dir[2] + i)};
        const M flip = VGT(dot3v(n, d), VS(0.0f));
        for (int k = 0; k < 3; k++)
            n[k] = VSEL(flip, VNEG(n[k]), n[k]);
        const V t = VLD(p->t + i);
        const V hit[3] = {VADD(VS(env->eye[0]), VMUL(t, d[0])), VADD(VS(env->eye[1]), VMUL(t, d[1])),
                          VADD(VS(env->eye[2]), VMUL(t, d[2]))};
        V light[3];
        if (env->nlights == 0) { /* head light: unit intensity, no falloff */
            const V L[3] = {VSUB(VS(env->eye[0]), hit[0]), VSUB(VS(env->eye[1]), hit[1]),
                            VSUB(VS(env->eye[2]), hit[2])};
            const V nl = dot3v(n, L), ll = dot3v(L, L);
            const V lam = VDIV(nl, VSQRT(VMUL(nn, ll)));
            const V a = VS(FV_SCENE_AMBIENT);
            light[0] = light[1] = light[2] = VSEL(MAND(VGT(nl, VS(0.0f)), VGT(ll, VS(0.0f))), VADD(a, lam), a);
        } else {
            const V inv_n = VDIV(VS(1.0f), VSQRT(nn)); /* nn > 0 on every lane that counts */
            for (int k = 0; k < 3; k++)
                n[k] = VMUL(n[k], inv_n);
            light[0] = light[1] = light[2] = VS(FV_SCENE_AMBIENT);
            for (int j = 0; j < env->nlights; j++) {
                const fv_light_rec *lr = &env->lights[j];
                const fv_light *l = &lr->l;
                V L[3], atten = VS(1.0f);
                M ok = VGE(VS(1.0f), VS(0.0f)); /* every lane */
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
                    V win = VS(1.0f); /* range_window (scene_impl.h) */
                    if (l->range > 0.0f) {
                        const V x = VDIV(dist, VS(l->range));
                        const V x4 = VMUL(VMUL(VMUL(x, x), x), x);
                        win = VSEL(VGE(x4, VS(1.0f)), VS(0.0f), VSUB(VS(1.0f), x4));
                    }
                    atten = VDIV(win, VMUL(dist, dist));
                    if (l->type == FV_LIGHT_SPOT) {
                        const V ld[3] = {VS(l->dir[0]), VS(l->dir[1]), VS(l->dir[2])};
                        atten = VMUL(atten, smoothstepv(lr->cos_outer, lr->cos_inner, VNEG(dot3v(ld, L))));
                    }
                }
                const V lam = VMAX0(dot3v(n, L));
                const V e = VMUL(VMUL(VMUL(lam, atten), VS(l->intensity)), VS(env->exposure));
                ok = MAND(ok, MAND(VGT(e, VS(0.0f)), VLT(e, VS(INFINITY))));
                for (int k = 0; k < 3; k++)
                    light[k] = VSEL(ok, VADD(light[k], VMUL(VS(l->color[k]), e)), light[k]);
            }
        }
        for (int k = 0; k < 3; k++)
            VST(rgb[k] + i, VMUL(VLD(p->base[k] + i), light[k]));
    }
    return degenerate;
}
