#include "image.h"

#include <errno.h>
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <string.h>
#include <stb/stb_image.h>

#include "base/err.h"
#include "base/pngcheck.h"

/* The largest PNG file read, and the largest image decoded (eye-camera frames and textures are
 * far smaller; the decoder is never asked for more). */
#define FV_PNG_MAX_FILE_BYTES ((size_t)256 << 20)
#define FV_PNG_MAX_SIDE 16384u
#define FV_PNG_MAX_PIXELS ((uint64_t)1 << 26)

uint8_t *fv_read_png(const char *path, int *w, int *h, char *err, size_t err_len)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        fv_err(err, err_len, "%s: %s", path, strerror(errno));
        return NULL;
    }
    struct stat st;
    if (fstat(fileno(f), &st) || !S_ISREG(st.st_mode)) {
        fv_err(err, err_len, "%s: %s", path, S_ISDIR(st.st_mode) ? "is a directory" : "not a regular file");
        fclose(f);
        return NULL;
    }
    if ((uint64_t)st.st_size > FV_PNG_MAX_FILE_BYTES) {
        fv_err(err, err_len, "%s: %lld bytes, larger than the %zu MiB limit for a PNG", path, (long long)st.st_size,
               FV_PNG_MAX_FILE_BYTES >> 20);
        fclose(f);
        return NULL;
    }
    const size_t len = (size_t)st.st_size;
    uint8_t *data = malloc(len ? len : 1);
    const size_t got = data ? fread(data, 1, len, f) : 0;
    fclose(f);
    if (!data || got != len) {
        fv_err(err, err_len, "%s: %s", path, data ? "read error" : "out of memory");
        free(data);
        return NULL;
    }
    char why[300];
    uint8_t *px = fv_decode_png(data, len, w, h, why, sizeof why);
    free(data);
    if (!px)
        fv_err(err, err_len, "%s: %s", path, why);
    return px;
}

uint8_t *fv_decode_png(const uint8_t *data, size_t len, int *w, int *h, char *err, size_t err_len)
{
    /* chunk lengths are checked against the bytes before stb sees them (stb reserves what they claim) */
    char why[160];
    if (!fv_png_is_png(data, len)) {
        fv_err(err, err_len, "not a PNG file");
        return NULL;
    }
    if (fv_png_check(data, len, FV_PNG_MAX_SIDE, FV_PNG_MAX_PIXELS, NULL, NULL, why, sizeof why)) {
        fv_err(err, err_len, "corrupt PNG (%s)", why);
        return NULL;
    }
    int n;
    uint8_t *px = len <= INT_MAX ? stbi_load_from_memory(data, (int)len, w, h, &n, 3) : NULL;
    if (!px)
        fv_err(err, err_len, "corrupt PNG (%s)", stbi_failure_reason());
    return px;
}
