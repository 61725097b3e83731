/* fovea: strict number parsing for command-line values, into caller-provided error buffers (the
 * messages name the flag). platform/cli.c turns a failure into the usage error; the bench's sweep
 * parser (core/bench.c) reuses them so both say the same thing. */
#ifndef FOVEA_PARSE_H
#define FOVEA_PARSE_H

#include <stddef.h>

/* The whole string must be a number in [lo, hi]. 0, or -1 with "FLAG: ..." in err. */
int fv_parse_long(const char *flag, const char *s, long lo, long hi, long *v, char *err, size_t err_len);
int fv_parse_float(const char *flag, const char *s, float lo, float hi, float *v, char *err, size_t err_len);
/* WxH, each in [16, 8192]. */
int fv_parse_size(const char *flag, const char *s, int *w, int *h, char *err, size_t err_len);

#endif
