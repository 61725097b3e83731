/* fovea platform: gaze calibration files (the text form of core/eyetrack/calib.h), written
 * atomically. */
#ifndef FOVEA_CALIBFILE_H
#define FOVEA_CALIBFILE_H

#include <stddef.h>

#include "eyetrack/calib.h"

int fv_calib_save(const fv_calib *c, const char *path, char *err, size_t err_len);
/* 0, or -1 with "PATH: reason" / "PATH:LINE: reason" in err. */
int fv_calib_load(fv_calib *c, const char *path, char *err, size_t err_len);

#endif
