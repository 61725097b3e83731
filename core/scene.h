/* fovea: the scene. glTF 2.0 (.gltf/.glb, through a small C++ tinygltf shim) or meshes
 * added by hand, flattened to world space into one Embree 3 scene (static, high-quality BVH),
 * with materials (base colour factor + texture with mip chain), lights and shading. */
#ifndef FOVEA_SCENE_H
#define FOVEA_SCENE_H

#include <stddef.h>
#include <stdint.h>
#include <embree3/rtcore.h>

typedef struct fv_scene fv_scene;

/* Radiance of the uniform white environment fv_scene_shade reflects (docs/materials.md): a
 * matte surface gets this fraction of its base colour where no light reaches it. */
#define FV_SCENE_AMBIENT 0.15f

/* Loads a .gltf or .glb. Returns NULL and writes a one-line reason into err on failure
 * (missing file, malformed JSON, bad accessor, out-of-range index, unsupported required
 * extension, no triangles at all, ...). Never crashes. Meshes of all TRIANGLES primitives
 * reachable from the default scene (or all root nodes) are flattened with their world
 * transforms. Materials as docs/materials.md says: metallic-roughness with base colour,
 * metallic-roughness, occlusion, emissive and normal maps, vertex colours, alpha MASK and BLEND,
 * doubleSided, sampler wrap and filter modes and KHR_texture_transform. Skins,
 * morph targets and animations are ignored. The first perspective camera in depth-first node
 * order becomes the default view. */
fv_scene *fv_scene_load(const char *path, char *err, size_t err_len);
/* The same, with the folder the scene's external files must lie in (NULL: the scene file's own
 * folder, which fv_scene_load uses): a URI leading elsewhere is refused, naming it. */
fv_scene *fv_scene_load_in(const char *path, const char *asset_root, char *err, size_t err_len);
/* The loader's one-line warning for the user, "" when none (e.g. "skipped 2 point or line
 * primitives (only triangles are rendered)"); the programs print it once. */
const char *fv_scene_warning(const fv_scene *s);
/* (loaders) Sets that line; NULL clears it. */
void fv_scene_set_warning(fv_scene *s, const char *w);

/* Building a scene by hand (tests, generators): create, add meshes, commit. */
/* A material's texture maps besides base colour (glTF's, read as the specification says): each
 * a texture index (fv_scene_add_texture_linear for metallic-roughness and occlusion,
 * fv_scene_add_texture for emissive) or -1. They use the mesh's uvs. */
typedef struct fv_material_maps {
    int metallic_roughness; /* G: roughness, B: metallic, multiplying the factors */
    int occlusion;          /* R: ambient occlusion, applied as 1 + strength (R - 1) */
    int emissive;           /* RGB (sRGB), multiplying the emissive factor */
    float occlusion_strength; /* [0, 1] */
    int normal;             /* tangent-space normal map (linear texture): RGB = (x, y, z) / 2 + 1/2 */
    float normal_scale;     /* normalTexture.scale: multiplies the map's x and y */
    /* KHR_texture_transform of the base colour, metallic-roughness, occlusion, emissive and
     * normal textures when has_uv_transform: u' = m[0] u + m[1] v + m[2], v' = m[3] u + m[4] v + m[5]
     * (the mip level is not adjusted for the scale) */
    int has_uv_transform;
    float uv_transform[5][6];
} fv_material_maps;
typedef struct fv_mesh_desc {
    const float *positions; /* 3 floats per vertex, world space (the transform below is applied) */
    const float *normals;   /* 3 per vertex, or NULL: computed (area-weighted smooth) */
    const float *uvs;       /* 2 per vertex, or NULL */
    const float *colors;    /* 3 per vertex, linear RGB multiplying the base colour (glTF COLOR_0), or NULL */
    const float *tangents;  /* 4 per vertex (glTF TANGENT: x y z, w = +-1, bitangent = w n x t), or NULL:
                             * generated from the uvs when a normal map needs them (docs/materials.md) */
    const uint32_t *indices;/* 3 per triangle, or NULL: non-indexed, vertex_count/3 triangles */
    size_t vertex_count, index_count;
    float base_color[4];    /* linear RGBA factor */
    int texture;            /* index from fv_scene_add_texture, or -1 */
    /* glTF metallic-roughness (docs/materials.md). All zero (memset) is the matte material:
     * pure Lambert, no highlight, no emission. */
    float metallic;         /* [0, 1] */
    float roughness;        /* [0, 1] (clamped to FV_MIN_ROUGHNESS, core/brdf.h, when shading) */
    float specular;         /* [0, 1] weight of the dielectric Fresnel: 1 for glTF materials, 0 matte */
    float emissive[3];      /* linear RGB added to the shaded colour (>= 0), emissive strength applied */
    const fv_material_maps *maps; /* NULL: none */
    float alpha_cutoff;     /* > 0: glTF alpha MASK: rays pass through where the base alpha (factor x
                             * texture, bilinear at mip 0) is below it; 0: opaque */
    int alpha_blend;        /* glTF alpha BLEND: composited over what lies behind, front to back, by the ray
                             * stage (core/blend.c); a ray query without it passes through */
    int single_sided;       /* glTF doubleSided false: rays pass through the back faces (those whose
                             * corners 0, 1, 2 appear clockwise); 0 (memset): double-sided */
    float transform[16];    /* column-major 4x4, glTF convention; all zero = identity */
} fv_mesh_desc;
fv_scene *fv_scene_create(void);
/* rgba8 is sRGB-encoded 8-bit RGBA, copied. Returns the texture index or -1. */
int fv_scene_add_texture(fv_scene *s, const uint8_t *rgba8, int w, int h);
/* The same for data (metallic-roughness, occlusion): the bytes are linear, v / 255. */
int fv_scene_add_texture_linear(fv_scene *s, const uint8_t *rgba8, int w, int h);
/* Texture addressing outside [0, 1] (glTF sampler wrapS / wrapT); a new texture repeats. */
typedef enum { FV_WRAP_REPEAT, FV_WRAP_CLAMP, FV_WRAP_MIRROR } fv_wrap;
/* Sets texture tex's wrap modes; 0, or -1 if tex does not exist. */
int fv_scene_set_texture_wrap(fv_scene *s, int tex, fv_wrap wrap_s, fv_wrap wrap_t);
/* Texture filtering (glTF sampler magFilter / minFilter): the texel nearest the point instead of
 * the bilinear blend when magnifying (lod <= 0: mag_nearest) or minifying (min_nearest), and the
 * mip levels blended (FV_MIP_LINEAR, a new texture's: trilinear), the nearest level taken
 * (FV_MIP_NEAREST) or level 0 only (FV_MIP_NONE). 0, or -1 if tex does not exist. */
typedef enum { FV_MIP_LINEAR, FV_MIP_NEAREST, FV_MIP_NONE } fv_mip;
int fv_scene_set_texture_filter(fv_scene *s, int tex, int mag_nearest, int min_nearest, fv_mip mip);
/* Validates (indices < vertex_count, counts multiple of 3, finite data, texture index) and
 * flattens the mesh to world space. Returns 0, or -1 with err (the scene is unchanged).
 * Meshes get Embree geometry IDs 0, 1, 2, ... in the order they were added successfully. */
int fv_scene_add_mesh(fv_scene *s, const fv_mesh_desc *m, char *err, size_t err_len);
typedef enum { FV_LIGHT_DIRECTIONAL, FV_LIGHT_POINT, FV_LIGHT_SPOT } fv_light_type;
typedef struct fv_light {
    fv_light_type type;
    float color[3], intensity; /* glTF KHR_lights_punctual units */
    float pos[3], dir[3];      /* world space; dir is where the light points */
    float range;               /* 0 = infinite */
    float inner_cone, outer_cone; /* radians, spot only */
} fv_light;
void fv_scene_add_light(fv_scene *s, const fv_light *l);
/* Sets the pose fv_scene_default_view returns (glTF camera node); quat x,y,z,w as there. */
void fv_scene_set_default_view(fv_scene *s, const float pos[3], const float quat[4]);
int fv_scene_commit(fv_scene *s, char *err, size_t err_len); /* builds the BVH; 0 on success */
void fv_scene_free(fv_scene *s);

RTCScene fv_scene_rtc(const fv_scene *s);
/* Closest hits as the materials define them (use these, not rtcIntersect*, for camera rays):
 * rtcIntersectN, then the lanes whose hit is the back face of a single-sided (glTF doubleSided
 * false) mesh traced again, from the start, with a context filter that culls such faces. A
 * MASK or BLEND mesh culls in its own filter; a plain one carries no filter on the common path,
 * since a filter on every single-sided mesh cost the range scene ~20 % of its ray stage and
 * back faces are rarely the closest hit. ictx as rtcInitIntersectContext leaves it. */
void fv_scene_intersect1(const fv_scene *s, struct RTCIntersectContext *ictx, struct RTCRayHit *rh);
void fv_scene_intersect8(const fv_scene *s, const int *valid, struct RTCIntersectContext *ictx, struct RTCRayHit8 *rh);
void fv_scene_intersect16(const fv_scene *s, const int *valid, struct RTCIntersectContext *ictx,
                          struct RTCRayHit16 *rh);
size_t fv_scene_triangle_count(const fv_scene *s);
void fv_scene_bounds(const fv_scene *s, float lo[3], float hi[3]);
int fv_scene_light_count(const fv_scene *s);
/* Copies light i (world space, dir normalised) into out; 0 on success, -1 if out of range. */
int fv_scene_get_light(const fv_scene *s, int i, fv_light *out);

/* Shadows from the KHR punctual lights (off by default): shading traces an occlusion ray from
 * each hit towards each light (core/shadow.c, docs/materials.md). Returns 0, or -1 (shadows stay
 * off) if the scene has more than 16 KHR lights. Set it before rendering, not during. */
int fv_scene_set_shadows(fv_scene *s, int on);

/* Default viewpoint: the first glTF camera node if the file has one (returns 1), otherwise
 * looking down -Z from in front of the bounds, framing them in the vertical FOV (returns 0).
 * quat is x,y,z,w, rotating eye space (looking down -Z, +Y up) into world space. */
int fv_scene_default_view(const fv_scene *s, float fov_y_deg, float aspect, float pos[3], float quat[4]);

/* A hit's alpha: base colour factor x texture alpha (bilinear at mip 0), in [0, 1]; 1 for no
 * such hit. The MASK filter compares it with the cutoff, BLEND (core/blend.c) composites with it. */
float fv_scene_alpha(const fv_scene *s, unsigned geom_id, unsigned prim_id, float u, float v);

/* Shades one hit: the glTF metallic-roughness BRDF (core/brdf.h, docs/materials.md) with base
 * colour (factor x texture, bilinear, mip level from the ray footprint), metallic, roughness and
 * specular weight over the scene's lights, plus a uniform ambient term (FV_SCENE_AMBIENT, the
 * BRDF's normal-incidence reflectance) and emission. Without KHR_lights_punctual a head light
 * of irradiance 1 at eye_pos is used; a light's pi f n.l is scaled so that a white matte
 * surface facing irradiance 1 gives 1. footprint_rad is the angular size of one pixel along this ray (the
 * ray-cone spread), so the footprint at the hit is about t*|dir|*footprint_rad metres.
 * KHR light contributions are scaled by one exposure per scene, fixed at commit so that the
 * brightest light gives irradiance 1.0 at the bounds' centre (glTF intensities are often in
 * the thousands). Normals face the ray (a single-sided mesh's back faces are never hit: the
 * ray query passes through them). Writes linear RGB. */
void fv_scene_shade(const fv_scene *s, unsigned geom_id, unsigned prim_id, float u, float v,
                    const float org[3], const float dir[3], float t, float footprint_rad,
                    const float eye_pos[3], float rgb[3]);

/* One Embree packet's hits for fv_scene_shade_packet, lane q in element q of each array (read
 * straight from Embree's RTCRayHitN). A lane with geom RTC_INVALID_GEOMETRY_ID is a miss. */
typedef struct fv_hit_packet {
    const unsigned *geom, *prim;
    const float *u, *v, *t;
    const float *dir[3];
} fv_hit_packet;
/* Asks for the shading data of n hits (geometry and primitive IDs as Embree returns them) to
 * be brought into the cache: call it as soon as a packet is traced, shade it later. */
void fv_scene_shade_prefetch(const fv_scene *s, const unsigned *geom, const unsigned *prim, int n);
struct fv_shade_dsp;
/* fv_scene_shade for lanes 0 .. n-1 of a packet of camera rays from eye_pos, each with
 * footprint px_tan / |dir| (the camera's pixel angle), with the shading kernels of dsp: the same
 * bits as fv_scene_shade lane by lane. Misses' rgb is unspecified. */
void fv_scene_shade_packet(const fv_scene *s, const struct fv_shade_dsp *dsp, const fv_hit_packet *h, int n,
                           float px_tan, const float eye_pos[3], float rgb[3][16]);

#endif
