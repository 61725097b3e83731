/* PNG chunk structure check (core/base/pngcheck.c) and the PNG reader built on it
 * (platform/image.c): a real PNG passes; lying lengths, truncation, oversize and missing
 * chunks are refused with their reason before stb_image sees the bytes (stb reserves what an
 * IDAT length claims: 2 GiB for an 83-byte file). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/pngcheck.h"
#include "image.h"
#include "output.h"
#include "testutil.h"

static void put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 24), p[1] = (uint8_t)(v >> 16), p[2] = (uint8_t)(v >> 8), p[3] = (uint8_t)v;
}

/* A real 7x5 PNG written by the project's writer, read back as bytes. */
static uint8_t *real_png(size_t *len, char *path)
{
    uint8_t rgb[7 * 5 * 3];
    for (size_t i = 0; i < sizeof rgb; i++)
        rgb[i] = (uint8_t)(i * 37);
    char err[256];
    fv_test_temp_file(path, "");
    assert_int_equal(fv_write_png(path, rgb, 7, 5, 7 * 3, err, sizeof err), 0);
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    uint8_t *d = malloc(1 << 16);
    *len = fread(d, 1, 1 << 16, f);
    fclose(f);
    return d;
}

/* offset of the chunk of the given type */
static size_t chunk_at(const uint8_t *d, size_t len, const char *type)
{
    size_t at = 8;
    while (at + 12 <= len) {
        if (!memcmp(d + at + 4, type, 4))
            return at;
        at += 12 + ((size_t)d[at] << 24 | (size_t)d[at + 1] << 16 | (size_t)d[at + 2] << 8 | d[at + 3]);
    }
    fail_msg("no %s chunk", type);
    return 0;
}

static void expect(const uint8_t *d, size_t len, const char *want)
{
    char err[256] = "";
    uint32_t w = 0, h = 0;
    const int rc = fv_png_check(d, len, 16384, (uint64_t)1 << 26, &w, &h, err, sizeof err);
    if (!want) {
        if (rc)
            fail_msg("a sound PNG was refused: %s", err);
        assert_int_equal(w, 7);
        assert_int_equal(h, 5);
    } else if (rc != -1 || !strstr(err, want)) {
        fail_msg("want '%s', got rc %d '%s'", want, rc, err);
    }
}

static void test_structure(void **st)
{
    (void)st;
    char path[] = "/tmp/fovea_png_XXXXXX";
    size_t len;
    uint8_t *d = real_png(&len, path), *m = malloc(len);
    expect(d, len, NULL);
    const size_t idat = chunk_at(d, len, "IDAT"), iend = chunk_at(d, len, "IEND");

    memcpy(m, d, len); /* the IDAT length lies: 2 GiB - 1 */
    put32(m + idat, 0x7fffffffu);
    expect(m, len, "PNG chunk IDAT claims 2147483647 bytes but");
    memcpy(m, d, len); /* over the specification's 2^31 - 1 */
    put32(m + idat, 0x80000000u);
    expect(m, len, "PNG chunk IDAT claims 2147483648 bytes");
    expect(d, iend, "truncated PNG (no IEND chunk)");         /* cut before IEND */
    expect(d, idat + 20, "PNG chunk IDAT claims");               /* cut inside IDAT */
    expect(d, 7, "not a PNG file");                              /* shorter than the signature */
    memcpy(m, d, len); /* IHDR's width beyond the limit */
    put32(m + 16, 100000);
    expect(m, len, "PNG size 100000x5 is larger than 16384 pixels a side");
    put32(m + 16, 16384), put32(m + 20, 16384); /* each side allowed, the area not */
    expect(m, len, "is larger than");
    memcpy(m, d, len);
    put32(m + 16, 0);
    expect(m, len, "PNG size 0x5 is empty");
    memcpy(m, d, len); /* a chunk type that is not four letters */
    m[idat + 4] = '\0';
    expect(m, len, "invalid type");
    memcpy(m, d, len); /* IDAT renamed: no image data before IEND */
    memcpy(m + idat + 4, "tEXt", 4);
    expect(m, len, "no image data");
    memcpy(m, d, len); /* IHDR not first */
    memcpy(m + 12, "IHDX", 4);
    expect(m, len, "does not start with a 13-byte IHDR");

    /* the reader: the sound file decodes to the written pixels' size, the lying one is refused
     * with the reason and the file named */
    int w, h;
    char err[512];
    uint8_t *px = fv_read_png(path, &w, &h, err, sizeof err);
    assert_non_null(px);
    assert_int_equal(w, 7);
    assert_int_equal(h, 5);
    free(px);
    memcpy(m, d, len);
    put32(m + idat, 0x7fffffffu);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(m, 1, len, f), len);
    fclose(f);
    assert_null(fv_read_png(path, &w, &h, err, sizeof err));
    char want[256];
    snprintf(want, sizeof want, "%s: corrupt PNG (PNG chunk IDAT claims 2147483647 bytes but", path);
    if (strncmp(err, want, strlen(want)))
        fail_msg("got '%s'", err);
    unlink(path);
    assert_null(fv_read_png("/tmp", &w, &h, err, sizeof err));
    assert_string_equal(err, "/tmp: is a directory");
    free(m);
    free(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_structure),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
