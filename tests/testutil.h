/* fovea test helpers shared by the cmocka suites. */
#pragma once
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <setjmp.h>
#include <stdlib.h>
#include <cmocka.h>

/* Path of ../shared (scenes, eye images): $SHARED, else ../shared from the repo root. */
static inline const char *fv_test_shared(void)
{
    const char *s = getenv("SHARED");
    return (s && *s) ? s : "../shared";
}

/* Small deterministic PRNG (splitmix64) so failures reproduce. */
static inline uint64_t fv_test_rand(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
static inline float fv_test_randf(uint64_t *state) /* [0,1) */
{
    return (float)(fv_test_rand(state) >> 40) * (1.0f / 16777216.0f);
}

/* An exact-size buffer of `count` floats, starting `off` floats into its allocation (so ASan
 * catches over-reads and rows start unaligned). Free `base`. */
typedef struct {
    float *base, *p;
} buf;
static inline buf buf_new(size_t count, int off)
{
    buf b;
    b.base = (float *)malloc((count + (size_t)off) * sizeof(float));
    assert_non_null(b.base);
    b.p = b.base + off;
    return b;
}

/* A new temporary file holding text: path is a mkstemp template ("/tmp/fovea_x_XXXXXX"), filled
 * in with the name. The caller removes it. */
static inline void fv_test_temp_file(char *path, const char *text)
{
    const int fd = mkstemp(path);
    assert_true(fd >= 0);
    FILE *f = fdopen(fd, "w");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
}
/* Replaces the contents of the file at path with text. */
static inline void fv_test_write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
}
