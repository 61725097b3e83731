/* fovea: plain C view of a glTF 2.0 file, read and validated by tinygltf behind a C++17 shim.
 * Everything scene.c needs is already decoded, checked and flattened into C arrays:
 * triangle primitives as float/uint32 arrays (mesh-local space), the nodes reachable from
 * the scene's roots with their world matrices, materials, decoded base colour images and
 * KHR_lights_punctual lights. The model owns all memory; fv_gltf_free releases it. */
#ifndef FOVEA_GLTF_SHIM_H
#define FOVEA_GLTF_SHIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct fv_gltf_prim {
    const float *positions;  /* 3 per vertex, mesh-local, all finite */
    const float *normals;    /* 3 per vertex, or NULL */
    const float *uvs;        /* 2 per vertex (the set the material's textures use), or NULL */
    const float *colors;     /* 3 per vertex: COLOR_0's RGB (linear; alpha dropped), or NULL */
    const float *tangents;   /* 4 per vertex: TANGENT (x y z, w handedness), or NULL */
    const uint32_t *indices; /* index_count, each < vertex_count; NULL: non-indexed */
    size_t vertex_count, index_count; /* index_count (or vertex_count if non-indexed) % 3 == 0 */
    int material;            /* index into materials, or -1 (glTF default material) */
} fv_gltf_prim;

typedef struct fv_gltf_mesh {
    const fv_gltf_prim *prims; /* triangles (strips and fans converted to lists); points and lines skipped */
    size_t prim_count;
} fv_gltf_mesh;

/* A node reachable from the roots, in depth-first pre-order (roots in scene order). */
typedef struct fv_gltf_node {
    double world[16];  /* column-major local-to-world, parents' transforms applied */
    int mesh;          /* index into meshes, or -1 */
    int camera;        /* perspective camera index, or -1 (orthographic cameras are ignored) */
    int light;         /* index into lights (KHR_lights_punctual), or -1 */
} fv_gltf_node;

typedef struct fv_gltf_material {
    float base_color[4]; /* pbrMetallicRoughness.baseColorFactor, linear RGBA */
    int image;           /* base colour texture's image (decoded), or -1 */
    float metallic, roughness; /* pbrMetallicRoughness factors, [0, 1] (default 1, 1) */
    float specular;      /* KHR_materials_specular specularFactor, [0, 1] (default 1) */
    float emissive[3];   /* emissiveFactor x KHR_materials_emissive_strength, >= 0 */
    /* metallicRoughnessTexture, occlusionTexture, emissiveTexture, normalTexture images (decoded),
     * or -1; only those on the same TEXCOORD set as the material's first texture (prim uvs) are kept */
    int mr_image, occlusion_image, emissive_image, normal_image;
    float normal_scale;  /* normalTexture.scale (default 1) */
    float occlusion_strength; /* occlusionTexture.strength, [0, 1] */
    float alpha_cutoff;  /* alphaMode MASK: alphaCutoff (default 0.5); OPAQUE and BLEND: 0 */
    int wrap[5][2];      /* base colour, metallic-roughness, occlusion, emissive, normal textures' sampler
                          * wrapS, wrapT: 0 REPEAT, 1 CLAMP_TO_EDGE, 2 MIRRORED_REPEAT (fv_wrap) */
    int filter[5][3];    /* per texture as wrap[]: the sampler's magFilter NEAREST (1) or LINEAR (0),
                          * minFilter's within-level NEAREST (1) or LINEAR (0), and its mipmaps
                          * (fv_mip: 0 LINEAR, 1 NEAREST, 2 none); zeros: trilinear (no filter given) */
    int has_uvx;         /* some texture has KHR_texture_transform: */
    float uvx[5][6];     /* per texture as wrap[]: u' = [0] u + [1] v + [2], v' = [3] u + [4] v + [5] */
    int double_sided;    /* doubleSided (default false: back faces culled) */
    int alpha_blend;     /* alphaMode BLEND */
} fv_gltf_material;

typedef struct fv_gltf_image {
    const uint8_t *rgba8; /* RGBA8 as stored, width*height*4; NULL if no material uses it */
    int width, height;
} fv_gltf_image;

typedef struct fv_gltf_light {
    int type;          /* 0 directional, 1 point, 2 spot (same order as fv_light_type) */
    float color[3], intensity;
    float range;       /* 0 = infinite */
    float inner_cone_rad, outer_cone_rad;
} fv_gltf_light;

typedef struct fv_gltf_model {
    const fv_gltf_mesh *meshes;         size_t mesh_count;
    const fv_gltf_node *nodes;          size_t node_count;
    const fv_gltf_material *materials;  size_t material_count;
    const fv_gltf_image *images;        size_t image_count;
    const fv_gltf_light *lights;        size_t light_count;
    const char *warning; /* one line for the user ("" when none): e.g. skipped point or line primitives */
    void *impl; /* owner of the arrays above */
} fv_gltf_model;

/* Reads a .gltf or .glb (detected by content). External files (buffers, images) must lie inside
 * asset_root's folder tree, or the scene file's own folder when asset_root is NULL (after `..`,
 * percent-escapes and symbolic links are resolved; absolute paths and URI schemes other than
 * data: are refused, the message naming the URI). Returns NULL with a one-line reason in err on
 * any failure; never throws. */
fv_gltf_model *fv_gltf_load(const char *path, const char *asset_root, char *err, size_t err_len);
void fv_gltf_free(fv_gltf_model *m);

#ifdef __cplusplus
}
#endif

#endif
