/* fovea checkasm: the ray-generation kernel (raygen_dsp.h), every ISA version against the C
 * reference, bit for bit: random cameras (also huge and tiny pixel angles, negative axes), random
 * pixel lists of both packet widths, sample positions anywhere in the pixel (centre, edges, random), tiles anywhere up to 16384 px. Outputs are canaried. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkasm.h"

#include "raygen_dsp.h"

static float rnd(float lo, float hi) { return lo + (hi - lo) * checkasm_randf(); }

static void test_tables(void **state)
{
    (void)state;
    checkasm_rng = 0x5eedca3e7aull;
    static const char *const names[] = {"camera_rays"};
    fv_raygen_dsp ref;
    fv_raygen_dsp_init(&ref, FV_ISA_C);
    assert_true(ref.camera_rays == fv_camera_rays_c);
    CHECKASM_CHECK_ISA_TABLES("raygen", fv_raygen_dsp, &ref, names);
}

static void test_camera_rays(void **state)
{
    (void)state;
    int tested = 0;
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "camera_rays"))
            continue;
        fv_raygen_dsp d;
        fv_raygen_dsp_init(&d, isa);
        if (!d.camera_rays || d.camera_rays == fv_camera_rays_c)
            fail_msg("camera_rays: %s has no version of its own", fv_isa_name(isa));
        int runs = 0;
        for (int r = 0; r < 3000; r++) {
            const int n = r & 1 ? 16 : 8;
            static const float scale[] = {1e-3f, 1.0f, 1e-30f, 1e20f};
            const float s = scale[r % 4];
            /* the pixel centre, and (fovea anti-aliasing) anywhere in the pixel, its edges too */
            static const float edge[] = {0.0f, 0.99999994f, 0.5f};
            const float ox = r % 5 < 3 ? edge[r % 5] : checkasm_randf(), oy = r % 7 < 3 ? edge[r % 7] : checkasm_randf();
            fv_raygen_cam c = {rnd(-2, 0) * s, rnd(0, 2) * s, rnd(0, 0.01f) * s, {0}, {0}, {0}, ox, oy};
            for (int i = 0; i < 3; i++)
                c.right[i] = rnd(-1, 1), c.up[i] = rnd(-1, 1), c.back[i] = rnd(-1, 1) * s;
            uint8_t px[16];
            for (int i = 0; i < 16; i++)
                px[i] = (uint8_t)(checkasm_rand() & 255u);
            const int x0 = 16 * (int)(checkasm_rand() % 1024), y0 = 16 * (int)(checkasm_rand() % 1024);
            float ref[3][16];
            fv_camera_rays_c(&c, px, x0, y0, ref[0], ref[1], ref[2], n);
            buf got[3];
            for (int i = 0; i < 3; i++)
                got[i] = checkasm_out_f32((size_t)n, r & 3);
            d.camera_rays(&c, px, x0, y0, got[0].p, got[1].p, got[2].p, n);
            for (int i = 0; i < 3; i++) {
                checkasm_check_guards_f32(&got[i], (size_t)n, fv_isa_name(isa), "camera_rays", n);
                checkasm_compare(ref[i], got[i].p, (size_t)n, CHECKASM_F32, 1, CHECKASM_EXACT,
                                 "%s camera_rays run %d axis %d n %d", fv_isa_name(isa), r, i, n);
                free(got[i].base);
            }
            runs++;
        }
        printf("[ checkasm ] camera_rays: %-7s == c on %d packets (bit-exact)\n", fv_isa_name(isa), runs);
        tested++;
    }
    printf("[ checkasm ] camera_rays: %d ISA version(s) tested\n", tested);
}

const struct CMUnitTest checkasm_raygen_tests[] = {
    cmocka_unit_test(test_tables),
    cmocka_unit_test(test_camera_rays),
    {0},
};
