#include "output.h"
#include "base/clock.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <stb/stb_image_write.h>

#include "pipeline.h" /* fv_time_ns */
#include "base/err.h"

int fv_afile_open(fv_afile *a, const char *path, char *err, size_t err_len)
{
    memset(a, 0, sizeof *a);
    if (strlen(path) >= sizeof a->path)
        return fv_err(err, err_len, "%s: path too long", path);
    strcpy(a->path, path);
    snprintf(a->tmp, sizeof a->tmp, "%s.tmp", path);
    a->f = fopen(a->tmp, "wb");
    if (!a->f)
        return fv_err(err, err_len, "%s: %s", a->tmp, strerror(errno));
    return 0;
}

int fv_output_probe(const char *path, char *err, size_t err_len)
{
    struct stat st;
    if (!stat(path, &st) && S_ISDIR(st.st_mode))
        return fv_err(err, err_len, "%s: is a directory", path);
    fv_afile a;
    if (fv_afile_open(&a, path, err, err_len))
        return -1;
    fv_afile_abort(&a);
    return 0;
}

int fv_output_probe_dir(const char *dir, char *err, size_t err_len)
{
    if (fv_mkdirs(dir, err, err_len))
        return -1;
    char probe[4200];
    if (snprintf(probe, sizeof probe, "%s/.fovea-probe-%ld", dir, (long)getpid()) >= (int)sizeof probe)
        return fv_err(err, err_len, "%s: path too long", dir);
    FILE *f = fopen(probe, "wb");
    if (!f)
        return fv_err(err, err_len, "%s: cannot write in it (%s)", dir, strerror(errno));
    fclose(f);
    unlink(probe);
    return 0;
}

int fv_afile_commit(fv_afile *a, char *err, size_t err_len)
{
    if (!a->f)
        return fv_err(err, err_len, "%s: not open", a->path);
    int bad = ferror(a->f);
    bad |= fclose(a->f) != 0;
    a->f = NULL;
    if (bad) {
        unlink(a->tmp);
        return fv_err(err, err_len, "%s: write error (disk full?)", a->path);
    }
    if (rename(a->tmp, a->path)) {
        int e = errno;
        unlink(a->tmp);
        return fv_err(err, err_len, "%s: %s", a->path, strerror(e));
    }
    return 0;
}

void fv_afile_abort(fv_afile *a)
{
    if (a->f) {
        fclose(a->f);
        a->f = NULL;
        unlink(a->tmp);
    }
}

typedef struct {
    FILE *f;
} png_ctx;
static void png_write_cb(void *ctx, void *data, int size) { fwrite(data, 1, (size_t)size, ((png_ctx *)ctx)->f); }

int fv_write_png(const char *path, const uint8_t *rgb, int w, int h, ptrdiff_t stride, char *err, size_t err_len)
{
    fv_afile a;
    if (fv_afile_open(&a, path, err, err_len))
        return -1;
    png_ctx c = {a.f};
    if (!stbi_write_png_to_func(png_write_cb, &c, w, h, 3, rgb, (int)stride)) {
        fv_afile_abort(&a);
        return fv_err(err, err_len, "%s: PNG encoding failed", path);
    }
    return fv_afile_commit(&a, err, err_len);
}

int fv_y4m_open(fv_y4m_writer *y, const char *path, int w, int h, int fps, char *err, size_t err_len)
{
    memset(y, 0, sizeof *y);
    if (w < 2 || h < 2 || (w | h) & 1)
        return fv_err(err, err_len, "%s: Y4M 4:2:0 needs even frame sizes, got %dx%d", path, w, h);
    y->w = w;
    y->h = h;
    y->yuv = malloc((size_t)w * h * 3 / 2);
    if (!y->yuv)
        return fv_err(err, err_len, "%s: out of memory", path);
    if (fv_afile_open(&y->file, path, err, err_len)) {
        free(y->yuv);
        y->yuv = NULL;
        return -1;
    }
    fprintf(y->file.f, "YUV4MPEG2 W%d H%d F%d:1 Ip A1:1 C420jpeg XYSCSS=420JPEG\n", w, h, fps);
    return 0;
}

static inline uint8_t clamp8(int v) { return (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : v); }

int fv_y4m_write_rgb(fv_y4m_writer *y, const uint8_t *rgb, ptrdiff_t stride, char *err, size_t err_len)
{
    int w = y->w, h = y->h;
    uint8_t *Y = y->yuv, *U = Y + (size_t)w * h, *V = U + (size_t)w * h / 4;
    for (int j = 0; j < h; j++)
        for (int i = 0; i < w; i++) {
            const uint8_t *p = rgb + j * stride + 3 * i;
            Y[(size_t)j * w + i] = clamp8((77 * p[0] + 150 * p[1] + 29 * p[2] + 128) >> 8);
        }
    for (int j = 0; j < h / 2; j++)
        for (int i = 0; i < w / 2; i++) {
            int r = 0, g = 0, b = 0;
            for (int k = 0; k < 4; k++) {
                const uint8_t *p = rgb + (2 * j + (k >> 1)) * stride + 3 * (2 * i + (k & 1));
                r += p[0];
                g += p[1];
                b += p[2];
            }
            U[(size_t)j * (w / 2) + i] = clamp8(((-43 * r - 85 * g + 128 * b + 512) >> 10) + 128);
            V[(size_t)j * (w / 2) + i] = clamp8(((128 * r - 107 * g - 21 * b + 512) >> 10) + 128);
        }
    fputs("FRAME\n", y->file.f);
    if (fwrite(y->yuv, 1, (size_t)w * h * 3 / 2, y->file.f) != (size_t)w * h * 3 / 2)
        return fv_err(err, err_len, "%s: write error", y->file.path);
    return 0;
}

int fv_y4m_close(fv_y4m_writer *y, char *err, size_t err_len)
{
    free(y->yuv);
    y->yuv = NULL;
    return fv_afile_commit(&y->file, err, err_len);
}

void fv_y4m_abort(fv_y4m_writer *y)
{
    free(y->yuv);
    y->yuv = NULL;
    fv_afile_abort(&y->file);
}

void fv_progress_begin(fv_progress *p, const char *what, long total)
{
    memset(p, 0, sizeof *p);
    p->what = what;
    p->total = total;
    p->start_ns = p->last_ns = fv_time_ns();
    p->tty = isatty(STDERR_FILENO);
}

void fv_progress_update(fv_progress *p, long done)
{
    int64_t now = fv_time_ns();
    if (now - p->start_ns < 2000000000 || now - p->last_ns < (p->tty ? 500000000 : 2000000000))
        return;
    p->last_ns = now;
    p->shown = 1;
    double el = (double)(now - p->start_ns) * 1e-9;
    double eta = done > 0 ? el * (double)(p->total - done) / (double)done : 0.0;
    fprintf(stderr, "%s%s %ld/%ld (%d%%), %.0f s elapsed, about %.0f s left%s", p->tty ? "\r" : "", p->what, done,
            p->total, (int)(100 * done / (p->total ? p->total : 1)), el, eta, p->tty ? "   " : "\n");
    fflush(stderr);
}

void fv_progress_end(fv_progress *p)
{
    if (p->shown && p->tty)
        fputc('\n', stderr);
}

int fv_mkdirs(const char *path, char *err, size_t err_len)
{
    char buf[4096];
    if (strlen(path) >= sizeof buf)
        return fv_err(err, err_len, "%s: path too long", path);
    strcpy(buf, path);
    for (char *s = buf + 1;; s++) {
        if (*s == '/' || *s == '\0') {
            char c = *s;
            *s = '\0';
            if (mkdir(buf, 0777) && errno != EEXIST)
                return fv_err(err, err_len, "%s: %s", buf, strerror(errno));
            *s = c;
            if (!c)
                break;
        }
    }
    struct stat st;
    if (stat(path, &st) || !S_ISDIR(st.st_mode))
        return fv_err(err, err_len, "%s: not a directory", path);
    return 0;
}

long fv_read_text_file(const char *path, char *buf, size_t cap, const char *kind, char *err, size_t err_len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return fv_err(err, err_len, "%s: %s", path, strerror(errno));
    const size_t n = fread(buf, 1, cap - 1, f);
    const int bad = ferror(f), more = !feof(f) && fgetc(f) != EOF;
    fclose(f);
    if (bad)
        return fv_err(err, err_len, "%s: read error (a directory?)", path);
    if (more)
        return fv_err(err, err_len, "%s: too large for %s", path, kind);
    buf[n] = '\0';
    if (memchr(buf, '\0', n))
        return fv_err(err, err_len, "%s: not a text file", path);
    return (long)n;
}

char *fv_read_file_alloc(const char *path, size_t max_bytes, size_t *len_out, char *err, size_t err_len)
{
    *len_out = 0;
    FILE *f = fopen(path, "rb");
    if (!f) {
        fv_err(err, err_len, "%s: %s", path, strerror(errno));
        return NULL;
    }
    /* A regular file is judged by its size before anything is read or reserved; pipes and devices
     * (no size) are read in growing steps that stop at the limit, or at the first NUL byte: a text
     * format ends there, so /dev/zero costs one 64 KiB step, not a gigabyte. */
    struct stat st;
    if (fstat(fileno(f), &st)) {
        fv_err(err, err_len, "%s: %s", path, strerror(errno));
        fclose(f);
        return NULL;
    }
    if (S_ISDIR(st.st_mode)) {
        fv_err(err, err_len, "%s: is a directory", path);
        fclose(f);
        return NULL;
    }
    if (S_ISREG(st.st_mode) && (uint64_t)st.st_size > max_bytes) {
        fv_err(err, err_len, "%s: %lld bytes, larger than the %zu MiB limit", path, (long long)st.st_size,
               max_bytes >> 20);
        fclose(f);
        return NULL;
    }
    size_t cap = S_ISREG(st.st_mode) ? (size_t)st.st_size + 1 : (size_t)1 << 16, len = 0;
    cap = cap < max_bytes + 1 ? cap : max_bytes + 1;
    char *buf = malloc(cap);
    for (;;) {
        if (!buf) {
            fclose(f);
            fv_err(err, err_len, "%s: out of memory", path);
            return NULL;
        }
        const size_t got = fread(buf + len, 1, cap - len, f);
        if (memchr(buf + len, '\0', got)) {
            free(buf);
            fclose(f);
            fv_err(err, err_len, "%s: not a text file (NUL byte)", path);
            return NULL;
        }
        len += got;
        if (len < cap)
            break;
        if (len > max_bytes) {
            free(buf);
            fclose(f);
            fv_err(err, err_len, "%s: larger than the %zu MiB limit", path, max_bytes >> 20);
            return NULL;
        }
        const size_t ncap = cap > max_bytes / 2 ? max_bytes + 1 : 2 * cap;
        char *nb = realloc(buf, ncap);
        if (!nb)
            free(buf);
        buf = nb;
        cap = ncap;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) {
        free(buf);
        fv_err(err, err_len, "%s: read error", path);
        return NULL;
    }
    *len_out = len;
    return buf;
}
