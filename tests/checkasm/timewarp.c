/* fovea checkasm: the timewarp kernel (timewarp_dsp.h), every ISA version against the C
 * reference, bit for bit (bytes and disocclusion count): maps from random head motions (small
 * turns and steps, a turn past 90 degrees that puts source points behind the eye, steps that
 * hit the depth conversion's floor), sources with depth edges, flat depth, the nearest and the
 * farthest depth codes; every row length from 1 up with tails, offsets into the row, the first
 * and last rows. Outputs canaried; source planes exact-size plus the contract's padding. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkasm.h"

#include "camera.h"
#include "timewarp.h"

static const char *const names[] = {"tw_row"};

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
        for (int trial = 0; trial < 48; trial++) {
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

const struct CMUnitTest checkasm_timewarp_tests[] = {
    cmocka_unit_test(test_tables),
    cmocka_unit_test(test_tw_row),
    {0},
};
