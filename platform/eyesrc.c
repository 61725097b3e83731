/* fovea platform: Y4M and image-list eye sources (see eyesrc.h). */
#include "eyesrc.h"
#include "base/clock.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>
#include <time.h>

#include <stb/stb_image.h>

#include "base/err.h"
#include "base/pngcheck.h"

/* The largest eye image read from a list (a camera frame is far smaller). */
#define FV_EYE_IMAGE_MAX_BYTES ((uint64_t)64 << 20)

typedef struct {
    char *path; /* as written */
    int line;
    int has_label;
    float x, y;
} list_entry;

struct fv_eyesrc {
    int is_list;
    /* camera */
    fv_v4l2 *cam;
    int silent_ms;
    const volatile sig_atomic_t *stop;
    long frames;
    char path[4096];
    /* y4m */
    FILE *f;
    int w, h;
    size_t frame_bytes;
    uint8_t *frame;
    /* list */
    char dir[4096];
    list_entry *e;
    long n, next;
    int labels;
    uint8_t *img;
};

static fv_eyesrc *alloc_src(const char *path)
{
    fv_eyesrc *s = calloc(1, sizeof *s);
    if (s)
        snprintf(s->path, sizeof s->path, "%s", path);
    return s;
}

/* ---------------------------------------------------------------- Y4M */

static int parse_int(const char *tok, int *v)
{
    char *end;
    errno = 0;
    long x = strtol(tok, &end, 10);
    if (end == tok || errno || x < 1 || x > 16384)
        return -1;
    *v = (int)x;
    return 0;
}

/* Reads the header from s->f (owned by s from here on). */
static int open_y4m_stream(fv_eyesrc **out, fv_eyesrc *s, char *err, size_t err_len)
{
    const char *path = s->path;
    char hdr[1024];
    size_t n = 0;
    int c;
    while ((c = fgetc(s->f)) != EOF && c != '\n' && n + 1 < sizeof hdr)
        hdr[n++] = (char)c;
    hdr[n] = '\0';
    const char *what = NULL;
    if (c == EOF && ferror(s->f))
        what = "read error (a directory?)";
    else if (strncmp(hdr, "YUV4MPEG2", 9) || (hdr[9] != ' ' && hdr[9] != '\0'))
        what = "not a YUV4MPEG2 file (no 'YUV4MPEG2 ' signature)";
    else if (c != '\n')
        what = "truncated or overlong YUV4MPEG2 header";
    const char *cs = "420jpeg";
    char csbuf[32] = "";
    s->w = s->h = 0;
    if (!what) {
        for (char *tok = strtok(hdr + 9, " "); tok && !what; tok = strtok(NULL, " ")) {
            switch (tok[0]) {
            case 'W': if (parse_int(tok + 1, &s->w)) what = "bad width (W) in the header"; break;
            case 'H': if (parse_int(tok + 1, &s->h)) what = "bad height (H) in the header"; break;
            case 'C': snprintf(csbuf, sizeof csbuf, "%s", tok + 1); cs = csbuf; break;
            default: break; /* F, I, A, X: not needed to read luma */
            }
        }
    }
    if (!what && (!s->w || !s->h))
        what = "the header lacks W or H";
    size_t luma = (size_t)s->w * s->h, cw = (size_t)(s->w + 1) / 2, ch = (size_t)(s->h + 1) / 2;
    if (!what) {
        if (!strcmp(cs, "mono"))
            s->frame_bytes = luma;
        else if (!strcmp(cs, "420") || !strcmp(cs, "420jpeg") || !strcmp(cs, "420paldv") || !strcmp(cs, "420mpeg2"))
            s->frame_bytes = luma + 2 * cw * ch; /* the 8-bit 4:2:0 sitings; not 420p10 etc. */
        else if (!strcmp(cs, "422"))
            s->frame_bytes = luma + 2 * cw * (size_t)s->h;
        else if (!strcmp(cs, "444"))
            s->frame_bytes = 3 * luma;
        else {
            fv_err(err, err_len, "%s: colour space C%s is not supported (C420*, C422, C444, Cmono, 8 bit)", path, cs);
            fv_eyesrc_close(s);
            return -1;
        }
    }
    if (what) {
        fv_err(err, err_len, "%s: %s", path, what);
        fv_eyesrc_close(s);
        return -1;
    }
    s->frame = malloc(s->frame_bytes);
    if (!s->frame) {
        fv_eyesrc_close(s);
        return fv_err(err, err_len, "out of memory");
    }
    *out = s;
    return 0;
}

int fv_eyesrc_open_y4m(fv_eyesrc **out, const char *path, char *err, size_t err_len)
{
    *out = NULL;
    fv_eyesrc *s = alloc_src(path);
    if (!s)
        return fv_err(err, err_len, "out of memory");
    s->f = fopen(path, "rb");
    if (!s->f) {
        fv_err(err, err_len, "%s: %s", path, strerror(errno));
        free(s);
        return -1;
    }
    return open_y4m_stream(out, s, err, err_len);
}

int fv_eyesrc_open_y4m_mem(fv_eyesrc **out, const void *data, size_t size, const char *name, char *err,
                           size_t err_len)
{
    *out = NULL;
    fv_eyesrc *s = alloc_src(name);
    if (!s)
        return fv_err(err, err_len, "out of memory");
    /* a read-only stream over the caller's bytes: the same stdio reads as a file (fmemopen takes a
     * non-const pointer for its write modes; "rb" never writes) */
    s->f = fmemopen((void *)(uintptr_t)data, size, "rb");
    if (!s->f) {
        fv_err(err, err_len, "%s: %s", name, strerror(errno));
        free(s);
        return -1;
    }
    return open_y4m_stream(out, s, err, err_len);
}

static int next_y4m(fv_eyesrc *s, fv_eye_frame *f, char *err, size_t err_len)
{
    char tag[256];
    size_t n = 0;
    int c;
    while ((c = fgetc(s->f)) != EOF && c != '\n' && n + 1 < sizeof tag)
        tag[n++] = (char)c;
    tag[n] = '\0';
    if (c == EOF && n == 0)
        return ferror(s->f) ? fv_err(err, err_len, "%s: read error", s->path) : 0;
    if (strncmp(tag, "FRAME", 5) || (tag[5] != ' ' && tag[5] != '\0') || c != '\n')
        return fv_err(err, err_len, "%s: frame %ld: corrupt data (no FRAME marker)", s->path, s->next);
    const size_t got = fread(s->frame, 1, s->frame_bytes, s->f);
    if (got != s->frame_bytes)
        return fv_err(err, err_len, "%s: frame %ld is truncated (%zu of %zu bytes)", s->path, s->next, got,
                      s->frame_bytes);
    f->luma = s->frame;
    f->w = s->w;
    f->h = s->h;
    f->stride = s->w;
    f->index = s->next++;
    f->name = NULL;
    f->has_label = 0;
    return 1;
}

/* ---------------------------------------------------------------- image list */

static int parse_float(const char *t, float *v)
{
    char *end;
    errno = 0;
    double d = strtod(t, &end);
    if (end == t || *end || errno || !isfinite(d))
        return -1;
    *v = (float)d;
    return 0;
}

/* Parses the list from f (closed here); entries resolve against dir. */
static int open_list_stream(fv_eyesrc **out, fv_eyesrc *s, FILE *f, const char *dir, char *err, size_t err_len)
{
    const char *path = s->path;
    s->is_list = 1;
    snprintf(s->dir, sizeof s->dir, "%s", dir);
    char line[8192];
    long cap = 0;
    int ln = 0, labelled = 0, unlabelled = 0, rc = 0;
    while (fgets(line, sizeof line, f)) {
        ln++;
        if (!strchr(line, '\n') && !feof(f)) {
            rc = fv_err(err, err_len, "%s:%d: line too long", path, ln);
            break;
        }
        char *tok[4];
        int nt = 0;
        for (char *t = strtok(line, " \t\r\n"); t; t = strtok(NULL, " \t\r\n")) {
            if (nt == 0 && t[0] == '#')
                break;
            if (nt < 4)
                tok[nt] = t;
            nt++;
        }
        if (nt == 0)
            continue;
        if (nt != 1 && nt != 3) {
            rc = fv_err(err, err_len, "%s:%d: %d fields, expected PATH [X Y]", path, ln, nt);
            break;
        }
        list_entry e = { 0 };
        e.line = ln;
        if (nt == 3) {
            if (parse_float(tok[1], &e.x) || parse_float(tok[2], &e.y)) {
                rc = fv_err(err, err_len, "%s:%d: label '%s %s' is not two numbers", path, ln, tok[1], tok[2]);
                break;
            }
            e.has_label = 1;
            labelled++;
        } else {
            unlabelled++;
        }
        e.path = strdup(tok[0]);
        if (s->n == cap) {
            cap = cap ? 2 * cap : 256;
            list_entry *ne = realloc(s->e, (size_t)cap * sizeof *ne);
            if (!ne || !e.path) {
                free(e.path);
                rc = fv_err(err, err_len, "out of memory");
                break;
            }
            s->e = ne;
        }
        s->e[s->n++] = e;
    }
    if (!rc && ferror(f))
        rc = fv_err(err, err_len, "%s: read error (a directory?)", path);
    fclose(f);
    if (!rc && s->n == 0)
        rc = fv_err(err, err_len, "%s: no images listed", path);
    if (rc) {
        fv_eyesrc_close(s);
        return -1;
    }
    s->labels = labelled > 0;
    (void)unlabelled;
    *out = s;
    return 0;
}

int fv_eyesrc_open_list(fv_eyesrc **out, const char *path, char *err, size_t err_len)
{
    *out = NULL;
    fv_eyesrc *s = alloc_src(path);
    if (!s)
        return fv_err(err, err_len, "out of memory");
    char dir[4096];
    const char *slash = strrchr(path, '/');
    if (slash)
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    else
        snprintf(dir, sizeof dir, ".");
    FILE *f = fopen(path, "r");
    if (!f) {
        fv_err(err, err_len, "%s: %s", path, strerror(errno));
        free(s);
        return -1;
    }
    return open_list_stream(out, s, f, dir, err, err_len);
}

int fv_eyesrc_open_list_mem(fv_eyesrc **out, const void *data, size_t size, const char *name, const char *dir,
                            char *err, size_t err_len)
{
    *out = NULL;
    fv_eyesrc *s = alloc_src(name);
    if (!s)
        return fv_err(err, err_len, "out of memory");
    FILE *f = fmemopen((void *)(uintptr_t)data, size, "r"); /* as in fv_eyesrc_open_y4m_mem */
    if (!f) {
        fv_err(err, err_len, "%s: %s", name, strerror(errno));
        free(s);
        return -1;
    }
    return open_list_stream(out, s, f, dir, err, err_len);
}

static int next_list(fv_eyesrc *s, fv_eye_frame *f, char *err, size_t err_len)
{
    if (s->next >= s->n)
        return 0;
    const list_entry *e = &s->e[s->next];
    char full[8192];
    if (e->path[0] == '/')
        snprintf(full, sizeof full, "%s", e->path);
    else
        snprintf(full, sizeof full, "%s/%s", s->dir, e->path);
    stbi_image_free(s->img);
    s->img = NULL;
    int w, h, comp;
    /* read whole within a size limit, and a PNG's chunk lengths checked, before stb sees the bytes
     * (stb reserves what an IDAT length claims) */
    char why[200] = "";
    FILE *t = fopen(full, "rb");
    struct stat st;
    uint8_t *bytes = NULL;
    size_t len = 0;
    if (!t)
        snprintf(why, sizeof why, "%s", strerror(errno));
    else if (fstat(fileno(t), &st) || !S_ISREG(st.st_mode))
        snprintf(why, sizeof why, "not a regular file");
    else if ((uint64_t)st.st_size > FV_EYE_IMAGE_MAX_BYTES)
        snprintf(why, sizeof why, "%lld bytes, larger than the %d MiB limit", (long long)st.st_size,
                 (int)(FV_EYE_IMAGE_MAX_BYTES >> 20));
    else if (!(bytes = malloc((size_t)st.st_size + 1)) || fread(bytes, 1, (size_t)st.st_size, t) != (size_t)st.st_size)
        snprintf(why, sizeof why, "%s", bytes ? "read error" : "out of memory");
    else
        len = (size_t)st.st_size;
    if (t)
        fclose(t);
    if (!why[0] && fv_png_is_png(bytes, len))
        (void)fv_png_check(bytes, len, 16384, (uint64_t)1 << 26, NULL, NULL, why, sizeof why); /* why set on failure */
    if (!why[0] && !(s->img = stbi_load_from_memory(bytes, (int)len, &w, &h, &comp, 1)))
        snprintf(why, sizeof why, "%s", stbi_failure_reason() ? stbi_failure_reason() : "cannot read image");
    free(bytes);
    if (!s->img)
        return fv_err(err, err_len, "%s:%d: %s: %s", s->path, e->line, e->path, why);
    f->luma = s->img;
    f->w = w;
    f->h = h;
    f->stride = w;
    f->index = s->next++;
    f->name = e->path;
    f->has_label = e->has_label;
    f->label_x = e->x;
    f->label_y = e->y;
    return 1;
}

int fv_eyesrc_open_v4l2(fv_eyesrc **out, const fv_v4l2_config *cfg, int silent_ms, const volatile sig_atomic_t *stop,
                        char *err, size_t err_len)
{
    *out = NULL;
    fv_eyesrc *s = alloc_src(cfg->path ? cfg->path : "");
    if (!s || !(s->cam = calloc(1, sizeof *s->cam))) {
        free(s);
        return fv_err(err, err_len, "out of memory");
    }
    if (fv_v4l2_open(s->cam, cfg, err, err_len)) {
        free(s->cam);
        free(s);
        return -1;
    }
    s->silent_ms = silent_ms > 0 ? silent_ms : 1;
    s->stop = stop;
    *out = s;
    return 0;
}


static int next_v4l2(fv_eyesrc *s, fv_eye_frame *f, char *err, size_t err_len)
{
    const int64_t since = fv_time_ns();
    char why[512] = "";
    while (!(s->stop && *s->stop)) {
        fv_v4l2_frame vf;
        /* short waits, so a stop request is seen within 100 ms */
        const fv_v4l2_status st = fv_v4l2_next(s->cam, 100, &vf, why, sizeof why);
        if (st == FV_V4L2_ERROR)
            return fv_err(err, err_len, "%s", why);
        if (st == FV_V4L2_FRAME) {
            memset(f, 0, sizeof *f);
            f->luma = vf.luma;
            f->w = vf.width;
            f->h = vf.height;
            f->stride = (ptrdiff_t)vf.stride;
            f->index = s->frames++;
            f->t_ns = vf.t_ns;
            return 1;
        }
        if (fv_time_ns() - since > (int64_t)s->silent_ms * 1000000) {
            if (st == FV_V4L2_GONE)
                return fv_err(err, err_len, "%s: no frame for %d ms, the device is gone (%s)", s->cam->path,
                              s->silent_ms, why);
            return fv_err(err, err_len, "%s: no frame for %d ms", s->cam->path, s->silent_ms);
        }
    }
    return 0;
}

int fv_eyesrc_next(fv_eyesrc *s, fv_eye_frame *f, char *err, size_t err_len)
{
    if (s->cam)
        return next_v4l2(s, f, err, err_len);
    return s->is_list ? next_list(s, f, err, err_len) : next_y4m(s, f, err, err_len);
}

long fv_eyesrc_count(const fv_eyesrc *s) { return s->is_list ? s->n : -1; }
int fv_eyesrc_has_labels(const fv_eyesrc *s) { return s->labels; }

void fv_eyesrc_close(fv_eyesrc *s)
{
    if (!s)
        return;
    if (s->cam) {
        fv_v4l2_close(s->cam);
        free(s->cam);
    }
    if (s->f)
        fclose(s->f);
    free(s->frame);
    for (long i = 0; i < s->n; i++)
        free(s->e[i].path);
    free(s->e);
    stbi_image_free(s->img);
    free(s);
}
