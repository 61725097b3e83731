/* fovea platform: reading images back (the compare tool and tests). */
#ifndef FOVEA_IMAGE_H
#define FOVEA_IMAGE_H

#include <stddef.h>
#include <stdint.h>

/* Loads a PNG as 8-bit RGB (w * h * 3 bytes, rows packed; free() it). Grey, grey+alpha and
 * RGBA are converted (alpha dropped). NULL with a one-line reason naming the file in err: it
 * cannot be opened, is not a PNG (signature), or does not decode (corrupt or truncated). */
uint8_t *fv_read_png(const char *path, int *w, int *h, char *err, size_t err_len);
/* The same from len bytes in memory (no file named in err). */
uint8_t *fv_decode_png(const uint8_t *data, size_t len, int *w, int *h, char *err, size_t err_len);

#endif
