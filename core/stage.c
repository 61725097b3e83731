#include "stage.h"

const char *const fv_stage_names[FV_STAGE_COUNT] = {"trace", "reproject", "reconstruct", "coc", "dof_filter", "combine",
                                                    "output"};
