/* GPIO vsync through libgpiod 1.6 (the v1 character-device uAPI). */
#include "vsync.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "base/err.h"

#ifdef FV_HAVE_GPIOD
#include <gpiod.h>

struct fv_vsync_gpio {
    struct gpiod_chip *chip;
    struct gpiod_line *line;
    int falling;
    /* Kernels before 5.7 stamp v1 line events with CLOCK_REALTIME; later ones with
     * CLOCK_MONOTONIC. Decided on the first event by which clock it is close to. */
    int clock_known, realtime;
};

static int64_t ts_ns(const struct timespec *ts) { return (int64_t)ts->tv_sec * 1000000000 + ts->tv_nsec; }

int fv_vsync_gpio_open(fv_vsync_gpio **out, const char *chip, unsigned line, int falling, char *err, size_t err_len)
{
    *out = NULL;
    fv_vsync_gpio *g = calloc(1, sizeof *g);
    if (!g)
        return fv_err(err, err_len, "gpio: out of memory");
    g->falling = falling;
    g->chip = gpiod_chip_open_lookup(chip);
    if (!g->chip) {
        int e = errno;
        free(g);
        return fv_err(err, err_len, "gpiod_chip_open_lookup(%s): %s", chip, strerror(e ? e : ENODEV));
    }
    if (line >= gpiod_chip_num_lines(g->chip)) {
        fv_err(err, err_len, "gpio chip %s: line %u out of range (the chip has %u lines)", chip, line,
               gpiod_chip_num_lines(g->chip));
        goto bad;
    }
    g->line = gpiod_chip_get_line(g->chip, line);
    if (!g->line) {
        fv_err(err, err_len, "gpiod_chip_get_line(%s, %u): %s", chip, line, strerror(errno));
        goto bad;
    }
    int rc = falling ? gpiod_line_request_falling_edge_events(g->line, "fovea-vsync")
                     : gpiod_line_request_rising_edge_events(g->line, "fovea-vsync");
    if (rc) {
        fv_err(err, err_len, "gpiod_line_request_%s_edge_events(%s, %u): %s", falling ? "falling" : "rising", chip,
               line, strerror(errno));
        g->line = NULL;
        goto bad;
    }
    *out = g;
    return 0;
bad:
    fv_vsync_gpio_close(g);
    return -1;
}

int fv_vsync_gpio_wait(fv_vsync_gpio *g, int64_t timeout_ns, int64_t *t_ns, char *err, size_t err_len)
{
    if (timeout_ns < 0)
        timeout_ns = 0;
    struct timespec to = {(time_t)(timeout_ns / 1000000000), (long)(timeout_ns % 1000000000)};
    int rc = gpiod_line_event_wait(g->line, &to);
    if (rc < 0)
        return fv_err(err, err_len, "gpiod_line_event_wait: %s", strerror(errno));
    if (rc == 0)
        return 0;
    struct gpiod_line_event ev;
    if (gpiod_line_event_read(g->line, &ev))
        return fv_err(err, err_len, "gpiod_line_event_read: %s", strerror(errno));
    int64_t t = ts_ns(&ev.ts);
    if (!g->clock_known) {
        struct timespec m, r;
        clock_gettime(CLOCK_MONOTONIC, &m);
        clock_gettime(CLOCK_REALTIME, &r);
        int64_t dm = llabs(ts_ns(&m) - t), dr = llabs(ts_ns(&r) - t);
        g->realtime = dr < dm;
        g->clock_known = 1;
    }
    if (g->realtime) { /* map to CLOCK_MONOTONIC by the clocks' current offset */
        struct timespec m, r;
        clock_gettime(CLOCK_MONOTONIC, &m);
        clock_gettime(CLOCK_REALTIME, &r);
        t -= ts_ns(&r) - ts_ns(&m);
    }
    *t_ns = t;
    return 1;
}

void fv_vsync_gpio_close(fv_vsync_gpio *g)
{
    if (!g)
        return;
    if (g->line)
        gpiod_line_release(g->line);
    if (g->chip)
        gpiod_chip_close(g->chip);
    free(g);
}

#else /* no libgpiod at build time */

struct fv_vsync_gpio {
    int unused;
};
int fv_vsync_gpio_open(fv_vsync_gpio **g, const char *chip, unsigned line, int falling, char *err, size_t err_len)
{
    (void)line;
    (void)falling;
    *g = NULL;
    return fv_err(err, err_len, "gpio %s: fovea was built without libgpiod", chip);
}
int fv_vsync_gpio_wait(fv_vsync_gpio *g, int64_t timeout_ns, int64_t *t_ns, char *err, size_t err_len)
{
    (void)g;
    (void)timeout_ns;
    (void)t_ns;
    return fv_err(err, err_len, "gpio: fovea was built without libgpiod");
}
void fv_vsync_gpio_close(fv_vsync_gpio *g) { (void)g; }
#endif
