#include "base/parse.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/err.h"

int fv_parse_long(const char *flag, const char *s, long lo, long hi, long *out, char *err, size_t err_len)
{
    char *end;
    errno = 0;
    const long v = strtol(s, &end, 10);
    if (end == s || *end || errno)
        return fv_err(err, err_len, "%s: '%s' is not a whole number", flag, s);
    if (v < lo || v > hi)
        return fv_err(err, err_len, "%s: %ld is out of range [%ld, %ld]", flag, v, lo, hi);
    *out = v;
    return 0;
}

int fv_parse_float(const char *flag, const char *s, float lo, float hi, float *out, char *err, size_t err_len)
{
    char *end;
    errno = 0;
    const double v = strtod(s, &end);
    if (end == s || *end || errno || !isfinite(v))
        return fv_err(err, err_len, "%s: '%s' is not a number", flag, s);
    if (v < lo || v > hi)
        return fv_err(err, err_len, "%s: %g is out of range [%g, %g]", flag, v, (double)lo, (double)hi);
    *out = (float)v;
    return 0;
}

int fv_parse_size(const char *flag, const char *s, int *w, int *h, char *err, size_t err_len)
{
    char a[32], b[32];
    const char *x = strchr(s, 'x');
    if (!x || x == s || (size_t)(x - s) >= sizeof a || strlen(x + 1) >= sizeof b || !x[1])
        return fv_err(err, err_len, "%s: '%s' is not WxH (for example 1280x1440)", flag, s);
    memcpy(a, s, (size_t)(x - s));
    a[x - s] = '\0';
    strcpy(b, x + 1);
    long vw, vh;
    if (fv_parse_long(flag, a, 16, 8192, &vw, err, err_len) || fv_parse_long(flag, b, 16, 8192, &vh, err, err_len))
        return -1;
    *w = (int)vw;
    *h = (int)vh;
    return 0;
}
