#include "pixfmt.h"

#include <ctype.h>
#include <string.h>

int fv_pix_supported(uint32_t fourcc)
{
    switch (fourcc) {
    case FV_PIX_GREY: case FV_PIX_Y10: case FV_PIX_Y12: case FV_PIX_Y16: case FV_PIX_YUYV: case FV_PIX_UYVY:
        return 1;
    default:
        return 0;
    }
}

size_t fv_pix_min_stride(uint32_t fourcc, int w)
{
    if (w <= 0)
        return 0;
    size_t n = (size_t)w;
    switch (fourcc) {
    case FV_PIX_GREY: return n;
    case FV_PIX_Y10: case FV_PIX_Y12: case FV_PIX_Y16: return 2 * n;
    case FV_PIX_YUYV: case FV_PIX_UYVY: return 4 * ((n + 1) / 2);
    default: return 0;
    }
}

size_t fv_pix_min_size(uint32_t fourcc, int w, int h, size_t src_stride)
{
    size_t row = fv_pix_min_stride(fourcc, w);
    if (!row || h <= 0 || src_stride < row)
        return 0;
    size_t rows = (size_t)h - 1;
    if (rows && src_stride > (SIZE_MAX - row) / rows)
        return 0;
    return rows * src_stride + row;
}

/* 16-bit little-endian words to 8 bits: v >> shift, saturated (bits above the format's range). */
static void words_to_luma(const uint8_t *s, uint8_t *d, int w, unsigned shift)
{
    for (int x = 0; x < w; x++) {
        unsigned v = ((unsigned)s[2 * x] | (unsigned)s[2 * x + 1] << 8) >> shift;
        d[x] = (uint8_t)(v > 255 ? 255 : v);
    }
}

int fv_pix_to_luma8(uint32_t fourcc, const uint8_t *src, size_t src_len, size_t src_stride, int w, int h,
                    uint8_t *dst, size_t dst_stride)
{
    size_t need = fv_pix_min_size(fourcc, w, h, src_stride);
    if (!need || src_len < need || dst_stride < (size_t)w)
        return -1;
    for (int y = 0; y < h; y++) {
        const uint8_t *s = src + (size_t)y * src_stride;
        uint8_t *d = dst + (size_t)y * dst_stride;
        switch (fourcc) {
        case FV_PIX_GREY: memcpy(d, s, (size_t)w); break;
        case FV_PIX_Y10: words_to_luma(s, d, w, 2); break;
        case FV_PIX_Y12: words_to_luma(s, d, w, 4); break;
        case FV_PIX_Y16:
            for (int x = 0; x < w; x++) /* the high byte of each word */
                d[x] = s[2 * x + 1];
            break;
        case FV_PIX_YUYV:
            for (int x = 0; x < w; x++)
                d[x] = s[2 * x];
            break;
        case FV_PIX_UYVY:
            for (int x = 0; x < w; x++)
                d[x] = s[2 * x + 1];
            break;
        }
    }
    return 0;
}

const char *fv_pix_name(uint32_t fourcc, char buf[5])
{
    for (int i = 0; i < 4; i++) {
        unsigned char c = (unsigned char)(fourcc >> (8 * i));
        buf[i] = isprint(c) ? (char)c : '?';
    }
    buf[4] = 0;
    for (int i = 3; i > 0 && buf[i] == ' '; i--)
        buf[i] = 0;
    return buf;
}

uint32_t fv_pix_parse(const char *name)
{
    size_t n = strlen(name);
    if (n == 0 || n > 4)
        return 0;
    char c[4] = {' ', ' ', ' ', ' '};
    for (size_t i = 0; i < n; i++)
        c[i] = (char)toupper((unsigned char)name[i]);
    uint32_t f = FV_FOURCC(c[0], c[1], c[2], c[3]);
    return fv_pix_supported(f) ? f : 0;
}
