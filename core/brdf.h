/* fovea: the glTF 2.0 metallic-roughness BRDF (specification, appendix B), one lane in plain C.
 * fv_scene_shade (core/shade.c) and the packet kernel's C reference (core/shade_ref.c) both use
 * these, so they give the same bits; core/shade_tmpl.h writes the same operations in the same
 * order for the vector ISAs. docs/materials.md has the formulas and the conventions.
 *
 *   f = mix(dielectric, metal, metallic)
 *   dielectric = mix(baseColor / pi, V*D, specular * F(0.04)),   metal = V*D * F(baseColor)
 *   F(f0) = f0 + (1 - f0) (1 - |v.h|)^5            (Schlick)
 *   D = a2 / (pi ((n.h)^2 (a2 - 1) + 1)^2)          (Trowbridge-Reitz / GGX, a = roughness^2)
 *   V = 0.5 / (n.l sqrt((n.v)^2 (1 - a2) + a2) + n.v sqrt((n.l)^2 (1 - a2) + a2))  (Smith joint)
 *
 * `specular` is KHR_materials_specular's weight of the dielectric Fresnel: 1 for every glTF
 * material, 0 for the matte (pure Lambert) material of meshes built by hand. Everything is
 * returned times pi (pi f n.l): a white Lambert surface lit head-on by irradiance 1 gives 1,
 * the convention the lights' exposure was fixed with. */
#ifndef FOVEA_BRDF_H
#define FOVEA_BRDF_H

#include <math.h>

#define FV_PI_F 3.14159265358979f
/* Roughness is clamped to [FV_MIN_ROUGHNESS, 1] so D stays finite for a mirror (Filament's
 * MIN_PERCEPTUAL_ROUGHNESS): a2 >= 4.1e-6, D <= 7.8e4. */
#define FV_MIN_ROUGHNESS 0.045f
#define FV_DIELECTRIC_F0 0.04f /* ((1 - ior) / (1 + ior))^2 for ior 1.5 */

/* x clamped to [0, 1]; NaN gives 0 (the vector kernels' selects do the same). */
static inline float fv_clamp01(float x) { return x > 0.0f ? (x < 1.0f ? x : 1.0f) : 0.0f; }

static inline float fv_ggx_a2(float roughness)
{
    const float r = roughness > FV_MIN_ROUGHNESS ? (roughness < 1.0f ? roughness : 1.0f) : FV_MIN_ROUGHNESS;
    const float a = r * r;
    return a * a;
}

/* Trowbridge-Reitz normal distribution D(n.h). The denominator's (n.h)^2 (a2 - 1) + 1 is
 * computed as (1 - n.h)(1 + n.h) + (n.h)^2 a2: the same in exact arithmetic, but exact at the
 * peak (n.h = 1 gives a2) where the plain form loses a2 to the rounding of a2 - 1 (0.6 % of D
 * at the roughness floor, tests/test_brdf.c). */
static inline float fv_ggx_d(float a2, float nh)
{
    const float d = (1.0f - nh) * (1.0f + nh) + nh * nh * a2;
    return a2 / (FV_PI_F * (d * d));
}

/* Smith joint visibility V = G / (4 n.l n.v), height-correlated GGX. 0 when both cosines are 0. */
static inline float fv_smith_v(float a2, float nl, float nv)
{
    const float gv = nl * sqrtf(nv * nv * (1.0f - a2) + a2);
    const float gl = nv * sqrtf(nl * nl * (1.0f - a2) + a2);
    const float s = gv + gl;
    return s > 0.0f ? 0.5f / s : 0.0f;
}

/* (1 - v.h)^5, Schlick's weight, v.h clamped to [0, 1]. */
static inline float fv_schlick_w(float vh)
{
    const float x = 1.0f - fv_clamp01(vh), x2 = x * x;
    return x2 * x2 * x;
}

/* A material at one hit. */
typedef struct fv_brdf_mat {
    float base[3];   /* linear base colour (factor x texture) */
    float metallic;  /* [0, 1] */
    float a2;        /* fv_ggx_a2(roughness) */
    float specular;  /* dielectric Fresnel weight (1 glTF, 0 matte) */
} fv_brdf_mat;

/* pi f(l, v) n.l for unit n, l, v given as their cosines (nl > 0; nv, nh, vh are clamped here). */
static inline void fv_brdf_cos(const fv_brdf_mat *m, float nl, float nv, float nh, float vh, float out[3])
{
    nv = fv_clamp01(nv), nh = fv_clamp01(nh);
    const float spec = FV_PI_F * (fv_smith_v(m->a2, nl, nv) * fv_ggx_d(m->a2, nh)); /* pi V D */
    const float w = fv_schlick_w(vh);
    const float fd = m->specular * (FV_DIELECTRIC_F0 + (1.0f - FV_DIELECTRIC_F0) * w);
    for (int k = 0; k < 3; k++) {
        const float diel = (1.0f - fd) * m->base[k] + fd * spec;
        const float metal = spec * (m->base[k] + (1.0f - m->base[k]) * w);
        out[k] = ((1.0f - m->metallic) * diel + m->metallic * metal) * nl;
    }
}

/* fv_brdf_cos for the head light, which sits at the eye: l = v, so h = v, n.l = n.h = n.v and
 * v.h = 1 (Schlick's weight is 0). The same bits as fv_brdf_cos(m, nv, nv, nv, 1) for nv in
 * (0, 1] (tests/test_brdf.c), with one square root for Smith's two equal terms and no half
 * vector: 3 of the 6 square roots and 2 of the 6 divisions of a lane lit by the head light. */
static inline void fv_brdf_cos_head(const fv_brdf_mat *m, float nv, float out[3])
{
    nv = fv_clamp01(nv);
    const float g = nv * sqrtf(nv * nv * (1.0f - m->a2) + m->a2);
    const float s = g + g;
    const float vis = s > 0.0f ? 0.5f / s : 0.0f;
    const float spec = FV_PI_F * (vis * fv_ggx_d(m->a2, nv)); /* pi V D */
    const float fd = m->specular * FV_DIELECTRIC_F0;
    for (int k = 0; k < 3; k++) {
        const float diel = (1.0f - fd) * m->base[k] + fd * spec;
        const float metal = spec * m->base[k];
        out[k] = ((1.0f - m->metallic) * diel + m->metallic * metal) * nv;
    }
}

/* The environment term: a uniform white surround of radiance `ambient`, reflected with the
 * BRDF's normal-incidence mix (Fresnel f0, the specular lobe's albedo taken as 1, roughness
 * ignored): dielectric (1 - s f0) base + s f0, metal base. Keeps unlit sides from going black. */
static inline void fv_brdf_ambient(const fv_brdf_mat *m, float ambient, float out[3])
{
    const float f0 = m->specular * FV_DIELECTRIC_F0;
    for (int k = 0; k < 3; k++) {
        const float diel = (1.0f - f0) * m->base[k] + f0;
        out[k] = ambient * ((1.0f - m->metallic) * diel + m->metallic * m->base[k]);
    }
}

#endif
