/* fovea: checkasm-style kernel tests (in the spirit of dav1d's tests/checkasm). Every kernel in
 * fv_dsp, for every ISA this machine runs, is compared against its plain-C reference on random
 * and edge-case inputs. The contract (dsp.h) is bit-identity for finite inputs, so the
 * comparison is exact (bitwise, which also catches -0 vs +0). Inputs live in exact-size heap
 * buffers (ASan catches any over-read); outputs are framed by canaries that must survive.
 * Deterministic: a fixed-seed splitmix64 PRNG. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "camera.h"
#include "dsp.h"
#include "pullpush.h"
#include "reproject.h"

#define CANARY 16 /* floats checked after (and 4 before) every output row */
static const uint32_t canary_bits = 0x7fc0dead; /* a NaN no kernel computes */

static const int sizes[] = { 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 15, 16, 17, 31, 32, 33, 63, 64, 65, 640, 641, 1281 };
#define NSIZES ((int)(sizeof sizes / sizeof sizes[0]))

/* M_GARBAGE: zero-weight pixels hold NaN / Inf / huge colours, which the contract says are never used */
/* M_BINARY_EXTREME: weights 0/1 only (the ray tracer's level 0, a separate fast path in some
 * kernels) with extreme colours */
enum { M_RANDOM, M_BINARY, M_ZERO_W, M_ONE_W, M_EXTREME, M_GARBAGE, M_BINARY_EXTREME, M_COUNT };
static const char *mode_name[M_COUNT] = { "random",       "binary-w", "all-w-0",        "all-w-1",
                                          "extreme",      "hole-garbage", "binary-w-extreme" };

static const unsigned isa_list[] = {
#if defined(__x86_64__)
    FV_ISA_SSE41, FV_ISA_AVX2,
#elif defined(__aarch64__)
    FV_ISA_NEON,
#endif
    0 /* sentinel */
};

static uint64_t rng = 0x5eed0f0bea2018ull;

static float rnd(void) { return fv_test_randf(&rng); }

static float gen_weight(int mode)
{
    static const float ext[] = { 0.0f, 1.0f, 1.0f, 0.0f, 1e-30f, 1e-7f, 0.5f, 0.99999994f, 1e-38f };
    switch (mode) {
    case M_BINARY:
    case M_BINARY_EXTREME: return (fv_test_rand(&rng) & 1) ? 1.0f : 0.0f;
    case M_ZERO_W: return 0.0f;
    case M_ONE_W: return 1.0f;
    case M_EXTREME: return ext[fv_test_rand(&rng) % (sizeof ext / sizeof ext[0])];
    default: {
        const float u = rnd();
        return u < 0.3f ? 0.0f : u < 0.5f ? 1.0f : rnd();
    }
    }
}

static float gen_value(int mode, int channel)
{
    static const float ext[] = { 0.0f, -0.0f, 1e-30f, 1.4e-45f, 1e-38f, 1e4f, 3e4f, 0.5f, 1e-7f, 65504.0f, 1.0f };
    if (mode == M_EXTREME || mode == M_BINARY_EXTREME)
        return ext[fv_test_rand(&rng) % (sizeof ext / sizeof ext[0])];
    return channel == 3 ? 0.1f + 100.0f * rnd() : rnd();
}

/* exact-size buffers: buf_new in testutil.h */

/* An output row with 4 canaries before and CANARY after. */
static buf out_new(size_t count, int off)
{
    buf b;
    b.base = malloc((count + (size_t)off + 4 + CANARY) * sizeof(float));
    assert_non_null(b.base);
    b.p = b.base + off + 4;
    for (int i = 0; i < 4; i++)
        memcpy(b.p - 1 - i, &canary_bits, 4);
    for (int i = 0; i < CANARY; i++)
        memcpy(b.p + count + i, &canary_bits, 4);
    return b;
}

static void check_canaries(const buf *b, size_t count, const char *isa, const char *kernel, int n)
{
    for (int i = -4; i < CANARY; i++) {
        const float *q = i < 0 ? b->p + i : b->p + count + i;
        uint32_t v;
        memcpy(&v, q, 4);
        if (v != canary_bits)
            fail_msg("%s %s n=%d: wrote outside its output row (canary at index %s%d clobbered)", isa, kernel,
                     n, i < 0 ? "" : "n+", i);
    }
}

static void compare(const float *ref, const float *got, size_t count, int per_px, const char *isa,
                    const char *kernel, const char *what, int n, int off, int mode)
{
    for (size_t i = 0; i < count; i++) {
        uint32_t a, b;
        memcpy(&a, ref + i, 4);
        memcpy(&b, got + i, 4);
        if (a != b)
            fail_msg("%s %s (%s) n=%d offset=%d mode=%s: pixel %zu channel %zu: c=%.9g (%a) %s=%.9g (%a)", isa,
                     kernel, what, n, off, mode_name[mode], i / (size_t)per_px, i % (size_t)per_px, (double)ref[i],
                     (double)ref[i], isa, (double)got[i], (double)got[i]);
    }
}

/* Zero-weight pixels get colours that must never be used. */
static void garbage(float *rgbd, const float *w, size_t px, int mode)
{
    if (mode != M_GARBAGE)
        return;
    const float bad[] = { NAN, -NAN, INFINITY, -INFINITY, 3e38f, -3e38f };
    for (size_t i = 0; i < px; i++)
        if (w[i] == 0.0f)
            for (int c = 0; c < 4; c++)
                rgbd[4 * i + (size_t)c] = bad[fv_test_rand(&rng) % (sizeof bad / sizeof bad[0])];
}

static void assert_finite(const float *v, size_t count, const char *kernel, int n)
{
    for (size_t i = 0; i < count; i++)
        if (!isfinite(v[i]))
            fail_msg("c %s n=%d: reference output %zu is %g although every used input is finite", kernel, n, i,
                     (double)v[i]);
}

static void fill(float *p, size_t px, int channels, int mode, int weights)
{
    for (size_t i = 0; i < px; i++)
        for (int c = 0; c < channels; c++)
            p[i * (size_t)channels + (size_t)c] = weights ? gen_weight(mode) : gen_value(mode, c);
}

/* ------------------------------------------------------------------ pull_row */

static int run_pull(fv_pull_row_fn fn, const char *isa, int n, int off, int mode)
{
    const size_t sn = 2 * (size_t)n;
    buf a = buf_new(4 * sn, off), aw = buf_new(sn, off), b = buf_new(4 * sn, off), bw = buf_new(sn, off);
    fill(a.p, sn, 4, mode, 0);
    fill(b.p, sn, 4, mode, 0);
    fill(aw.p, sn, 1, mode, 1);
    fill(bw.p, sn, 1, mode, 1);
    garbage(a.p, aw.p, sn, mode);
    garbage(b.p, bw.p, sn, mode);
    buf rc = out_new(4 * (size_t)n, off), rw = out_new((size_t)n, off);
    buf tc = out_new(4 * (size_t)n, off), tw = out_new((size_t)n, off);
    fv_pull_row_c(rc.p, rw.p, a.p, aw.p, b.p, bw.p, n);
    fn(tc.p, tw.p, a.p, aw.p, b.p, bw.p, n);
    check_canaries(&tc, 4 * (size_t)n, isa, "pull_row", n);
    check_canaries(&tw, (size_t)n, isa, "pull_row", n);
    compare(rc.p, tc.p, 4 * (size_t)n, 4, isa, "pull_row", "rgbd", n, off, mode);
    compare(rw.p, tw.p, (size_t)n, 1, isa, "pull_row", "weight", n, off, mode);
    assert_finite(rc.p, 4 * (size_t)n, "pull_row", n);
    /* sanity of the reference itself on this input: weights in [0,1], all-zero -> zeros */
    for (int i = 0; i < n; i++) {
        assert_true(rw.p[i] >= 0.0f && rw.p[i] <= 1.0f);
        if (mode == M_ZERO_W)
            for (int c = 0; c < 4; c++)
                assert_true(rc.p[4 * i + c] == 0.0f);
    }
    free(a.base), free(aw.base), free(b.base), free(bw.base);
    free(rc.base), free(rw.base), free(tc.base), free(tw.base);
    return 1;
}

static void test_pull_row(void **state)
{
    (void)state;
    int tested = 0;
    for (int k = 0; isa_list[k]; k++) {
        const unsigned isa = isa_list[k];
        if (!(fv_cpu_isas() & isa)) {
            printf("[ kernels  ] pull_row: %-7s not on this CPU, skipped\n", fv_isa_name(isa));
            continue;
        }
        fv_dsp d;
        fv_dsp_init(&d, isa);
        assert_int_equal(d.isa, isa);
        if (d.pull_row == fv_pull_row_c) {
            printf("[ kernels  ] pull_row: %-7s has no version of its own, skipped\n", fv_isa_name(isa));
            continue;
        }
        int runs = 0;
        for (int si = 0; si < NSIZES; si++)
            for (int off = 0; off < 2; off++)
                for (int mode = 0; mode < M_COUNT; mode++)
                    runs += run_pull(d.pull_row, fv_isa_name(isa), sizes[si], off, mode);
        for (int r = 0; r < 200; r++) /* random sizes, offsets and modes */
            runs += run_pull(d.pull_row, fv_isa_name(isa), 1 + (int)(fv_test_rand(&rng) % 300),
                             (int)(fv_test_rand(&rng) % 4), (int)(fv_test_rand(&rng) % M_COUNT));
        printf("[ kernels  ] pull_row: %-7s == c on %d rows (bit-exact)\n", fv_isa_name(isa), runs);
        tested++;
    }
    printf("[ kernels  ] pull_row: %d ISA version(s) tested\n", tested);
}

/* ------------------------------------------------------------------ push_row */

static int run_push(fv_push_row_fn fn, const char *isa, int n, int off, int mode)
{
    const size_t cn = (size_t)(n + 1) / 2 + 2; /* coarse pixels -1 .. (n+1)/2 */
    buf nr = buf_new(4 * cn, off), fr = buf_new(4 * cn, off), w = buf_new((size_t)n, off);
    fill(nr.p, cn, 4, mode, 0);
    fill(fr.p, cn, 4, mode, 0);
    fill(w.p, (size_t)n, 1, mode, 1);
    buf rc = out_new(4 * (size_t)n, off), tc = out_new(4 * (size_t)n, off);
    fill(rc.p, (size_t)n, 4, mode, 0);
    garbage(rc.p, w.p, (size_t)n, mode);
    memcpy(tc.p, rc.p, 4 * (size_t)n * sizeof(float));
    float *orig = malloc(4 * (size_t)n * sizeof(float));
    assert_non_null(orig);
    memcpy(orig, rc.p, 4 * (size_t)n * sizeof(float));
    fv_push_row_c(rc.p, w.p, nr.p + 4, fr.p + 4, n);
    fn(tc.p, w.p, nr.p + 4, fr.p + 4, n);
    check_canaries(&tc, 4 * (size_t)n, isa, "push_row", n);
    compare(rc.p, tc.p, 4 * (size_t)n, 4, isa, "push_row", "rgbd", n, off, mode);
    /* sanity of the reference: w = 1 pixels keep their bits, the rest is finite */
    for (int i = 0; i < n; i++)
        if (w.p[i] == 1.0f)
            assert_memory_equal(orig + 4 * i, rc.p + 4 * i, 4 * sizeof(float));
        else
            assert_finite(rc.p + 4 * i, 4, "push_row", n);
    free(orig);
    free(nr.base), free(fr.base), free(w.base), free(rc.base), free(tc.base);
    return 1;
}

static void test_push_row(void **state)
{
    (void)state;
    int tested = 0;
    for (int k = 0; isa_list[k]; k++) {
        const unsigned isa = isa_list[k];
        if (!(fv_cpu_isas() & isa)) {
            printf("[ kernels  ] push_row: %-7s not on this CPU, skipped\n", fv_isa_name(isa));
            continue;
        }
        fv_dsp d;
        fv_dsp_init(&d, isa);
        assert_int_equal(d.isa, isa);
        if (d.push_row == fv_push_row_c) {
            printf("[ kernels  ] push_row: %-7s has no version of its own, skipped\n", fv_isa_name(isa));
            continue;
        }
        int runs = 0;
        for (int si = 0; si < NSIZES; si++)
            for (int off = 0; off < 2; off++)
                for (int mode = 0; mode < M_COUNT; mode++)
                    runs += run_push(d.push_row, fv_isa_name(isa), sizes[si], off, mode);
        for (int r = 0; r < 200; r++)
            runs += run_push(d.push_row, fv_isa_name(isa), 1 + (int)(fv_test_rand(&rng) % 300),
                             (int)(fv_test_rand(&rng) % 4), (int)(fv_test_rand(&rng) % M_COUNT));
        printf("[ kernels  ] push_row: %-7s == c on %d rows (bit-exact)\n", fv_isa_name(isa), runs);
        tested++;
    }
    printf("[ kernels  ] push_row: %d ISA version(s) tested\n", tested);
}

/* ------------------------------------------------------------------ reprojection */

/* A history pyramid with random content on every level (borders included): colours in [0, 1],
 * depths in [0.3, 30] m with some at the miss depth, weights per mode (0/1, random, all 0). */
static void random_history(fv_pyramid *h, int w, int hgt, int wmode)
{
    assert_int_equal(fv_pyramid_init(h, w, hgt), 0);
    for (int l = 0; l < h->levels; l++) {
        fv_pyr_level *L = &h->lv[l];
        for (int y = -1; y <= L->h; y++)
            for (int x = -1; x <= L->w; x++) {
                float *c = L->rgbd + 4 * ((ptrdiff_t)y * L->stride + x);
                for (int k = 0; k < 3; k++)
                    c[k] = rnd();
                const float u = rnd(), r1 = rnd(), r2 = rnd(); /* drawn in a fixed order */
                /* mostly one surface near 3 m (so history agrees with the samples and the blend
                 * and the fill really run), some texels elsewhere and some misses */
                c[3] = u < 0.05f ? 1000.0f : u < 0.3f ? 0.3f + 30.0f * r1 * r2 : 3.0f * (1.0f + 0.04f * (r1 - 0.5f));
                const int border = x < 0 || y < 0 || x >= L->w || y >= L->h;
                float wt = wmode == 0 ? (float)(fv_test_rand(&rng) & 1) : wmode == 1 ? (rnd() < 0.2f ? 0.0f : rnd()) : 0.0f;
                L->wgt[(ptrdiff_t)y * L->stride + x] = border ? 0.0f : wt;
            }
    }
}

/* Cameras of the current and previous frame: equal (identity), a small head motion, or a large
 * one that sends much of the image outside the previous frame. */
static void random_cameras(fv_camera *cur, fv_camera *prev, int w, int h, int motion)
{
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.width = w;
    d.height = h;
    fv_pose a = {{0.1f, 1.6f, 0.2f}, {0, 0, 0, 1}}, b = a;
    const float amt = motion == 1 ? 0.02f : 0.4f;
    if (motion) {
        for (int k = 0; k < 3; k++)
            b.pos[k] += amt * (rnd() - 0.5f);
        b.quat[0] = amt * (rnd() - 0.5f);
        b.quat[1] = amt * (rnd() - 0.5f);
        b.quat[2] = 0.3f * amt * (rnd() - 0.5f);
        fv_quat_normalize(b.quat);
    }
    assert_int_equal(fv_camera_setup(cur, &d, &a), 0);
    assert_int_equal(fv_camera_setup(prev, &d, &b), 0);
}

/* A row of n current pixels: samples (weight 1) with depths, holes (weight 0), and pixels of
 * other weights that both kernels must leave alone. */
static void random_row(float *rgbd, float *wgt, int n)
{
    static const float depths[] = { 1000.0f, 1e-3f, 0.31f, 2.0f, 7.5f };
    for (int i = 0; i < n; i++) {
        const float u = rnd();
        wgt[i] = u < 0.4f ? 1.0f : u < 0.9f ? 0.0f : rnd();
        for (int k = 0; k < 3; k++)
            rgbd[4 * i + k] = rnd();
        const float v = rnd(), r1 = rnd(), r2 = rnd(); /* drawn in a fixed order */
        rgbd[4 * i + 3] = v < 0.1f ? depths[fv_test_rand(&rng) % 5] : v < 0.3f ? 0.3f + 30.0f * r1 * r2
                                                                          : 3.0f * (1.0f + 0.04f * (r1 - 0.5f));
    }
}

static const char *motion_name[3] = { "identity", "small", "large" };
static long taa_blended, taa_quincunx, taa_filled; /* how often the paths really ran */

/* One block of w pixels by h rows (rows stride pixels apart; the padding between rows is part of
 * the buffer and must come back untouched) at a random place of the image. */
static int run_taa(const fv_dsp *d, const char *isa, const fv_taa_frame *f, int w, int h, int pad, int off, int motion)
{
    const int W = (int)f->prev_w, H = (int)f->prev_h;
    const int x0 = (int)(fv_test_rand(&rng) % (unsigned)(W - w + 1)), y0 = (int)(fv_test_rand(&rng) % (unsigned)(H - h + 1));
    const ptrdiff_t stride = w + pad;
    const size_t n = (size_t)(h - 1) * (size_t)stride + (size_t)w; /* pixels in the buffer */
    /* footprints of one texel, of several levels, and wide enough for quincunx taps */
    static const float widen[] = { 1.0f, 1.0f, 1.3f, 2.2360680f, 2.6f, 3.0f, 4.0f, 9.0f };
    fv_taa_tile t = { 1.0f, 1.0f, 0, 0 };
    t.widen = widen[fv_test_rand(&rng) % 8]; /* one statement each: the draws' order is fixed */
    t.alpha = 0.05f + 0.95f * rnd();
    /* fill flow: small, or far enough that rows / runs leave the previous image */
    const int big = fv_test_rand(&rng) % 8 == 0;
    t.flow_x = (int)(fv_test_rand(&rng) % 7) - 3;
    if (big)
        t.flow_x += (int)(fv_test_rand(&rng) % (unsigned)(2 * W)) - W;
    t.flow_y = (int)(fv_test_rand(&rng) % 7) - 3;
    if (big)
        t.flow_y += (int)(fv_test_rand(&rng) % (unsigned)(2 * H)) - H;
    buf rc = out_new(4 * n, off), rw = out_new(n, off);
    buf tc = out_new(4 * n, off), tw = out_new(n, off);
    random_row(rc.p, rw.p, (int)n);
    memcpy(tc.p, rc.p, 4 * n * sizeof(float));
    memcpy(tw.p, rw.p, n * sizeof(float));
    fv_taa_flow fr = { 0.5f, -0.25f, 3.0f }, ft = fr; /* sums continue from earlier calls */
    float *before = malloc(4 * n * sizeof(float)), *wbefore = malloc(n * sizeof(float));
    assert_non_null(before);
    assert_non_null(wbefore);
    memcpy(before, rc.p, 4 * n * sizeof(float));
    fv_taa_blend_c(f, &t, rc.p, rw.p, stride, x0, y0, w, h, &fr);
    for (size_t i = 0; i < n; i++)
        if (memcmp(before + 4 * i, rc.p + 4 * i, 3 * sizeof(float))) {
            if ((ptrdiff_t)(i % (size_t)stride) >= w)
                fail_msg("c taa_blend wrote into the padding between rows (pixel %zu)", i);
            taa_blended++;
            taa_quincunx += t.widen >= 2.6f;
        }
    d->taa_blend(f, &t, tc.p, tw.p, stride, x0, y0, w, h, &ft);
    check_canaries(&tc, 4 * n, isa, "taa_blend", w);
    check_canaries(&tw, n, isa, "taa_blend", w);
    compare(rc.p, tc.p, 4 * n, 4, isa, "taa_blend", motion_name[motion], w, off, 0);
    compare(rw.p, tw.p, n, 1, isa, "taa_blend", "weight", w, off, 0);
    compare(&fr.dx, &ft.dx, 3, 3, isa, "taa_blend", "flow sums", w, off, 0);
    assert_finite(rc.p, 4 * n, "taa_blend", w);
    memcpy(wbefore, rw.p, n * sizeof(float));
    fv_taa_fill_c(f, &t, rc.p, rw.p, stride, x0, y0, w, h);
    for (size_t i = 0; i < n; i++)
        if (wbefore[i] == 0.0f && rw.p[i] > 0.0f) {
            if ((ptrdiff_t)(i % (size_t)stride) >= w)
                fail_msg("c taa_fill wrote into the padding between rows (pixel %zu)", i);
            taa_filled++;
        } else if (wbefore[i] != rw.p[i]) { /* only holes are filled */
            fail_msg("c taa_fill changed the weight of pixel %zu from %g", i, (double)wbefore[i]);
        }
    free(before);
    free(wbefore);
    d->taa_fill(f, &t, tc.p, tw.p, stride, x0, y0, w, h);
    check_canaries(&tc, 4 * n, isa, "taa_fill", w);
    check_canaries(&tw, n, isa, "taa_fill", w);
    compare(rc.p, tc.p, 4 * n, 4, isa, "taa_fill", motion_name[motion], w, off, 0);
    compare(rw.p, tw.p, n, 1, isa, "taa_fill", "weight", w, off, 0);
    assert_finite(rc.p, 4 * n, "taa_fill", w);
    for (size_t i = 0; i < n; i++)
        assert_true(rw.p[i] >= 0.0f && rw.p[i] <= 1.0f);
    free(rc.base), free(rw.base), free(tc.base), free(tw.base);
    return 1;
}

static void test_taa_blocks(void **state)
{
    (void)state;
    int tested = 0;
    for (int k = 0; isa_list[k]; k++) {
        const unsigned isa = isa_list[k];
        if (!(fv_cpu_isas() & isa)) {
            printf("[ kernels  ] taa: %-7s not on this CPU, skipped\n", fv_isa_name(isa));
            continue;
        }
        fv_dsp d;
        fv_dsp_init(&d, isa);
        if (d.taa_blend == fv_taa_blend_c || d.taa_fill == fv_taa_fill_c) {
            printf("[ kernels  ] taa: %-7s has no version of its own, skipped\n", fv_isa_name(isa));
            continue;
        }
        int runs = 0;
        rng = 0x7aa2018ull; /* the same inputs for every ISA and every compiler */
        static const int dims[][2] = { { 67, 53 }, { 160, 180 }, { 9, 7 }, { 1, 1 } };
        for (int di = 0; di < 4; di++)
            for (int wmode = 0; wmode < 3; wmode++)
                for (int motion = 0; motion < 3; motion++) {
                    const int W = dims[di][0], H = dims[di][1];
                    fv_pyramid hist;
                    random_history(&hist, W, H, wmode);
                    fv_camera cur, prev;
                    random_cameras(&cur, &prev, W, H, motion);
                    fv_taa_frame f;
                    fv_taa_frame_setup(&f, &cur, &prev, &hist, 0.03f);
                    assert_int_equal(f.identity, motion == 0);
                    const int wmax = W < 64 ? W : 64;
                    for (int r = 0; r < 40; r++) {
                        /* single rows of the edge-case widths first, then random blocks up to 64x16 */
                        int w = 1 + (int)(fv_test_rand(&rng) % (unsigned)wmax);
                        int h = r < 20 ? 1 : 1 + (int)(fv_test_rand(&rng) % (unsigned)(H < 16 ? H : 16));
                        if (r < NSIZES && sizes[r] <= wmax)
                            w = sizes[r];
                        const int pad = (int)(fv_test_rand(&rng) % 6), off = (int)(fv_test_rand(&rng) % 4);
                        runs += run_taa(&d, fv_isa_name(isa), &f, w, h, pad, off, motion);
                    }
                    fv_pyramid_free(&hist);
                }
        printf("[ kernels  ] taa_blend, taa_fill: %-7s == c on %d blocks (bit-exact); %ld samples blended "
               "(%ld with wide footprints), %ld holes filled\n", fv_isa_name(isa), runs, taa_blended, taa_quincunx,
               taa_filled);
        /* the inputs must really exercise the blend, the quincunx taps and the fill */
        assert_true(taa_blended > 1000 && taa_quincunx > 100 && taa_filled > 500);
        taa_blended = taa_quincunx = taa_filled = 0;
        tested++;
    }
    printf("[ kernels  ] taa: %d ISA version(s) tested\n", tested);
}

/* ------------------------------------------------------------------ dispatch */

static void test_dispatch(void **state)
{
    (void)state;
    const unsigned have = fv_cpu_isas();
    printf("[ kernels  ] cpu ISAs:");
    for (unsigned b = 1; b <= FV_ISA_NEON; b <<= 1)
        if (have & b)
            printf(" %s", fv_isa_name(b));
    printf("%s\n", have ? "" : " (none: plain C only)");
    fv_dsp d;
    fv_dsp_init(&d, FV_ISA_C);
    assert_int_equal(d.isa, FV_ISA_C);
    assert_ptr_equal(d.pull_row, fv_pull_row_c);
    assert_ptr_equal(d.push_row, fv_push_row_c);
    assert_ptr_equal(d.taa_blend, fv_taa_blend_c);
    assert_ptr_equal(d.taa_fill, fv_taa_fill_c);
    fv_dsp_init(&d, ~0u); /* best: the highest ISA bit this CPU has */
    unsigned best = 0;
    for (unsigned b = 1; b <= FV_ISA_NEON; b <<= 1)
        if (have & b)
            best = b;
    assert_int_equal(d.isa, best);
    printf("[ kernels  ] fv_dsp_init(~0) selects %s\n", fv_isa_name(d.isa));
    assert_string_equal(fv_isa_name(FV_ISA_C), "c");
    assert_string_equal(fv_isa_name(12345), "?");
#if defined(__aarch64__)
    assert_true(have & FV_ISA_NEON);
#endif
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dispatch),
        cmocka_unit_test(test_pull_row),
        cmocka_unit_test(test_push_row),
        cmocka_unit_test(test_taa_blocks),
    };
    return cmocka_run_group_tests_name("kernels", tests, NULL, NULL);
}
