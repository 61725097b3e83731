/* fovea platform: HMD lens profile files (the model: core/lens.h). Text, one `key values` per
 * line, '#' comments and blank lines skipped, every key optional (defaults: no distortion):
 *   k1 0.10                  radial coefficients
 *   k2 0.02
 *   chroma 0.994 1.0 1.008   per-channel scale R G B (lateral chromatic aberration)
 *   left_center 0.53 0.5     lens centre per eye, normalised image coordinates
 *   right_center 0.47 0.5
 * Unknown keys, missing or extra values and a mapping that folds over within r_max are errors. */
#ifndef FOVEA_LENSFILE_H
#define FOVEA_LENSFILE_H

#include <stddef.h>

#include "lens.h"

/* name is used in messages ("NAME:LINE: reason"). */
int fv_lens_parse(fv_lens *l, const char *text, const char *name, float r_max, char *err, size_t err_len);
int fv_lens_load(fv_lens *l, const char *path, float r_max, char *err, size_t err_len);

#endif
