/* fovea eye tracker kernels, sse41: none of its own yet (the C references stay in the table). */
#include "dsp.h"

void fv_eyetrack_init_sse41(fv_dsp *d)
{
    (void)d;
}
