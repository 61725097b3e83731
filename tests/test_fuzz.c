/* The fuzz harnesses (tests/fuzz/) in every `make test`: each target runs its seed corpus
 * (tests/fuzz/corpus/NAME) unchanged, then FV_FUZZ_MUTATIONS (default 2000) deterministic
 * mutations of it (bit flips, interesting bytes, deletions, duplications, truncations, splices
 * between seeds), so the harnesses and the parsers' error paths are exercised on every run and
 * cannot rot. A parser bug shows as a crash (or, in `make check-asan`, a sanitizer report). The
 * real search is `make fuzz` (clang libFuzzer, ASan+UBSan). The seeds themselves must parse:
 * a seed that the parser refuses has stopped covering the accepting paths. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz/targets.h"
#include "testutil.h"

typedef struct seed {
    uint8_t *d;
    size_t n;
} seed;

static int load_seeds(const char *name, seed *out, int cap)
{
    char dir[256];
    snprintf(dir, sizeof dir, "tests/fuzz/corpus/%s", name);
    DIR *d = opendir(dir);
    if (!d)
        fail_msg("no seed corpus %s (run from the project root)", dir);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) && n < cap) {
        if (e->d_name[0] == '.')
            continue;
        char p[600];
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        FILE *f = fopen(p, "rb");
        assert_non_null(f);
        out[n].d = malloc(1 << 20);
        assert_non_null(out[n].d);
        out[n].n = fread(out[n].d, 1, 1 << 20, f);
        fclose(f);
        n++;
    }
    closedir(d);
    if (n == 0)
        fail_msg("empty seed corpus %s", dir);
    return n;
}

static size_t mutate(uint8_t *buf, size_t n, size_t cap, const seed *seeds, int nseeds, uint64_t *rng)
{
    static const uint8_t interesting[] = {0, 0xff, 0x7f, 0x80, '0', '9', ',', '\n', '-', 'e', '.', ' ', '"', '{', '}', '['};
    const int ops = 1 + (int)(fv_test_rand(rng) % 4);
    for (int k = 0; k < ops; k++) {
        const uint64_t r = fv_test_rand(rng);
        const size_t at = n ? (size_t)(fv_test_rand(rng) % n) : 0;
        switch (r % 7) {
        case 0: if (n) buf[at] ^= (uint8_t)(1u << (r >> 8) % 8); break;
        case 1: if (n) buf[at] = interesting[(r >> 8) % sizeof interesting]; break;
        case 2: { /* delete a run */
            const size_t len = n - at < 16 ? n - at : 1 + (size_t)((r >> 8) % 16);
            memmove(buf + at, buf + at + len, n - at - len);
            n -= len;
            break;
        }
        case 3: { /* duplicate a run */
            const size_t len = 1 + (size_t)((r >> 8) % 32);
            if (n && n + len <= cap && at + len <= n) {
                memmove(buf + at + len, buf + at, n - at);
                n += len;
            }
            break;
        }
        case 4: n = at; break; /* truncate */
        case 5: /* random bytes */
            for (size_t i = 0; i < 4 && at + i < n; i++)
                buf[at + i] = (uint8_t)fv_test_rand(rng);
            break;
        default: { /* splice: the tail of another seed */
            const seed *o = &seeds[(r >> 8) % (uint64_t)nseeds];
            const size_t from = o->n ? (size_t)(fv_test_rand(rng) % o->n) : 0, len = o->n - from;
            if (at + len <= cap) {
                memcpy(buf + at, o->d + from, len);
                n = at + len;
            }
        }
        }
    }
    return n;
}

static void run_target(const fv_fuzz_target *t)
{
    seed seeds[32];
    const int ns = load_seeds(t->name, seeds, 32);
    const char *env = getenv("FV_FUZZ_MUTATIONS");
    const long muts = env ? atol(env) : 2000;
    for (int i = 0; i < ns; i++)
        if (!t->fn(seeds[i].d, seeds[i].n))
            fail_msg("%s: seed %d (%zu bytes) is refused: it no longer covers the accepting paths", t->name, i,
                     seeds[i].n);
    const size_t cap = t->max_len;
    uint8_t *buf = malloc(cap);
    assert_non_null(buf);
    uint64_t rng = 0x5eed0000u ^ (uint64_t)strlen(t->name) * 0x9e3779b97f4a7c15ull;
    long accepted = 0;
    for (long m = 0; m < muts; m++) {
        const seed *s = &seeds[m % ns];
        size_t n = s->n < cap ? s->n : cap;
        memcpy(buf, s->d, n);
        n = mutate(buf, n, cap, seeds, ns, &rng);
        accepted += t->fn(buf, n);
    }
    printf("[ fuzz ] %s: %d seeds, %ld mutations (%ld accepted)\n", t->name, ns, muts, accepted);
    free(buf);
    for (int i = 0; i < ns; i++)
        free(seeds[i].d);
}

static void test_target(void **state)
{
    run_target((const fv_fuzz_target *)*state);
}

int main(void)
{
    struct CMUnitTest tests[16];
    int n = 0;
    for (int i = 0; i < fv_fuzz_target_count && n < 16; i++) {
        tests[n] = (struct CMUnitTest)cmocka_unit_test_prestate(test_target, (void *)&fv_fuzz_targets[i]);
        tests[n].name = fv_fuzz_targets[i].name;
        n++;
    }
    return _cmocka_run_group_tests("fuzz", tests, (size_t)n, NULL, NULL);
}
