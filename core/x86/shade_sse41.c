/* fovea: the packet shading kernel, SSE4.1: 4 lanes a vector, the body of core/shade_tmpl.h.
 * Bit-identical to the C reference (IEEE operations in its order, no FMA). */
#define FV_X86_W 4
#define FV_X86_FN(name) name##_sse41
#include "x86/shade_tmpl.h"

void fv_shade_dsp_init_sse41(fv_shade_dsp *d) { d->brdf = brdf_sse41; }
