/* fovea: the shading kernels (one table per module, dav1d style; core/cpu.h has the pattern and
 * the contract every ISA version keeps). The ray stage shades a whole Embree packet at once: the
 * scene's driver (fv_scene_shade_packet, core/shade.c) gathers each hit's vertex normals and base
 * colour (texture applied) and material into a structure of arrays, and the kernel does the
 * arithmetic of every lane together: normal interpolation and orientation, the glTF
 * metallic-roughness BRDF (core/brdf.h) over the head light or the KHR lights, the ambient term
 * and emission. C reference: core/shade_ref.c; the body every ISA shares: core/shade_tmpl.h. Same IEEE operations in the same order as the scalar fv_scene_shade (true
 * division and square root, no FMA): every ISA gives the reference's bits, and the reference
 * gives fv_scene_shade's. */
#ifndef FOVEA_SHADE_DSP_H
#define FOVEA_SHADE_DSP_H

#include "cpu.h"
#include "scene.h"

#define FV_SHADE_LANES 16 /* the widest Embree packet */

/* A KHR light as shading reads it (the scene keeps them so, core/scene_impl.h). */
typedef struct fv_light_rec {
    fv_light l;
    float cos_inner, cos_outer; /* spot only */
} fv_light_rec;

/* What is the same for every lane of a packet. */
typedef struct fv_shade_env {
    const fv_light_rec *lights; /* nlights of them; none: a head light at eye */
    int nlights;
    float exposure; /* multiplies every KHR light's contribution */
    float eye[3];   /* every ray's origin, and the head light */
    /* shadows (core/shadow.c): nlights rows of FV_SHADE_LANES, lit[j * FV_SHADE_LANES + i] > 0
     * where KHR light j reaches lane i's hit, 0 where it is occluded; NULL: every light reaches
     * every hit */
    const float *lit;
} fv_shade_env;

/* One packet's hits, lane i in element i of every array. The geometry is read where it lies:
 * each lane's corner normals in its triangle's record (nrm_at), barycentrics, distances and
 * directions in the traced packet (Embree's SoA RTCRayHit16 rows). Copying them into the packet
 * first cost a scalar store per value, and the kernel's vector loads of those rows then waited for
 * the stores (a load spanning several smaller stores is not forwarded): docs/raystage.md. */
typedef struct fv_shade_packet {
    const float *nrm_at[FV_SHADE_LANES]; /* lane i's triangle's vertex normals: n0 x y z, n1 x y z, n2 x y z */
    const float *u, *v;            /* FV_SHADE_LANES each: Embree's barycentrics (u weights n1, v n2) */
    const float *t;                /* hit distance along dir */
    const float *dir[3];           /* ray direction (unnormalised) */
    float base[3][FV_SHADE_LANES]; /* base colour, texture applied */
    float metal[FV_SHADE_LANES];   /* metallic */
    float a2[FV_SHADE_LANES];      /* fv_ggx_a2(roughness) (core/brdf.h) */
    float spec[FV_SHADE_LANES];    /* dielectric Fresnel weight: 1 glTF, 0 matte */
    float emit[3][FV_SHADE_LANES]; /* emitted radiance, linear RGB */
    float occl[FV_SHADE_LANES];    /* ambient occlusion, 1 = none */
} fv_shade_packet;

/* Storage for a packet's geometry where it is not read in place (short packets, normal-mapped
 * lanes, tests); fv_shade_packet_lanes points p at it. */
typedef struct fv_shade_lanes {
    float nrm[FV_SHADE_LANES][9];
    float u[FV_SHADE_LANES], v[FV_SHADE_LANES], t[FV_SHADE_LANES], dir[3][FV_SHADE_LANES];
} fv_shade_lanes;
static inline void fv_shade_packet_lanes(fv_shade_packet *p, const fv_shade_lanes *l)
{
    for (int i = 0; i < FV_SHADE_LANES; i++) p->nrm_at[i] = l->nrm[i];
    p->u = l->u, p->v = l->v, p->t = l->t;
    for (int k = 0; k < 3; k++) p->dir[k] = l->dir[k];
}

/* brdf: rgb of every one of the FV_SHADE_LANES lanes (all lanes are read and written: pad a
 * short packet with copies of a real lane). Returns the lanes whose interpolated normal is
 * degenerate (|n|^2 <= 1e-24 or NaN; bit i: lane i): their rgb is unspecified, the caller shades
 * them with the face normal (fv_scene_shade). Bound against the reference: exact. */
typedef unsigned (*fv_shade_brdf_fn)(const fv_shade_packet *p, const fv_shade_env *env,
                                        float rgb[3][FV_SHADE_LANES]);
typedef struct fv_shade_dsp {
    fv_shade_brdf_fn brdf;
} fv_shade_dsp;

/* Fills d with the best kernels allowed by isa_mask & fv_cpu_isas() (FV_ISA_C: the references). */
void fv_shade_dsp_init(fv_shade_dsp *d, unsigned isa_mask);

/* ---- internal: references and per-ISA fillers ---- */
unsigned fv_shade_brdf_c(const fv_shade_packet *p, const fv_shade_env *env, float rgb[3][FV_SHADE_LANES]);
#if defined(__x86_64__)
void fv_shade_dsp_init_sse41(fv_shade_dsp *d);
void fv_shade_dsp_init_avx2(fv_shade_dsp *d);
#elif defined(__aarch64__)
void fv_shade_dsp_init_neon(fv_shade_dsp *d);
#endif

#endif
