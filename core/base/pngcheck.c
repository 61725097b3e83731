/* fovea: PNG chunk structure check (pngcheck.h). */
#include "base/pngcheck.h"

#include <string.h>

#include "base/err.h"

static uint32_t be32(const uint8_t *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

int fv_png_is_png(const uint8_t *data, size_t len)
{
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    return len >= sizeof sig && !memcmp(data, sig, sizeof sig);
}

int fv_png_check(const uint8_t *data, size_t len, uint32_t max_side, uint64_t max_pixels, uint32_t *w, uint32_t *h,
                 char *err, size_t err_len)
{
    if (!fv_png_is_png(data, len))
        return fv_err(err, err_len, "not a PNG file");
    size_t at = 8;
    int idat = 0;
    for (int n = 0;; n++) {
        if (len - at < 12)
            return fv_err(err, err_len, "truncated PNG (no IEND chunk)");
        const uint32_t clen = be32(data + at);
        char type[5];
        memcpy(type, data + at + 4, 4);
        type[4] = '\0';
        for (int i = 0; i < 4; i++) /* chunk types are ASCII letters; keep the message printable */
            if (!((type[i] >= 'A' && type[i] <= 'Z') || (type[i] >= 'a' && type[i] <= 'z')))
                return fv_err(err, err_len, "PNG chunk %d has an invalid type", n);
        /* the specification caps lengths at 2^31 - 1; the bytes must be there */
        if (clen > 0x7fffffffu || clen > len - at - 12)
            return fv_err(err, err_len, "PNG chunk %s claims %lu bytes but %lu remain", type, (unsigned long)clen,
                          (unsigned long)(len - at - 12));
        const uint8_t *d = data + at + 8;
        if (n == 0) {
            if (strcmp(type, "IHDR") || clen != 13)
                return fv_err(err, err_len, "PNG does not start with a 13-byte IHDR chunk");
            const uint32_t iw = be32(d), ih = be32(d + 4);
            if (iw == 0 || ih == 0)
                return fv_err(err, err_len, "PNG size %lux%lu is empty", (unsigned long)iw, (unsigned long)ih);
            if (iw > max_side || ih > max_side || (uint64_t)iw * ih > max_pixels)
                return fv_err(err, err_len, "PNG size %lux%lu is larger than %lu pixels a side or %llu in all",
                              (unsigned long)iw, (unsigned long)ih, (unsigned long)max_side,
                              (unsigned long long)max_pixels);
            if (w)
                *w = iw;
            if (h)
                *h = ih;
        } else if (!strcmp(type, "IHDR")) {
            return fv_err(err, err_len, "PNG has a second IHDR chunk");
        }
        if (!strcmp(type, "IDAT"))
            idat = 1;
        at += 12 + (size_t)clen;
        if (!strcmp(type, "IEND"))
            return idat ? 0 : fv_err(err, err_len, "PNG has no image data (IDAT)");
    }
}
