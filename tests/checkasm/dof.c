/* fovea checkasm: the depth-of-field kernels (dof/dof_dsp.h), every ISA version against the
 * plain-C references of core/dof/dof_ref.c on random and edge-case inputs, bit for bit (so -0 vs
 * +0 counts). Inputs live in exact-size heap buffers starting at odd offsets (ASan catches
 * over-reads); outputs are canaried rows (checkasm.h), so a write outside [x0, x0 + n) or past
 * the row shows. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkasm.h"

#include "dof/dof_dsp.h"
#include "dof/weier_impl.h"

static float rnd(void) { return fv_test_randf(&checkasm_rng); }
static int rndi(int n) { return (int)(fv_test_rand(&checkasm_rng) % (uint64_t)n); }

static fv_dof_gauss_tab tab;

/* a colour channel: mostly ordinary, sometimes signed zeros, tiny or large values, negatives */
static float colour(void)
{
    static const float ext[] = {0.0f, -0.0f, 1e-30f, -1e-30f, 1.4e-45f, 1e4f, 0.5f, 1.0f, -0.25f, 65504.0f};
    return rndi(8) == 0 ? ext[rndi((int)(sizeof ext / sizeof ext[0]))] : 2.0f * rnd() - 0.25f;
}

static unsigned long compared; /* floats compared, all ISAs */

static void compare(const float *ref, const float *got, size_t count, size_t per_px, const char *isa,
                    const char *kernel, const char *what)
{
    checkasm_compare(ref, got, count, CHECKASM_F32, per_px, CHECKASM_EXACT, "%s %s (%s)", isa, kernel, what);
    compared += count;
}

/* an output row (canaried, checkasm.h): its guards, then every float of it (the ones the call
 * must not write still hold the canary in both) */
static void compare_out(const buf *r, const buf *t, size_t count, size_t per_px, const char *isa, const char *kernel,
                        const char *what)
{
    checkasm_check_guards_f32(t, count, isa, kernel, (int)count);
    compare(r->p, t->p, count, per_px, isa, kernel, what);
}

typedef void (*runner)(const fv_dof_dsp *d, const char *isa);

static void run_all(const char *kernel, runner fn, size_t member)
{
    int tested = 0;
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, kernel))
            continue;
        fv_dof_dsp d, c;
        fv_dof_dsp_init(&d, isa);
        fv_dof_dsp_init(&c, FV_ISA_C);
        void *f, *fc;
        memcpy(&f, (const char *)&d + member, sizeof f);
        memcpy(&fc, (const char *)&c + member, sizeof fc);
        if (!f || f == fc) /* an ISA this build has must implement the kernel: a failure, not a skip */
            fail_msg("%s: %s has no version of its own", kernel, fv_isa_name(isa));
        const unsigned long before = compared;
        fn(&d, fv_isa_name(isa));
        printf("[ checkasm ] %s: %-7s bit-identical to C (%lu floats)\n", kernel, fv_isa_name(isa), compared - before);
        tested++;
    }
    if (!tested)
        printf("[ checkasm ] %s: no ISA version on this machine\n", kernel);
}

/* ------------------------------------------------------------------ tables */

static const char *const names[] = {"dof_coc_row", "dof_hgauss_row", "dof_vgauss_row", "dof_combine_row", "dof_upsample_row", "dof_pyrblur_row",
                                     "dof_nearblk_row", "dof_nearbox_row", "dof_periph_row", "dof_hcoc_row",
                                     "dof_nearfin_row"};

/* Every ISA this build has an init for must implement every kernel (checkasm.h); the C table
 * holds the references. Also seeds the module's inputs. */
static void test_tables(void **state)
{
    (void)state;
    checkasm_rng = 0xd0f5eed2026ull;
    fv_dof_gauss_tab_init(&tab);
    fv_dof_dsp ref;
    fv_dof_dsp_init(&ref, FV_ISA_C);
    assert_true(ref.dof_coc_row == fv_dof_coc_row_c);
    assert_true(ref.dof_hgauss_row == fv_dof_hgauss_row_c);
    assert_true(ref.dof_vgauss_row == fv_dof_vgauss_row_c);
    assert_true(ref.dof_combine_row == fv_dof_combine_row_c);
    assert_true(ref.dof_upsample_row == fv_dof_upsample_row_c);
    assert_true(ref.dof_pyrblur_row == fv_dof_pyrblur_row_c);
    assert_true(ref.dof_nearblk_row == fv_dof_nearblk_row_c);
    assert_true(ref.dof_nearbox_row == fv_dof_nearbox_row_c);
    assert_true(ref.dof_periph_row == fv_dof_periph_row_c);
    assert_true(ref.dof_hcoc_row == fv_dof_hcoc_row_c);
    assert_true(ref.dof_nearfin_row == fv_dof_nearfin_row_c);
    CHECKASM_CHECK_ISA_TABLES("dof", fv_dof_dsp, &ref, names);
}

/* ------------------------------------------------------------------ coc_row */

static float depth(int mode, float dn, float df)
{
    switch (mode == 0 ? rndi(9) : mode) {
    case 1: return 0.05f * rnd();                  /* below the 0.05 m floor */
    case 2: return 1000.0f;                        /* a miss */
    case 3: return dn;                             /* exactly at a bound: CoC 0 */
    case 4: return df;
    case 5: return dn + (df - dn) * rnd();         /* in focus: CoC 0 */
    case 6: return 0.05f;
    case 7: return -1.0f;
    default: return 0.01f + 60.0f * rnd() * rnd();
    }
}

static void run_coc(const fv_dof_dsp *d, const char *isa)
{
    for (int n = 1; n <= 70 + 2; n++) {
        const int nn = n <= 70 ? n : n == 71 ? 640 : 1281;
        for (int mode = 0; mode < 8; mode++) {
            const int off = rndi(4);
            const float dn = 0.3f + 2.0f * rnd(), df = dn + (rndi(4) == 0 ? 0.0f : 5.0f * rnd());
            const float K = rndi(5) == 0 ? 0.0f : 1.0f + 40.0f * rnd();
            buf in = buf_new(4 * (size_t)nn, off);
            for (int i = 0; i < nn; i++) {
                for (int c = 0; c < 3; c++)
                    in.p[4 * i + c] = colour();
                in.p[4 * i + 3] = depth(mode, dn, df);
            }
            buf r = checkasm_out_f32((size_t)nn, off), t = checkasm_out_f32((size_t)nn, off);
            fv_dof_coc_row_c(r.p, in.p, nn, K, dn, df);
            d->dof_coc_row(t.p, in.p, nn, K, dn, df);
            compare_out(&r, &t, (size_t)nn, 1, isa, "coc_row", "coc + canaries");
            for (int i = 0; i < nn; i++)
                assert_true(isfinite(r.p[i]));
            free(in.base), free(r.base), free(t.base);
        }
    }
}

static void test_coc_row(void **state)
{
    (void)state;
    run_all("dof_coc_row", run_coc, offsetof(fv_dof_dsp, dof_coc_row));
}

/* ------------------------------------------------------------------ sigma indices */

static void gen_sig(uint8_t *sig, int n, int mode)
{
    const int m = FV_DOF_NSIG - 1;
    int run = 0, s = 0;
    for (int i = 0; i < n; i++) {
        switch (mode) {
        case 0: sig[i] = (uint8_t)rndi(FV_DOF_NSIG); break;     /* every pixel its own */
        case 1: sig[i] = 0; break;                              /* in focus (radius 1, w = 1 0) */
        case 2: sig[i] = (uint8_t)m; break;                     /* the largest kernel */
        case 3: sig[i] = (uint8_t)(rndi(2) ? 0 : m); break;     /* extremes mixed */
        default:                                                /* runs, as along a real row */
            if (run-- <= 0)
                run = rndi(9), s = rndi(4) ? 8 + rndi(25) : rndi(FV_DOF_NSIG);
            sig[i] = (uint8_t)s;
        }
    }
}

static void test_gauss_tab(void **state)
{
    (void)state;
    /* the ISA versions run blocks of pixels to the block's largest radius and rely on this */
    for (int s = 0; s < FV_DOF_NSIG; s++) {
        assert_true(tab.rad[s] >= 1 && tab.rad[s] <= FV_DOF_RMAX);
        for (int j = tab.rad[s] + 1; j <= FV_DOF_RMAX; j++)
            assert_true(tab.w[s][j] == 0.0f && !signbit(tab.w[s][j]));
        for (int j = 0; j <= FV_DOF_RMAX; j++)
            assert_true(tab.w[s][j] >= 0.0f);
    }
}

/* ------------------------------------------------------------------ hgauss_row */

static void run_hgauss1(const fv_dof_dsp *d, const char *isa, int w, int x0, int n, int smode, int off)
{
    buf rgbd = buf_new(4 * (size_t)w, off), coc = buf_new((size_t)w, off);
    const int cmode = rndi(5);
    for (int i = 0; i < w; i++) {
        const float u = rnd();
        coc.p[i] = cmode == 0 ? 1.0f + rnd() : cmode == 1 ? -2.0f : /* all far / all near */
                   u < 0.15f ? 0.0f : u < 0.2f ? -0.0f : u < 0.4f ? -8.0f * rnd() : u < 0.45f ? 1e-30f : 16.0f * rnd();
        for (int c = 0; c < 4; c++)
            rgbd.p[4 * i + c] = colour();
        if (!(coc.p[i] > 0.0f) && rndi(2)) { /* colours of near / focused samples are never used */
            const int ch = rndi(3);
            rgbd.p[4 * i + ch] = rndi(2) ? NAN : INFINITY;
        }
    }
    uint8_t *sig = malloc((size_t)n + 1);
    assert_non_null(sig);
    gen_sig(sig, n, smode);
    buf r = checkasm_out_f32(4 * (size_t)w, off), t = checkasm_out_f32(4 * (size_t)w, off);
    fv_dof_hgauss_row_c(r.p, rgbd.p, coc.p, w, x0, n, sig, &tab);
    d->dof_hgauss_row(t.p, rgbd.p, coc.p, w, x0, n, sig, &tab);
    compare_out(&r, &t, 4 * (size_t)w, 4, isa, "hgauss_row", "whole row + canaries");
    for (int i = 4 * x0; i < 4 * (x0 + n); i++)
        assert_true(isfinite(r.p[i]));
    free(sig), free(rgbd.base), free(coc.base), free(r.base), free(t.base);
}

static void run_hgauss(const fv_dof_dsp *d, const char *isa)
{
    for (int n = 1; n <= 70; n++)
        for (int smode = 0; smode < 5; smode++) {
            const int w = n + (rndi(3) == 0 ? 0 : rndi(60)); /* span reaching both edges or not */
            const int x0 = rndi(w - n + 1);
            run_hgauss1(d, isa, w, x0, n, smode, rndi(4));
        }
    for (int k = 0; k < 40; k++) { /* production spans (TILE * 8) and tiny rows */
        const int w = k < 20 ? 128 + rndi(1200) : 1 + rndi(8);
        const int cut = k < 20 && w >= 128 && rndi(2) ? rndi(128) : 0; /* one draw after the other */
        const int n = k < 20 ? (w < 128 ? w : 128 - cut) : 1 + rndi(w);
        /* draws in a fixed order (argument evaluation order is unspecified) */
        const int x0 = rndi(w - n + 1), sm = rndi(5), off = rndi(4);
        run_hgauss1(d, isa, w, x0, n, sm, off);
    }
    run_hgauss1(d, isa, 1281, 0, 1281, 4, 1); /* longer than one chunk */
}

static void test_hgauss_row(void **state)
{
    (void)state;
    run_all("dof_hgauss_row", run_hgauss, offsetof(fv_dof_dsp, dof_hgauss_row));
}

/* ------------------------------------------------------------------ vgauss_row */

static void run_vgauss1(const fv_dof_dsp *d, const char *isa, int w, int h, int x0, int n, int smode, int off)
{
    const ptrdiff_t stride = w + rndi(3);
    const size_t count = 4 * (size_t)(stride * (h - 1) + w);
    buf src = buf_new(count, off);
    for (size_t i = 0; i < count; i++)
        src.p[i] = colour();
    const int ylo = rndi(h), yhi = ylo + 1 + rndi(h - ylo), y = ylo + rndi(yhi - ylo);
    uint8_t *sig = malloc((size_t)n + 1);
    assert_non_null(sig);
    gen_sig(sig, n, smode);
    buf r = checkasm_out_f32(4 * (size_t)w, off), t = checkasm_out_f32(4 * (size_t)w, off);
    fv_dof_vgauss_row_c(r.p, src.p, stride, y, ylo, yhi, x0, n, sig, &tab);
    d->dof_vgauss_row(t.p, src.p, stride, y, ylo, yhi, x0, n, sig, &tab);
    compare_out(&r, &t, 4 * (size_t)w, 4, isa, "vgauss_row", "whole row + canaries");
    free(sig), free(src.base), free(r.base), free(t.base);
}

static void run_vgauss(const fv_dof_dsp *d, const char *isa)
{
    for (int n = 1; n <= 70; n++)
        for (int smode = 0; smode < 5; smode++) {
            const int w = n + rndi(20), h = 1 + rndi(rndi(2) ? 8 : 70);
            const int x0 = rndi(w - n + 1), off = rndi(4);
            run_vgauss1(d, isa, w, h, x0, n, smode, off);
        }
    for (int k = 0; k < 10; k++) {
        const int w = 128 + rndi(400);
        const int hh = 16 + rndi(60), x0 = rndi(w - 127), sm = rndi(5), off = rndi(4);
        run_vgauss1(d, isa, w, hh, x0, 128, sm, off);
    }
}

static void test_vgauss_row(void **state)
{
    (void)state;
    run_all("dof_vgauss_row", run_vgauss, offsetof(fv_dof_dsp, dof_vgauss_row));
}

/* ------------------------------------------------------------------ combine_row */

static long comb_far, comb_lnear, comb_near, comb_enh; /* how often the steps ran (reference) */

/* Rows of w pixels; the span [x0, x0 + n). What the reference does not read (far unless coc > 0
 * or coc < 0 < t, lnear where t <= 0, enh where gain t <= 0) holds NaN / Inf: an ISA version may
 * read it but must not let it through. */
static void run_combine1(const fv_dof_dsp *d, const char *isa, int w, int x0, int n, int off)
{
    const size_t w4 = 4 * (size_t)w;
    buf sharp = buf_new(w4, off), coc = buf_new((size_t)w, off), far = buf_new(w4, off), near = buf_new(w4, off);
    buf lnear = buf_new(w4, off), t = buf_new((size_t)w, off), enh = buf_new(w4, off);
    const int cmode = rndi(5), tmode = rndi(5);
    const float gain = rndi(4) ? 2.0f * rnd() : 0.0f;
    float run_t = 0.0f;
    for (int i = 0; i < w; i++) {
        const float u = rnd();
        coc.p[i] = cmode == 0 ? 0.0f : cmode == 1 ? 20.0f * rnd() : cmode == 2 ? -12.0f * rnd() :
                   u < 0.15f ? 0.0f : u < 0.2f ? -0.0f : u < 0.3f ? -4.0f : u < 0.45f ? -12.0f * rnd() :
                   u < 0.55f ? rnd() : u < 0.6f ? 1.0f : 20.0f * rnd();
        if (tmode == 0)
            t.p[i] = 0.0f;
        else if (tmode == 1)
            t.p[i] = 1.0f;
        else { /* runs of 0, 1 and in between (the transition), as along a real row */
            if (rndi(6) == 0)
                run_t = rndi(3) == 0 ? 0.0f : rndi(2) ? 1.0f : rnd();
            t.p[i] = tmode == 2 ? rnd() : run_t;
        }
        const float nw = rndi(3) ? 0.05f + 1.5f * rnd() : 0.0f, lw = rndi(3) ? 0.05f + 1.5f * rnd() : 0.0f;
        for (int c = 0; c < 4; c++) {
            sharp.p[4 * i + c] = colour();
            far.p[4 * i + c] = colour();
            near.p[4 * i + c] = c < 3 ? nw * colour() : nw;
            lnear.p[4 * i + c] = c < 3 ? lw * colour() : lw;
            enh.p[4 * i + c] = colour();
        }
        const float bad = rndi(2) ? NAN : -INFINITY;
        if (!(coc.p[i] > 0.0f) && !(coc.p[i] < 0.0f && t.p[i] > 0.0f))
            far.p[4 * i + rndi(4)] = bad;
        if (!(t.p[i] > 0.0f))
            lnear.p[4 * i + rndi(4)] = bad;
        if (!(gain * t.p[i] > 0.0f))
            enh.p[4 * i + rndi(4)] = bad;
    }
    const fv_dof_combine_args a = {
        .sharp = sharp.p,
        .coc = coc.p,
        .far = far.p,
        .near = rndi(4) ? near.p : NULL,
        .lnear = rndi(4) ? lnear.p : NULL,
        .t = t.p,
        .enh = rndi(3) ? enh.p : NULL,
        .gain = gain,
    };
    buf r = checkasm_out_f32(w4, off), o = checkasm_out_f32(w4, off);
    fv_dof_combine_row_c(r.p, &a, x0, n);
    d->dof_combine_row(o.p, &a, x0, n);
    compare_out(&r, &o, w4, 4, isa, "combine_row", "whole row + canaries");
    for (int x = x0; x < x0 + n; x++) {
        for (int c = 0; c < 4; c++)
            assert_true(isfinite(r.p[4 * x + c]));
        comb_far += coc.p[x] > 0.0f || (coc.p[x] < 0.0f && t.p[x] > 0.0f);
        comb_lnear += a.lnear && t.p[x] > 0.0f;
        comb_near += a.near && near.p[4 * x + 3] > 0.0f;
        comb_enh += a.enh && gain * t.p[x] > 0.0f;
    }
    free(sharp.base), free(coc.base), free(far.base), free(near.base), free(lnear.base), free(t.base);
    free(enh.base), free(r.base), free(o.base);
}

static void run_combine(const fv_dof_dsp *d, const char *isa)
{
    for (int n = 1; n <= 70; n++)
        for (int rep = 0; rep < 6; rep++) {
            const int w = n + (rndi(3) == 0 ? 0 : rndi(40));
            const int x0 = rndi(w - n + 1), off = rndi(4);
            run_combine1(d, isa, w, x0, n, off);
        }
    for (int k = 0; k < 10; k++) { /* whole production rows, as core/dof/weier.c calls it */
        const int w = 1200 + rndi(200);
        run_combine1(d, isa, w, 0, w, rndi(4));
    }
}

static void test_combine_row(void **state)
{
    (void)state;
    run_all("dof_combine_row", run_combine, offsetof(fv_dof_dsp, dof_combine_row));
    printf("[ checkasm ] combine steps run (all ISAs): far %ld, lnear %ld, near coverage %ld, enhancement %ld\n",
           comb_far, comb_lnear, comb_near, comb_enh);
}

/* ------------------------------------------------------------------ upsample_row */

static const float below1 = 0x1.fffffep-1f; /* the largest float < 1 */

/* n output pixels from x0 by 2^L from a tmp row of sw texels. mode 0: the pipeline's rows
 * (core/dof/weier_filter.c: sw = ceil((x0 + n) / 2^L), or one more), so the right border clamps
 * or not; 1: a short row (sw 1..4), most pixels clamped; 2: sw = ceil(w / 2^L) for a row
 * w >= x0 + n (the call covers part of it). L 0 and 6..7 take the references' path in the ISA
 * versions. Every texel is finite and distinct; the row is allocated to its exact size (ASan). */
static void run_upsample1(const fv_dof_dsp *d, const char *isa, int L, int x0, int n, int mode)
{
    const int s = 1 << L, e = x0 + n;
    const int sw = mode == 0 ? (e + s - 1) / s + rndi(2) : mode == 1 ? 1 + rndi(4) : (e + rndi(64) + s - 1) / s;
    float *tmp = malloc(4 * sizeof(float) * (size_t)sw);
    assert_non_null(tmp);
    for (int i = 0; i < 4 * sw; i++)
        tmp[i] = colour();
    const int off = rndi(4);
    buf r = checkasm_out_f32(4 * (size_t)n, off), t = checkasm_out_f32(4 * (size_t)n, off);
    fv_dof_upsample_row_c(r.p, tmp, L, sw, x0, n);
    d->dof_upsample_row(t.p, tmp, L, sw, x0, n);
    compare_out(&r, &t, 4 * (size_t)n, 4, isa, "upsample_row", "row + canaries");
    free(tmp), free(r.base), free(t.base);
}

static void run_upsample(const fv_dof_dsp *d, const char *isa)
{
    for (int L = 0; L <= 7; L++)
        for (int n = 1; n <= 72; n++)
            for (int mode = 0; mode < 3; mode++) {
                const int x0 = rndi(3) == 0 ? rndi(4) : rndi(3 << L); /* the row's start or any phase */
                run_upsample1(d, isa, L, x0, n, mode);
            }
    for (int L = 1; L <= 5; L++) /* whole rows and the transition's spans (any start) */
        for (int k = 0; k < 4; k++)
            run_upsample1(d, isa, L, k < 2 ? 0 : rndi(600), 1280 - (k & 1) * rndi(600), k % 3);
}

/* the reference's taps against the float formula it states (u = (x + 0.5) / s - 0.5): core/dof/
 * weier_filter.c's rows must keep their bits */
static void test_upsample_ref_formula(void **state)
{
    (void)state;
    const int sw = 7;
    float tmp[4 * 7];
    for (int i = 0; i < 4 * sw; i++)
        tmp[i] = colour();
    for (int L = 0; L <= 5; L++)
        for (int x = 0; x < 8 * sw; x++) {
            const float u = ((float)x + 0.5f) / (float)(1 << L) - 0.5f, fu = floorf(u), a = u - fu;
            const int j = (int)fu, i0 = j < 0 ? 0 : j > sw - 1 ? sw - 1 : j, i1 = j + 1 > sw - 1 ? sw - 1 : j + 1 < 0 ? 0 : j + 1;
            float got[4];
            fv_dof_upsample_row_c(got, tmp, L, sw, x, 1);
            for (int c = 0; c < 4; c++) {
                const float want = tmp[4 * i0 + c] + a * (tmp[4 * i1 + c] - tmp[4 * i0 + c]);
                assert_memory_equal(&got[c], &want, sizeof want);
            }
        }
}

static void test_upsample_row(void **state)
{
    (void)state;
    run_all("dof_upsample_row", run_upsample, offsetof(fv_dof_dsp, dof_upsample_row));
}

/* ------------------------------------------------------------------ pyrblur_row */

static long pb_active, pb_mix, pb_beyond, pb_frac; /* how often (reference, all ISAs) */
static long pb_blk_all, pb_blk_mix; /* 8-pixel blocks from x0: all 8 blended (none mixing), all 8 mixed */

/* Rows of w pixels; the span [x0, x0 + n). The level table: core/dof/weier.c's (steps 8, 512
 * entries) or a short random one (levels >= 0, some whole, some above need), so CoCs run past
 * its end. What the reference does not read (blur and the up rows where it skips a pixel, blur
 * where it does not mix) holds NaN / Inf sometimes: an ISA version may read it but must not let
 * it through; skipped pixels must keep their bits. */
static void run_pyrblur1(const fv_dof_dsp *d, const char *isa, int w, int x0, int n, int off)
{
    const size_t w4 = 4 * (size_t)w;
    const int need = rndi(6), prod = rndi(2);
    const int steps = prod ? 8 : 1 + rndi(16), lmax = prod ? 512 : rndi(40);
    float *lambda = malloc(sizeof(float) * (size_t)(lmax + 1));
    assert_non_null(lambda);
    for (int i = 0; i <= lmax; i++) {
        if (prod) { /* as core/dof/weier.c */
            const float c = (float)i / 8.0f, var = c * c * (1.0f / 16.0f);
            float lo = 0.0f, l = 0.0f;
            for (int L = 1; L <= 5; L++) {
                const float hi = (3.0f * (float)(1 << (2 * L)) - 1.0f) / 12.0f;
                if (var < hi) {
                    l = (float)(L - 1) + (var - lo) / (hi - lo);
                    break;
                }
                lo = hi, l = (float)L;
            }
            lambda[i] = l;
        } else
            lambda[i] = rndi(4) == 0 ? (float)rndi(7) : rndi(8) == 0 ? below1 * (float)(1 + rndi(5)) : 6.0f * rnd();
    }
    buf coc = buf_new((size_t)w, off), t = buf_new((size_t)w, off);
    buf up[6];
    for (int L = 0; L <= need; L++)
        up[L] = buf_new(w4, off);
    const int cmode = rndi(7), tmode = rndi(5);
    const float camp = 1.0f + 30.0f * rnd(); /* cmode 6: a smooth CoC (blocks of one level pair, as rendered) */
    float run_t = 0.0f;
    for (int i = 0; i < w; i++) {
        static const float ext[] = {0.0f, -0.0f, 1e-30f, -1e-30f, 1.4e-45f, -1.4e-45f, 64.0f, -64.0f, 64.0625f,
                                    100.0f, -1000.0f, 1e6f, -1.25e8f, 1.25e8f, 0.125f, -0.0625f};
        const float u = rnd(), sg = rndi(2) ? 1.0f : -1.0f; /* (one draw a statement: the same inputs whatever the compiler) */
        coc.p[i] = cmode == 0 ? 0.0f : cmode == 1 ? 20.0f * rnd() : cmode == 2 ? -12.0f * rnd() :
                   cmode == 3 ? sg * 80.0f * rnd() : cmode == 6 ? camp * sinf((float)i * 0.02f) :
                   u < 0.25f ? ext[rndi((int)(sizeof ext / sizeof ext[0]))] : sg * 70.0f * rnd();
        if (tmode == 0)
            t.p[i] = 1.0f;
        else if (tmode == 1)
            t.p[i] = rndi(3) ? rnd() : rndi(2) ? 0.0f : -0.0f;
        else { /* runs of 0, 1 and in between (the transition), as along a real row */
            if (rndi(6) == 0)
                run_t = rndi(3) == 0 ? 0.0f : rndi(2) ? 1.0f : rndi(8) == 0 ? below1 : rndi(8) == 0 ? 1e-30f : rnd();
            t.p[i] = tmode == 2 ? (rndi(8) == 0 ? -rnd() : rnd()) : run_t;
        }
        const float c = coc.p[i], tt = t.p[i], m = c < 0.0f ? -c : c;
        const int act = m > 0.0f && tt > 0.0f;
        for (int L = 0; L <= need; L++)
            for (int k = 0; k < 4; k++)
                up[L].p[4 * i + k] = !act && rndi(3) == 0 ? (rndi(2) ? NAN : -INFINITY) : colour();
    }
    buf r = checkasm_out_f32(w4, off), o = checkasm_out_f32(w4, off);
    for (int i = 0; i < w; i++) {
        const float c = coc.p[i], tt = t.p[i], m = c < 0.0f ? -c : c;
        const int mix = m > 0.0f && tt > 0.0f && c > 0.0f && tt < 1.0f;
        for (int k = 0; k < 4; k++)
            r.p[4 * i + k] = !mix && rndi(3) == 0 ? (rndi(2) ? NAN : INFINITY) : colour();
    }
    memcpy(o.p, r.p, w4 * sizeof(float));
    const float *ups[6];
    for (int L = 0; L <= need; L++)
        ups[L] = up[L].p;
    const fv_dof_pyrblur_args a = {.coc = coc.p, .t = t.p, .up = ups, .need = need, .lambda = lambda,
                                   .lambda_steps = steps, .lambda_max = lmax};
    fv_dof_pyrblur_row_c(r.p, &a, x0, n);
    d->dof_pyrblur_row(o.p, &a, x0, n);
    compare_out(&r, &o, w4, 4, isa, "pyrblur_row", "whole row + canaries");
    for (int i = x0; i < x0 + n; i++) {
        const float c = coc.p[i], tt = t.p[i], m = c < 0.0f ? -c : c;
        if (!(m > 0.0f && tt > 0.0f))
            continue;
        pb_active++;
        pb_mix += c > 0.0f && tt < 1.0f;
        pb_beyond += m * (float)steps >= (float)lmax;
        const int li = (int)(m * (float)steps);
        const float l = lambda[li < lmax ? li : lmax];
        pb_frac += l < (float)need && l != floorf(l);
        for (int k = 0; k < 4; k++)
            assert_true(isfinite(r.p[4 * i + k]));
    }
    for (int b = x0; b + 8 <= x0 + n; b += 8) { /* the AVX2 version's select-free blocks happen */
        int na = 0, nm = 0;
        for (int i = b; i < b + 8; i++) {
            const float c = coc.p[i], tt = t.p[i], m = c < 0.0f ? -c : c;
            na += m > 0.0f && tt > 0.0f;
            nm += m > 0.0f && tt > 0.0f && c > 0.0f && tt < 1.0f;
        }
        pb_blk_all += na == 8 && nm == 0;
        pb_blk_mix += nm == 8;
    }
    for (int L = 0; L <= need; L++)
        free(up[L].base);
    free(lambda), free(coc.base), free(t.base), free(r.base), free(o.base);
}

static void run_pyrblur(const fv_dof_dsp *d, const char *isa)
{
    for (int n = 1; n <= 70; n++)
        for (int rep = 0; rep < 8; rep++) {
            const int w = n + (rndi(3) == 0 ? 0 : rndi(40)), x0 = rndi(w - n + 1);
            run_pyrblur1(d, isa, w, x0, n, rndi(4));
        }
    for (int k = 0; k < 12; k++) { /* whole production rows, as core/dof/weier.c calls it, and offset ones */
        const int x0 = k < 6 ? 0 : 1 + rndi(9), w = 1280 + x0 + (k & 1) * rndi(7);
        run_pyrblur1(d, isa, w, x0, 1280, rndi(4));
    }
}

static void test_pyrblur_row(void **state)
{
    (void)state;
    run_all("dof_pyrblur_row", run_pyrblur, offsetof(fv_dof_dsp, dof_pyrblur_row));
    printf("[ checkasm ] pyrblur pixels blended (all ISAs): %ld, mixed into the blur %ld, past the LUT's end %ld, "
           "between two levels %ld; 8-pixel blocks all blended %ld, all mixed %ld\n",
           pb_active, pb_mix, pb_beyond, pb_frac, pb_blk_all, pb_blk_mix);
    assert_true(pb_blk_all > 0 && pb_blk_mix > 0);
}

/* ------------------------------------------------------------------ nearblk_row */

/* Rows of every length mod 8 (partial blocks, the AVX2 pair loop's tail), CoCs mixing near, far,
 * signed zeros and all-near / all-far runs; the accumulators start from earlier rows' values
 * (signed zeros among them), and each case runs the kernel on 1-4 rows in a row as the CoC pass
 * does. */
static void run_nearblk(const fv_dof_dsp *d, const char *isa)
{
    static const float zc[] = {0.0f, -0.0f, -1e-30f, 1e-30f, -24.0f, 64.0f};
    for (int n = 1; n <= 40 + 2; n++) {
        const int nn = n <= 40 ? n : n == 41 ? 640 : 1283;
        const int nb = (nn + 3) / 4;
        for (int mode = 0; mode < 6; mode++) {
            const int off = rndi(4), rows = 1 + rndi(4);
            buf in = buf_new(4 * (size_t)nn * rows, off), c = buf_new((size_t)nn * rows, off);
            for (int i = 0; i < nn * rows; i++) {
                for (int k = 0; k < 4; k++)
                    in.p[4 * i + k] = colour();
                const int sel = mode == 1 ? 0 : mode == 2 ? 1 : mode == 3 ? 2 + rndi(4) : rndi(mode == 4 ? 2 : 8);
                c.p[i] = sel == 0 ? -(0.01f + 30.0f * rnd()) : sel == 1 ? 0.01f + 30.0f * rnd()
                                                             : sel < 8 ? zc[sel - 2] : 0.0f;
            }
            buf rs = checkasm_out_f32(4 * (size_t)nb, off), ts = checkasm_out_f32(4 * (size_t)nb, off);
            buf re = checkasm_out_f32(2 * (size_t)nb, off), te = checkasm_out_f32(2 * (size_t)nb, off);
            for (int i = 0; i < 4 * nb; i++)
                rs.p[i] = ts.p[i] = rndi(3) == 0 ? 0.0f : 4.0f * rnd();
            for (int i = 0; i < 2 * nb; i++)
                re.p[i] = te.p[i] = rndi(3) == 0 ? (rndi(2) ? -0.0f : 0.0f) : (i & 1 ? 20.0f : -20.0f) * rnd();
            for (int y = 0; y < rows; y++) {
                fv_dof_nearblk_row_c(rs.p, re.p, c.p + y * nn, in.p + 4 * (size_t)y * nn, nn);
                d->dof_nearblk_row(ts.p, te.p, c.p + y * nn, in.p + 4 * (size_t)y * nn, nn);
            }
            compare_out(&rs, &ts, 4 * (size_t)nb, 4, isa, "nearblk_row", "block sums + canaries");
            compare_out(&re, &te, 2 * (size_t)nb, 2, isa, "nearblk_row", "block min / max + canaries");
            free(in.base), free(c.base), free(rs.base), free(ts.base), free(re.base), free(te.base);
        }
    }
}

static void test_nearblk_row(void **state)
{
    (void)state;
    run_all("dof_nearblk_row", run_nearblk, offsetof(fv_dof_dsp, dof_nearblk_row));
}

/* ------------------------------------------------------------------ nearbox_row */

/* Rows of 1-60 pixels and 640, spans anywhere in them (the row's ends take the reference's path in
 * the ISA versions), reaches 0-24; radii -1 (not near) or 0-24, mostly small so that taps both
 * reach and do not; weights the box's 1 / (2r + 1) or arbitrary (>= +0, zeros among them). */
static void run_nearbox(const fv_dof_dsp *d, const char *isa)
{
    for (int w = 1; w <= 60 + 1; w++) {
        const int ww = w <= 60 ? w : 640;
        for (int rep = 0; rep < 6; rep++) {
            const int off = rndi(4), reach = rndi(5) == 0 ? FV_DOF_RMAX : rndi(12);
            const int x0 = rndi(ww), n = 1 + rndi(ww - x0);
            buf src = buf_new(4 * (size_t)ww, off), r = buf_new((size_t)ww, off), wg = buf_new((size_t)ww, off);
            for (int i = 0; i < ww; i++) {
                for (int k = 0; k < 4; k++)
                    src.p[4 * i + k] = colour();
                r.p[i] = rndi(4) == 0 ? -1.0f : (float)(rndi(6) == 0 ? rndi(FV_DOF_RMAX + 1) : rndi(6));
                wg.p[i] = rndi(3) ? 1.0f / (2.0f * (r.p[i] > 0.0f ? r.p[i] : 0.0f) + 1.0f)
                                  : (rndi(4) == 0 ? 0.0f : 2.0f * rnd());
            }
            buf ro = checkasm_out_f32(4 * (size_t)ww, off), to = checkasm_out_f32(4 * (size_t)ww, off);
            buf rr = checkasm_out_f32((size_t)ww, off), tr = checkasm_out_f32((size_t)ww, off);
            buf rw = checkasm_out_f32((size_t)ww, off), tw = checkasm_out_f32((size_t)ww, off);
            fv_dof_nearbox_row_c(ro.p, rr.p, rw.p, src.p, r.p, wg.p, ww, x0, n, reach);
            d->dof_nearbox_row(to.p, tr.p, tw.p, src.p, r.p, wg.p, ww, x0, n, reach);
            compare_out(&ro, &to, 4 * (size_t)ww, 4, isa, "nearbox_row", "box sums + canaries");
            compare_out(&rr, &tr, (size_t)ww, 1, isa, "nearbox_row", "largest radius + canaries");
            compare_out(&rw, &tw, (size_t)ww, 1, isa, "nearbox_row", "box weight + canaries");
            free(src.base), free(r.base), free(wg.base), free(ro.base), free(to.base), free(rr.base), free(tr.base);
            free(rw.base), free(tw.base);
        }
    }
}

static void test_nearbox_row(void **state)
{
    (void)state;
    run_all("dof_nearbox_row", run_nearbox, offsetof(fv_dof_dsp, dof_nearbox_row));
}

/* ------------------------------------------------------------------ periph_row */

static long pr_blend, pr_near; /* pixels blurred / covered by the near layer (reference, all ISAs) */

/* Rows of w pixels, spans [x0, x0 + n) from odd and even x; the half row an exact-size buffer of
 * (w + 1) / 2 + 2 texels (the clamped copies at -1 and hw included), so a read past the taps
 * shows under ASan. CoCs: 0, -0, below a pixel, around the level-1 knee (|c| = sqrt(44 / 3)),
 * large, both signs; the near layer NULL or with coverage 0, fractions, above 1, and NaN at near
 * pixels (which the reference does not read: an ISA version may read it but must not use it). */
static void run_periph1(const fv_dof_dsp *d, const char *isa, int w, int x0, int n, int off)
{
    const int hw = (w + 1) / 2, cmode = rndi(5), lmode = rndi(3);
    buf sharp = buf_new(4 * (size_t)w, off), coc = buf_new((size_t)w, off), half = buf_new(4 * (size_t)(hw + 2), off);
    buf ln = buf_new(4 * (size_t)w, off);
    for (int i = 0; i < 4 * (hw + 2); i++)
        half.p[i] = colour();
    for (int i = 0; i < w; i++) {
        static const float ext[] = {0.0f, -0.0f, 1e-30f, -1e-30f, 1.0f, -1.0f, 3.8297084f, -3.8297084f, 3.8297086f,
                                    64.0f, -100.0f, 1e6f, 0.5f, -0.999f};
        const float u = rnd(), sg = rndi(2) ? 1.0f : -1.0f;
        coc.p[i] = cmode == 0 ? 0.0f : cmode == 1 ? sg * 1.2f * rnd() : cmode == 2 ? sg * 6.0f * rnd() :
                   u < 0.3f ? ext[rndi((int)(sizeof ext / sizeof ext[0]))] : sg * 20.0f * rnd();
        for (int k = 0; k < 4; k++)
            sharp.p[4 * i + k] = colour();
        const int near = coc.p[i] < 0.0f;
        for (int k = 0; k < 3; k++)
            ln.p[4 * i + k] = near && rndi(3) == 0 ? NAN : colour();
        const float cv = rnd();
        ln.p[4 * i + 3] = near && rndi(3) == 0 ? NAN : rndi(3) == 0 ? 0.0f : rndi(3) == 0 ? 1.0f + cv : cv;
    }
    const float *lnear = lmode == 0 ? NULL : ln.p;
    buf r = checkasm_out_f32(4 * (size_t)w, off), o = checkasm_out_f32(4 * (size_t)w, off);
    fv_dof_periph_row_c(r.p, sharp.p, coc.p, half.p + 4, lnear, x0, n);
    d->dof_periph_row(o.p, sharp.p, coc.p, half.p + 4, lnear, x0, n);
    compare_out(&r, &o, 4 * (size_t)w, 4, isa, "periph_row", "whole row + canaries");
    for (int i = x0; i < x0 + n; i++) {
        const float m = fabsf(coc.p[i]);
        pr_blend += m > 0.0f;
        pr_near += lnear && !(coc.p[i] < 0.0f) && lnear[4 * i + 3] > 0.0f;
        for (int k = 0; k < 4; k++)
            assert_true(isfinite(r.p[4 * i + k]));
    }
    free(sharp.base), free(coc.base), free(half.base), free(ln.base), free(r.base), free(o.base);
}

static void run_periph(const fv_dof_dsp *d, const char *isa)
{
    for (int n = 1; n <= 40; n++)
        for (int rep = 0; rep < 8; rep++) {
            const int w = n + (rndi(3) == 0 ? 0 : rndi(20)), x0 = rndi(w - n + 1);
            run_periph1(d, isa, w, x0, n, rndi(4));
        }
    for (int k = 0; k < 12; k++) { /* production rows: the periphery left and right of the disc */
        const int w = 1280 + (k & 1), a = 300 + rndi(200), b = a + rndi(400);
        run_periph1(d, isa, w, 0, a, rndi(4));
        run_periph1(d, isa, w, b, w - b, rndi(4));
    }
}

static void test_periph_row(void **state)
{
    (void)state;
    run_all("dof_periph_row", run_periph, offsetof(fv_dof_dsp, dof_periph_row));
    printf("[ checkasm ] periph pixels blurred (all ISAs): %ld, under the near layer %ld\n", pr_blend, pr_near);
    assert_true(pr_blend > 1000 && pr_near > 1000);
}

/* ------------------------------------------------------------------ hcoc_row */

/* Two CoC rows of 2n floats in exact-size buffers (an over-read shows under ASan): both signs,
 * signed zeros, tiny and large values; bit for bit (the same additions in the same order; |x| is
 * exact). Also a hand-computed case against the formula. */
static void run_hcoc(const fv_dof_dsp *d, const char *isa)
{
    for (int n = 1; n <= 42; n++)
        for (int rep = 0; rep < 6; rep++) {
            const int nn = n <= 40 ? n : n == 41 ? 640 : 641, off = rndi(4);
            buf ca = buf_new(2 * (size_t)nn, off), cb = buf_new(2 * (size_t)nn, off);
            for (int i = 0; i < 2 * nn; i++) {
                static const float ext[] = {0.0f, -0.0f, 1e-30f, -1e-30f, 1.4e-45f, 0.125f, -64.0f, 1e6f, -3.9f};
                ca.p[i] = rndi(4) == 0 ? ext[rndi(9)] : 40.0f * rnd() - 20.0f;
                cb.p[i] = rndi(4) == 0 ? ext[rndi(9)] : 40.0f * rnd() - 20.0f;
            }
            buf r = checkasm_out_f32((size_t)nn, off), t = checkasm_out_f32((size_t)nn, off);
            fv_dof_hcoc_row_c(r.p, ca.p, cb.p, nn);
            d->dof_hcoc_row(t.p, ca.p, cb.p, nn);
            compare_out(&r, &t, (size_t)nn, 1, isa, "hcoc_row", "half-resolution CoC + canaries");
            free(ca.base), free(cb.base), free(r.base), free(t.base);
        }
    /* (|-1| + |2|) + (|-0.5| + |4.5|) = 8, / 4 = 2, for 9 texels (a vector step and a tail) */
    float a[18], b[18], o[9];
    for (int i = 0; i < 9; i++)
        a[2 * i] = -1.0f, a[2 * i + 1] = 2.0f, b[2 * i] = -0.5f, b[2 * i + 1] = 4.5f;
    d->dof_hcoc_row(o, a, b, 9);
    for (int i = 0; i < 9; i++)
        assert_true(o[i] == 2.0f);
}

static void test_hcoc_row(void **state)
{
    (void)state;
    run_all("dof_hcoc_row", run_hcoc, offsetof(fv_dof_dsp, dof_hcoc_row));
}

/* ------------------------------------------------------------------ nearfin_row */

/* Block rows of n blocks in exact-size buffers: min CoC (ext even) +0 (nearblk's zero), negative
 * (near: radii below, at and above the cap, fractions, whole and odd multiples of 2 and 8 px),
 * positive (no near pixel), tiny; counts 0, fractions, whole; sums and radii bit for bit (so the
 * -0 radius of a block whose min is +0 counts). Also a hand-computed block. */
static void run_nearfin(const fv_dof_dsp *d, const char *isa)
{
    static const float emin[] = {0.0f, -1e-30f, 1e-30f, -0.5f, -2.0f, -3.9f, -8.0f, -9.9f, -16.0f, -48.0f, -49.5f,
                                 -50.0f, -200.0f, 3.0f, -1e6f};
    for (int n = 1; n <= 42; n++)
        for (int rep = 0; rep < 6; rep++) {
            const int nn = n <= 40 ? n : n == 41 ? 320 : 321, off = rndi(4);
            buf ext = buf_new(2 * (size_t)nn, off), s0 = buf_new(4 * (size_t)nn, off);
            for (int i = 0; i < nn; i++) {
                ext.p[2 * i] = rndi(3) == 0 ? emin[rndi((int)(sizeof emin / sizeof emin[0]))] : -60.0f * rnd() + 4.0f;
                ext.p[2 * i + 1] = 20.0f * rnd() - 2.0f;
                for (int k = 0; k < 3; k++)
                    s0.p[4 * i + k] = colour();
                s0.p[4 * i + 3] = rndi(3) == 0 ? 0.0f : rndi(2) ? (float)(1 + rndi(16)) : 16.0f * rnd();
            }
            buf rs = checkasm_out_f32(4 * (size_t)nn, off), ts = checkasm_out_f32(4 * (size_t)nn, off);
            memcpy(rs.p, s0.p, 4 * (size_t)nn * sizeof(float)), memcpy(ts.p, s0.p, 4 * (size_t)nn * sizeof(float));
            buf rr = checkasm_out_f32((size_t)nn, off), tr = checkasm_out_f32((size_t)nn, off);
            buf rb = checkasm_out_f32((size_t)nn, off), tb = checkasm_out_f32((size_t)nn, off);
            buf rw = checkasm_out_f32((size_t)nn, off), tw = checkasm_out_f32((size_t)nn, off);
            const float inv = rndi(2) ? 1.0f / 16.0f : 1.0f / 12.0f;
            fv_dof_nearfin_row_c(rr.p, rb.p, rw.p, rs.p, ext.p, nn, inv);
            d->dof_nearfin_row(tr.p, tb.p, tw.p, ts.p, ext.p, nn, inv);
            compare_out(&rs, &ts, 4 * (size_t)nn, 4, isa, "nearfin_row", "block means + canaries");
            compare_out(&rr, &tr, (size_t)nn, 1, isa, "nearfin_row", "near radius + canaries");
            compare_out(&rb, &tb, (size_t)nn, 1, isa, "nearfin_row", "radius in blocks + canaries");
            compare_out(&rw, &tw, (size_t)nn, 1, isa, "nearfin_row", "box weight + canaries");
            free(ext.base), free(s0.base), free(rs.base), free(ts.base), free(rr.base), free(tr.base);
            free(rb.base), free(tb.base), free(rw.base), free(tw.base);
        }
    /* min c -19 px: radius floor(9.5) = 9, 2 blocks, weight 1/5; a count of 8: mean = sum / 16;
     * 5 blocks (a vector step of 4 and a tail) */
    float e[10], s[20], r[5], b[5], w[5];
    for (int i = 0; i < 5; i++) {
        e[2 * i] = -19.0f, e[2 * i + 1] = 1.0f;
        s[4 * i] = 4.0f, s[4 * i + 1] = 2.0f, s[4 * i + 2] = 1.0f, s[4 * i + 3] = 8.0f;
    }
    d->dof_nearfin_row(r, b, w, s, e, 5, 1.0f / 16.0f);
    for (int i = 0; i < 5; i++)
        assert_true(r[i] == 9.0f && b[i] == 2.0f && w[i] == 1.0f / 5.0f && s[4 * i] == 0.25f && s[4 * i + 3] == 0.5f);
}

static void test_nearfin_row(void **state)
{
    (void)state;
    run_all("dof_nearfin_row", run_nearfin, offsetof(fv_dof_dsp, dof_nearfin_row));
}

const struct CMUnitTest checkasm_dof_tests[] = {
    cmocka_unit_test(test_tables),
    cmocka_unit_test(test_gauss_tab),
    cmocka_unit_test(test_coc_row),
    cmocka_unit_test(test_hgauss_row),
    cmocka_unit_test(test_vgauss_row),
    cmocka_unit_test(test_combine_row),
    cmocka_unit_test(test_upsample_row),
    cmocka_unit_test(test_upsample_ref_formula),
    cmocka_unit_test(test_pyrblur_row),
    cmocka_unit_test(test_nearblk_row),
    cmocka_unit_test(test_nearbox_row),
    cmocka_unit_test(test_periph_row),
    cmocka_unit_test(test_hcoc_row),
    cmocka_unit_test(test_nearfin_row),
    {0},
};
