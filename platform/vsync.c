/* Vsync sources by spec: GPIO (vsync_gpio.c), timer, replay of recorded edges. */
#include "vsync.h"
#include "base/clock.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "base/err.h"


void fv_clock_sleep_until_ns(int64_t t_ns)
{
    struct timespec ts = {(time_t)(t_ns / 1000000000), (long)(t_ns % 1000000000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
}

enum { K_GPIO, K_TIMER, K_REPLAY };

struct fv_vsync {
    int kind;
    fv_vsync_gpio *gpio;
    int64_t period_ns; /* timer */
    int64_t t0_ns;     /* timer: first tick; replay: open time */
    int64_t next_k;    /* timer: index of the next tick to report */
    int64_t *edges_ns; /* replay, relative to the first */
    long n_edges, next_edge;
};

static int open_replay(fv_vsync *v, const char *path, char *err, size_t err_len)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return fv_err(err, err_len, "vsync replay %s: %s", path, strerror(errno));
    char line[256];
    long cap = 0, lineno = 0;
    int64_t first = 0;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        char *s = line;
        while (*s == ' ' || *s == '\t')
            s++;
        if (*s == '#' || *s == '\n' || *s == '\r' || !*s)
            continue;
        char *end;
        errno = 0;
        long long t = strtoll(s, &end, 10);
        while (*end == ' ' || *end == '\t' || *end == '\r' || *end == '\n')
            end++;
        if (errno || end == s || *end) {
            fclose(f);
            return fv_err(err, err_len, "vsync replay %s:%ld: not an integer time in ns", path, lineno);
        }
        if (v->n_edges == cap) {
            cap = cap ? 2 * cap : 256;
            int64_t *n = realloc(v->edges_ns, (size_t)cap * sizeof *n);
            if (!n) {
                fclose(f);
                return fv_err(err, err_len, "vsync replay %s: out of memory", path);
            }
            v->edges_ns = n;
        }
        if (v->n_edges == 0)
            first = t;
        if (v->n_edges && t - first < v->edges_ns[v->n_edges - 1]) {
            fclose(f);
            return fv_err(err, err_len, "vsync replay %s:%ld: times go backwards", path, lineno);
        }
        v->edges_ns[v->n_edges++] = t - first;
    }
    fclose(f);
    if (v->n_edges == 0)
        return fv_err(err, err_len, "vsync replay %s: no edge times", path);
    v->t0_ns = fv_time_ns();
    return 0;
}

int fv_vsync_open(fv_vsync **out, const char *spec, char *err, size_t err_len)
{
    *out = NULL;
    fv_vsync *v = calloc(1, sizeof *v);
    if (!v)
        return fv_err(err, err_len, "vsync: out of memory");
    if (!strncmp(spec, "timer:", 6)) {
        char *end;
        errno = 0;
        double hz = strtod(spec + 6, &end);
        if (errno || end == spec + 6 || *end || !(hz >= 1.0 && hz <= 1000.0)) {
            free(v);
            return fv_err(err, err_len, "--vsync %s: HZ must be a number in [1, 1000]", spec);
        }
        v->kind = K_TIMER;
        v->period_ns = (int64_t)(1e9 / hz + 0.5);
        v->t0_ns = fv_time_ns() + v->period_ns;
    } else if (!strncmp(spec, "replay:", 7)) {
        v->kind = K_REPLAY;
        if (open_replay(v, spec + 7, err, err_len)) {
            fv_vsync_close(v);
            return -1;
        }
    } else if (!strncmp(spec, "gpio:", 5)) {
        /* gpio:CHIP:LINE[:EDGE]; CHIP may itself be a path ("/dev/gpiochip0") but has no ':' */
        char chip[256];
        const char *a = spec + 5, *c = strchr(a, ':');
        if (!c || c == a || (size_t)(c - a) >= sizeof chip) {
            free(v);
            return fv_err(err, err_len, "--vsync %s: want gpio:CHIP:LINE[:rising|falling]", spec);
        }
        memcpy(chip, a, (size_t)(c - a));
        chip[c - a] = 0;
        char *end;
        errno = 0;
        long line = strtol(c + 1, &end, 10);
        int falling = 0;
        if (*end == ':') {
            if (!strcmp(end + 1, "falling"))
                falling = 1;
            else if (strcmp(end + 1, "rising"))
                end = (char *)"?";
            else
                end += strlen(end);
        }
        if (errno || end == c + 1 || *end || line < 0 || line > 65535) {
            free(v);
            return fv_err(err, err_len, "--vsync %s: LINE must be a line offset, EDGE rising or falling", spec);
        }
        v->kind = K_GPIO;
        if (fv_vsync_gpio_open(&v->gpio, chip, (unsigned)line, falling, err, err_len)) {
            free(v);
            return -1;
        }
    } else {
        free(v);
        return fv_err(err, err_len, "--vsync %s: want gpio:CHIP:LINE, timer:HZ or replay:FILE", spec);
    }
    *out = v;
    return 0;
}

int fv_vsync_wait(fv_vsync *v, int64_t timeout_ns, int64_t *t_ns, char *err, size_t err_len)
{
    if (timeout_ns < 0)
        timeout_ns = 0;
    if (v->kind == K_GPIO)
        return fv_vsync_gpio_wait(v->gpio, timeout_ns, t_ns, err, err_len);
    int64_t now = fv_time_ns(), deadline = now + timeout_ns, t;
    if (v->kind == K_TIMER) {
        /* like a GPIO line read late: the kernel queues 16 events, older ones are lost */
        int64_t passed = (now - v->t0_ns) / v->period_ns;
        if (now >= v->t0_ns && passed - 15 > v->next_k)
            v->next_k = passed - 15;
        t = v->t0_ns + v->next_k * v->period_ns;
    } else {
        if (v->next_edge >= v->n_edges) { /* silent after the recording */
            fv_clock_sleep_until_ns(deadline);
            return 0;
        }
        t = v->t0_ns + v->edges_ns[v->next_edge];
    }
    if (t > deadline) {
        fv_clock_sleep_until_ns(deadline);
        return 0;
    }
    if (t > now)
        fv_clock_sleep_until_ns(t);
    if (v->kind == K_TIMER)
        v->next_k++;
    else
        v->next_edge++;
    *t_ns = t;
    return 1;
}

int64_t fv_vsync_nominal_period_ns(const fv_vsync *v) { return v->kind == K_TIMER ? v->period_ns : 0; }

const char *fv_vsync_kind(const fv_vsync *v)
{
    return v->kind == K_GPIO ? "gpio" : v->kind == K_TIMER ? "timer" : "replay";
}

void fv_vsync_close(fv_vsync *v)
{
    if (!v)
        return;
    fv_vsync_gpio_close(v->gpio);
    free(v->edges_ns);
    free(v);
}
