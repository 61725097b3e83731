/* fovea platform: Motion-JPEG camera frames decoded to 8-bit luma with libjpeg-turbo (Debian's
 * libjpeg62-turbo). Pure (no device I/O) so it is tested on JPEGs made in the test. UVC cameras
 * often leave the Huffman tables out of each frame; libjpeg-turbo supplies the standard ones. */
#ifndef FOVEA_MJPEG_H
#define FOVEA_MJPEG_H

#include <stddef.h>
#include <stdint.h>

#include "pixfmt.h"

#define FV_PIX_MJPEG FV_FOURCC('M', 'J', 'P', 'G')

/* Decodes one JPEG of exactly w x h pixels to luma (the Y channel, or the grey one), rows
 * dst_stride (>= w) bytes apart. 0, or -1 with a reason (not a JPEG, corrupt or truncated data,
 * other size); dst may be partly written then. */
int fv_mjpeg_to_luma8(const uint8_t *src, size_t src_len, int w, int h, uint8_t *dst, size_t dst_stride,
                      char *err, size_t err_len);

#endif
