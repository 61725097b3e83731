/* fovea: the ray-generation kernel, SSE4.1: 4 lanes a vector (core/x86/raygen_tmpl.h). Exact. */
#define FV_X86_W 4
#define FV_X86_FN(name) name##_sse41
#include "x86/raygen_tmpl.h"

void fv_raygen_dsp_init_sse41(fv_raygen_dsp *d) { d->camera_rays = camera_rays_sse41; }
