/* fovea: the stages of one eye's frame, in pipeline order. One enum for the pipeline's stage
 * times, the profiler's stage tracks and the bench's tables and JSON. */
#ifndef FOVEA_STAGE_H
#define FOVEA_STAGE_H

typedef enum fv_stage {
    FV_STAGE_TRACE,       /* ray casting and shading of the sampled pixels (core/raycast.c) */
    FV_STAGE_REPROJECT,   /* temporal reprojection of the previous frame (core/reproject.c) */
    FV_STAGE_RECONSTRUCT, /* pull-push hole filling (core/pullpush.c) */
    FV_STAGE_COC,         /* focus depth and circles of confusion (core/dof/focus.c, coc.c) */
    FV_STAGE_DOF_FILTER,  /* the depth-of-field model's filter (core/dof/<model>.c) */
    FV_STAGE_COMBINE,     /* sharp and blurred layers combined (core/dof/combine.c) */
    FV_STAGE_OUTPUT,      /* conversion to the display format (core/output_convert.c) */
    FV_STAGE_COUNT
} fv_stage;

/* JSON / CSV / table names: trace, reproject, reconstruct, coc, dof_filter, combine, output */
extern const char *const fv_stage_names[FV_STAGE_COUNT];

#endif
