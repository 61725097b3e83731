/* fovea platform: gaze calibration files (see calibfile.h). */
#include "calibfile.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/err.h"
#include "output.h"

int fv_calib_save(const fv_calib *c, const char *path, char *err, size_t err_len)
{
    char buf[2048];
    const int n = fv_calib_format(c, buf, sizeof buf);
    if (n < 0 || (size_t)n >= sizeof buf)
        return fv_err(err, err_len, "%s: calibration does not fit the text form", path);
    fv_afile a;
    if (fv_afile_open(&a, path, err, err_len))
        return -1;
    fputs(buf, a.f);
    return fv_afile_commit(&a, err, err_len);
}

int fv_calib_load(fv_calib *c, const char *path, char *err, size_t err_len)
{
    char buf[8192];
    if (fv_read_text_file(path, buf, sizeof buf, "a calibration file", err, err_len) < 0)
        return -1;
    char why[256];
    if (fv_calib_parse(c, buf, why, sizeof why))
        return fv_err(err, err_len, "%s: %s", path, why);
    return 0;
}
