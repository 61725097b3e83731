#include "proftrace.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "output.h"
#include "pipeline.h"

static int by_track_time(const void *a, const void *b)
{
    const fv_prof_event *x = *(const fv_prof_event *const *)a, *y = *(const fv_prof_event *const *)b;
    if (x->track != y->track)
        return (x->track > y->track) - (x->track < y->track);
    if (x->t0_ns != y->t0_ns)
        return (x->t0_ns > y->t0_ns) - (x->t0_ns < y->t0_ns);
    return (x->t1_ns < y->t1_ns) - (x->t1_ns > y->t1_ns); /* the longer (outer) span first */
}

static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++)
        if (*s == '"' || *s == '\\')
            fprintf(f, "\\%c", *s);
        else if ((unsigned char)*s < 0x20)
            fprintf(f, "\\u%04x", *s);
        else
            fputc(*s, f);
    fputc('"', f);
}

static void track_name(char *buf, size_t len, int track)
{
    if (track >= FV_PROF_TRACK_MARKERS)
        snprintf(buf, len, "markers");
    else if (track >= FV_PROF_TRACK_STAGE && track < FV_PROF_TRACK_STAGE + FV_PROF_STAGES)
        snprintf(buf, len, "stage %s", fv_prof_stage_name(track - FV_PROF_TRACK_STAGE));
    else if (track >= FV_PROF_TRACK_STAGE)
        snprintf(buf, len, "stage %d", track - FV_PROF_TRACK_STAGE);
    else
        snprintf(buf, len, track == 0 ? "worker 0 (main)" : "worker %d", track);
}

static void event(FILE *f, int *first, char ph, const fv_prof_event *e, int64_t t_ns, int64_t base)
{
    fprintf(f, "%s\n{\"ph\":\"%c\",\"pid\":1,\"tid\":%d,\"ts\":%.3f", *first ? "" : ",", ph, (int)e->track,
            (double)(t_ns - base) * 1e-3);
    *first = 0;
    if (ph != 'E') {
        fputs(",\"name\":", f);
        json_str(f, e->name ? e->name : "?");
        fputs(",\"cat\":\"fovea\"", f);
        if (ph == 'i')
            fputs(",\"s\":\"t\"", f);
        if (e->arg >= 0)
            fprintf(f, ",\"args\":{\"arg\":%d}", (int)e->arg);
    }
    fputc('}', f);
}

int fv_prof_write_json(const fv_prof *p, const char *path, const char *label, char *err, size_t err_len)
{
    size_t n = 0;
    const int slots = fv_prof_slots(p);
    for (int s = 0; s < slots; s++)
        n += fv_prof_count(p, s);
    const fv_prof_event **ev = malloc((n ? n : 1) * sizeof *ev);
    const fv_prof_event **stack = malloc((n ? n : 1) * sizeof *stack);
    if (!ev || !stack) {
        free(ev);
        free(stack);
        snprintf(err, err_len, "out of memory for %zu trace events", n);
        return -1;
    }
    size_t k = 0, dropped = 0;
    int64_t base = INT64_MAX;
    for (int s = 0; s < slots; s++) {
        dropped += fv_prof_dropped(p, s);
        for (size_t i = 0; i < fv_prof_count(p, s); i++) {
            ev[k] = fv_prof_event_at(p, s, i);
            if (ev[k]->t0_ns < base)
                base = ev[k]->t0_ns;
            k++;
        }
    }
    if (base == INT64_MAX)
        base = 0;
    qsort(ev, n, sizeof *ev, by_track_time);
    fv_afile a;
    if (fv_afile_open(&a, path, err, err_len)) {
        free(ev);
        free(stack);
        return -1;
    }
    FILE *f = a.f;
    fputs("{\"displayTimeUnit\":\"ms\",\"otherData\":{\"producer\":\"fovea\",\"dropped_events\":", f);
    fprintf(f, "%zu,\"threads\":%d},\n\"traceEvents\":[", dropped, slots);
    int first = 1;
    fputs("\n{\"ph\":\"M\",\"pid\":1,\"tid\":0,\"name\":\"process_name\",\"args\":{\"name\":", f);
    json_str(f, label ? label : "fovea");
    fputs("}}", f);
    first = 0;
    /* every worker gets a track even if it recorded nothing */
    char name[64];
    for (int t = 0; t < slots; t++) {
        track_name(name, sizeof name, t);
        fprintf(f, ",\n{\"ph\":\"M\",\"pid\":1,\"tid\":%d,\"name\":\"thread_name\",\"args\":{\"name\":\"%s\"}}", t,
                name);
        fprintf(f, ",\n{\"ph\":\"M\",\"pid\":1,\"tid\":%d,\"name\":\"thread_sort_index\",\"args\":{\"sort_index\":%d}}",
                t, 100 + t);
    }
    for (size_t i = 0; i < n; i++) {
        const int t = ev[i]->track;
        if (t < slots || (i > 0 && ev[i - 1]->track == t))
            continue;
        track_name(name, sizeof name, t);
        fprintf(f, ",\n{\"ph\":\"M\",\"pid\":1,\"tid\":%d,\"name\":\"thread_name\",\"args\":{\"name\":\"%s\"}}", t,
                name);
        fprintf(f, ",\n{\"ph\":\"M\",\"pid\":1,\"tid\":%d,\"name\":\"thread_sort_index\",\"args\":{\"sort_index\":%d}}",
                t, t >= FV_PROF_TRACK_MARKERS ? 0 : t - FV_PROF_TRACK_STAGE + 1);
    }
    /* per track: spans sorted by start (outer first), emitted through a stack so that every "E"
     * closes the innermost open "B" (a span reaching past its parent is cut at the parent's end) */
    size_t sp = 0;
    int64_t ends[256];
    for (size_t i = 0; i <= n; i++) {
        const fv_prof_event *e = i < n ? ev[i] : NULL;
        while (sp > 0 && (!e || e->track != stack[sp - 1]->track || ends[sp - 1] <= e->t0_ns)) {
            sp--;
            event(f, &first, 'E', stack[sp], ends[sp], base);
        }
        if (!e)
            break;
        if (e->kind == 'i') {
            event(f, &first, 'i', e, e->t0_ns, base);
            continue;
        }
        if (sp == sizeof ends / sizeof *ends)
            continue; /* absurdly deep: drop */
        int64_t end = e->t1_ns;
        if (sp > 0 && end > ends[sp - 1])
            end = ends[sp - 1];
        event(f, &first, 'B', e, e->t0_ns, base);
        stack[sp] = e;
        ends[sp++] = end;
    }
    fputs("\n]}\n", f);
    free(ev);
    free(stack);
    return fv_afile_commit(&a, err, err_len);
}
