/* fovea: the ray-generation kernel, AVX2: 8 lanes a vector (core/x86/raygen_tmpl.h). Exact. */
#define FV_X86_W 8
#define FV_X86_FN(name) name##_avx2
#include "x86/raygen_tmpl.h"

void fv_raygen_dsp_init_avx2(fv_raygen_dsp *d) { d->camera_rays = camera_rays_avx2; }
