/* fovea: pull-push reconstruction tests (core/pullpush.c + every kernel ISA). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "pullpush.h"

static uint64_t rng = 0x9a11b005ull;

/* ------------------------------------------------------------------ helpers */

typedef struct {
    int w, h;
    float *rgbd, *wgt; /* w*h*4, w*h */
} image;

static image img_new(int w, int h)
{
    image im = { w, h, calloc((size_t)w * h * 4, sizeof(float)), calloc((size_t)w * h, sizeof(float)) };
    assert_non_null(im.rgbd);
    assert_non_null(im.wgt);
    return im;
}

static void img_free(image *im)
{
    free(im->rgbd);
    free(im->wgt);
}

static void set_px(image *im, int x, int y, const float c[4], float w)
{
    memcpy(im->rgbd + 4 * ((size_t)y * im->w + x), c, 4 * sizeof(float));
    im->wgt[(size_t)y * im->w + x] = w;
}

/* Level 0 <- image: clear first (as a renderer would), then write the samples. */
static void load(fv_pyramid *p, const image *im, fv_pool *pool)
{
    fv_pyramid_clear(p, pool);
    const fv_pyr_level *L = &p->lv[0];
    for (int y = 0; y < im->h; y++) {
        memcpy(L->rgbd + 4 * (ptrdiff_t)y * L->stride, im->rgbd + 4 * (size_t)y * im->w, 16 * (size_t)im->w);
        memcpy(L->wgt + (ptrdiff_t)y * L->stride, im->wgt + (size_t)y * im->w, 4 * (size_t)im->w);
    }
}

static const float *px(const fv_pyr_level *L, int x, int y) { return L->rgbd + 4 * ((ptrdiff_t)y * L->stride + x); }

/* Same weights, but every zero-weight pixel of level 0 gets a NaN / Inf colour (never to be used). */
static void poison_holes(fv_pyramid *p)
{
    const fv_pyr_level *L = &p->lv[0];
    const float bad[] = { NAN, INFINITY, -INFINITY, -NAN };
    for (int y = 0; y < L->h; y++)
        for (int x = 0; x < L->w; x++)
            if (L->wgt[(ptrdiff_t)y * L->stride + x] == 0.0f)
                for (int c = 0; c < 4; c++)
                    ((float *)px(L, x, y))[c] = bad[(x + y + c) & 3];
}

/* Weier-like foveated sampling: disc of radius r0 fully sampled, then density falling off to pmin. */
static void foveated(image *im, double gx, double gy, double r0, double pmin, double fall)
{
    for (int y = 0; y < im->h; y++)
        for (int x = 0; x < im->w; x++) {
            const double r = hypot(x - gx, y - gy);
            const double pr = r < r0 ? 1.0 : fmax(pmin, exp(-(r - r0) / fall));
            if (fv_test_randf(&rng) < pr) {
                const float c[4] = { 0.5f + 0.4f * sinf((float)x * 0.05f), (float)y / (float)im->h,
                                     fv_test_randf(&rng), 1.0f + 50.0f * fv_test_randf(&rng) };
                set_px(im, x, y, c, fv_test_randf(&rng) < 0.8f ? 1.0f : 0.05f + 0.95f * fv_test_randf(&rng));
            }
        }
}

/* Every byte a consumer may read: valid pixels, the 1-pixel border, all weights. */
static void assert_pyramids_equal(const fv_pyramid *a, const fv_pyramid *b, const char *what)
{
    assert_int_equal(a->levels, b->levels);
    for (int l = 0; l < a->levels; l++) {
        const fv_pyr_level *A = &a->lv[l], *B = &b->lv[l];
        assert_int_equal(A->w, B->w);
        assert_int_equal(A->h, B->h);
        for (int y = -1; y <= A->h; y++) {
            if (memcmp(px(A, -1, y), px(B, -1, y), 16 * (size_t)(A->w + 2)) != 0) {
                for (int x = -1; x <= A->w; x++)
                    for (int c = 0; c < 4; c++)
                        if (memcmp(&px(A, x, y)[c], &px(B, x, y)[c], 4) != 0)
                            fail_msg("%s: level %d (%dx%d) pixel (%d,%d) channel %d: %.9g vs %.9g", what, l, A->w,
                                     A->h, x, y, c, (double)px(A, x, y)[c], (double)px(B, x, y)[c]);
            }
            if (y >= 0 && y < A->h)
                if (memcmp(A->wgt + (ptrdiff_t)y * A->stride, B->wgt + (ptrdiff_t)y * B->stride, 4 * (size_t)A->w))
                    fail_msg("%s: level %d weights of row %d differ", what, l, y);
        }
    }
}

/* |v - ref| <= tol * max(1, |ref|) on every pixel of every level; returns the worst relative error. */
static double check_constant(const fv_pyramid *p, const float k[4], double tol, const char *what)
{
    double worst = 0;
    for (int l = 0; l < p->levels; l++) {
        const fv_pyr_level *L = &p->lv[l];
        for (int y = 0; y < L->h; y++)
            for (int x = 0; x < L->w; x++)
                for (int c = 0; c < 4; c++) {
                    const double v = px(L, x, y)[c];
                    const double e = fabs(v - k[c]) / fmax(1.0, fabs(k[c]));
                    if (!(e <= tol))
                        fail_msg("%s: level %d (%dx%d) pixel (%d,%d) channel %d = %.9g, want %.9g (rel err %.3g > %.3g)",
                                 what, l, L->w, L->h, x, y, c, v, (double)k[c], e, tol);
                    if (e > worst)
                        worst = e;
                }
    }
    return worst;
}

static void check_borders(const fv_pyramid *p)
{
    for (int l = 0; l < p->levels; l++) {
        const fv_pyr_level *L = &p->lv[l];
        for (int y = -1; y <= L->h; y++) {
            const int sy = y < 0 ? 0 : y >= L->h ? L->h - 1 : y;
            for (int x = -1; x <= L->w; x++) {
                const int sx = x < 0 ? 0 : x >= L->w ? L->w - 1 : x;
                if (memcmp(px(L, x, y), px(L, sx, sy), 16) != 0)
                    fail_msg("level %d: border pixel (%d,%d) is not a copy of (%d,%d)", l, x, y, sx, sy);
            }
        }
    }
}

/* ------------------------------------------------------------------ tests */

static void test_init(void **state)
{
    (void)state;
    fv_pyramid p;
    assert_int_equal(fv_pyramid_init(&p, 0, 5), -1);
    assert_int_equal(fv_pyramid_init(&p, 5, -1), -1);
    assert_int_equal(fv_pyramid_init(&p, 1 << 20, 4), -1);
    fv_pyramid_free(&p); /* harmless after a failed init */
    static const int dims[][2] = { { 1, 1 }, { 1, 7 }, { 7, 1 }, { 13, 5 }, { 1280, 1440 }, { 1281, 1441 } };
    for (size_t i = 0; i < sizeof dims / sizeof dims[0]; i++) {
        const int w = dims[i][0], h = dims[i][1];
        assert_int_equal(fv_pyramid_init(&p, w, h), 0);
        int lw = w, lh = h, levels = 1;
        assert_int_equal(p.lv[0].w, w);
        assert_int_equal(p.lv[0].h, h);
        while (lw > 1 || lh > 1) {
            lw = (lw + 1) / 2, lh = (lh + 1) / 2;
            assert_int_equal(p.lv[levels].w, lw);
            assert_int_equal(p.lv[levels].h, lh);
            levels++;
        }
        assert_int_equal(p.levels, levels);
        for (int l = 0; l < p.levels; l++) {
            assert_true(p.lv[l].stride >= p.lv[l].w + 2);
            assert_int_equal((uintptr_t)p.lv[l].rgbd % 64, 0);
            assert_int_equal((uintptr_t)p.lv[l].wgt % 64, 0);
        }
        fv_pyramid_free(&p);
    }
}

/* A constant image with 70% random holes plus a big hole region reconstructs to the constant
 * on every pixel of every level (pull averages equal values; bilinear push of equal values is
 * exact in v + 1/4 (v' - v) form; only the pull's rounding remains). */
static void test_constant_with_holes(void **state)
{
    (void)state;
    static const int dims[][2] = { { 1280, 1440 }, { 317, 251 }, { 1, 1 }, { 1, 7 }, { 7, 1 }, { 13, 5 }, { 1281, 1441 } };
    const float k[4] = { 0.3f, 0.55f, 0.8f, 12.5f };
    double worst = 0;
    for (size_t i = 0; i < sizeof dims / sizeof dims[0]; i++) {
        const int w = dims[i][0], h = dims[i][1];
        image im = img_new(w, h);
        int samples = 0;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                const int in_hole = (x > w / 5 && x < w / 2 && y > h / 4 && y < 3 * h / 4) ||
                                    hypot(x - 0.75 * w, y - 0.3 * h) < 0.15 * (w < h ? w : h);
                if (!in_hole && fv_test_randf(&rng) < 0.3f) {
                    set_px(&im, x, y, k, fv_test_randf(&rng) < 0.5f ? 1.0f : 0.01f + 0.99f * fv_test_randf(&rng));
                    samples++;
                }
            }
        if (samples == 0)
            set_px(&im, w / 2, h / 2, k, 1.0f);
        fv_pyramid p;
        assert_int_equal(fv_pyramid_init(&p, w, h), 0);
        fv_pullpush_dsp d;
        fv_pullpush_dsp_init(&d, ~0u);
        load(&p, &im, NULL);
        poison_holes(&p);
        fv_pullpush(&p, &d, NULL);
        const double e = check_constant(&p, k, 1e-6, "constant with holes");
        if (e > worst)
            worst = e;
        check_borders(&p);
        fv_pyramid_free(&p);
        img_free(&im);
    }
    printf("[ pullpush ] constant with holes: worst relative error %.3g (bound 1e-6)\n", worst);
}

/* Linear ramp f(x, y) = a + b x + c y per channel, Weier-like sampling: a fully sampled disc and
 * 20% random samples elsewhere, all weights 1.
 *
 * Error bound, by induction over the pyramid (exact arithmetic; float rounding adds a slack):
 *  - Pull: with 0/1 weights every pulled weight is 0 or 1, and a pulled colour is the mean of
 *    its children's colours, so (f linear) a level-l pixel with weight 1 holds f(q) for a point
 *    q in the convex hull of its 2^l x 2^l footprint (in level-0 pixel centres): its error
 *    against f at its own centre is at most E_l = G (2^l - 1) / 2, G = |b| + |c|.
 *  - Push: a weight-1 pixel is kept; a hole gets the bilinear interpolation (3/4, 1/4 per axis)
 *    of the 4 coarse pixels around it, and bilinear interpolation of exact samples of a linear
 *    function at the coarse centres is exact at the fine centre (the fine centre is 1/4 of a
 *    coarse step from the nearest coarse centre). So the fine error is a convex combination of
 *    the coarse errors: at most the maximum of theirs.
 *  - Let L be the first level whose pixels all have a sample in their footprint (all weights 1).
 *    Then every level-0 value has error <= max_{l <= L} E_l = E_L.
 *  - "Away from borders": clamped (replicated) stencils are not linear; the dependency cone of a
 *    level-0 pixel on level l is about 2^(l+1) pixels wide, so pixels closer than 2^(L+2) to an
 *    edge are not checked. */
static void test_linear_ramp(void **state)
{
    (void)state;
    const int w = 613, h = 477;
    const float a[4] = { 0.1f, 0.9f, 0.4f, 2.0f }, b[4] = { 0.001f, -0.0007f, 0.0f, 0.01f },
                c[4] = { 0.0005f, 0.0012f, -0.0009f, 0.004f };
    image im = img_new(w, h);
    unsigned char *mask = calloc((size_t)w * h, 1);
    assert_non_null(mask);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            if (hypot(x - 0.6 * w, y - 0.45 * h) < 90 || fv_test_randf(&rng) < 0.2f) {
                float v[4];
                for (int k = 0; k < 4; k++)
                    v[k] = a[k] + b[k] * (float)x + c[k] * (float)y;
                set_px(&im, x, y, v, 1.0f);
                mask[(size_t)y * w + x] = 1;
            }
    /* L: first level at which every footprint holds a sample (from the mask, not the pyramid) */
    int L = 0;
    for (;; L++) {
        const int s = 1 << L, lw = (w + s - 1) / s, lh = (h + s - 1) / s;
        int all = 1;
        for (int Y = 0; Y < lh && all; Y++)
            for (int X = 0; X < lw && all; X++) {
                int any = 0;
                for (int y = Y * s; y < (Y + 1) * s && y < h && !any; y++)
                    for (int x = X * s; x < (X + 1) * s && x < w && !any; x++)
                        any = mask[(size_t)y * w + x];
                all = any;
            }
        if (all)
            break;
    }
    fv_pyramid p;
    assert_int_equal(fv_pyramid_init(&p, w, h), 0);
    fv_pullpush_dsp d;
    fv_pullpush_dsp_init(&d, ~0u);
    load(&p, &im, NULL);
    fv_pullpush(&p, &d, NULL);
    const int margin = 1 << (L + 2);
    double worst_ratio = 0;
    for (int k = 0; k < 4; k++) {
        const double G = fabs(b[k]) + fabs(c[k]);
        const double fmaxv = fabs(a[k]) + fabs(b[k]) * w + fabs(c[k]) * h;
        const double bound = G * ((1 << L) - 1) / 2.0 + 64 * 1.2e-7 * fmaxv; /* + float rounding */
        for (int y = margin; y < h - margin; y++)
            for (int x = margin; x < w - margin; x++) {
                const double want = (double)a[k] + (double)b[k] * x + (double)c[k] * y;
                const double got = px(&p.lv[0], x, y)[k];
                if (mask[(size_t)y * w + x] && got != (float)(a[k] + b[k] * (float)x + c[k] * (float)y))
                    fail_msg("ramp: sample (%d,%d) channel %d changed", x, y, k);
                if (!(fabs(got - want) <= bound))
                    fail_msg("ramp: pixel (%d,%d) channel %d = %.7g, want %.7g (err %.3g > bound %.3g, L=%d)", x, y, k,
                             got, want, fabs(got - want), bound, L);
                if (fabs(got - want) / bound > worst_ratio)
                    worst_ratio = fabs(got - want) / bound;
            }
    }
    printf("[ pullpush ] linear ramp (%dx%d, disc + 20%%): L=%d, worst error = %.2f of the bound\n", w, h, L,
           worst_ratio);
    fv_pyramid_free(&p);
    free(mask);
    img_free(&im);
}

/* A sharp check of the push geometry (9/16, 3/16, 3/16, 1/16 at the right neighbours): sample a
 * linear ramp only at even (x, y). Every level-1 pixel then holds exactly f(2X, 2Y), i.e. the
 * linear function g(x, y) = f(x - 1/2, y - 1/2) at its centre, with weight 1. So every hole of
 * level 0 away from the border must be exactly g at its centre: bilinear interpolation of a
 * linear function. Wrong stencil weights or neighbours give errors of a pixel's worth of slope. */
static void test_ramp_even_grid(void **state)
{
    (void)state;
    const int w = 201, h = 143;
    const float a = 1.0f, b = 0.02f, c = -0.013f;
    image im = img_new(w, h);
    for (int y = 0; y < h; y += 2)
        for (int x = 0; x < w; x += 2) {
            const float v = a + b * (float)x + c * (float)y;
            const float col[4] = { v, v, v, v };
            set_px(&im, x, y, col, 1.0f);
        }
    unsigned isas = fv_cpu_isas(), tried = 0;
    for (unsigned isa = 0; isa <= FV_ISA_NEON; isa = isa ? isa << 1 : 1) {
        if (isa && !(isas & isa))
            continue;
        fv_pyramid p;
        assert_int_equal(fv_pyramid_init(&p, w, h), 0);
        fv_pullpush_dsp d;
        fv_pullpush_dsp_init(&d, isa);
        load(&p, &im, NULL);
        fv_pullpush(&p, &d, NULL);
        double worst = 0;
        for (int y = 2; y < h - 2; y++)
            for (int x = 2; x < w - 2; x++) {
                const int sample = !(x & 1) && !(y & 1);
                const double want = sample ? a + b * x + c * y : a + b * (x - 0.5) + c * (y - 0.5);
                const double e = fabs(px(&p.lv[0], x, y)[0] - want);
                if (!(e <= 1e-5))
                    fail_msg("%s: even-grid ramp pixel (%d,%d) = %.7g, want %.7g", fv_isa_name(isa), x, y,
                             (double)px(&p.lv[0], x, y)[0], want);
                if (e > worst)
                    worst = e;
            }
        tried++;
        fv_pyramid_free(&p);
        printf("[ pullpush ] even-grid ramp %-6s: worst error %.3g (bound 1e-5)\n", fv_isa_name(isa), worst);
    }
    assert_true(tried >= 1);
    img_free(&im);
}

static void test_hole_free_unchanged(void **state)
{
    (void)state;
    const int w = 333, h = 197;
    image im = img_new(w, h);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float col[4] = { fv_test_randf(&rng), fv_test_randf(&rng) * 1e-30f, -fv_test_randf(&rng),
                                   1e4f * fv_test_randf(&rng) };
            set_px(&im, x, y, col, 1.0f);
        }
    fv_pyramid p;
    assert_int_equal(fv_pyramid_init(&p, w, h), 0);
    fv_pullpush_dsp d;
    fv_pullpush_dsp_init(&d, ~0u);
    load(&p, &im, NULL);
    fv_pullpush(&p, &d, NULL);
    for (int y = 0; y < h; y++) {
        assert_memory_equal(px(&p.lv[0], 0, y), im.rgbd + 4 * (size_t)y * w, 16 * (size_t)w);
        for (int x = 0; x < w; x++)
            assert_true(p.lv[0].wgt[(ptrdiff_t)y * p.lv[0].stride + x] == 1.0f);
    }
    for (int l = 1; l < p.levels; l++) /* coarser levels: full weight everywhere */
        for (int y = 0; y < p.lv[l].h; y++)
            for (int x = 0; x < p.lv[l].w; x++)
                assert_true(p.lv[l].wgt[(ptrdiff_t)y * p.lv[l].stride + x] == 1.0f);
    fv_pyramid_free(&p);
    img_free(&im);
}

static void test_single_sample(void **state)
{
    (void)state;
    static const int dims[][2] = { { 1, 1 }, { 1, 7 }, { 13, 5 }, { 64, 64 }, { 301, 203 } };
    const float k[4] = { 0.7f, 0.123f, 0.9f, 4321.5f };
    for (size_t i = 0; i < sizeof dims / sizeof dims[0]; i++)
        for (int rep = 0; rep < 3; rep++) {
            const int w = dims[i][0], h = dims[i][1];
            const float sw = rep == 2 ? 0.37f : 1.0f;
            image im = img_new(w, h);
            set_px(&im, (int)(fv_test_rand(&rng) % (unsigned)w), (int)(fv_test_rand(&rng) % (unsigned)h), k, sw);
            fv_pyramid p;
            assert_int_equal(fv_pyramid_init(&p, w, h), 0);
            fv_pullpush_dsp d;
            fv_pullpush_dsp_init(&d, ~0u);
            load(&p, &im, NULL);
            poison_holes(&p);
            fv_pullpush(&p, &d, NULL);
            /* weight 1: every pixel of every level is k to the bit; 0.37: within rounding */
            check_constant(&p, k, sw == 1.0f ? 0.0 : 1e-6, "single sample");
            fv_pyramid_free(&p);
            img_free(&im);
        }
}

static void test_empty_image(void **state)
{
    (void)state;
    const int w = 37, h = 21;
    fv_pyramid p;
    assert_int_equal(fv_pyramid_init(&p, w, h), 0);
    fv_pullpush_dsp d;
    fv_pullpush_dsp_init(&d, ~0u);
    fv_pyramid_clear(&p, NULL);
    poison_holes(&p);
    fv_pullpush(&p, &d, NULL);
    const float zero[4] = { 0, 0, 0, 0 };
    check_constant(&p, zero, 0.0, "no samples at all");
    fv_pyramid_free(&p);
}

/* Same input, any pool size (and none): the same bytes everywhere.
 * FV_TEST_MAX_THREADS=n skips pools larger than n, and says so (for an emulator or sandbox
 * without threads; the qemu-aarch64 leg runs with threads and needs no limit). */
static void test_thread_count_invariance(void **state)
{
    (void)state;
    const char *env = getenv("FV_TEST_MAX_THREADS");
    const int max_threads = env && *env ? atoi(env) : 1 << 20;
    const int w = 1281, h = 1441;
    image im = img_new(w, h);
    foveated(&im, 0.55 * w, 0.45 * h, 180, 0.1, 220);
    fv_pullpush_dsp d;
    fv_pullpush_dsp_init(&d, ~0u);
    fv_pyramid ref;
    assert_int_equal(fv_pyramid_init(&ref, w, h), 0);
    load(&ref, &im, NULL);
    fv_pullpush(&ref, &d, NULL);
    static const int sizes[] = { 1, 2, 5 };
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        if (sizes[i] > max_threads) {
            printf("[ pullpush ] pool of %d skipped (FV_TEST_MAX_THREADS=%d)\n", sizes[i], max_threads);
            continue;
        }
        fv_pool *pool = fv_pool_create(sizes[i]);
        assert_non_null(pool);
        fv_pyramid p;
        assert_int_equal(fv_pyramid_init(&p, w, h), 0);
        for (int rep = 0; rep < 2; rep++) { /* also: a second frame on a used pyramid */
            load(&p, &im, pool);
            fv_pullpush(&p, &d, pool);
            char what[64];
            snprintf(what, sizeof what, "pool of %d (frame %d) vs no pool", sizes[i], rep);
            assert_pyramids_equal(&ref, &p, what);
        }
        fv_pyramid_free(&p);
        fv_pool_destroy(pool);
    }
    fv_pyramid_free(&ref);
    img_free(&im);
}

/* A used pyramid (other content, stale borders) gives the same result as a fresh one. */
static void test_reuse(void **state)
{
    (void)state;
    const int w = 257, h = 129;
    image a = img_new(w, h), b = img_new(w, h);
    foveated(&a, 30, 40, 20, 0.05, 50);
    foveated(&b, 200, 100, 15, 0.02, 40);
    fv_pullpush_dsp d;
    fv_pullpush_dsp_init(&d, ~0u);
    fv_pyramid fresh, used;
    assert_int_equal(fv_pyramid_init(&fresh, w, h), 0);
    assert_int_equal(fv_pyramid_init(&used, w, h), 0);
    load(&used, &a, NULL);
    fv_pullpush(&used, &d, NULL);
    load(&used, &b, NULL);
    fv_pullpush(&used, &d, NULL);
    load(&fresh, &b, NULL);
    fv_pullpush(&fresh, &d, NULL);
    assert_pyramids_equal(&fresh, &used, "reused vs fresh pyramid");
    fv_pyramid_free(&fresh);
    fv_pyramid_free(&used);
    img_free(&a);
    img_free(&b);
}

/* Every ISA: the whole pull-push gives the C reference's bytes (the kernels' contract is
 * bit-identity), on a foveated input whose holes hold NaN / Inf. */
static void test_isa_matches_c(void **state)
{
    (void)state;
    static const int dims[][2] = { { 1281, 1441 }, { 13, 5 }, { 1, 7 }, { 96, 33 } };
    const unsigned isas = fv_cpu_isas();
    for (size_t i = 0; i < sizeof dims / sizeof dims[0]; i++) {
        const int w = dims[i][0], h = dims[i][1];
        image im = img_new(w, h);
        foveated(&im, 0.4 * w, 0.6 * h, 0.1 * w, 0.08, 0.2 * w + 1);
        fv_pullpush_dsp dc;
        fv_pullpush_dsp_init(&dc, FV_ISA_C);
        fv_pyramid ref;
        assert_int_equal(fv_pyramid_init(&ref, w, h), 0);
        load(&ref, &im, NULL);
        poison_holes(&ref);
        fv_pullpush(&ref, &dc, NULL);
        for (unsigned isa = 1; isa <= FV_ISA_NEON; isa <<= 1) {
            if (!(isas & isa))
                continue;
            fv_pullpush_dsp d;
            fv_pullpush_dsp_init(&d, isa);
            fv_pyramid p;
            assert_int_equal(fv_pyramid_init(&p, w, h), 0);
            load(&p, &im, NULL);
            poison_holes(&p);
            fv_pullpush(&p, &d, NULL);
            char what[64];
            snprintf(what, sizeof what, "%s vs c at %dx%d", fv_isa_name(isa), w, h);
            assert_pyramids_equal(&ref, &p, what);
            if (i == 0)
                printf("[ pullpush ] whole pull-push %s == c (bit-exact)\n", fv_isa_name(isa));
            fv_pyramid_free(&p);
        }
        fv_pyramid_free(&ref);
        img_free(&im);
    }
}

/* The C reference kernels against the paper's formulas evaluated in double precision. */
static void test_reference_formulas(void **state)
{
    (void)state;
    enum { N = 37 };
    float a[8 * N], b[8 * N], wa[2 * N], wb[2 * N], out[4 * N], ow[N];
    for (int i = 0; i < 8 * N; i++)
        a[i] = fv_test_randf(&rng) * 10, b[i] = fv_test_randf(&rng) * 10;
    for (int i = 0; i < 2 * N; i++) {
        wa[i] = fv_test_randf(&rng) < 0.3f ? 0.0f : fv_test_randf(&rng);
        wb[i] = fv_test_randf(&rng) < 0.3f ? 0.0f : 1.0f;
    }
    fv_pull_row_c(out, ow, a, wa, b, wb, N);
    for (int x = 0; x < N; x++) {
        const double w4[4] = { wa[2 * x], wa[2 * x + 1], wb[2 * x], wb[2 * x + 1] };
        const float *c4[4] = { a + 8 * x, a + 8 * x + 4, b + 8 * x, b + 8 * x + 4 };
        const double sw = w4[0] + w4[1] + w4[2] + w4[3];
        assert_float_equal(ow[x], fmin(1.0, sw), 1e-6);
        for (int c = 0; c < 4; c++) {
            double t = 0;
            for (int k = 0; k < 4; k++)
                t += w4[k] * c4[k][c];
            const double want = sw > 0 ? t / sw : 0;
            assert_true(fabs(out[4 * x + c] - want) <= 1e-6 * fmax(1, fabs(want)));
        }
    }
    /* push: hole pixels get 9/16 (own coarse), 3/16 (horizontal, vertical neighbour), 1/16 (diagonal) */
    float nr[4 * (N + 3)], fr[4 * (N + 3)], fine[4 * 2 * N], orig[4 * 2 * N], fw[2 * N];
    for (int i = 0; i < 4 * (N + 3); i++)
        nr[i] = fv_test_randf(&rng) * 5, fr[i] = fv_test_randf(&rng) * 5;
    for (int i = 0; i < 2 * N; i++)
        fw[i] = i % 3 == 0 ? 0.0f : i % 3 == 1 ? 1.0f : fv_test_randf(&rng);
    for (int i = 0; i < 8 * N; i++)
        orig[i] = fine[i] = fv_test_randf(&rng) * 5;
    const float *cn = nr + 4, *cf = fr + 4;
    fv_push_row_c(fine, fw, cn, cf, 2 * N);
    for (int x = 0; x < 2 * N; x++) {
        const int X = x / 2, Xf = (x & 1) ? X + 1 : X - 1;
        for (int c = 0; c < 4; c++) {
            const double ip = 9.0 / 16 * cn[4 * X + c] + 3.0 / 16 * cn[4 * Xf + c] + 3.0 / 16 * cf[4 * X + c] +
                              1.0 / 16 * cf[4 * Xf + c];
            const double cv = fw[x] > 0 ? orig[4 * x + c] : 0;
            const double want = cv + (1.0 - fw[x]) * (ip - cv);
            assert_true(fabs(fine[4 * x + c] - want) <= 1e-6 * fmax(1, fabs(want)));
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_init),
        cmocka_unit_test(test_reference_formulas),
        cmocka_unit_test(test_constant_with_holes),
        cmocka_unit_test(test_linear_ramp),
        cmocka_unit_test(test_ramp_even_grid),
        cmocka_unit_test(test_hole_free_unchanged),
        cmocka_unit_test(test_single_sample),
        cmocka_unit_test(test_empty_image),
        cmocka_unit_test(test_thread_count_invariance),
        cmocka_unit_test(test_reuse),
        cmocka_unit_test(test_isa_matches_c),
    };
    return cmocka_run_group_tests_name("pullpush", tests, NULL, NULL);
}
