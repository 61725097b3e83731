/* fovea: the packet shading kernel (glTF BRDF), AVX2: 8 lanes a vector, the body of core/shade_tmpl.h.
 * Bit-identical to the C reference (IEEE operations in its order, no FMA). */
#define FV_X86_W 8
#define FV_X86_FN(name) name##_avx2
#include "x86/shade_tmpl.h"

void fv_shade_dsp_init_avx2(fv_shade_dsp *d) { d->brdf = brdf_avx2; }
