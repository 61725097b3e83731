#include "eyetrack/labelstats.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const double fv_eye_label_radii_px[FV_EYE_LABEL_RADII] = {1, 2, 3, 5};

static fv_eye_label_group *group_new(fv_eye_label_stats *s, const char *name)
{
    if (s->n == FV_EYE_LABEL_GROUPS)
        return NULL;
    fv_eye_label_group *g = &s->g[s->n];
    memset(g, 0, sizeof *g);
    snprintf(g->name, sizeof g->name, "%s", name);
    if (!(g->err_px = malloc((size_t)s->cap * sizeof(double))))
        return NULL;
    s->n++;
    return g;
}

int fv_eye_label_stats_init(fv_eye_label_stats *s, long cap)
{
    memset(s, 0, sizeof *s);
    s->cap = cap > 0 ? cap : 1;
    return group_new(s, "all") ? 0 : -1;
}

void fv_eye_label_stats_free(fv_eye_label_stats *s)
{
    for (int i = 0; i < s->n; i++)
        free(s->g[i].err_px);
    memset(s, 0, sizeof *s);
}

static void add_to(fv_eye_label_group *g, double e)
{
    g->err_px[g->n++] = e;
    for (int k = 0; k < FV_EYE_LABEL_RADII; k++)
        g->within[k] += e <= fv_eye_label_radii_px[k];
}

int fv_eye_label_stats_add(fv_eye_label_stats *s, const char *path, double err_px)
{
    if (s->n == 0 || s->g[0].n >= s->cap)
        return -1;
    add_to(&s->g[0], err_px);
    char sensor[16], name[16];
    if (!path || !fv_eye_mrl_sensor(path, sensor))
        return 0;
    snprintf(name, sizeof name, "sensor %.6s", sensor);
    fv_eye_label_group *g = NULL;
    for (int i = 1; i < s->n && !g; i++)
        if (!strcmp(s->g[i].name, name))
            g = &s->g[i];
    if (!g && s->n == FV_EYE_LABEL_GROUPS)
        return 0; /* more sensors than groups: counted in "all" only */
    if (!g && !(g = group_new(s, name)))
        return -1;
    add_to(g, err_px);
    return 0;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

double fv_eye_label_median(fv_eye_label_group *g)
{
    if (!g->n)
        return NAN;
    qsort(g->err_px, (size_t)g->n, sizeof(double), cmp_double);
    return g->n % 2 ? g->err_px[g->n / 2] : 0.5 * (g->err_px[g->n / 2 - 1] + g->err_px[g->n / 2]);
}

int fv_eye_mrl_sensor(const char *path, char out[16])
{
    const char *b = strrchr(path, '/');
    b = b ? b + 1 : path;
    int us = 0;
    const char *last = NULL;
    for (const char *p = b; *p; p++)
        if (*p == '_')
            us++, last = p + 1;
    if (us != 7 || !last)
        return 0;
    const char *dot = strchr(last, '.');
    const int len = dot ? (int)(dot - last) : (int)strlen(last);
    if (len < 1 || len > 8)
        return 0;
    snprintf(out, 16, "%.*s", len, last);
    return 1;
}
