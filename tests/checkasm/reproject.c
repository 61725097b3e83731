/* fovea checkasm: the temporal reprojection kernels (reproject_dsp.h), every ISA version against
 * the C reference on random histories, cameras and blocks, bit for bit. Outputs are canaried
 * (checkasm.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "checkasm.h"

#include "camera.h"
#include "reproject.h"
#include "reproject_dsp.h"

static const int sizes[] = { 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 15, 16, 17, 31, 32, 33, 63, 64, 65, 640, 641, 1281 };
#define NSIZES ((int)(sizeof sizes / sizeof sizes[0]))

static float rnd(void) { return checkasm_randf(); }

static void assert_finite(const float *v, size_t count, const char *kernel, int n)
{
    for (size_t i = 0; i < count; i++)
        if (!isfinite(v[i]))
            fail_msg("c %s n=%d: reference output %zu is %g although every used input is finite", kernel, n, i,
                     (double)v[i]);
}

static void compare(const float *ref, const float *got, size_t count, int per_px, const char *isa,
                    const char *kernel, const char *what, int n, int off, int mode)
{
    checkasm_compare(ref, got, count, CHECKASM_F32, (size_t)per_px, CHECKASM_EXACT, "%s %s (%s) n=%d offset=%d mode=%d",
                     isa, kernel, what, n, off, mode);
}

/* ------------------------------------------------------------------ tables */

static const char *const names[] = {"taa_blend", "taa_fill", "taa_still", "taa_aa"};

/* Every ISA this build has an init for must implement every kernel (checkasm.h); the C table
 * holds the references. Also seeds the module's inputs. */
static void test_tables(void **state)
{
    (void)state;
    checkasm_rng = 0x7aa2018ull;
    fv_reproject_dsp ref;
    fv_reproject_dsp_init(&ref, FV_ISA_C);
    assert_true(ref.taa_blend == fv_taa_blend_c);
    assert_true(ref.taa_fill == fv_taa_fill_c);
    assert_true(ref.taa_still == fv_taa_still_c);
    assert_true(ref.taa_aa == fv_taa_aa_tile_c);
    CHECKASM_CHECK_ISA_TABLES("reproject", fv_reproject_dsp, &ref, names);
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
                float wt = wmode == 0 ? (float)(fv_test_rand(&checkasm_rng) & 1) : wmode == 1 ? (rnd() < 0.2f ? 0.0f : rnd()) : 0.0f;
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
        rgbd[4 * i + 3] = v < 0.1f ? depths[fv_test_rand(&checkasm_rng) % 5] : v < 0.3f ? 0.3f + 30.0f * r1 * r2
                                                                          : 3.0f * (1.0f + 0.04f * (r1 - 0.5f));
    }
}

static const char *motion_name[3] = { "identity", "small", "large" };
static long taa_blended, taa_quincunx, taa_filled; /* how often the paths really ran */

/* One block of w pixels by h rows (rows stride pixels apart; the padding between rows is part of
 * the buffer and must come back untouched) at a random place of the image. */
static int run_taa(const fv_reproject_dsp *d, const char *isa, const fv_taa_frame *f, int w, int h, int pad, int off, int motion)
{
    const int W = (int)f->prev_w, H = (int)f->prev_h;
    const int x0 = (int)(fv_test_rand(&checkasm_rng) % (unsigned)(W - w + 1)), y0 = (int)(fv_test_rand(&checkasm_rng) % (unsigned)(H - h + 1));
    const ptrdiff_t stride = w + pad;
    const size_t n = (size_t)(h - 1) * (size_t)stride + (size_t)w; /* pixels in the buffer */
    /* footprints of one texel, of several levels, and wide enough for quincunx taps */
    static const float widen[] = { 1.0f, 1.0f, 1.3f, 2.2360680f, 2.6f, 3.0f, 4.0f, 9.0f };
    fv_taa_tile t = { 1.0f, 1.0f, 0, 0 };
    t.widen = widen[fv_test_rand(&checkasm_rng) % 8]; /* one statement each: the draws' order is fixed */
    t.alpha = 0.05f + 0.95f * rnd();
    /* fill flow: small, or far enough that rows / runs leave the previous image */
    const int big = fv_test_rand(&checkasm_rng) % 8 == 0;
    t.flow_x = (int)(fv_test_rand(&checkasm_rng) % 7) - 3;
    if (big)
        t.flow_x += (int)(fv_test_rand(&checkasm_rng) % (unsigned)(2 * W)) - W;
    t.flow_y = (int)(fv_test_rand(&checkasm_rng) % 7) - 3;
    if (big)
        t.flow_y += (int)(fv_test_rand(&checkasm_rng) % (unsigned)(2 * H)) - H;
    buf rc = checkasm_out_f32(4 * n, off), rw = checkasm_out_f32(n, off);
    buf tc = checkasm_out_f32(4 * n, off), tw = checkasm_out_f32(n, off);
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
    checkasm_check_guards_f32(&tc, 4 * n, isa, "taa_blend", w);
    checkasm_check_guards_f32(&tw, n, isa, "taa_blend", w);
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
    checkasm_check_guards_f32(&tc, 4 * n, isa, "taa_fill", w);
    checkasm_check_guards_f32(&tw, n, isa, "taa_fill", w);
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
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "taa"))
            continue;
        fv_reproject_dsp d;
        fv_reproject_dsp_init(&d, isa);
        if (!d.taa_blend || !d.taa_fill || d.taa_blend == fv_taa_blend_c || d.taa_fill == fv_taa_fill_c)
            fail_msg("taa: %s has no version of its own", fv_isa_name(isa)); /* a failure, not a skip */
        int runs = 0;
        checkasm_rng = 0x7aa2018ull; /* the same inputs for every ISA and every compiler */
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
                        /* single rows of the edge-case widths first, then random blocks up to 64x16,
                         * the last ones up to 64x40 (the SIMD blends list samples 16 rows at a time) */
                        int w = 1 + (int)(fv_test_rand(&checkasm_rng) % (unsigned)wmax);
                        const int hmax = r < 36 ? 16 : 40;
                        int h = r < 20 ? 1 : 1 + (int)(fv_test_rand(&checkasm_rng) % (unsigned)(H < hmax ? H : hmax));
                        if (r < NSIZES && sizes[r] <= wmax)
                            w = sizes[r];
                        const int pad = (int)(fv_test_rand(&checkasm_rng) % 6), off = (int)(fv_test_rand(&checkasm_rng) % 4);
                        runs += run_taa(&d, fv_isa_name(isa), &f, w, h, pad, off, motion);
                    }
                    fv_pyramid_free(&hist);
                }
        printf("[ checkasm ] taa_blend, taa_fill: %-7s == c on %d blocks (bit-exact); %ld samples blended "
               "(%ld with wide footprints), %ld holes filled\n", fv_isa_name(isa), runs, taa_blended, taa_quincunx,
               taa_filled);
        /* the inputs must really exercise the blend, the quincunx taps and the fill */
        assert_true(taa_blended > 1000 && taa_quincunx > 100 && taa_filled > 500);
        taa_blended = taa_quincunx = taa_filled = 0;
        tested++;
    }
    printf("[ checkasm ] taa: %d ISA version(s) tested\n", tested);
}

/* ------------------------------------------------------------------ the still head's blend */

/* taa_still on n samples in planes pad floats longer than n (SoA, canaried): sample depths mostly
 * on their history texel's surface (within and beyond the tolerance), some on another, the miss
 * depth, 0 (1/0: NaN footprints); weights 0, 1, in between; footprint scales on both sides of two
 * texels (fp = depth / depth x widen) and history shares around the texel's confidence. Counts
 * the blended and the wide lanes. */
static long still_blended, still_wide;
static void run_still(const fv_reproject_dsp *d, const char *isa, int n, int pad, int off)
{
    static const float widens[] = {1.0f, 1.0001f, 1.3f, 1.99f, 2.0f, 2.5f, 4.0f};
    static const float alphas[] = {0.3f, 0.83f, 0.05f, 0.999f};
    const float widen = widens[fv_test_rand(&checkasm_rng) % 7];
    const float alpha = alphas[fv_test_rand(&checkasm_rng) % 4];
    const ptrdiff_t plane = n + pad;
    float *in = malloc(sizeof(float) * (size_t)(9 * plane + 1));
    assert_non_null(in);
    float *hs = in + 4 * plane;
    for (int k = 0; k < n; k++) {
        for (int c = 0; c < 3; c++) {
            in[c * plane + k] = rnd();
            hs[c * plane + k] = rnd();
        }
        const float v = rnd(), dep = v < 0.03f ? 1000.0f : v < 0.05f ? 0.0f : 0.3f + 30.0f * rnd() * rnd();
        in[3 * plane + k] = dep;
        const float u = rnd();
        hs[3 * plane + k] = u < 0.7f ? dep * (1.0f + 0.08f * (rnd() - 0.5f)) : u < 0.9f ? 0.3f + 30.0f * rnd() : dep;
        const float q = rnd();
        hs[4 * plane + k] = q < 0.2f ? 0.0f : q < 0.6f ? 1.0f : rnd();
    }
    buf rs = checkasm_out_f32(4 * (size_t)plane, off), ts = checkasm_out_f32(4 * (size_t)plane, off);
    uint8_t *rb, *tb, *rw = checkasm_out_u8((size_t)n, off, &rb), *tw = checkasm_out_u8((size_t)n, off, &tb);
    for (int c = 0; c < 4; c++) {
        memcpy(rs.p + c * plane, in + c * plane, sizeof(float) * (size_t)n);
        memcpy(ts.p + c * plane, in + c * plane, sizeof(float) * (size_t)n);
    }
    fv_taa_still_c(rs.p, hs, plane, n, widen, alpha, 30.0f, rw);
    d->taa_still(ts.p, hs, plane, n, widen, alpha, 30.0f, tw);
    checkasm_compare(rs.p, ts.p, 4 * (size_t)plane, CHECKASM_F32, 1, CHECKASM_EXACT, "%s taa_still (samples) n=%d pad=%d off=%d",
                     isa, n, pad, off);
    checkasm_compare(rw, tw, (size_t)n, CHECKASM_U8, 1, CHECKASM_EXACT, "%s taa_still (wide) n=%d", isa, n);
    checkasm_check_guards_f32(&ts, 4 * (size_t)plane, isa, "taa_still", n);
    checkasm_check_guards(tw, (size_t)n, isa, "taa_still", n);
    for (int k = 0; k < n; k++) {
        still_wide += rw[k];
        still_blended += rs.p[k] != in[k];
    }
    free(rs.base), free(ts.base), free(rb), free(tb), free(in);
}

static void test_taa_still(void **state)
{
    (void)state;
    int tested = 0;
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "taa_still"))
            continue;
        fv_reproject_dsp d;
        fv_reproject_dsp_init(&d, isa);
        if (!d.taa_still || d.taa_still == fv_taa_still_c)
            fail_msg("taa_still: %s has no version of its own", fv_isa_name(isa));
        checkasm_rng = 0x57111ull; /* the same inputs for every ISA */
        int runs = 0;
        for (int r = 0; r < 3; r++)
            for (int i = 0; i < NSIZES; i++, runs++)
                run_still(&d, fv_isa_name(isa), sizes[i], (int)(fv_test_rand(&checkasm_rng) % 9),
                          (int)(fv_test_rand(&checkasm_rng) % 4));
        run_still(&d, fv_isa_name(isa), 0, 0, 0);
        printf("[ checkasm ] taa_still: %-7s == c on %d runs (bit-exact); %ld samples blended, %ld wide\n",
               fv_isa_name(isa), runs, still_blended, still_wide);
        assert_true(still_blended > 2000 && still_wide > 1000);
        still_blended = still_wide = 0;
        tested++;
    }
    printf("[ checkasm ] taa_still: %d ISA version(s) tested\n", tested);
}

/* ------------------------------------------------------------------ the fovea's anti-aliasing */

/* taa_aa on tiles of a W x H image (level 0 all samples, as the AA tiles are): history weights
 * per wmode (0/1, random with holes, all 0, or all 1 but a few holes so Catmull-Rom's 16 texels
 * are often complete), the history read from the pyramid or from a snapshot copy of its level 0
 * (the still head's h_* view), counts 0 .. FV_TAA_AA_MAX_N (max included), tiles anywhere
 * (image edges, partial tw / th < 16). Everything the kernel may write (the whole level 0 and
 * the whole count plane) is compared. */
static long aa_blended, aa_hist, aa_max_n; /* how often the paths really ran (C reference) */
typedef struct {
    int W, H, motion, snap, no_prev, no_frame;
    const fv_taa_frame *f;
    const fv_pyramid *hist;
    const uint8_t *n_prev;
} aa_case;

static void run_aa(fv_taa_aa_fn fn, const char *isa, const aa_case *c)
{
    const int W = c->W, H = c->H;
    int tw = 1 + (int)(fv_test_rand(&checkasm_rng) % 16), th = 1 + (int)(fv_test_rand(&checkasm_rng) % 16);
    if (fv_test_rand(&checkasm_rng) % 2) /* whole tiles half the time */
        tw = th = 16;
    tw = tw < W ? tw : W, th = th < H ? th : H;
    const unsigned e = (unsigned)(fv_test_rand(&checkasm_rng) % 4); /* at the image's edges, or anywhere */
    int x0 = (int)(fv_test_rand(&checkasm_rng) % (unsigned)(W - tw + 1));
    int y0 = (int)(fv_test_rand(&checkasm_rng) % (unsigned)(H - th + 1));
    x0 = e == 1 ? 0 : e == 2 ? W - tw : x0;
    y0 = e == 1 ? H - th : e == 2 ? 0 : y0;
    fv_pyramid cur;
    assert_int_equal(fv_pyramid_init(&cur, W, H), 0);
    fv_pyr_level *L = &cur.lv[0];
    const size_t n = (size_t)L->stride * (size_t)(H + 2); /* the level with its border */
    float *base = L->rgbd - 4 * (L->stride + 1);
    for (size_t i = 0; i < n; i++) {
        for (int k = 0; k < 3; k++) { /* some +-0 (which zero min / max pick never shows: hc + alpha (s - hc)) */
            const float u = rnd(), r = rnd();
            base[4 * i + k] = u < 0.04f ? 0.0f : u < 0.08f ? -0.0f : r;
        }
        const float v = rnd(), r1 = rnd();
        base[4 * i + 3] = v < 0.15f ? 0.3f + 30.0f * r1 : v < 0.2f ? 1000.0f : 3.0f * (1.0f + 0.04f * (r1 - 0.5f));
    }
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            L->wgt[(ptrdiff_t)y * L->stride + x] = 1.0f;
    float *ref = malloc(4 * n * sizeof(float)), *in = malloc(4 * n * sizeof(float));
    assert_non_null(ref);
    assert_non_null(in);
    memcpy(in, base, 4 * n * sizeof(float));
    uint8_t *nc_base, *nt_base;
    const size_t nn = (size_t)W * (size_t)H;
    uint8_t *nr = checkasm_out_u8(nn, (int)(fv_test_rand(&checkasm_rng) % 4), &nc_base);
    uint8_t *nt = checkasm_out_u8(nn, (int)(fv_test_rand(&checkasm_rng) % 4), &nt_base);
    memset(nr, 0xa5, nn), memset(nt, 0xa5, nn); /* counts outside the tile must stay */
    fv_taa_aa_frame a;
    memset(&a, 0, sizeof a);
    a.n_prev = c->no_prev ? NULL : c->n_prev;
    a.stride = W;
    a.ox = rnd(), a.oy = rnd();
    float *snap = NULL;
    if (c->snap && c->hist) { /* level 0 with its border ring, as fv_taa_aa_snapshot copies it */
        const fv_pyr_level *h0 = &c->hist->lv[0];
        const int bw = W + 2, bh = H + 2;
        snap = malloc((size_t)bw * (size_t)bh * 5 * sizeof(float));
        assert_non_null(snap);
        for (int y = -1; y <= H; y++) {
            const ptrdiff_t o = (ptrdiff_t)y * h0->stride - 1, r = (ptrdiff_t)(y + 1) * bw;
            memcpy(snap + 4 * r, h0->rgbd + 4 * o, (size_t)bw * 4 * sizeof(float));
            memcpy(snap + (size_t)bw * (size_t)bh * 4 + r, h0->wgt + o, (size_t)bw * sizeof(float));
        }
        a.h_rgbd = snap, a.h_wgt = snap + (size_t)bw * (size_t)bh * 4, a.h_stride = bw, a.h_x0 = -1, a.h_y0 = -1;
    }
    const fv_taa_frame *f = c->no_frame ? NULL : c->f;
    a.n_cur = nr;
    fv_taa_aa_tile_c(f, &a, L, x0, y0, tw, th);
    memcpy(ref, base, 4 * n * sizeof(float));
    for (int y = 0; y < th; y++)
        for (int x = 0; x < tw; x++) {
            const uint8_t k = nr[(size_t)(y0 + y) * (size_t)W + (size_t)(x0 + x)];
            aa_hist += k > 1, aa_max_n += k == FV_TAA_AA_MAX_N;
            const ptrdiff_t o = (ptrdiff_t)(y0 + y + 1) * L->stride + x0 + x + 1;
            aa_blended += memcmp(in + 4 * o, ref + 4 * o, 3 * sizeof(float)) != 0;
        }
    memcpy(base, in, 4 * n * sizeof(float));
    a.n_cur = nt;
    fn(f, &a, L, x0, y0, tw, th);
    char ctx[160];
    snprintf(ctx, sizeof ctx, "%s taa_aa %dx%d tile %dx%d at (%d, %d) motion=%s snapshot=%d no_prev=%d no_frame=%d", isa,
             W, H, tw, th, x0, y0, motion_name[c->motion], c->snap, c->no_prev, c->no_frame);
    checkasm_compare(ref, base, 4 * n, CHECKASM_F32, 4, CHECKASM_EXACT, "%s (pixels)", ctx);
    checkasm_compare(nr, nt, nn, CHECKASM_U8, 1, CHECKASM_EXACT, "%s (counts)", ctx);
    checkasm_check_guards(nt, nn, isa, "taa_aa", tw);
    assert_finite(ref, 4 * n, "taa_aa", tw);
    free(nc_base), free(nt_base), free(ref), free(in), free(snap);
    fv_pyramid_free(&cur);
}

static void test_taa_aa(void **state)
{
    (void)state;
    int tested = 0;
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "taa_aa"))
            continue;
        fv_reproject_dsp d;
        fv_reproject_dsp_init(&d, isa);
        if (!d.taa_aa || d.taa_aa == fv_taa_aa_tile_c)
            fail_msg("taa_aa: %s has no version of its own", fv_isa_name(isa));
        checkasm_rng = 0xaa14ull; /* the same inputs for every ISA */
        int runs = 0;
        static const int dims[][2] = { { 67, 53 }, { 40, 37 }, { 16, 16 }, { 5, 3 } };
        for (int di = 0; di < 4; di++)
            for (int wmode = 0; wmode < 4; wmode++)
                for (int motion = 0; motion < 3; motion++) {
                    const int W = dims[di][0], H = dims[di][1];
                    fv_pyramid hist;
                    random_history(&hist, W, H, wmode < 3 ? wmode : 0);
                    for (int y = -1; y <= H; y++) /* colours +-0 too (run_aa's samples have them) */
                        for (int x = -1; x <= W; x++) {
                            float *t = hist.lv[0].rgbd + 4 * ((ptrdiff_t)y * hist.lv[0].stride + x);
                            for (int ch = 0; ch < 3; ch++) {
                                const float u = rnd();
                                t[ch] = u < 0.1f ? 0.0f : u < 0.2f ? -0.0f : t[ch];
                            }
                        }
                    if (wmode == 3) /* all samples but a few holes */
                        for (int y = 0; y < H; y++)
                            for (int x = 0; x < W; x++)
                                hist.lv[0].wgt[(ptrdiff_t)y * hist.lv[0].stride + x] = rnd() < 0.03f ? 0.0f : 1.0f;
                    fv_camera cur, prev;
                    random_cameras(&cur, &prev, W, H, motion);
                    fv_taa_frame f;
                    fv_taa_frame_setup(&f, &cur, &prev, &hist, 0.03f);
                    uint8_t *np = malloc((size_t)W * (size_t)H);
                    assert_non_null(np);
                    for (int i = 0; i < W * H; i++) { /* counts 0 .. MAX_N, the cap often */
                        const unsigned r = (unsigned)(fv_test_rand(&checkasm_rng) % 24);
                        np[i] = (uint8_t)(r > FV_TAA_AA_MAX_N ? FV_TAA_AA_MAX_N : r);
                    }
                    for (int r = 0; r < 24; r++) {
                        aa_case c = { W, H, motion, r % 3 == 1, r == 7, r == 13, &f, &hist, np };
                        run_aa(d.taa_aa, fv_isa_name(isa), &c);
                        runs++;
                    }
                    free(np);
                    fv_pyramid_free(&hist);
                }
        printf("[ checkasm ] taa_aa: %-7s == c on %d tiles (bit-exact); %ld pixels blended with history, %ld "
               "changed, %ld at n = %d\n", fv_isa_name(isa), runs, aa_hist, aa_blended, aa_max_n, FV_TAA_AA_MAX_N);
        assert_true(aa_hist > 5000 && aa_blended > 5000 && aa_max_n > 500);
        aa_blended = aa_hist = aa_max_n = 0;
        tested++;
    }
    printf("[ checkasm ] taa_aa: %d ISA version(s) tested\n", tested);
}

const struct CMUnitTest checkasm_reproject_tests[] = {
    cmocka_unit_test(test_tables),
    cmocka_unit_test(test_taa_blocks),
    cmocka_unit_test(test_taa_still),
    cmocka_unit_test(test_taa_aa),
    {0},
};
