#define _GNU_SOURCE
#include "perfctr.h"

#include <dirent.h>
#include <errno.h>
#include <linux/perf_event.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/syscall.h>
#include <unistd.h>

const char *const fv_perf_names[FV_PERF_N] = {"cycles", "instructions", "cache_misses", "branch_misses"};

static const uint64_t configs[FV_PERF_N] = {PERF_COUNT_HW_CPU_CYCLES, PERF_COUNT_HW_INSTRUCTIONS,
                                            PERF_COUNT_HW_CACHE_MISSES, PERF_COUNT_HW_BRANCH_MISSES};

#define MAX_TASKS 256

struct fv_perfctr {
    int n;                      /* threads */
    int fd[MAX_TASKS][FV_PERF_N];
};

static int open_one(pid_t tid, int k)
{
    struct perf_event_attr a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.type = PERF_TYPE_HARDWARE;
    a.config = configs[k];
    a.exclude_kernel = 1;
    a.exclude_hv = 1;
    a.read_format = PERF_FORMAT_TOTAL_TIME_ENABLED | PERF_FORMAT_TOTAL_TIME_RUNNING;
    return (int)syscall(SYS_perf_event_open, &a, tid, -1, -1, 0);
}

fv_perfctr *fv_perfctr_open(char *why, size_t why_len)
{
    const char *env = getenv("FOVEA_PERF");
    if (env && !strcmp(env, "off")) {
        snprintf(why, why_len, "switched off (FOVEA_PERF=off)");
        return NULL;
    }
    fv_perfctr *pc = calloc(1, sizeof *pc);
    if (!pc) {
        snprintf(why, why_len, "out of memory");
        return NULL;
    }
    DIR *d = opendir("/proc/self/task");
    if (!d) {
        snprintf(why, why_len, "cannot list threads: /proc/self/task: %s", strerror(errno));
        free(pc);
        return NULL;
    }
    struct dirent *de;
    while ((de = readdir(d)) != NULL && pc->n < MAX_TASKS) {
        if (de->d_name[0] < '0' || de->d_name[0] > '9')
            continue;
        const pid_t tid = (pid_t)atoi(de->d_name);
        for (int k = 0; k < FV_PERF_N; k++) {
            pc->fd[pc->n][k] = open_one(tid, k);
            if (pc->fd[pc->n][k] < 0) {
                const int e = errno;
                snprintf(why, why_len, "perf_event_open(%s): %s", fv_perf_names[k],
                         e == ENOENT || e == EOPNOTSUPP ? "not supported here (no PMU in this VM or CPU)"
                         : e == EACCES || e == EPERM    ? "not permitted (kernel.perf_event_paranoid)"
                                                        : strerror(e));
                for (int j = 0; j < k; j++) /* the partial row; the complete ones below */
                    close(pc->fd[pc->n][j]);
                closedir(d);
                fv_perfctr_close(pc);
                return NULL;
            }
        }
        pc->n++;
    }
    closedir(d);
    if (pc->n == 0) {
        snprintf(why, why_len, "no threads found");
        free(pc);
        return NULL;
    }
    /* a counter the PMU cannot schedule at all reads as never running: unavailable too */
    uint64_t v[FV_PERF_N];
    if (fv_perfctr_read(pc, v)) {
        snprintf(why, why_len, "counters opened but not readable");
        fv_perfctr_close(pc);
        return NULL;
    }
    return pc;
}

int fv_perfctr_read(fv_perfctr *pc, uint64_t v[FV_PERF_N])
{
    for (int k = 0; k < FV_PERF_N; k++) {
        double sum = 0.0;
        for (int t = 0; t < pc->n; t++) {
            uint64_t r[3];
            if (read(pc->fd[t][k], r, sizeof r) != (ssize_t)sizeof r)
                return -1;
            /* r: value, time enabled, time running (multiplexed counters are scaled) */
            sum += r[2] ? (double)r[0] * ((double)r[1] / (double)r[2]) : 0.0;
        }
        v[k] = (uint64_t)sum;
    }
    return 0;
}

void fv_perfctr_close(fv_perfctr *pc)
{
    if (!pc)
        return;
    for (int t = 0; t < pc->n; t++)
        for (int k = 0; k < FV_PERF_N; k++)
            close(pc->fd[t][k]);
    free(pc);
}
