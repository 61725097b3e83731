/* fovea HIL: vsync adapter over libgpiod 1.6 (rising-edge events with kernel timestamps) and a
 * least-squares vsync predictor (edge time against edge number over the last 32 edges; a gap of
 * k periods counts k edge numbers, so a dropped edge does not break the lock).
 * Stand-in until the headset's platform vsync source and predictor land (issue 6); then this file
 * becomes a thin wrapper over them. */
#include "hil_vsync.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <gpiod.h>

#define HIST 32

struct fv_hil_vsync {
    struct gpiod_chip *chip;
    struct gpiod_line *line;
    double period;           /* ns */
    int64_t base;            /* time origin of the fit (first edge) */
    long idx[HIST];
    double t[HIST];          /* ns since base */
    int n, head;
    long last_idx;
    double a, b;             /* t = a + b * idx */
    int fitted;
    int rejected;            /* consecutive edges far from the prediction */
};

fv_hil_vsync *fv_hil_vsync_open(const char *chip, int line, double nominal_period_ns, char *err, size_t err_len)
{
    fv_hil_vsync *v = calloc(1, sizeof *v);
    if (!v) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    v->period = nominal_period_ns;
    v->chip = gpiod_chip_open_lookup(chip);
    if (!v->chip) {
        snprintf(err, err_len, "gpiod_chip_open_lookup %s: %s", chip, strerror(errno));
        free(v);
        return NULL;
    }
    v->line = gpiod_chip_get_line(v->chip, (unsigned)line);
    if (!v->line || gpiod_line_request_rising_edge_events(v->line, "fovea-hil")) {
        snprintf(err, err_len, "line %d of %s: %s", line, chip, strerror(errno));
        gpiod_chip_close(v->chip);
        free(v);
        return NULL;
    }
    return v;
}

static void refit(fv_hil_vsync *v)
{
    double si = 0, st = 0;
    for (int i = 0; i < v->n; i++) {
        si += (double)v->idx[i];
        st += v->t[i];
    }
    double mi = si / v->n, mt = st / v->n, sii = 0, sit = 0;
    for (int i = 0; i < v->n; i++) {
        double di = (double)v->idx[i] - mi;
        sii += di * di;
        sit += di * (v->t[i] - mt);
    }
    if (v->n >= 8 && sii > 0) {
        v->b = sit / sii;
        v->a = mt - v->b * mi;
        v->period = v->b;
        v->fitted = 1;
    }
}

int fv_hil_vsync_wait(fv_hil_vsync *v, int timeout_ms, int64_t *edge_ns, int64_t *predicted_ns, char *err,
                      size_t err_len)
{
    struct timespec to = {.tv_sec = timeout_ms / 1000, .tv_nsec = (long)(timeout_ms % 1000) * 1000000};
    int r = gpiod_line_event_wait(v->line, &to);
    if (r < 0) {
        snprintf(err, err_len, "gpiod_line_event_wait: %s", strerror(errno));
        return -1;
    }
    if (r == 0)
        return 0;
    struct gpiod_line_event ev;
    if (gpiod_line_event_read(v->line, &ev)) {
        snprintf(err, err_len, "gpiod_line_event_read: %s", strerror(errno));
        return -1;
    }
    int64_t t = (int64_t)ev.ts.tv_sec * 1000000000 + ev.ts.tv_nsec;
    *edge_ns = t;
    *predicted_ns = 0;
    if (v->n == 0) {
        v->base = t;
        v->last_idx = 0;
        v->idx[0] = 0;
        v->t[0] = 0;
        v->n = 1;
        v->head = 1;
        return 1;
    }
    double rel = (double)(t - v->base);
    double last_t = v->t[(v->head + HIST - 1) % HIST];
    long k = lround((rel - last_t) / v->period);
    if (k < 1)
        k = 1;
    long idx = v->last_idx + k;
    if (v->fitted) {
        double pred = v->a + v->b * (double)idx;
        *predicted_ns = v->base + (int64_t)llround(pred);
        /* an edge a quarter period off is not a vsync (spurious or a jump): skip it, and after
         * three in a row start over */
        if (fabs(pred - rel) > v->period / 4) {
            if (++v->rejected < 3)
                return 1;
            v->n = 0;
            v->fitted = 0;
            v->rejected = 0;
            v->base = t;
            v->last_idx = 0;
            v->idx[0] = 0;
            v->t[0] = 0;
            v->n = 1;
            v->head = 1;
            return 1;
        }
    }
    v->rejected = 0;
    v->idx[v->head] = idx;
    v->t[v->head] = rel;
    v->head = (v->head + 1) % HIST;
    if (v->n < HIST)
        v->n++;
    v->last_idx = idx;
    refit(v);
    return 1;
}

double fv_hil_vsync_period_ns(const fv_hil_vsync *v)
{
    return v->period;
}

void fv_hil_vsync_close(fv_hil_vsync *v)
{
    if (!v)
        return;
    gpiod_line_release(v->line);
    gpiod_chip_close(v->chip);
    free(v);
}
