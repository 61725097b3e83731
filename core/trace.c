#include "trace.h"
#include "base/err.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void fv_trace_free(fv_trace *tr)
{
    free(tr->s);
    memset(tr, 0, sizeof *tr);
}

static const char *const head_cols[] = {"head_px", "head_py", "head_pz", "head_qx", "head_qy", "head_qz", "head_qw"};

/* Splits one line (no newline) into comma-separated fields, trimming blanks. */
static int split(char *line, char **f, int max)
{
    int n = 0;
    char *p = line;
    for (;;) {
        while (*p == ' ' || *p == '\t')
            p++;
        if (n == max)
            return max + 1;
        f[n++] = p;
        char *c = strchr(p, ',');
        char *end = c ? c : p + strlen(p);
        char *e = end;
        while (e > p && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\r'))
            e--;
        *e = '\0';
        if (!c)
            return n;
        p = c + 1;
    }
}

int fv_trace_parse(fv_trace *tr, const char *text, size_t len, const char *name, char *err, size_t err_len)
{
    memset(tr, 0, sizeof *tr);
    char *buf = malloc(len + 1);
    if (!buf)
        return fv_err(err, err_len, "%s: out of memory", name);
    memcpy(buf, text, len);
    buf[len] = '\0';
    if (memchr(text, '\0', len)) {
        free(buf);
        return fv_err(err, err_len, "%s: not a text file (NUL byte)", name);
    }
    int cap = 0, lineno = 0, header = 0, ncols = 0, rc = -1;
    char *save = NULL;
    for (char *line = buf; line; line = save) {
        save = strchr(line, '\n');
        if (save)
            *save++ = '\0';
        lineno++;
        char *p = line;
        while (*p == ' ' || *p == '\t' || *p == '\r')
            p++;
        if (*p == '\0' || *p == '#')
            continue;
        char *f[12];
        int nf = split(p, f, 11);
        if (!header) {
            if (nf < 3 || strcmp(f[0], "t_ms") || strcmp(f[1], "gaze_x") || strcmp(f[2], "gaze_y")) {
                fv_err(err, err_len, "%s:%d: header must start with t_ms,gaze_x,gaze_y", name, lineno);
                goto out;
            }
            if (nf != 3 && nf != 10) {
                fv_err(err, err_len, "%s:%d: header has %d columns; expected 3, or 10 with head pose", name, lineno, nf);
                goto out;
            }
            for (int i = 3; i < nf; i++)
                if (strcmp(f[i], head_cols[i - 3])) {
                    fv_err(err, err_len, "%s:%d: column %d is '%s', expected '%s'", name, lineno, i + 1, f[i], head_cols[i - 3]);
                    goto out;
                }
            header = 1;
            ncols = nf;
            tr->has_head = nf == 10;
            continue;
        }
        if (nf != ncols) {
            fv_err(err, err_len, "%s:%d: %d fields, expected %d (truncated or malformed line)", name, lineno, nf > 11 ? 11 : nf, ncols);
            goto out;
        }
        double v[10];
        for (int i = 0; i < nf; i++) {
            char *end;
            errno = 0;
            v[i] = strtod(f[i], &end);
            if (end == f[i] || *end || errno == ERANGE || !isfinite(v[i])) {
                fv_err(err, err_len, "%s:%d: field %d ('%s') is not a finite number", name, lineno, i + 1, f[i]);
                goto out;
            }
        }
        /* Values are checked at the type and range they are used in, not only as finite doubles:
         * t_ms becomes integer nanoseconds (int64 up to 9.2e18), the head position a float in metres
         * that Embree asserts finite in every ray (1e30 m squared is infinite). */
        if (fabs(v[0]) > FV_TRACE_MAX_T_MS) {
            fv_err(err, err_len, "%s:%d: t_ms %g out of range (|t_ms| <= %g)", name, lineno, v[0], FV_TRACE_MAX_T_MS);
            goto out;
        }
        for (int i = 3; i < 6 && i < nf; i++)
            if (fabs(v[i]) > FV_TRACE_MAX_POS_M) {
                fv_err(err, err_len, "%s:%d: head position %s = %g m out of range (|p| <= %g m)", name, lineno,
                       head_cols[i - 3], v[i], FV_TRACE_MAX_POS_M);
                goto out;
            }
        if (tr->n && v[0] < tr->s[tr->n - 1].t_ms) {
            fv_err(err, err_len, "%s:%d: t_ms goes backwards (%g after %g)", name, lineno, v[0], tr->s[tr->n - 1].t_ms);
            goto out;
        }
        /* Off-image gaze is legal (the eye can look past the panel edge) but not absurd values. */
        if (v[1] < -1.0 || v[1] > 2.0 || v[2] < -1.0 || v[2] > 2.0) {
            fv_err(err, err_len, "%s:%d: gaze (%g, %g) is far outside the normalised image [0,1]", name, lineno, v[1], v[2]);
            goto out;
        }
        if (tr->n == cap) {
            cap = cap ? 2 * cap : 256;
            fv_trace_sample *ns = realloc(tr->s, (size_t)cap * sizeof *ns);
            if (!ns) {
                fv_err(err, err_len, "%s: out of memory", name);
                goto out;
            }
            tr->s = ns;
        }
        fv_trace_sample *s = &tr->s[tr->n++];
        memset(s, 0, sizeof *s);
        s->t_ms = v[0];
        s->gaze_x = (float)v[1];
        s->gaze_y = (float)v[2];
        s->head.quat[3] = 1.0f;
        if (tr->has_head) {
            for (int i = 0; i < 3; i++)
                s->head.pos[i] = (float)v[3 + i];
            double qn = sqrt(v[6] * v[6] + v[7] * v[7] + v[8] * v[8] + v[9] * v[9]);
            if (qn < 0.5 || qn > 2.0) {
                fv_err(err, err_len, "%s:%d: head quaternion has length %g, expected about 1", name, lineno, qn);
                goto out;
            }
            for (int i = 0; i < 4; i++)
                s->head.quat[i] = (float)(v[6 + i] / qn);
        }
    }
    if (!header) {
        fv_err(err, err_len, "%s: no header line (t_ms,gaze_x,gaze_y)", name);
        goto out;
    }
    if (tr->n == 0) {
        fv_err(err, err_len, "%s: no samples after the header", name);
        goto out;
    }
    rc = 0;
out:
    free(buf);
    if (rc)
        fv_trace_free(tr);
    return rc;
}

void fv_trace_at(const fv_trace *tr, double t_ms, fv_trace_sample *out)
{
    if (tr->n == 0) {
        memset(out, 0, sizeof *out);
        out->gaze_x = out->gaze_y = 0.5f;
        out->head.quat[3] = 1.0f;
        return;
    }
    if (t_ms <= tr->s[0].t_ms) {
        *out = tr->s[0];
        return;
    }
    if (t_ms >= tr->s[tr->n - 1].t_ms) {
        *out = tr->s[tr->n - 1];
        return;
    }
    int lo = 0, hi = tr->n - 1; /* s[lo].t <= t < s[hi].t */
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (tr->s[mid].t_ms <= t_ms)
            lo = mid;
        else
            hi = mid;
    }
    const fv_trace_sample *a = &tr->s[lo], *b = &tr->s[hi];
    double span = b->t_ms - a->t_ms;
    float u = span > 0.0 ? (float)((t_ms - a->t_ms) / span) : 0.0f;
    out->t_ms = t_ms;
    out->gaze_x = a->gaze_x + u * (b->gaze_x - a->gaze_x);
    out->gaze_y = a->gaze_y + u * (b->gaze_y - a->gaze_y);
    for (int i = 0; i < 3; i++)
        out->head.pos[i] = a->head.pos[i] + u * (b->head.pos[i] - a->head.pos[i]);
    fv_quat_slerp(a->head.quat, b->head.quat, u, out->head.quat);
}

double fv_trace_loop_ms(const fv_trace *tr, double elapsed_ms)
{
    const double span = tr->s[tr->n - 1].t_ms - tr->s[0].t_ms;
    return tr->s[0].t_ms + (span > 0 ? fmod(elapsed_ms, span) : 0.0);
}
