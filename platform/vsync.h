/* fovea platform: vsync sources. Each returns the time of the next vertical-sync edge
 * (CLOCK_MONOTONIC, ns) or times out; none blocks longer than the timeout it is given.
 *  - GPIO (libgpiod 1.6): a line of a chip (by name, label or path: gpiod_chip_open_lookup),
 *    rising or falling edge, the kernel's event timestamp (queued by the kernel, so a late
 *    reader still gets the true edge times);
 *  - timer: absolute clock_nanosleep on CLOCK_MONOTONIC at HZ;
 *  - replay: recorded edge times from a file (one integer t_ns per line, '#' comments), played
 *    back in real time from the first edge's time mapped to the open time; after the last edge
 *    the source is silent (timeouts), like a line that stopped.
 * Each GPIO / timer / replay source also has its own small API for test programs (the
 * hardware-in-the-loop guest links only what it uses). */
#ifndef FOVEA_VSYNC_H
#define FOVEA_VSYNC_H

#include <stddef.h>
#include <stdint.h>

/* ---- GPIO line (platform/vsync_gpio.c; -lgpiod) ---- */
typedef struct fv_vsync_gpio fv_vsync_gpio;
/* chip: "gpiochip0", "/dev/gpiochip0", a chip label or a number; falling: edge to use.
 * 0, or -1 with "gpiod_xxx(chip): reason" in err. Without libgpiod at build time: always -1. */
int fv_vsync_gpio_open(fv_vsync_gpio **g, const char *chip, unsigned line, int falling, char *err, size_t err_len);
/* 1: an edge, its kernel timestamp in *t_ns; 0: none within timeout_ns (0 = just poll);
 * -1: the read failed (line gone), reason in err. */
int fv_vsync_gpio_wait(fv_vsync_gpio *g, int64_t timeout_ns, int64_t *t_ns, char *err, size_t err_len);
void fv_vsync_gpio_close(fv_vsync_gpio *g);

/* ---- any source by spec ---- */
typedef struct fv_vsync fv_vsync;
/* spec: "gpio:CHIP:LINE[:rising|falling]" (default rising), "timer:HZ", "replay:FILE".
 * 0, or -1 with a one-line reason in err. */
int fv_vsync_open(fv_vsync **v, const char *spec, char *err, size_t err_len);
/* As fv_vsync_gpio_wait, for any source. */
int fv_vsync_wait(fv_vsync *v, int64_t timeout_ns, int64_t *t_ns, char *err, size_t err_len);
/* Nominal period (timer), 0 when the source does not know it (GPIO, replay). */
int64_t fv_vsync_nominal_period_ns(const fv_vsync *v);
const char *fv_vsync_kind(const fv_vsync *v); /* "gpio", "timer", "replay" */
void fv_vsync_close(fv_vsync *v);

/* ---- clocks ---- */
void fv_clock_sleep_until_ns(int64_t t_ns); /* absolute clock_nanosleep, restarted on EINTR */

#endif
