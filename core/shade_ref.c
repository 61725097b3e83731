/* fovea: the C reference of the packet shading kernel (shade_dsp.h) and the table's init. One
 * lane at a time, the operations of fv_scene_shade (core/shade.c) for a smooth normal. */
#include "shade_dsp.h"

#include <math.h>

static float dot3f(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static float smoothstep_ref(float e0, float e1, float x)
{
    if (e1 <= e0) return x >= e1 ? 1.0f : 0.0f;
    float t = (x - e0) / (e1 - e0);
    t = t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
    return t * t * (3.0f - 2.0f * t);
}

static float window_ref(float d, float range)
{
    if (range <= 0.0f) return 1.0f;
    const float x = d / range, x4 = x * x * x * x;
    return x4 >= 1.0f ? 0.0f : 1.0f - x4;
}

unsigned fv_shade_lambert_c(const fv_shade_packet *p, const fv_shade_env *env, float rgb[3][FV_SHADE_LANES])
{
    unsigned degenerate = 0;
    for (int i = 0; i < FV_SHADE_LANES; i++) {
        const float u = p->u[i], v = p->v[i], w = 1.0f - u - v;
        float n[3];
        for (int k = 0; k < 3; k++)
            n[k] = w * p->nrm[k][i] + u * p->nrm[3 + k][i] + v * p->nrm[6 + k][i];
        const float nn = dot3f(n, n);
        if (!(nn > 1e-24f))
            degenerate |= 1u << i;
        const float d[3] = {p->dir[0][i], p->dir[1][i], p->dir[2][i]};
        if (dot3f(n, d) > 0.0f)
            for (int k = 0; k < 3; k++) n[k] = -n[k];
        const float t = p->t[i];
        const float hit[3] = {env->eye[0] + t * d[0], env->eye[1] + t * d[1], env->eye[2] + t * d[2]};
        float light[3] = {FV_SCENE_AMBIENT, FV_SCENE_AMBIENT, FV_SCENE_AMBIENT};
        if (env->nlights == 0) { /* head light: unit intensity, no falloff */
            const float L[3] = {env->eye[0] - hit[0], env->eye[1] - hit[1], env->eye[2] - hit[2]};
            const float nl = dot3f(n, L), ll = dot3f(L, L);
            if (nl > 0.0f && ll > 0.0f) {
                const float lam = nl / sqrtf(nn * ll);
                for (int k = 0; k < 3; k++) light[k] += lam;
            }
        } else {
            const float inv_n = 1.0f / sqrtf(nn);
            for (int k = 0; k < 3; k++) n[k] *= inv_n;
            for (int j = 0; j < env->nlights; j++) {
                const fv_light_rec *lr = &env->lights[j];
                const fv_light *l = &lr->l;
                float L[3], atten = 1.0f;
                if (l->type == FV_LIGHT_DIRECTIONAL) {
                    for (int k = 0; k < 3; k++) L[k] = -l->dir[k];
                } else {
                    for (int k = 0; k < 3; k++) L[k] = l->pos[k] - hit[k];
                    const float dist = sqrtf(dot3f(L, L));
                    if (!(dist > 0.0f)) continue;
                    for (int k = 0; k < 3; k++) L[k] /= dist;
                    atten = window_ref(dist, l->range) / (dist * dist);
                    if (l->type == FV_LIGHT_SPOT)
                        atten *= smoothstep_ref(lr->cos_outer, lr->cos_inner, -dot3f(l->dir, L));
                }
                const float lam = fmaxf(0.0f, dot3f(n, L));
                const float e = lam * atten * l->intensity * env->exposure;
                if (!(e > 0.0f) || !isfinite(e)) continue;
                for (int k = 0; k < 3; k++) light[k] += l->color[k] * e;
            }
        }
        for (int k = 0; k < 3; k++) rgb[k][i] = p->base[k][i] * light[k];
    }
    return degenerate;
}

void fv_shade_dsp_init(fv_shade_dsp *d, unsigned isa_mask)
{
    const unsigned isas = isa_mask & fv_cpu_isas();
    d->lambert = fv_shade_lambert_c;
#if defined(__x86_64__)
    if (isas & FV_ISA_SSE41)
        fv_shade_dsp_init_sse41(d);
    if (isas & FV_ISA_AVX2)
        fv_shade_dsp_init_avx2(d);
#elif defined(__aarch64__)
    if (isas & FV_ISA_NEON)
        fv_shade_dsp_init_neon(d);
#else
    (void)isas;
#endif
}
