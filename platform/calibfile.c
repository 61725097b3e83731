/* fovea platform: gaze calibration files (see calibfile.h). */
#include "calibfile.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "err.h"
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
    FILE *f = fopen(path, "rb");
    if (!f)
        return fv_err(err, err_len, "%s: %s", path, strerror(errno));
    char buf[8192];
    const size_t n = fread(buf, 1, sizeof buf - 1, f);
    const int bad = ferror(f), more = !feof(f) && fgetc(f) != EOF;
    fclose(f);
    if (bad)
        return fv_err(err, err_len, "%s: read error (a directory?)", path);
    if (more)
        return fv_err(err, err_len, "%s: too large for a calibration file", path);
    buf[n] = '\0';
    if (memchr(buf, '\0', n))
        return fv_err(err, err_len, "%s: not a text file", path);
    char why[256];
    if (fv_calib_parse(c, buf, why, sizeof why))
        return fv_err(err, err_len, "%s: %s", path, why);
    return 0;
}
