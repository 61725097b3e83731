/* fovea: the C reference of the packet shading kernel (shade_dsp.h) and the table's init. One
 * lane at a time through fv_shade_lane (core/shade_lane.h), the very code fv_scene_shade
 * (core/shade.c) runs for a smooth normal. */
#include "shade_lane.h"

unsigned fv_shade_brdf_c(const fv_shade_packet *p, const fv_shade_env *env, float rgb[3][FV_SHADE_LANES])
{
    unsigned degenerate = 0;
    for (int i = 0; i < FV_SHADE_LANES; i++) {
        const float u = p->u[i], v = p->v[i], w = 1.0f - u - v;
        float n[3];
        for (int k = 0; k < 3; k++)
            n[k] = w * p->nrm_at[i][k] + u * p->nrm_at[i][3 + k] + v * p->nrm_at[i][6 + k];
        const float nn = fv_lane_dot3(n, n);
        if (!(nn > 1e-24f))
            degenerate |= 1u << i;
        const float d[3] = {p->dir[0][i], p->dir[1][i], p->dir[2][i]};
        const fv_brdf_mat m = {{p->base[0][i], p->base[1][i], p->base[2][i]}, p->metal[i], p->a2[i], p->spec[i]};
        const float emit[3] = {p->emit[0][i], p->emit[1][i], p->emit[2][i]};
        float c[3];
        fv_shade_lane(&m, p->occl[i], emit, n, nn, env->eye, d, p->t[i], env->eye, env->lights, env->nlights, env->exposure,
                      env->lit ? env->lit + i : NULL, FV_SHADE_LANES, c);
        for (int k = 0; k < 3; k++) rgb[k][i] = c[k];
    }
    return degenerate;
}

void fv_shade_dsp_init(fv_shade_dsp *d, unsigned isa_mask)
{
    const unsigned isas = isa_mask & fv_cpu_isas();
    d->brdf = fv_shade_brdf_c;
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
