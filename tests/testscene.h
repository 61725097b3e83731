/* fovea test helper: hand-built scenes (quads facing the eye). */
#pragma once
#include <string.h>

#include "testutil.h"
#include "scene.h"

/* Axis-aligned quad facing +Z at depth z (the eye at the origin looks down -Z), base colour rgb,
 * texture index tex (uv spanning the quad) or -1. */
static inline void fv_test_add_quad(fv_scene *s, float x0, float y0, float x1, float y1, float z, const float rgb[3],
                                    int tex)
{
    float pos[] = {x0, y0, z, x1, y0, z, x1, y1, z, x0, y1, z};
    float nrm[] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    float uv[] = {0, 1, 1, 1, 1, 0, 0, 0};
    uint32_t idx[] = {0, 1, 2, 0, 2, 3};
    fv_mesh_desc m;
    memset(&m, 0, sizeof m);
    m.positions = pos;
    m.normals = nrm;
    m.uvs = uv;
    m.indices = idx;
    m.vertex_count = 4;
    m.index_count = 6;
    for (int k = 0; k < 3; k++)
        m.base_color[k] = rgb[k];
    m.base_color[3] = 1.0f;
    m.texture = tex;
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
}
