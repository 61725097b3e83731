/* fovea: shadows from the scene's KHR punctual lights (fv_scene_set_shadows): the occlusion
 * rays of the shading paths (core/shade.c), in packets (rtcOccluded16) and one at a time. */
#ifndef FOVEA_SHADOW_H
#define FOVEA_SHADOW_H

#include "scene.h"
#include "shade_dsp.h"

#define FV_SHADOW_MAX_LIGHTS 16 /* fv_scene_set_shadows refuses scenes with more KHR lights */

/* lit[j] = 1 where light j reaches the hit (unnormalised shading normal n, nn = |n|^2 > 0, the
 * ray's direction dir), 0 where something lies between; lights past light_count get 1. */
void fv_shadow_scalar(const fv_scene *s, const float hit[3], const float n[3], float nn, const float dir[3],
                      float lit[FV_SHADOW_MAX_LIGHTS]);
/* The same for the lanes of a gathered packet of camera rays from eye (bit q of lanes: lane q is
 * a hit; the others get 1): rows of lit as fv_shade_env.lit reads them. */
void fv_shadow_packet(const fv_scene *s, const fv_shade_packet *pk, unsigned lanes, const float eye[3],
                      float lit[FV_SHADOW_MAX_LIGHTS][FV_SHADE_LANES]);

#endif
