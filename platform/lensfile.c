/* fovea platform: HMD lens profile files (see lensfile.h). */
#include "lensfile.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/err.h"
#include "output.h"

/* Reads exactly n numbers from s; 0 or -1. */
static int numbers(const char *s, float *v, int n)
{
    for (int i = 0; i < n; i++) {
        char *end;
        errno = 0;
        double d = strtod(s, &end);
        if (end == s || errno || !isfinite(d))
            return -1;
        v[i] = (float)d;
        s = end;
    }
    while (*s == ' ' || *s == '\t' || *s == '\r')
        s++;
    return *s ? -1 : 0;
}

int fv_lens_parse(fv_lens *l, const char *text, const char *name, float r_max, char *err, size_t err_len)
{
    fv_lens_default(l);
    int lineno = 0;
    const char *p = text;
    while (*p) {
        const char *nl = strchr(p, '\n');
        size_t len = nl ? (size_t)(nl - p) : strlen(p);
        lineno++;
        char line[512];
        if (len >= sizeof line)
            return fv_err(err, err_len, "%s:%d: line too long", name, lineno);
        memcpy(line, p, len);
        line[len] = 0;
        p += len + (nl ? 1 : 0);
        char *hash = strchr(line, '#');
        if (hash)
            *hash = 0;
        char *s = line;
        while (*s == ' ' || *s == '\t' || *s == '\r')
            s++;
        if (!*s)
            continue;
        char *key = s;
        while (*s && *s != ' ' && *s != '\t')
            s++;
        if (*s)
            *s++ = 0;
        float v[3];
        int want, rc;
        if (!strcmp(key, "k1") || !strcmp(key, "k2"))
            want = 1;
        else if (!strcmp(key, "chroma"))
            want = 3;
        else if (!strcmp(key, "left_center") || !strcmp(key, "right_center"))
            want = 2;
        else
            return fv_err(err, err_len, "%s:%d: unknown key '%s' (k1, k2, chroma, left_center, right_center)", name,
                          lineno, key);
        rc = numbers(s, v, want);
        if (rc)
            return fv_err(err, err_len, "%s:%d: %s wants %d number%s", name, lineno, key, want, want > 1 ? "s" : "");
        if (!strcmp(key, "k1"))
            l->k1 = v[0];
        else if (!strcmp(key, "k2"))
            l->k2 = v[0];
        else if (!strcmp(key, "chroma"))
            memcpy(l->scale, v, sizeof l->scale);
        else
            memcpy(l->center[key[0] == 'r'], v, 2 * sizeof(float));
    }
    char why[200];
    if (fv_lens_validate(l, r_max, why, sizeof why))
        return fv_err(err, err_len, "%s: %s", name, why);
    return 0;
}

int fv_lens_load(fv_lens *l, const char *path, float r_max, char *err, size_t err_len)
{
    char buf[16384];
    if (fv_read_text_file(path, buf, sizeof buf, "a lens profile", err, err_len) < 0)
        return -1;
    return fv_lens_parse(l, buf, path, r_max, err, err_len);
}
