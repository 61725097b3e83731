/* fovea fuzz targets: one function per parser of untrusted input, taking the raw bytes. Built two
 * ways: into tests/test_fuzz (gcc, every `make test`: each seed corpus plus a few thousand
 * deterministic mutations, so the harnesses cannot rot) and, by `make fuzz`, each into a clang
 * libFuzzer binary with ASan+UBSan (tests/fuzz/libfuzzer.c). A target returns 1 when the parser
 * accepted the input, 0 when it refused it (the replay test checks that its seeds are accepted);
 * a bug shows as a crash or a sanitizer report. */
#ifndef FOVEA_FUZZ_TARGETS_H
#define FOVEA_FUZZ_TARGETS_H

#include <stddef.h>
#include <stdint.h>

typedef int (*fv_fuzz_fn)(const uint8_t *data, size_t size);

typedef struct fv_fuzz_target {
    const char *name;   /* also the seed folder tests/fuzz/corpus/NAME */
    fv_fuzz_fn fn;
    size_t max_len;     /* inputs longer than this are not tried (-max_len for libFuzzer) */
} fv_fuzz_target;

int fv_fuzz_gltf(const uint8_t *data, size_t size);
int fv_fuzz_trace(const uint8_t *data, size_t size);
int fv_fuzz_lens(const uint8_t *data, size_t size);
int fv_fuzz_calib(const uint8_t *data, size_t size);
int fv_fuzz_y4m(const uint8_t *data, size_t size);
int fv_fuzz_imagelist(const uint8_t *data, size_t size);
int fv_fuzz_pixfmt(const uint8_t *data, size_t size);
int fv_fuzz_png(const uint8_t *data, size_t size);

extern const fv_fuzz_target fv_fuzz_targets[];
extern const int fv_fuzz_target_count;

/* A file holding the input, for parsers that take a path: one per process, rewritten each call. */
const char *fv_fuzz_tmpfile(const uint8_t *data, size_t size, const char *suffix);

#endif
