/* fovea platform: camera pixel formats reduced to 8-bit luma. Pure functions (no ioctl, no
 * allocation) so they can be tested against hand-made buffers; platform/v4l2.c uses them on the
 * driver's mmap'd buffers. The fourcc values are V4L2's (v4l2.c checks them at compile time). */
#ifndef FOVEA_PIXFMT_H
#define FOVEA_PIXFMT_H

#include <stddef.h>
#include <stdint.h>

#define FV_FOURCC(a, b, c, d) ((uint32_t)(a) | ((uint32_t)(b) << 8) | ((uint32_t)(c) << 16) | ((uint32_t)(d) << 24))

/* The formats fovea reads. Y10/Y12/Y16: one little-endian 16-bit word per pixel with 10/12/16
 * significant bits in the low bits (V4L2's layout). YUYV/UYVY: 4:2:2 packed, luma only is kept. */
#define FV_PIX_GREY FV_FOURCC('G', 'R', 'E', 'Y')
#define FV_PIX_Y10 FV_FOURCC('Y', '1', '0', ' ')
#define FV_PIX_Y12 FV_FOURCC('Y', '1', '2', ' ')
#define FV_PIX_Y16 FV_FOURCC('Y', '1', '6', ' ')
#define FV_PIX_YUYV FV_FOURCC('Y', 'U', 'Y', 'V')
#define FV_PIX_UYVY FV_FOURCC('U', 'Y', 'V', 'Y')

/* 1 if fovea can reduce this fourcc to luma. */
int fv_pix_supported(uint32_t fourcc);

/* Bytes one row of w pixels needs at least (YUYV/UYVY: whole 2-pixel groups, so odd widths round
 * up); 0 for an unsupported fourcc or w <= 0. */
size_t fv_pix_min_stride(uint32_t fourcc, int w);

/* Smallest buffer holding h rows of w pixels rows src_stride bytes apart (the last row need not
 * be padded); 0 when the arguments make no sense (src_stride below fv_pix_min_stride, ...). */
size_t fv_pix_min_size(uint32_t fourcc, int w, int h, size_t src_stride);

/* Converts one image to 8-bit luma: GREY copied, Y10 >> 2, Y12 >> 4, Y16 >> 8 (values above the
 * format's range, which only a misbehaving driver sends, saturate at 255), YUYV/UYVY luma bytes.
 * src holds src_len bytes, rows src_stride bytes apart; dst rows are dst_stride (>= w) apart.
 * Returns 0, or -1 (dst untouched) if the format is unsupported or src is too small. */
int fv_pix_to_luma8(uint32_t fourcc, const uint8_t *src, size_t src_len, size_t src_stride, int w, int h,
                    uint8_t *dst, size_t dst_stride);

/* "GREY", "Y10", "YUYV", ...: the fourcc's four characters with trailing spaces dropped, into buf
 * (>= 5 bytes; non-printable bytes become '?'). Returns buf. */
const char *fv_pix_name(uint32_t fourcc, char buf[5]);

/* Parses a fourcc name as written by fv_pix_name (case-insensitive, 1..4 characters, padded with
 * spaces). Returns 0 when the name is empty, longer than 4 or not a format fovea reads. */
uint32_t fv_pix_parse(const char *name);

#endif
