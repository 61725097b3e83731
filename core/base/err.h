/* fovea: one-line error messages into caller-provided buffers (no global error state). */
#ifndef FOVEA_ERR_H
#define FOVEA_ERR_H

#include <stddef.h>

/* Formats into err (if err and err_len) and returns -1, so `return fv_err(...)` reads naturally. */
int fv_err(char *err, size_t err_len, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

#endif
