/* fovea: structural check of a PNG in memory before a decoder sees it. stb_image trusts the
 * chunk lengths: an 83-byte file whose IDAT length claims 2 GiB made it reserve 2 GiB. Every
 * chunk's length must fit in the bytes that are there, IHDR must come first with a size within
 * the caller's limit, and IEND must be reached; CRCs are left to the decoder. */
#ifndef FOVEA_BASE_PNGCHECK_H
#define FOVEA_BASE_PNGCHECK_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* 1 when data starts with the PNG signature. */
int fv_png_is_png(const uint8_t *data, size_t len);

/* 0 when the chunk structure is sound and the image is at most max_side pixels on a side and
 * max_pixels in all; -1 with a reason ("truncated", "chunk IDAT claims N bytes but M remain",
 * "W x H is larger than ...") otherwise. *w, *h (optional) receive IHDR's size. */
int fv_png_check(const uint8_t *data, size_t len, uint32_t max_side, uint64_t max_pixels, uint32_t *w, uint32_t *h,
                 char *err, size_t err_len);

#ifdef __cplusplus
}
#endif

#endif
