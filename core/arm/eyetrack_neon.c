/* fovea eye tracker kernels, neon: none of its own yet (the C references stay in the table). */
#include "dsp.h"

void fv_eyetrack_init_neon(fv_dsp *d)
{
    (void)d;
}
