/* fovea fuzz targets (targets.h): the parsers of every file and buffer the programs accept. */
#include "targets.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/pngcheck.h"
#include "eyesrc.h"
#include "eyetrack/calib.h"
#include "gltf_shim.h"
#include "image.h"
#include "lens.h"
#include "mjpeg.h"
#include "pixfmt.h"
#include "trace.h"

const fv_fuzz_target fv_fuzz_targets[] = {
    {"gltf", fv_fuzz_gltf, 1 << 20},   {"trace", fv_fuzz_trace, 1 << 16}, {"lens", fv_fuzz_lens, 1 << 12},
    {"calib", fv_fuzz_calib, 1 << 12}, {"y4m", fv_fuzz_y4m, 1 << 18},     {"imagelist", fv_fuzz_imagelist, 1 << 12},
    {"pixfmt", fv_fuzz_pixfmt, 1 << 16}, {"png", fv_fuzz_png, 1 << 18},
};
const int fv_fuzz_target_count = (int)(sizeof fv_fuzz_targets / sizeof fv_fuzz_targets[0]);

static char paths[4][64];
static int used;

static void remove_tmpfiles(void)
{
    for (int k = 0; k < used; k++)
        unlink(paths[k]);
}

const char *fv_fuzz_tmpfile(const uint8_t *data, size_t size, const char *suffix)
{
    /* per process and suffix, in /tmp, removed at exit */
    int k = 0;
    for (; k < used; k++)
        if (strstr(paths[k], suffix))
            break;
    if (k == used) {
        if (used == 4)
            abort();
        snprintf(paths[k], sizeof paths[k], "/tmp/fovea-fuzz-%ld-%d%s", (long)getpid(), k, suffix);
        if (used++ == 0)
            atexit(remove_tmpfiles);
    }
    /* a new file each time: rewriting one in place (O_TRUNC) makes ext4 flush it at close */
    unlink(paths[k]);
    FILE *f = fopen(paths[k], "wb");
    if (!f || (size && fwrite(data, 1, size, f) != size) || fclose(f))
        abort(); /* the harness's own failure, not the parser's */
    return paths[k];
}

int fv_fuzz_gltf(const uint8_t *data, size_t size)
{
    /* the scene's folder is /tmp: external URIs are resolved and confined as for a real scene */
    char err[512];
    fv_gltf_model *m = fv_gltf_load(fv_fuzz_tmpfile(data, size, ".gltf"), NULL, err, sizeof err);
    if (m) { /* walk what the loader promises is valid */
        volatile float sink = 0;
        for (size_t i = 0; i < m->mesh_count; i++)
            for (size_t p = 0; p < m->meshes[i].prim_count; p++) {
                const fv_gltf_prim *pr = &m->meshes[i].prims[p];
                const size_t n = pr->indices ? pr->index_count : pr->vertex_count;
                for (size_t k = 0; k < n; k++) {
                    const size_t v = pr->indices ? pr->indices[k] : k;
                    sink += pr->positions[3 * v];
                }
            }
        for (size_t i = 0; i < m->image_count; i++)
            if (m->images[i].rgba8)
                sink += m->images[i].rgba8[(size_t)m->images[i].width * m->images[i].height * 4 - 1];
        (void)sink;
        fv_gltf_free(m);
    }
    return m != NULL;
}

int fv_fuzz_trace(const uint8_t *data, size_t size)
{
    fv_trace t;
    char err[512];
    const int ok = !fv_trace_parse(&t, (const char *)data, size, "fuzz.csv", err, sizeof err);
    if (ok) {
        fv_trace_sample s;
        const double t0 = t.s[0].t_ms, t1 = t.s[t.n - 1].t_ms;
        for (int i = 0; i <= 8; i++)
            fv_trace_at(&t, t0 + (t1 - t0) * i / 8.0, &s);
        (void)fv_trace_loop_ms(&t, 12345.0);
        fv_trace_free(&t);
    }
    return ok;
}

int fv_fuzz_lens(const uint8_t *data, size_t size)
{
    fv_lens l;
    char err[512];
    const int ok = !fv_lens_parse(&l, (const char *)data, size, "fuzz.lens", 1.5f, err, sizeof err);
    if (ok) {
        fv_lens_lca lca;
        fv_lens_lca_init(&lca, l.k1, l.k2, l.scale, 1.5f);
        float tx, ty;
        (void)fv_lens_undistort(l.k1, l.k2, l.scale[1], 0.0f, 0.0f, 0.7f, -0.4f, &tx, &ty);
    }
    return ok;
}

int fv_fuzz_calib(const uint8_t *data, size_t size)
{
    char *text = malloc(size + 1); /* the parser takes a C string */
    if (!text)
        return 0;
    memcpy(text, data, size);
    text[size] = '\0';
    fv_calib c;
    char err[512];
    const int ok = !fv_calib_parse(&c, text, err, sizeof err);
    if (ok) {
        float yaw, pitch;
        fv_calib_apply(&c, 0.3f, -0.2f, &yaw, &pitch);
        char buf[1024];
        (void)fv_calib_format(&c, buf, sizeof buf);
    }
    free(text);
    return ok;
}

static void drain(fv_eyesrc *s, int frames)
{
    fv_eye_frame f;
    char err[512];
    for (int i = 0; i < frames; i++) {
        if (fv_eyesrc_next(s, &f, err, sizeof err) != 1) /* 1: a frame; 0: the end; -1: an error */
            break;
        volatile uint8_t sink = f.luma[(size_t)(f.h - 1) * (size_t)f.stride + (size_t)f.w - 1];
        (void)sink;
    }
    fv_eyesrc_close(s);
}

int fv_fuzz_y4m(const uint8_t *data, size_t size)
{
    fv_eyesrc *s;
    char err[512];
    /* the parser on the bytes in memory (fmemopen): the same stdio reads as a file, ~10x the
     * executions per second of a temp file per input (docs/robustness.md) */
    const int ok = !fv_eyesrc_open_y4m_mem(&s, data, size, "fuzz.y4m", err, sizeof err);
    if (ok)
        drain(s, 4);
    return ok;
}

int fv_fuzz_imagelist(const uint8_t *data, size_t size)
{
    fv_eyesrc *s;
    char err[512];
    /* relative entries resolve against a folder of two tiny images (the seed list names them), so
     * the decoding after a good line runs too, and nothing else in a shared /tmp is read */
    const int ok = !fv_eyesrc_open_list_mem(&s, data, size, "fuzz.txt", "tests/fuzz/imagelist-dir", err, sizeof err);
    if (ok)
        drain(s, 4);
    return ok;
}

/* Byte 0: format; 1, 2: width and height (1..64); 3: row padding (0..7 bytes); the rest: the
 * camera's buffer. */
int fv_fuzz_pixfmt(const uint8_t *data, size_t size)
{
    static const uint32_t fmt[] = {FV_PIX_GREY, FV_PIX_Y10, FV_PIX_Y12, FV_PIX_Y16, FV_PIX_YUYV, FV_PIX_UYVY, FV_PIX_MJPEG};
    if (size < 4)
        return 0;
    const uint32_t fourcc = fmt[data[0] % 7];
    const int w = 1 + data[1] % 64, h = 1 + data[2] % 64;
    const size_t pad = data[3] % 8;
    data += 4, size -= 4;
    uint8_t dst[64 * 64];
    char err[256];
    if (fourcc == FV_PIX_MJPEG)
        return !fv_mjpeg_to_luma8(data, size, w, h, dst, 64, err, sizeof err);
    return !fv_pix_to_luma8(fourcc, data, size, fv_pix_min_stride(fourcc, w) + pad, w, h, dst, 64);
}

int fv_fuzz_png(const uint8_t *data, size_t size)
{
    char err[512];
    int w, h;
    uint8_t *px = fv_decode_png(data, size, &w, &h, err, sizeof err);
    if (px) {
        volatile uint8_t sink = px[(size_t)w * (size_t)h * 3 - 1];
        (void)sink;
        free(px);
    }
    return px != NULL;
}
