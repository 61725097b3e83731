/* fovea platform: file sinks (PNG, Y4M), CSV files written atomically, and progress on stderr.
 * Every file is written under a temporary name and renamed when complete, so an interrupted or
 * failed run never leaves a file that looks finished. */
#ifndef FOVEA_OUTPUT_H
#define FOVEA_OUTPUT_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

/* 8-bit RGB, rows of stride bytes. 0 on success, -1 with a reason in err. */
int fv_write_png(const char *path, const uint8_t *rgb, int w, int h, ptrdiff_t stride, char *err, size_t err_len);

/* A file written as PATH.tmp and renamed to PATH by fv_afile_commit (or removed by _abort). */
typedef struct fv_afile {
    FILE *f;
    char path[4096], tmp[4096 + 8];
} fv_afile;
int fv_afile_open(fv_afile *a, const char *path, char *err, size_t err_len);
int fv_afile_commit(fv_afile *a, char *err, size_t err_len);
void fv_afile_abort(fv_afile *a);
/* Start-up check of an output path the run will write at its end (or as it goes): PATH.tmp can be
 * created (and is removed again) and PATH is not a directory, so an unwritable output is bad usage
 * found before any work, not after a long run. 0, or -1 with the reason naming the path. */
int fv_output_probe(const char *path, char *err, size_t err_len);
/* The same for an output folder: made if missing (mkdir -p) and a file can be created in it. */
int fv_output_probe_dir(const char *dir, char *err, size_t err_len);

/* YUV4MPEG2 4:2:0 (C420jpeg, full-range BT.601) from RGB frames. */
typedef struct fv_y4m_writer {
    fv_afile file;
    int w, h;
    uint8_t *yuv;
} fv_y4m_writer;
int fv_y4m_open(fv_y4m_writer *y, const char *path, int w, int h, int fps, char *err, size_t err_len);
int fv_y4m_write_rgb(fv_y4m_writer *y, const uint8_t *rgb, ptrdiff_t stride, char *err, size_t err_len);
int fv_y4m_close(fv_y4m_writer *y, char *err, size_t err_len); /* commits */
void fv_y4m_abort(fv_y4m_writer *y);

/* Progress for long runs: silent for the first 2 s, then a line at most every 0.5 s
 * (carriage-return updates on a terminal, plain lines every 2 s otherwise). */
typedef struct fv_progress {
    const char *what;
    long total;
    int64_t start_ns, last_ns;
    int tty, shown;
} fv_progress;
void fv_progress_begin(fv_progress *p, const char *what, long total);
void fv_progress_update(fv_progress *p, long done);
void fv_progress_end(fv_progress *p);

/* Reads a small text file whole into buf (cap bytes, NUL-terminated): its length, or -1 with a
 * reason naming the file in err (cannot open, read error, over cap - 1 bytes: "too large for
 * <kind>", a NUL byte: "not a text file"). */
long fv_read_text_file(const char *path, char *buf, size_t cap, const char *kind, char *err, size_t err_len);
/* Reads a text file of up to max_bytes whole into a malloc'd buffer (the caller frees it), for
 * inputs with no small size bound (traces): the buffer, with *len bytes and no terminator; or
 * NULL with a reason naming the file in err (cannot open, a directory, "larger than the N MiB
 * limit" (a regular file's size is checked before reading), "not a text file (NUL byte)", "out of
 * memory", "read error"). Never reserves more than max_bytes + 1. */
char *fv_read_file_alloc(const char *path, size_t max_bytes, size_t *len, char *err, size_t err_len);

/* mkdir -p; 0 on success. */
int fv_mkdirs(const char *path, char *err, size_t err_len);

#endif
