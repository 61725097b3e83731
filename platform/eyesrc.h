/* fovea platform: eye-image sources for the tracker. A YUV4MPEG2 video (C420* / C422 / C444 /
 * Cmono, 8 bit; only the luma plane is used) or an image list (lines `PATH [X Y]`, PATH relative
 * to the list's folder, `#` comments and blank lines skipped; X Y an optional pupil label).
 * Errors are one line naming the file (and line or frame) and the problem. */
#ifndef FOVEA_EYESRC_H
#define FOVEA_EYESRC_H

#include <signal.h>
#include <stddef.h>
#include <stdint.h>

#include "v4l2.h"

typedef struct fv_eyesrc fv_eyesrc;

typedef struct fv_eye_frame {
    const uint8_t *luma; /* valid until the next call */
    int w, h;
    ptrdiff_t stride;
    long index;          /* 0-based frame / list entry */
    const char *name;    /* list: the PATH as written in the list; video: NULL */
    int has_label;
    float label_x, label_y;
    int64_t t_ns;        /* camera: capture time (CLOCK_MONOTONIC); files: 0 */
} fv_eye_frame;

/* 0 on success; -1 with a reason in err (missing file, not YUV4MPEG2, bad header, unsupported
 * colour space; for lists: a malformed line, no entries). The whole list is parsed here. */
int fv_eyesrc_open_y4m(fv_eyesrc **s, const char *path, char *err, size_t err_len);
int fv_eyesrc_open_list(fv_eyesrc **s, const char *path, char *err, size_t err_len);
/* The same parsers on bytes in memory (the fuzz harnesses; a video or list already read): name
 * stands for the path in errors; a list's entries resolve against dir. The bytes are read through
 * a stdio stream (fmemopen) exactly as a file's are, and must stay valid until close (a video's
 * frames are read as they are asked for). */
int fv_eyesrc_open_y4m_mem(fv_eyesrc **s, const void *data, size_t size, const char *name, char *err,
                           size_t err_len);
int fv_eyesrc_open_list_mem(fv_eyesrc **s, const void *data, size_t size, const char *name, const char *dir,
                            char *err, size_t err_len);
/* A live V4L2 camera (platform/v4l2.h; cfg as there). Frames come as they are captured; a
 * camera that vanishes is reopened with back-off (fv_v4l2_next), and next() fails only when no
 * frame has come for silent_ms. It ends (returns 0) once *stop is non-zero (a signal handler's
 * flag; may be NULL). The whole struct is copied. */
int fv_eyesrc_open_v4l2(fv_eyesrc **s, const fv_v4l2_config *cfg, int silent_ms, const volatile sig_atomic_t *stop,
                        char *err, size_t err_len);
/* 1: a frame in *f; 0: end of input; -1: error in err (truncated frame, bad FRAME marker,
 * unreadable image). */
int fv_eyesrc_next(fv_eyesrc *s, fv_eye_frame *f, char *err, size_t err_len);
long fv_eyesrc_count(const fv_eyesrc *s); /* list entries; -1 for a video */
int fv_eyesrc_has_labels(const fv_eyesrc *s);
void fv_eyesrc_close(fv_eyesrc *s);

#endif
