/* fovea: glTF import: turns the tinygltf shim's C view of a file (gltf_shim.h) into a scene
 * through the builder API (meshes, textures, KHR lights, the first camera). The file itself is
 * read by tinygltf's own loader inside the shim. */
#include "scene.h"
#include "base/err.h"

#include "gltf_shim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>


/* Rotation of a column-major matrix (scale divided out) as a quaternion x,y,z,w. */
static void matrix_quat(const double wm[16], float q[4])
{
    double c[3][3];
    for (int j = 0; j < 3; j++) {
        const double l = sqrt(wm[j * 4] * wm[j * 4] + wm[j * 4 + 1] * wm[j * 4 + 1] + wm[j * 4 + 2] * wm[j * 4 + 2]);
        for (int i = 0; i < 3; i++) c[j][i] = l > 0.0 ? wm[j * 4 + i] / l : (i == j);
    }
#define R(row, col) c[col][row]
    double x, y, z, w;
    const double tr = R(0, 0) + R(1, 1) + R(2, 2);
    if (tr > 0.0) {
        const double S = sqrt(tr + 1.0) * 2.0;
        w = 0.25 * S, x = (R(2, 1) - R(1, 2)) / S, y = (R(0, 2) - R(2, 0)) / S, z = (R(1, 0) - R(0, 1)) / S;
    } else if (R(0, 0) > R(1, 1) && R(0, 0) > R(2, 2)) {
        const double S = sqrt(1.0 + R(0, 0) - R(1, 1) - R(2, 2)) * 2.0;
        w = (R(2, 1) - R(1, 2)) / S, x = 0.25 * S, y = (R(0, 1) + R(1, 0)) / S, z = (R(0, 2) + R(2, 0)) / S;
    } else if (R(1, 1) > R(2, 2)) {
        const double S = sqrt(1.0 + R(1, 1) - R(0, 0) - R(2, 2)) * 2.0;
        w = (R(0, 2) - R(2, 0)) / S, x = (R(0, 1) + R(1, 0)) / S, y = 0.25 * S, z = (R(1, 2) + R(2, 1)) / S;
    } else {
        const double S = sqrt(1.0 + R(2, 2) - R(0, 0) - R(1, 1)) * 2.0;
        w = (R(1, 0) - R(0, 1)) / S, x = (R(0, 2) + R(2, 0)) / S, y = (R(1, 2) + R(2, 1)) / S, z = 0.25 * S;
    }
#undef R
    const double n = sqrt(x * x + y * y + z * z + w * w);
    if (!(n > 0.0) || !isfinite(n)) x = y = z = 0.0, w = 1.0;
    else x /= n, y /= n, z /= n, w /= n;
    q[0] = (float)x, q[1] = (float)y, q[2] = (float)z, q[3] = (float)w;
}

/* Textures an image may become: 2 colour spaces x 9 pairs of wrap modes x 12 filter settings */
#define TEX_VARIANTS (2 * 9 * 12)

/* The scene texture of image img, decoded once per colour space, pair of wrap modes and filter
 * setting (tex[TEX_VARIANTS * img + ...]); -1 for none (no image, or no uvs to sample it with);
 * -2 on failure. */
static int image_texture(fv_scene *s, const fv_gltf_model *g, int *tex, int img, int linear, const int wrap[2],
                         const int filter[3], const float *uvs)
{
    if (img < 0 || !uvs || !g->images[img].rgba8) return -1;
    const int ws = wrap[0] >= 0 && wrap[0] <= 2 ? wrap[0] : 0, wt = wrap[1] >= 0 && wrap[1] <= 2 ? wrap[1] : 0;
    const int mag = filter[0] != 0, min = filter[1] != 0, mip = filter[2] >= 0 && filter[2] <= 2 ? filter[2] : 0;
    int *t = &tex[TEX_VARIANTS * img + ((linear * 9 + 3 * ws + wt) * 2 + mag) * 6 + min * 3 + mip];
    if (*t < 0) {
        const fv_gltf_image *im = &g->images[img];
        *t = linear ? fv_scene_add_texture_linear(s, im->rgba8, im->width, im->height)
                    : fv_scene_add_texture(s, im->rgba8, im->width, im->height);
        if (*t < 0) return -2;
        fv_scene_set_texture_wrap(s, *t, (fv_wrap)ws, (fv_wrap)wt);
        fv_scene_set_texture_filter(s, *t, mag, min, (fv_mip)mip);
    }
    return *t;
}

/* Adds the glTF's meshes, lights and first camera through the builder. 0 on success. */
static int add_gltf(fv_scene *s, const fv_gltf_model *g, char *err, size_t err_len)
{
    int *tex_of_image = NULL;
    if (g->image_count) {
        tex_of_image = malloc(TEX_VARIANTS * g->image_count * sizeof *tex_of_image);
        if (!tex_of_image) {
            fv_err(err, err_len, "out of memory");
            return -1;
        }
        for (size_t i = 0; i < TEX_VARIANTS * g->image_count; i++) tex_of_image[i] = -1;
    }
    int have_camera = 0, rc = 0;
    for (size_t ni = 0; ni < g->node_count && rc == 0; ni++) {
        const fv_gltf_node *nd = &g->nodes[ni];
        if (nd->mesh >= 0) {
            const fv_gltf_mesh *gm = &g->meshes[nd->mesh];
            for (size_t pi = 0; pi < gm->prim_count; pi++) {
                const fv_gltf_prim *p = &gm->prims[pi];
                fv_mesh_desc d;
                fv_material_maps maps;
                memset(&d, 0, sizeof d);
                d.positions = p->positions, d.normals = p->normals, d.uvs = p->uvs, d.indices = p->indices;
                d.colors = p->colors;
                d.vertex_count = p->vertex_count, d.index_count = p->index_count;
                d.base_color[0] = d.base_color[1] = d.base_color[2] = d.base_color[3] = 1.0f;
                d.texture = -1;
                d.metallic = d.roughness = d.specular = 1.0f; /* the glTF default material */
                d.single_sided = 1;                           /* (doubleSided false) */
                if (p->material >= 0) {
                    const fv_gltf_material *mat = &g->materials[p->material];
                    memcpy(d.base_color, mat->base_color, sizeof d.base_color);
                    d.metallic = mat->metallic, d.roughness = mat->roughness, d.specular = mat->specular;
                    d.alpha_cutoff = mat->alpha_cutoff;
                    d.single_sided = !mat->double_sided;
                    d.alpha_blend = mat->alpha_blend;
                    memcpy(d.emissive, mat->emissive, sizeof d.emissive);
                    /* no uvs: factors only */
                    const int img[5] = {mat->image, mat->mr_image, mat->occlusion_image, mat->emissive_image,
                                        mat->normal_image};
                    int tx[5];
                    for (int j = 0; j < 5 && rc == 0; j++) { /* data maps (MR, occlusion, normal) are linear */
                        tx[j] = image_texture(s, g, tex_of_image, img[j], j == 1 || j == 2 || j == 4, mat->wrap[j],
                                              mat->filter[j], p->uvs);
                        if (tx[j] == -2) {
                            fv_err(err, err_len, "image %d: cannot add texture", img[j]);
                            rc = -1;
                        }
                    }
                    if (rc) break;
                    d.texture = tx[0];
                    memset(&maps, 0, sizeof maps);
                    maps.metallic_roughness = tx[1], maps.occlusion = tx[2], maps.emissive = tx[3];
                    maps.normal = tx[4], maps.normal_scale = mat->normal_scale;
                    d.tangents = p->tangents;
                    maps.occlusion_strength = mat->occlusion_strength;
                    maps.has_uv_transform = mat->has_uvx;
                    memcpy(maps.uv_transform, mat->uvx, sizeof maps.uv_transform);
                    d.maps = &maps;
                }
                for (int k = 0; k < 16; k++) d.transform[k] = (float)nd->world[k];
                char e[192];
                if (fv_scene_add_mesh(s, &d, e, sizeof e) < 0) {
                    fv_err(err, err_len, "mesh %d (node %zu in traversal order): %s", nd->mesh, ni, e);
                    rc = -1;
                    break;
                }
            }
        }
        if (nd->light >= 0) {
            const fv_gltf_light *gl = &g->lights[nd->light];
            fv_light l;
            memset(&l, 0, sizeof l);
            l.type = gl->type == 0 ? FV_LIGHT_DIRECTIONAL : gl->type == 1 ? FV_LIGHT_POINT : FV_LIGHT_SPOT;
            memcpy(l.color, gl->color, sizeof l.color);
            l.intensity = gl->intensity, l.range = gl->range;
            l.inner_cone = gl->inner_cone_rad, l.outer_cone = gl->outer_cone_rad;
            for (int k = 0; k < 3; k++) {
                l.pos[k] = (float)nd->world[12 + k];
                l.dir[k] = -(float)nd->world[8 + k]; /* lights point down the node's -Z */
            }
            fv_scene_add_light(s, &l);
        }
        if (nd->camera >= 0 && !have_camera) {
            const float pos[3] = {(float)nd->world[12], (float)nd->world[13], (float)nd->world[14]};
            float q[4];
            matrix_quat(nd->world, q);
            fv_scene_set_default_view(s, pos, q);
            have_camera = 1;
        }
    }
    free(tex_of_image);
    return rc;
}

fv_scene *fv_scene_load(const char *path, char *err, size_t err_len)
{
    return fv_scene_load_in(path, NULL, err, err_len);
}

fv_scene *fv_scene_load_in(const char *path, const char *asset_root, char *err, size_t err_len)
{
    char e[1024] = "";
    if (!path) {
        fv_err(err, err_len, "no path");
        return NULL;
    }
    fv_gltf_model *g = fv_gltf_load(path, asset_root, e, sizeof e);
    if (!g) {
        fv_err(err, err_len, "%s: %s", path, e);
        return NULL;
    }
    fv_scene *s = fv_scene_create();
    if (!s) {
        fv_gltf_free(g);
        fv_err(err, err_len, "%s: cannot create the Embree device/scene", path);
        return NULL;
    }
    int rc = add_gltf(s, g, e, sizeof e);
    fv_scene_set_warning(s, g->warning);
    fv_gltf_free(g);
    if (rc == 0 && fv_scene_triangle_count(s) == 0) { /* nothing to render: most likely not a real scene */
        fv_err(e, sizeof e, "no triangles reachable from the scene's root nodes");
        rc = -1;
    }
    if (rc == 0) rc = fv_scene_commit(s, e, sizeof e);
    if (rc != 0) {
        fv_err(err, err_len, "%s: %s", path, e);
        fv_scene_free(s);
        return NULL;
    }
    fv_err(err, err_len, "%s", "");
    return s;
}
