/* fovea eye tracker kernels, avx2: none of its own yet (the C references stay in the table). */
#include "dsp.h"

void fv_eyetrack_init_avx2(fv_dsp *d)
{
    (void)d;
}
