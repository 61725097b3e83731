#include "mjpeg.h"

#include <setjmp.h>
#include <stdio.h>
#include <jpeglib.h>

#include "base/err.h"

/* libjpeg reports fatal errors through error_exit (default: exit()): jump back instead. Corrupt
 * data it can limp past (a truncated frame, bad Huffman codes) only warns; a camera frame like
 * that is dropped, so warnings fail the decode too. */
typedef struct {
    struct jpeg_error_mgr pub;
    jmp_buf jump;
    char msg[JMSG_LENGTH_MAX];
} fv_jpeg_err;

static void on_error(j_common_ptr c)
{
    fv_jpeg_err *e = (fv_jpeg_err *)c->err;
    c->err->format_message(c, e->msg);
    longjmp(e->jump, 1);
}

static void on_message(j_common_ptr c, int level)
{
    fv_jpeg_err *e = (fv_jpeg_err *)c->err;
    if (level < 0 && !e->pub.num_warnings++) /* keep the first warning's text */
        c->err->format_message(c, e->msg);
}

int fv_mjpeg_to_luma8(const uint8_t *src, size_t src_len, int w, int h, uint8_t *dst, size_t dst_stride,
                      char *err, size_t err_len)
{
    if (!src_len || w <= 0 || h <= 0 || dst_stride < (size_t)w)
        return fv_err(err, err_len, "MJPEG: empty frame or bad size");
    struct jpeg_decompress_struct d;
    fv_jpeg_err e;
    d.err = jpeg_std_error(&e.pub);
    e.pub.error_exit = on_error;
    e.pub.emit_message = on_message;
    e.msg[0] = 0;
    jpeg_create_decompress(&d);
    /* volatile: read after a longjmp */
    volatile int ok = 0;
    if (setjmp(e.jump)) {
        fv_err(err, err_len, "MJPEG: %s", e.msg);
        goto done;
    }
    jpeg_mem_src(&d, src, (unsigned long)src_len);
    jpeg_read_header(&d, TRUE);
    d.out_color_space = JCS_GRAYSCALE; /* Y of YCbCr, no colour conversion */
    d.dct_method = JDCT_ISLOW;
    jpeg_start_decompress(&d);
    if ((int)d.output_width != w || (int)d.output_height != h || d.output_components != 1) {
        fv_err(err, err_len, "MJPEG: frame is %ux%u, the stream was set up for %dx%d", d.output_width,
               d.output_height, w, h);
        goto done;
    }
    while (d.output_scanline < d.output_height) {
        JSAMPROW row = dst + (size_t)d.output_scanline * dst_stride;
        jpeg_read_scanlines(&d, &row, 1);
    }
    jpeg_finish_decompress(&d);
    if (e.pub.num_warnings) {
        fv_err(err, err_len, "MJPEG: corrupt frame (%s)", e.msg);
        goto done;
    }
    ok = 1;
done:
    jpeg_destroy_decompress(&d);
    return ok ? 0 : -1;
}
