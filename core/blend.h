/* fovea: glTF alpha BLEND, composited front to back along each camera ray (docs/materials.md).
 * While a packet is traced, the scene's intersect filter records the blended surfaces a ray
 * crosses (up to FV_BLEND_LAYERS, the nearest kept) and lets the ray go on; after the packet's
 * opaque hits are shaded, each ray's blended layers in front of its opaque hit are shaded and
 * laid over it, nearest first. A ray query outside fv_blend_begin / fv_blend_end passes
 * through blended surfaces. */
#ifndef FOVEA_BLEND_H
#define FOVEA_BLEND_H

#include "scene.h"

#define FV_BLEND_LAYERS 4 /* blended surfaces per ray; behind the 4 nearest, more are ignored */

/* The blended surfaces one ray crossed, in the order found (unsorted). */
typedef struct fv_blend_lane {
    unsigned n;
    unsigned geom[FV_BLEND_LAYERS], prim[FV_BLEND_LAYERS];
    float u[FV_BLEND_LAYERS], v[FV_BLEND_LAYERS], t[FV_BLEND_LAYERS];
} fv_blend_lane;

/* A packet's rays (ids 0..15): bit q of used says lane[q] holds what ray q crossed (a lane whose
 * bit is clear crossed nothing and is not read: fv_blend_begin clears one word, not 16 lanes, and
 * the composite visits only the recorded lanes). */
typedef struct fv_blend_packet {
    unsigned used;
    fv_blend_lane lane[16];
} fv_blend_packet;

/* 1 if the scene has an alpha BLEND mesh (else the ray stage skips all of this). */
int fv_scene_has_blend(const fv_scene *s);
/* Records of the calling thread's next ray query go to p->lane[ray id] (ray ids 0..15; cleared
 * here); fv_blend_end stops recording. */
void fv_blend_begin(fv_blend_packet *p);
void fv_blend_end(void);
/* (the scene's intersect filter) a blended hit of the ray with this id at distance t */
void fv_blend_record(unsigned ray_id, unsigned geom, unsigned prim, float u, float v, float t);
/* Lays ray q's blended layers (those nearer than tfar[q]) over rgb[.][q], for q < n: rays from
 * org[.][q] (NULL: all from eye; the thin-lens reference's start on the lens) with direction dir
 * and pixel angle px_tan / |dir|, seen from eye. A lane whose ray missed
 * (geom RTC_INVALID_GEOMETRY_ID) is laid over background and becomes a hit of its nearest layer
 * (geom and tfar rewritten), so the ray stage writes its colour and that layer's depth. */
void fv_blend_composite(const fv_scene *s, const fv_blend_packet *p, unsigned *geom, float *tfar,
                        const float *const org[3], const float *const dir[3], int n, float px_tan, const float eye[3],
                        const float background[3], float rgb[3][16]);

#endif
