/* fovea: the scene's private parts, shared by the files that implement core/scene.h (scene.c:
 * lifecycle, lights, views; scene_mesh.c: Embree geometry; texture.c; shade.c). Not a public
 * API; gltf_import.c needs none of it (it uses the builder API). Mesh records (normals, uvs,
 * material, per-triangle texel density: fv_tri_attr) stay here for shading, indexed by Embree geometry ID. */
#ifndef FOVEA_SCENE_IMPL_H
#define FOVEA_SCENE_IMPL_H

#include "scene.h"
#include "shade_dsp.h" /* fv_light_rec: the lights as the shading kernels read them */

#include <math.h>
#include <pthread.h>
#include <stddef.h>
#include <stdint.h>

#define FV_TEX_MAX_SIDE 16384
#define FV_TEX_MAX_LEVELS 15 /* 16384 -> 1 */

typedef struct fv_texture {
    int levels;
    int w[FV_TEX_MAX_LEVELS], h[FV_TEX_MAX_LEVELS];
    const float *level[FV_TEX_MAX_LEVELS]; /* linear RGBA, rows top to bottom, into data */
    float *data;
    fv_wrap wrap_s, wrap_t; /* addressing along u and v */
    unsigned char mag_nearest, min_nearest; /* fv_scene_set_texture_filter */
    unsigned char mip;                      /* fv_mip */
} fv_texture;

/* A triangle's shading inputs, one cache line: its corners' normals (world, unit or zero if
 * degenerate) and uvs (0 without), mip-0 texels per metre (0 without texture). */
typedef struct fv_tri_attr {
    float n[9];  /* corner 0 x y z, corner 1, corner 2 */
    float uv[6]; /* corner 0 u v, corner 1, corner 2 */
    float texel_density;
} fv_tri_attr;
_Static_assert(sizeof(fv_tri_attr) == 64, "one cache line per triangle");

/* A textured triangle's face normal, unnormalised (cross of its edges), and its length. */
typedef struct fv_tri_face {
    float ng[3], ng_len;
} fv_tri_face;

enum { FV_MAP_MR, FV_MAP_OCC, FV_MAP_EMIS, FV_MAP_NRM, FV_MAPS };
#define FV_SLOTS (1 + FV_MAPS) /* base colour, then the maps */
typedef struct fv_mesh_rec {
    const float *pos;      /* world positions, 3 per vertex: Embree's vertex buffer */
    const uint32_t *tri;   /* 3 per triangle: Embree's index buffer */
    fv_tri_attr *attr;     /* per triangle, 64-byte aligned */
    fv_tri_face *face;     /* per triangle of a textured mesh (the mip level), else NULL */
    size_t vertex_count, tri_count;
    float base_color[4];
    int texture;
    float metallic, a2, specular; /* the BRDF's (core/brdf.h); a2 = fv_ggx_a2(roughness) */
    float roughness;              /* the factor (a metallic-roughness map multiplies it) */
    float emissive[3];            /* emitted radiance, strength applied */
    int map[FV_MAPS];             /* FV_MAP_*: texture index or -1 */
    float normal_scale;           /* the normal map's x, y factor */
    float *tan;                   /* with a normal map: per triangle 12 floats, its corners' world tangent
                                     x y z (unit) and handedness w (+-1); else NULL */
    float occlusion_strength;
    int tex_ref;                  /* the texture texel_density counts (first of texture, map[]), or -1 */
    float lod_bias[FV_SLOTS];     /* base colour, map[]: log2 of the texel ratio to tex_ref */
    signed char slot_src[FV_SLOTS];      /* per slot: the first slot sampled the same way (same texture and
                                     uv transform: glTF's packed occlusion-roughness-metallic), or itself */
    int has_uvx;                  /* uvx is used */
    float uvx[FV_SLOTS][6];       /* per slot (base colour, map[]): fv_material_maps.uv_transform */
    float *col;                   /* per triangle 9 floats, its corners' vertex colours, or NULL */
    float alpha_cutoff;           /* > 0: alpha MASK (an Embree intersect filter, set at commit) */
    const fv_texture *mask_tex;   /* the base colour texture the filter reads (set at commit), or NULL */
    int single_sided;             /* back faces culled: in the filter of a MASK / BLEND mesh, else by
                                   * fv_scene_intersect*'s second trace (scene.c) */
    int blend;                    /* alpha BLEND: hits recorded and passed (core/blend.c) */
} fv_mesh_rec;

struct fv_scene {
    RTCDevice device;
    RTCScene rtc;
    fv_mesh_rec *meshes;
    size_t mesh_count, mesh_cap;
    fv_texture *textures;
    int texture_count, texture_cap;
    fv_light_rec *lights;
    int light_count, light_cap;
    size_t triangle_count;
    float lo[3], hi[3];
    int committed;
    int has_blend;        /* some mesh is alpha BLEND */
    int cull_retrace;     /* some single-sided mesh has no filter: fv_scene_intersect* checks the hits */
    int shadows;          /* fv_scene_set_shadows: occlusion rays towards the KHR lights (core/shadow.c) */
    float light_exposure; /* multiplies every KHR light contribution, see update_exposure (scene.c) */
    int has_view;
    float view_pos[3], view_quat[4];
    unsigned long serial; /* unique per scene in the process (never 0): keys per-thread caches (shade.c) */
    pthread_mutex_t rtc_err_lock; /* Embree may report from its own threads */
    char rtc_err[192];
    char warning[256]; /* the loader's one line for the user ("" when none) */
};

/* ---- shared helpers ------------------------------------------------------------------ */

/* Grows *p (of *cap elements) to hold n; 0 on success. */
int fv_scene_grow(void **p, size_t *cap, size_t n, size_t elem);
/* Returns 1 and copies the first recorded Embree error into err, or 0 if none. */
int fv_scene_take_rtc_error(fv_scene *s, char *err, size_t err_len);
/* (scene_tangent.c) Per triangle, its corners' world tangents (x y z unit, w = +-1) into out
 * (12 floats a triangle) for a normal map: file_tan (4 per vertex, mesh space; M the mesh's
 * transform) when given, else generated from uvs and the world vertex normals (unit or zero).
 * 0, or -1 with err (non-finite tangent, out of memory). */
int fv_scene_mesh_tangents(const float *pos, const uint32_t *tri, size_t nv, size_t nt, const float *normals,
                           const float *uvs, const float *file_tan, const double M[16], float *out, char *err,
                           size_t err_len);
/* (shade_normal.c) The shading normal (unnormalised, and its squared length) of a hit on mesh
 * m (which has a normal map and m->tan) from the map's texel there. */
void fv_shade_normal_mapped(const fv_mesh_rec *m, unsigned prim, float u, float v, float w, const float texel[4],
                            float n[3], float *nn);
/* Trilinear between the two mip levels around lod (lod 0 = full resolution), with the texture's
 * wrap modes. */
void fv_texture_sample(const fv_texture *t, float u, float v, float lod, float out[4]);
/* fv_texture_sample in two steps, so a packet's texel fetches can be asked for before they are
 * used: the taps (texel addresses and weights), then the blend; the same bits. */
typedef struct fv_tex_tap {
    const float *p[4]; /* texels 00, 10, 01, 11 */
    float fx, fy;
} fv_tex_tap;
typedef struct fv_tex_taps {
    fv_tex_tap tap[2]; /* the finer level, the coarser one when f > 0 */
    float f;           /* weight of the coarser level */
} fv_tex_taps;
void fv_texture_taps(const fv_texture *t, float u, float v, float lod, fv_tex_taps *tp);
void fv_texture_taps_prefetch(const fv_tex_taps *tp);
void fv_texture_blend(const fv_tex_taps *tp, float out[4]);

static inline void cross3(const float a[3], const float b[3], float o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}
static inline float dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static inline float len3(const float a[3]) { return sqrtf(dot3(a, a)); }

static inline void tri_edges(const float *pos, const uint32_t *tri, float e1[3], float e2[3])
{
    const float *p0 = pos + 3 * (size_t)tri[0], *p1 = pos + 3 * (size_t)tri[1], *p2 = pos + 3 * (size_t)tri[2];
    for (int k = 0; k < 3; k++) e1[k] = p1[k] - p0[k], e2[k] = p2[k] - p0[k];
}

/* glTF's recommended range window: smooth falloff to zero at range (0 = infinite). Used by
 * shading and by the exposure fixed at commit. */
static inline float range_window(float d, float range)
{
    if (range <= 0.0f) return 1.0f;
    const float x = d / range, x4 = x * x * x * x;
    return x4 >= 1.0f ? 0.0f : 1.0f - x4;
}

#endif
