/* fovea: the kernel tables of the render pipeline's modules, held together so a stage that runs
 * several modules' kernels (the ray caster generates rays, shades, reprojects and pulls per tile) takes one pointer. The
 * eye tracker has its own table (eyetrack/eyetrack_dsp.h). */
#ifndef FOVEA_RENDER_DSP_H
#define FOVEA_RENDER_DSP_H

#include "dof/dof_dsp.h"
#include "pullpush_dsp.h"
#include "raygen_dsp.h"
#include "reproject_dsp.h"
#include "shade_dsp.h"

typedef struct fv_render_dsp {
    unsigned isa; /* the ISA selected (one FV_ISA_* value), for reports */
    fv_pullpush_dsp pp;
    fv_reproject_dsp taa;
    fv_dof_dsp dof;
    fv_shade_dsp shade;
    fv_raygen_dsp ray;
} fv_render_dsp;

/* Every module's fv_<module>_dsp_init(.., isa_mask). */
static inline void fv_render_dsp_init(fv_render_dsp *d, unsigned isa_mask)
{
    d->isa = fv_cpu_best_isa(isa_mask);
    fv_pullpush_dsp_init(&d->pp, isa_mask);
    fv_reproject_dsp_init(&d->taa, isa_mask);
    fv_dof_dsp_init(&d->dof, isa_mask);
    fv_shade_dsp_init(&d->shade, isa_mask);
    fv_raygen_dsp_init(&d->ray, isa_mask);
}

#endif
