#include "image.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <stb/stb_image.h>

#include "base/err.h"

uint8_t *fv_read_png(const char *path, int *w, int *h, char *err, size_t err_len)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        fv_err(err, err_len, "%s: %s", path, strerror(errno));
        return NULL;
    }
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    uint8_t head[8];
    const size_t got = fread(head, 1, sizeof head, f);
    if (ferror(f)) { /* e.g. a directory */
        fv_err(err, err_len, "%s: read error", path);
        fclose(f);
        return NULL;
    }
    if (got < sizeof head || memcmp(head, sig, sizeof sig)) {
        fv_err(err, err_len, "%s: not a PNG file", path);
        fclose(f);
        return NULL;
    }
    rewind(f);
    int n;
    uint8_t *px = stbi_load_from_file(f, w, h, &n, 3);
    fclose(f);
    if (!px)
        fv_err(err, err_len, "%s: corrupt PNG (%s)", path, stbi_failure_reason());
    return px;
}
