/* fovea checkasm: the timewarp kernels (timewarp_dsp.h), every ISA version against the C
 * reference, bit for bit: tw_row (bytes and disocclusion count) on maps from random head motions
 * (small turns and steps, a turn past 90 degrees that puts source points behind the eye, steps
 * that hit the depth conversion's floor, maps with a NaN), sources with depth edges, flat depth,
 * the nearest and the farthest depth codes; every row length from 1 up with tails, offsets into
 * the row, the first and last rows; tw_spans on random pieces (lengths 1 up, phases 0 and 63,
 * exact-size source rows); tw_runs over consecutive rows (the kept horizontal passes reused
 * and invalidated, aligned and unaligned display rows) against the C reference and against
 * tw_spans on the pieces of the translation's definition; tw_minmax on random rectangles. Then the block warp (core/timewarp.c) on every
 * ISA against the per-pixel C reference within its contract (timewarp.h): translated pixels
 * within FV_TW_BLOCK_POS_PX of the reference's tap and within the value bound, the others and
 * the disocclusion count exact. Outputs canaried; source planes exact-size plus the contract's
 * padding. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkasm.h"

#include "camera.h"
#include "timewarp.h"

static const char *const names[] = {"tw_row", "tw_spans", "tw_runs", "tw_minmax", "tw_stream"};

static void test_tables(void **state)
{
    (void)state;
    checkasm_rng = 0x71e3a2f5ull;
    fv_timewarp_dsp ref;
    fv_timewarp_dsp_init(&ref, FV_ISA_C);
    assert_true(ref.tw_row == fv_tw_row_c);
    CHECKASM_CHECK_ISA_TABLES("timewarp", fv_timewarp_dsp, &ref, names);
}

#define SW 97 /* odd sizes: no lucky alignment */
#define SH 61

static void random_pose(fv_pose *p, float turn_deg, float step_m)
{
    float axis[3] = {checkasm_randf() - 0.5f, checkasm_randf() - 0.5f, checkasm_randf() - 0.5f};
    const float n = sqrtf(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]) + 1e-6f;
    const float a = (checkasm_randf() - 0.5f) * 2.0f * turn_deg * 3.14159265f / 360.0f;
    for (int k = 0; k < 3; k++) {
        p->quat[k] = axis[k] / n * sinf(a);
        p->pos[k] = (checkasm_randf() - 0.5f) * 2.0f * step_m;
    }
    p->quat[3] = cosf(a);
}

/* mode 0: depth blocks with edges (0.3..30 m), 1: flat 2 m, 2: random codes incl. 0 and 65535,
 * 3: near objects (codes near the top: the conversion's floor with a forward step) */
static void fill_src(uint8_t *rgb, uint16_t *invd, int mode)
{
    for (int i = 0; i < SW * SH * 3 + FV_TW_RGB_PAD; i++)
        rgb[i] = (uint8_t)checkasm_rand();
    const float zb[4] = {0.3f, 1.0f, 4.0f, 30.0f};
    for (int y = 0; y < SH; y++)
        for (int x = 0; x < SW; x++) {
            uint16_t q;
            if (mode == 0)
                q = (uint16_t)(FV_TW_INVD_PER_M / zb[((x / 13) + (y / 9)) & 3] + 0.5f);
            else if (mode == 1)
                q = (uint16_t)(FV_TW_INVD_PER_M / 2.0f);
            else if (mode == 2) {
                const uint32_t r = (uint32_t)checkasm_rand();
                q = (uint16_t)((r & 3) == 0 ? 0 : (r & 3) == 1 ? 65535 : r >> 16);
            } else
                q = (uint16_t)(60000 + checkasm_rand() % 5536);
            invd[y * SW + x] = q;
        }
    for (int i = 0; i < FV_TW_INVD_PAD / 2; i++)
        invd[SW * SH + i] = (uint16_t)checkasm_rand();
}

static void test_tw_row(void **state)
{
    (void)state;
    uint8_t *rgb = malloc((size_t)SW * SH * 3 + FV_TW_RGB_PAD);
    uint16_t *invd = malloc(((size_t)SW * SH + FV_TW_INVD_PAD / 2) * sizeof *invd);
    assert_non_null(rgb);
    assert_non_null(invd);
    fv_camera_desc cd;
    fv_camera_desc_default(&cd);
    cd.width = SW, cd.height = SH;
    long checked = 0, holes_seen = 0;
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "tw_row"))
            continue;
        fv_timewarp_dsp d;
        fv_timewarp_dsp_init(&d, isa == FV_ISA_AVX2 ? FV_ISA_SSE41 | FV_ISA_AVX2 : isa);
        for (int trial = 0; trial < 52; trial++) {
            const int mode = trial & 3;
            fill_src(rgb, invd, mode);
            const float turn = trial % 12 == 11 ? 200.0f : trial % 3 == 0 ? 2.0f : 20.0f;
            const float step = trial % 5 == 4 ? 0.5f : trial % 5 == 0 ? 0.0f : 0.05f;
            fv_pose pa, pb;
            random_pose(&pa, turn, step);
            random_pose(&pb, turn, step);
            cd.eye = trial & 1 ? FV_EYE_RIGHT : FV_EYE_LEFT;
            fv_camera ca, cb;
            assert_int_equal(fv_camera_setup(&ca, &cd, &pa), 0);
            assert_int_equal(fv_camera_setup(&cb, &cd, &pb), 0);
            fv_tw_map m;
            fv_tw_setup(&m, &cb, &ca, 0.05f);
            /* NaN maps: the reference's selects turn a NaN into the bound (Z floor, depth
             * floor, clamps); max / min instructions that propagate NaN would not */
            if (trial == 48 || trial == 49)
                m.a0[2] = NAN;
            else if (trial == 50)
                m.a0[0] = NAN;
            else if (trial == 51)
                m.t[2] = NAN;
            const fv_tw_src s = {rgb, (ptrdiff_t)SW * 3, invd, SW, SW, SH};
            for (int n = 1; n <= SW; n += n < 20 ? 1 : 7) {
                const int x0 = (int)(checkasm_rand() % (uint64_t)(SW - n + 1));
                const int y = trial % 7 == 0 ? 0 : trial % 7 == 1 ? SH - 1 : (int)(checkasm_rand() % SH);
                const int off = n % 3;
                uint8_t *rb, *tb;
                uint8_t *r = checkasm_out_u8(3 * (size_t)n, off, &rb), *t = checkasm_out_u8(3 * (size_t)n, off, &tb);
                const int hr = fv_tw_row_c(r, x0, y, n, &m, &s);
                const int ht = d.tw_row(t, x0, y, n, &m, &s);
                checkasm_check_guards(t, 3 * (size_t)n, fv_isa_name(isa), "tw_row", n);
                checkasm_compare(r, t, 3 * (size_t)n, CHECKASM_U8, 3, CHECKASM_EXACT,
                                 "%s tw_row n=%d x0=%d y=%d trial=%d", fv_isa_name(isa), n, x0, y, trial);
                if (hr != ht)
                    fail_msg("%s tw_row n=%d trial=%d: %d disoccluded pixels, the reference %d", fv_isa_name(isa), n,
                             trial, ht, hr);
                holes_seen += hr;
                checked++;
                free(rb), free(tb);
            }
        }
    }
    free(rgb);
    free(invd);
    /* the edge cases were reached: some rows had disocclusions (the block depths with steps) */
    if (checked)
        assert_true(holes_seen > 0);
}

static void test_tw_spans(void **state)
{
    (void)state;
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "tw_spans"))
            continue;
        fv_timewarp_dsp d;
        fv_timewarp_dsp_init(&d, isa == FV_ISA_AVX2 ? FV_ISA_SSE41 | FV_ISA_AVX2 : isa);
        for (int trial = 0; trial < 300; trial++) {
            enum { MAXP = 6 };
            fv_tw_piece pc[MAXP];
            uint8_t *src[MAXP][2];
            const int np = 1 + (int)(checkasm_rand() % MAXP);
            int len = 0;
            for (int i = 0; i < np; i++) {
                /* lengths 1..200 bytes (every tail), phases with their extremes */
                const int n = trial < 100 ? 1 + (trial + 37 * i) % 100 : 1 + (int)(checkasm_rand() % 200);
                const uint64_t r = checkasm_rand();
                pc[i].fx = r % 5 == 0 ? 0 : r % 5 == 1 ? 63 : (int)((r >> 8) % 64);
                pc[i].fy = r % 7 == 0 ? 0 : r % 7 == 1 ? 63 : (int)((r >> 16) % 64);
                for (int j = 0; j < 2; j++) { /* exactly the n + 3 bytes the contract reads */
                    src[i][j] = malloc((size_t)n + 3);
                    assert_non_null(src[i][j]);
                    for (int b = 0; b < n + 3; b++) {
                        const uint64_t v = checkasm_rand();
                        src[i][j][b] = (uint8_t)(trial % 4 == 0 ? (v & 1) * 255 : v);
                    }
                }
                pc[i].s0 = src[i][0], pc[i].s1 = src[i][1];
                len += (int)(checkasm_rand() % 9); /* gaps the kernel must leave alone */
                pc[i].dst = len, pc[i].n = n;
                len += n;
            }
            uint8_t *rb, *tb;
            uint8_t *r = checkasm_out_u8((size_t)len, trial % 3, &rb), *t = checkasm_out_u8((size_t)len, trial % 3, &tb);
            fv_tw_spans_c(r, pc, np);
            d.tw_spans(t, pc, np);
            checkasm_check_guards(t, (size_t)len, fv_isa_name(isa), "tw_spans", len);
            checkasm_compare(r, t, (size_t)len, CHECKASM_U8, 1, CHECKASM_EXACT, "%s tw_spans trial=%d pieces=%d",
                             fv_isa_name(isa), trial, np);
            free(rb), free(tb);
            for (int i = 0; i < np; i++)
                free(src[i][0]), free(src[i][1]);
        }
    }
}

/* tw_runs on every ISA, several consecutive rows of the same runs (a run whose translation
 * steps one source row a row at a fixed phase reuses its kept pass), against the C reference
 * (bytes, the runs stepped alike) and the C reference against tw_spans on the pieces of the
 * runs' definition (timewarp_dsp.h): row k of run r translates by (qu + k dqu) / 2^22 px,
 * rounded to 1/64 px. Display rows with their 64 bytes around and the gaps between runs
 * compared too (nothing written there), at offsets that are and are not vector-aligned. */
static void test_tw_runs(void **state)
{
    (void)state;
    enum { RN_SW = 97, RN_SH = 40, RN_MAXR = 7, RN_ROWS = 9, RN_GUARD = 64 };
    const ptrdiff_t stride = 3 * RN_SW;
    uint8_t *rgb = malloc((size_t)stride * RN_SH);
    assert_non_null(rgb);
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "tw_runs"))
            continue;
        fv_timewarp_dsp d;
        fv_timewarp_dsp_init(&d, isa == FV_ISA_AVX2 ? FV_ISA_SSE41 | FV_ISA_AVX2 : isa);
        for (int trial = 0; trial < 200; trial++) {
            for (ptrdiff_t i = 0; i < stride * RN_SH; i++) {
                const uint64_t v = checkasm_rand();
                rgb[i] = (uint8_t)(trial % 4 == 0 ? (v & 1) * 255 : v);
            }
            const int nr = 1 + (int)(checkasm_rand() % RN_MAXR);
            fv_tw_run rr[RN_MAXR], rt[RN_MAXR];
            int64_t q0[RN_MAXR][2]; /* the unbiased first-row translations, 1/2^22 px */
            int len = trial % 3 ? (int)(checkasm_rand() % 40) : 0, x0[RN_MAXR], y0 = 4 + (int)(checkasm_rand() % 8);
            for (int i = 0; i < nr; i++) {
                /* lengths: the warp's 48, 96, 192 bytes (16, 32, 64 px) or any 1..200 */
                const uint64_t r = checkasm_rand();
                const int n = r % 4 == 0 ? 48 : r % 4 == 1 ? 96 : r % 4 == 2 ? 192 : 1 + (int)((r >> 8) % 200);
                const int px = (n + 2) / 3; /* display columns the run's bytes cover, near enough */
                x0[i] = 3 + (int)((r >> 16) % (uint64_t)(RN_SW - px - 10 > 1 ? RN_SW - px - 10 : 1));
                /* translations within +-3 px; steps: none (reuse every row), a phase a few rows
                 * (reuse mostly), or a source row and a bit a row (never the same row again) */
                q0[i][0] = (int64_t)((checkasm_rand() % 6001) - 3000) * ((int64_t)1 << 22) / 1000;
                q0[i][1] = (int64_t)((checkasm_rand() % 6001) - 3000) * ((int64_t)1 << 22) / 1000;
                const int kind = (int)(checkasm_rand() % 3);
                const int64_t du = kind == 0 ? 0 : kind == 1 ? ((int64_t)1 << 22) / 200 : ((int64_t)1 << 22) * 13 / 10;
                const int64_t dv = kind == 0 ? 0 : kind == 1 ? -((int64_t)1 << 22) / 150 : ((int64_t)1 << 22) * 11 / 10;
                fv_tw_run *o = &rr[i];
                o->qu = q0[i][0] + (FV_TW_RUN_BIAS << 22) + 32768, o->qv = q0[i][1] + (FV_TW_RUN_BIAS << 22) + 32768;
                o->dqu = du, o->dqv = kind == 2 ? dv : dv / 3;
                o->off = (int64_t)y0 * stride + 3 * x0[i] - FV_TW_RUN_BIAS * ((int64_t)stride + 3);
                o->hoff = -1, o->hfx = 0;
                if (trial % 3 == 0) /* 16-byte multiples: the aligned stores */
                    len = (len + 15) & ~15;
                o->dst = len, o->n = n;
                len += n + (int)(checkasm_rand() % 9) * (trial % 3 == 0 ? 16 : 1);
            }
            memcpy(rt, rr, sizeof rr);
            const int shift = trial % 3 == 0 ? 0 : trial % 3 == 1 ? 32 : 5 + trial % 11;
            const size_t all = (size_t)RN_GUARD + 64 + (size_t)len + RN_GUARD;
            uint8_t *bufr = aligned_alloc(64, (all + 63) & ~(size_t)63), *buft = aligned_alloc(64, (all + 63) & ~(size_t)63);
            uint8_t *bufs = aligned_alloc(64, (all + 63) & ~(size_t)63);
            int16_t *hb = malloc(((size_t)len + 16) * sizeof *hb);
            assert_true(bufr && buft && bufs && hb);
            for (size_t i = 0; i < all; i++)
                bufr[i] = buft[i] = bufs[i] = (uint8_t)(0xa5 ^ i);
            uint8_t *dr = bufr + RN_GUARD + shift, *dt = buft + RN_GUARD + shift, *ds = bufs + RN_GUARD + shift;
            for (int row = 0; row < RN_ROWS; row++) {
                const ptrdiff_t pf_end = (ptrdiff_t)(RN_SH - 1) * stride; /* rows below not read: the hint only */
                fv_tw_runs_c(dr, rr, nr, rgb, stride, pf_end, hb);
                d.tw_runs(dt, rt, nr, rgb, stride, pf_end, hb);
                checkasm_compare(bufr, buft, all, CHECKASM_U8, 1, CHECKASM_EXACT, "%s tw_runs trial=%d row=%d runs=%d",
                                 fv_isa_name(isa), trial, row, nr);
                for (int i = 0; i < nr; i++)
                    if (rr[i].qu != rt[i].qu || rr[i].qv != rt[i].qv || rr[i].off != rt[i].off)
                        fail_msg("%s tw_runs trial=%d row=%d run=%d: stepped differently", fv_isa_name(isa), trial, row, i);
                /* the definition: tw_spans on the pieces of the rounded translation */
                fv_tw_piece pc[RN_MAXR];
                for (int i = 0; i < nr; i++) {
                    const double tu = floor(((double)q0[i][0] + (double)row * (double)rr[i].dqu) / 65536.0 + 0.5);
                    const double tv = floor(((double)q0[i][1] + (double)row * (double)rr[i].dqv) / 65536.0 + 0.5);
                    const int ox = (int)floor(tu / 64.0), oy = (int)floor(tv / 64.0);
                    pc[i].fx = (int)(tu - 64.0 * ox), pc[i].fy = (int)(tv - 64.0 * oy);
                    pc[i].s0 = rgb + (y0 + row + oy) * stride + 3 * (x0[i] + ox);
                    pc[i].s1 = pc[i].fy ? pc[i].s0 + stride : pc[i].s0;
                    pc[i].dst = rr[i].dst, pc[i].n = rr[i].n;
                    assert_true(y0 + row + oy >= 0 && y0 + row + oy + 1 < RN_SH && x0[i] + ox >= 0);
                }
                fv_tw_spans_c(ds, pc, nr);
                checkasm_compare(bufs, bufr, all, CHECKASM_U8, 1, CHECKASM_EXACT, "tw_runs C against tw_spans trial=%d row=%d",
                                 trial, row);
            }
            free(bufr), free(buft), free(bufs), free(hb);
        }
    }
    free(rgb);
}

/* tw_spans' C reference against the bilinear value it rounds: within 1 level of
 * sum c w / 4096 over the 4 taps, w the 6-bit weights' products (the contract's accuracy) */
static void test_tw_spans_formula(void **state)
{
    (void)state;
    for (int i = 0; i < 20000; i++) {
        const uint64_t r = checkasm_rand();
        const uint8_t s0[4] = {(uint8_t)r, 0, 0, (uint8_t)(r >> 8)}, s1[4] = {(uint8_t)(r >> 16), 0, 0, (uint8_t)(r >> 24)};
        const fv_tw_piece p = {s0, s1, 0, 1, (int)((r >> 32) % 64), (int)((r >> 40) % 64)};
        uint8_t o;
        fv_tw_spans_c(&o, &p, 1);
        const double fx = p.fx / 64.0, fy = p.fy / 64.0;
        const double want = (1 - fy) * ((1 - fx) * s0[0] + fx * s0[3]) + fy * ((1 - fx) * s1[0] + fx * s1[3]);
        if (fabs(o - want) > 0.51)
            fail_msg("tw_spans: %d, the bilinear value %.3f (fx %d fy %d)", o, want, p.fx, p.fy);
    }
}

static void test_tw_minmax(void **state)
{
    (void)state;
    enum { MW = 53, MH = 11 };
    uint16_t *p = malloc(MW * MH * sizeof *p);
    assert_non_null(p);
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "tw_minmax"))
            continue;
        fv_timewarp_dsp d;
        fv_timewarp_dsp_init(&d, isa == FV_ISA_AVX2 ? FV_ISA_SSE41 | FV_ISA_AVX2 : isa);
        for (int trial = 0; trial < 400; trial++) {
            for (int i = 0; i < MW * MH; i++) {
                const uint64_t v = checkasm_rand();
                p[i] = (uint16_t)(trial % 5 == 0 ? (v & 1) * 65535 : trial % 5 == 1 ? 30000 + v % 3 : v);
            }
            const int w = 1 + (int)(checkasm_rand() % MW), h = 1 + (int)(checkasm_rand() % MH);
            const int x = (int)(checkasm_rand() % (uint64_t)(MW - w + 1)), y = (int)(checkasm_rand() % (uint64_t)(MH - h + 1));
            unsigned want[2] = {65535, 0}, got[2];
            for (int j = y; j < y + h; j++) /* the definition, not fv_tw_minmax_c */
                for (int i = x; i < x + w; i++)
                    want[0] = p[j * MW + i] < want[0] ? p[j * MW + i] : want[0], want[1] = p[j * MW + i] > want[1] ? p[j * MW + i] : want[1];
            d.tw_minmax(p + y * MW + x, MW, w, h, got);
            if (got[0] != want[0] || got[1] != want[1])
                fail_msg("%s tw_minmax %dx%d at (%d, %d): %u..%u, want %u..%u", fv_isa_name(isa), w, h, x, y, got[0], got[1],
                         want[0], want[1]);
        }
    }
    free(p);
}

static void test_tw_stream(void **state)
{
    (void)state;
    uint8_t src[700];
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "tw_stream"))
            continue;
        fv_timewarp_dsp d;
        fv_timewarp_dsp_init(&d, isa == FV_ISA_AVX2 ? FV_ISA_SSE41 | FV_ISA_AVX2 : isa);
        for (int n = 0; n <= 600; n += n < 80 ? 1 : 37) /* every head and tail around the alignment */
            for (int off = 0; off < 33; off += 7) {
                for (int i = 0; i < n; i++)
                    src[i] = (uint8_t)checkasm_rand();
                uint8_t *b;
                uint8_t *t = checkasm_out_u8((size_t)n, off, &b);
                d.tw_stream(t, src, n);
                d.tw_stream(NULL, NULL, 0); /* the fence */
                checkasm_check_guards(t, (size_t)n, fv_isa_name(isa), "tw_stream", n);
                checkasm_compare(src, t, (size_t)n, CHECKASM_U8, 1, CHECKASM_EXACT, "%s tw_stream n=%d off=%d",
                                 fv_isa_name(isa), n, off);
                free(b);
            }
    }
}

/* ---- the block warp against the per-pixel reference (timewarp.h's contract) ---- */
#define BW_W 331 /* odd: several blocks, clipped last ones */
#define BW_H 181 /* the last block row 53 rows: parts start off the 8-row grid */

/* the reference's tap position for display pixel (x, y) before its weight truncation: the
 * iteration of fv_tw_pixel with the same helpers, clamped as fv_tw_tap clamps */
static void ref_tap(const fv_tw_map *m, const fv_tw_src *s, int x, int y, float *bu, float *bv)
{
    const float py = (float)y + 0.5f, px = (float)x + 0.5f;
    const float r[3] = {m->a0[0] + py * m->ay[0], m->a0[1] + py * m->ay[1], m->a0[2] + py * m->ay[2]};
    const float A[3] = {r[0] + px * m->ax[0], r[1] + px * m->ax[1], r[2] + px * m->ax[2]};
    float u0, v0, u1, v1, u2, v2;
    fv_tw_proj(A, m->t, 0.0f, &u0, &v0);
    const float w1 = fv_tw_fetch_w(m, s, A[2], u0, v0);
    fv_tw_proj(A, m->t, w1, &u1, &v1);
    const float w2 = fv_tw_fetch_w(m, s, A[2], u1, v1);
    fv_tw_proj(A, m->t, w2, &u2, &v2);
    const float w3 = fv_tw_fetch_w(m, s, A[2], u2, v2);
    const float d = w3 > w2 ? w3 - w2 : w2 - w3, mx = w3 > w2 ? w3 : w2;
    const int first = d > m->tol * mx && w2 < w3;
    *bu = fv_tw_clampf((first ? u1 : u2) - 0.5f, (float)(s->w - 1));
    *bv = fv_tw_clampf((first ? v1 : v2) - 0.5f, (float)(s->h - 1));
}

static void test_block_warp(void **state)
{
    (void)state;
    checkasm_rng = 0x5eed0b10ull;
    const size_t npx = (size_t)BW_W * BW_H;
    uint8_t *rgb = malloc(npx * 3 + FV_TW_RGB_PAD), *ref = malloc(npx * 3), *blk = malloc(npx * 3), *bnd = malloc(npx * 3);
    uint16_t *invd = malloc((npx + FV_TW_INVD_PAD / 2) * sizeof *invd);
    uint8_t *refhole = malloc(npx), *fastpx = malloc(npx);
    const int tw = (BW_W + FV_TW_TILE - 1) / FV_TW_TILE, th = (BW_H + FV_TW_TILE - 1) / FV_TW_TILE;
    const int tw4 = (tw + 3) / 4, th4 = (th + 3) / 4;
    uint16_t *lohi = malloc(2 * (size_t)tw * th * sizeof *lohi), *want_tiles = malloc(2 * (size_t)tw * th * sizeof *lohi);
    uint16_t *lohi4 = malloc(2 * (size_t)tw4 * th4 * sizeof *lohi), *want4 = malloc(2 * (size_t)tw4 * th4 * sizeof *lohi);
    const int nbx = (BW_W + FV_TW_BLOCK_W - 1) / FV_TW_BLOCK_W;
    fv_tw_block *plan = malloc(FV_TW_BLOCK_SPLIT * (size_t)nbx * sizeof *plan);
    assert_true(rgb && ref && blk && bnd && invd && refhole && fastpx && lohi && want_tiles && lohi4 && want4 && plan);
    fv_camera_desc cd;
    fv_camera_desc_default(&cd);
    cd.width = BW_W, cd.height = BW_H;
    fv_timewarp_dsp c;
    fv_timewarp_dsp_init(&c, FV_ISA_C);
    long fast_total = 0, slow_total = 0, checked = 0, grid_total = 0;
    float worst_pos = 0.0f;
    for (int trial = 0; trial < 40; trial++) {
        /* sources: depth blocks with edges (random colours, and smooth colours so the value bound
         * is tight), flat, near objects, random codes, a wall at 1 m with poles at 0.3 m one
         * column wide (a pole just outside a block's footprint at w = 0 is hit once the parallax
         * counts) */
        const int mode = trial % 5 == 4 ? 2 : trial % 5 == 3 ? 3 : trial % 5 == 2 ? 1 : trial % 5 == 1 ? 4 : 0;
        for (size_t i = 0; i < npx * 3 + FV_TW_RGB_PAD; i++)
            rgb[i] = (uint8_t)(trial & 1 ? (i / 3 % BW_W) * 255 / BW_W + (i % 3) * 20 : checkasm_rand());
        const float zb[4] = {0.3f, 1.0f, 4.0f, 30.0f};
        for (int y = 0; y < BW_H; y++)
            for (int x = 0; x < BW_W; x++) {
                const uint64_t r = checkasm_rand();
                invd[y * BW_W + x] = (uint16_t)(mode == 0   ? FV_TW_INVD_PER_M / zb[((x / 45) + (y / 29)) & 3] + 0.5f
                                                : mode == 1 ? FV_TW_INVD_PER_M / 2.0f
                                                : mode == 2 ? (r & 3) == 0 ? 0 : (r & 3) == 1 ? 65535 : r >> 16
                                                : mode == 4 ? FV_TW_INVD_PER_M / (x % 40 == 17 ? 0.3f : 1.0f)
                                                            : 60000 + r % 5536);
            }
        /* small motions (a refresh or a few of head turn, eye steps up to 5 mm), and a larger one */
        const float turn = trial % 8 == 7 ? 8.0f : 0.2f + 0.3f * (float)(trial % 4);
        const float step = trial % 3 == 0 ? 0.0f : trial % 3 == 1 ? 0.001f : 0.005f;
        fv_pose pa, pb;
        random_pose(&pa, turn, step);
        random_pose(&pb, turn, step);
        cd.eye = trial & 1 ? FV_EYE_RIGHT : FV_EYE_LEFT;
        fv_camera ca, cb;
        assert_int_equal(fv_camera_setup(&ca, &cd, &pa), 0);
        assert_int_equal(fv_camera_setup(&cb, &cd, &pb), 0);
        fv_tw_map m;
        fv_tw_setup(&m, &cb, &ca, 0.05f);
        const fv_tw_src s = {rgb, (ptrdiff_t)BW_W * 3, invd, BW_W, BW_W, BW_H};
        fv_tw_warp_rows_pixel(&c, ref, (ptrdiff_t)BW_W * 3, 0, BW_H, &m, &s);
        for (int y = 0; y < BW_H; y++)
            for (int x = 0; x < BW_W; x++) {
                uint8_t px[3];
                refhole[y * BW_W + x] = (uint8_t)fv_tw_row_c(px, x, y, 1, &m, &s);
            }
        /* the tiles, against their definition */
        for (int ty = 0; ty < th; ty++)
            for (int tx = 0; tx < tw; tx++) {
                unsigned lo = 65535, hi = 0;
                for (int y = ty * FV_TW_TILE; y < (ty + 1) * FV_TW_TILE && y < BW_H; y++)
                    for (int x = tx * FV_TW_TILE; x < (tx + 1) * FV_TW_TILE && x < BW_W; x++)
                        lo = invd[y * BW_W + x] < lo ? invd[y * BW_W + x] : lo, hi = invd[y * BW_W + x] > hi ? invd[y * BW_W + x] : hi;
                want_tiles[2 * (ty * tw + tx)] = (uint16_t)lo, want_tiles[2 * (ty * tw + tx) + 1] = (uint16_t)hi;
            }
        const int T4 = 4 * FV_TW_TILE;
        for (int ty = 0; ty < th4; ty++)
            for (int tx = 0; tx < tw4; tx++) {
                unsigned lo = 65535, hi = 0;
                for (int y = ty * T4; y < (ty + 1) * T4 && y < BW_H; y++)
                    for (int x = tx * T4; x < (tx + 1) * T4 && x < BW_W; x++)
                        lo = invd[y * BW_W + x] < lo ? invd[y * BW_W + x] : lo, hi = invd[y * BW_W + x] > hi ? invd[y * BW_W + x] : hi;
                want4[2 * (ty * tw4 + tx)] = (uint16_t)lo, want4[2 * (ty * tw4 + tx) + 1] = (uint16_t)hi;
            }
        fv_tw_tiles tiles = {lohi, lohi4, 0, 0, 0, 0};
        const fv_tw_tiles *tp = trial & 2 ? &tiles : NULL;
        for (int k = -1; k < 0 || checkasm_isas[k]; k++) { /* C first, then this build's ISAs */
            const unsigned isa = k < 0 ? FV_ISA_C : checkasm_isas[k];
            if (isa != FV_ISA_C && !checkasm_cpu_runs(isa, "block warp"))
                continue;
            fv_timewarp_dsp d;
            fv_timewarp_dsp_init(&d, isa == FV_ISA_AVX2 ? FV_ISA_SSE41 | FV_ISA_AVX2 : isa);
            memset(lohi, 0, 2 * (size_t)tw * th * sizeof *lohi);
            fv_tw_tiles_build(&d, &tiles, &s);
            assert_int_equal(tiles.tw, tw);
            assert_int_equal(tiles.th, th);
            assert_int_equal(tiles.tw4, tw4);
            assert_int_equal(tiles.th4, th4);
            if (memcmp(lohi, want_tiles, 2 * (size_t)tw * th * sizeof *lohi) || memcmp(lohi4, want4, 2 * (size_t)tw4 * th4 * sizeof *lohi))
                fail_msg("%s: fv_tw_tiles_build differs from the tiles' least and greatest", fv_isa_name(isa));
            uint8_t *ob;
            uint8_t *o = checkasm_out_u8(npx * 3, 1, &ob);
            const long holes = fv_tw_warp_rows(&d, o, (ptrdiff_t)BW_W * 3, 0, BW_H, &m, &s, tp);
            checkasm_check_guards(o, npx * 3, fv_isa_name(isa), "block warp", trial);
            { /* the bounded warp (grid cells where the proof fails beyond a per-pixel budget of a
               * 16th of the pixels): every ISA gives the C one's bytes and split */
                uint8_t *bb;
                uint8_t *bo = checkasm_out_u8(npx * 3, 1, &bb);
                fv_tw_warp_stats st = {0, 0};
                const long bh = fv_tw_warp_rows_bounded(&d, bo, (ptrdiff_t)BW_W * 3, 0, BW_H, &m, &s, tp, (long)npx / 16, &st);
                checkasm_check_guards(bo, npx * 3, fv_isa_name(isa), "bounded warp", trial);
                static long c_holes, c_pixel, c_grid;
                if (k < 0) {
                    memcpy(bnd, bo, npx * 3);
                    c_holes = bh, c_pixel = st.pixel_px, c_grid = st.grid_px;
                    grid_total += st.grid_px;
                    assert_true(st.pixel_px <= (long)npx / 16 + FV_TW_BLOCK_W * FV_TW_BLOCK_H); /* the budget (+ a part) */
                } else {
                    checkasm_compare(bnd, bo, npx * 3, CHECKASM_U8, 3, CHECKASM_EXACT, "%s bounded warp trial=%d",
                                     fv_isa_name(isa), trial);
                    assert_int_equal(bh, c_holes);
                    assert_int_equal(st.pixel_px, c_pixel);
                    assert_int_equal(st.grid_px, c_grid);
                }
                free(bb);
            }
            if (k >= 0) { /* the kernels are exact: the same bytes as the C block warp */
                checkasm_compare(blk, o, npx * 3, CHECKASM_U8, 3, CHECKASM_EXACT, "%s block warp trial=%d",
                                 fv_isa_name(isa), trial);
                free(ob);
                continue;
            }
            memcpy(blk, o, npx * 3);
            free(ob);
            /* C: each pixel against the reference, by its block's plan */
            long want_holes = 0;
            memset(fastpx, 0, npx);
            for (int by = 0; by * FV_TW_BLOCK_H < BW_H; by++) {
                float g = 0.0f;
                const int n = fv_tw_plan_blocks(&c, &m, &s, tp, by, 0, nbx, plan, &g);
                /* the entries tile the block row, those of a row in column order */
                for (int y = by * FV_TW_BLOCK_H; y < (by + 1) * FV_TW_BLOCK_H && y < BW_H; y++) {
                    int x = 0;
                    for (int i = 0; i < n; i++)
                        if (plan[i].y0 <= y && y < plan[i].y1) {
                            assert_int_equal(plan[i].x0, x);
                            x = plan[i].x1;
                        }
                    assert_int_equal(x, BW_W);
                }
                for (int i = 0; i < n; i++) {
                    for (int y = plan[i].y0; y < plan[i].y1; y++)
                        for (int x = plan[i].x0; x < plan[i].x1; x++) {
                            const size_t j = (size_t)y * BW_W + x;
                            checked++;
                            if (!plan[i].fast) {
                                want_holes += refhole[j];
                                slow_total++;
                                if (memcmp(blk + 3 * j, ref + 3 * j, 3))
                                    fail_msg("trial %d: per-pixel block pixel (%d, %d) differs from the reference", trial, x, y);
                                continue;
                            }
                            fast_total++;
                            fastpx[j] = 1;
                            int ox, oy, fx, fy;
                            fv_tw_block_row(&plan[i], y, &ox, &oy, &fx, &fy);
                            const float tu = fv_tw_clampf((float)(x + ox) + (float)fx / 64.0f, (float)(BW_W - 1));
                            const float tv = fv_tw_clampf((float)(y + oy) + (float)fy / 64.0f, (float)(BW_H - 1));
                            float bu, bv;
                            ref_tap(&m, &s, x, y, &bu, &bv);
                            const float e = fmaxf(fabsf(tu - bu), fabsf(tv - bv));
                            worst_pos = e > worst_pos ? e : worst_pos;
                            if (e > FV_TW_BLOCK_POS_PX)
                                fail_msg("trial %d: pixel (%d, %d) taps (%.4f, %.4f), the reference (%.4f, %.4f): %.4f px "
                                         "apart, bound %.2f (block [%d, %d) bound %.4f)", trial, x, y, tu, tv, bu, bv, e,
                                         FV_TW_BLOCK_POS_PX, plan[i].x0, plan[i].x1, plan[i].err_px);
                            /* the value bound: 2 (bound + 1/128) x the channel's range over the 4x4
                             * pixels around the reference's tap, + 1 */
                            const int x0 = (int)bu, y0 = (int)bv;
                            for (int ch = 0; ch < 3; ch++) {
                                int lo = 255, hi = 0;
                                for (int yy = y0 - 1; yy <= y0 + 2; yy++)
                                    for (int xx = x0 - 1; xx <= x0 + 2; xx++) {
                                        const int cx = xx < 0 ? 0 : xx >= BW_W ? BW_W - 1 : xx;
                                        const int cy = yy < 0 ? 0 : yy >= BW_H ? BW_H - 1 : yy;
                                        const int v = rgb[((size_t)cy * BW_W + cx) * 3 + ch];
                                        lo = v < lo ? v : lo, hi = v > hi ? v : hi;
                                    }
                                const int bound = (int)(2.0f * (FV_TW_BLOCK_POS_PX + 1.0f / 128.0f) * (float)(hi - lo) + 1.01f);
                                const int diff = abs((int)blk[3 * j + ch] - (int)ref[3 * j + ch]);
                                if (diff > bound)
                                    fail_msg("trial %d: pixel (%d, %d) channel %d: %d, the reference %d, bound %d", trial, x,
                                             y, ch, blk[3 * j + ch], ref[3 * j + ch], bound);
                            }
                        }
                }
            }
            if (holes != want_holes)
                fail_msg("trial %d: %ld disoccluded pixels, the reference's over the per-pixel blocks %ld", trial, holes,
                         want_holes);
        }
    }
    printf("    bounded warp: %.1f %% of the pixels as grid cells\n", 100.0 * (double)grid_total / (double)checked);
    printf("    block warp: %ld pixels checked, %.1f %% translated, worst tap distance %.4f px\n", checked,
           100.0 * (double)fast_total / (double)(checked ? checked : 1), worst_pos);
    /* both paths were exercised */
    assert_true(fast_total > checked / 4);
    assert_true(slow_total > 0);
    assert_true(grid_total > 0); /* the bounded warp's grid cells were exercised */
    free(rgb), free(ref), free(blk), free(bnd), free(invd), free(refhole), free(fastpx), free(lohi), free(want_tiles), free(lohi4), free(want4), free(plan);
}

const struct CMUnitTest checkasm_timewarp_tests[] = {
    cmocka_unit_test(test_tables),
    cmocka_unit_test(test_tw_row),
    cmocka_unit_test(test_tw_spans),
    cmocka_unit_test(test_tw_spans_formula),
    cmocka_unit_test(test_tw_runs),
    cmocka_unit_test(test_tw_minmax),
    cmocka_unit_test(test_tw_stream),
    cmocka_unit_test(test_block_warp),
    {0},
};
