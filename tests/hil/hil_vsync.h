/* fovea HIL: the vsync source + predictor as the GPIO check drives it. An adapter, so the check
 * stays the same while the source behind it changes (tests/hil/hil_vsync.c). */
#ifndef FOVEA_HIL_VSYNC_H
#define FOVEA_HIL_VSYNC_H

#include <stddef.h>
#include <stdint.h>

typedef struct fv_hil_vsync fv_hil_vsync;

/* Rising edges of LINE on the GPIO chip CHIP (a /dev/gpiochipN path or a chip name); the
 * predictor starts from nominal_period_ns. NULL with a one-line reason in err. */
fv_hil_vsync *fv_hil_vsync_open(const char *chip, int line, double nominal_period_ns, char *err, size_t err_len);
/* Waits at most timeout_ms for the next edge: 1 with its kernel timestamp (CLOCK_MONOTONIC) in
 * *edge_ns and, in *predicted_ns, the time the predictor gave for that edge before it came (0
 * while it is not locked yet); 0 on timeout; -1 with err. */
int fv_hil_vsync_wait(fv_hil_vsync *v, int timeout_ms, int64_t *edge_ns, int64_t *predicted_ns, char *err,
                      size_t err_len);
double fv_hil_vsync_period_ns(const fv_hil_vsync *v); /* the predictor's current period */
void fv_hil_vsync_close(fv_hil_vsync *v);

#endif
