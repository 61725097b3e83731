/* fovea platform: HMD lens profile files (the format, its parser and the model: core/lens.h). */
#ifndef FOVEA_LENSFILE_H
#define FOVEA_LENSFILE_H

#include <stddef.h>

#include "lens.h"

/* Reads path (a small text file) and parses it (fv_lens_parse, messages named after path). 0, or
 * -1 with "PATH: reason" / "PATH:LINE: reason" in err. */
int fv_lens_load(fv_lens *l, const char *path, float r_max, char *err, size_t err_len);

#endif
