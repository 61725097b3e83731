/* fovea checkasm: the packet shading kernel (shade_dsp.h), every ISA version against the C
 * reference on random and edge-case packets, bit for bit (so -0 vs +0 counts): matte, dielectric,
 * metallic and mixed materials from mirror (the roughness floor) to rough, with emission; the head light
 * and every kind of KHR light (directional, point and spot, with and without range, a spot with
 * equal cones), hits at the eye (L = 0), normals facing away, opposite vertex normals
 * (degenerate), zero and huge distances. Outputs are canaried (checkasm.h). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkasm.h"

#include "brdf.h"
#include "shade_dsp.h"

static float rnd(float lo, float hi) { return lo + (hi - lo) * checkasm_randf(); }

enum { M_RANDOM, M_EDGE, M_COUNT };

/* p's geometry in l (fv_shade_packet_lanes); some lanes share another lane's corner normals (a
 * packet's lanes on one triangle) */
static void gen_packet(fv_shade_packet *p, fv_shade_lanes *l, int mode)
{
    static const float ext[] = {0.0f, -0.0f, 1e-30f, 1e-20f, 1.0f, -1.0f, 1e4f, 3e38f, 0.5f};
    for (int q = 0; q < FV_SHADE_LANES; q++) {
        float u = rnd(0.0f, 1.0f), v = rnd(0.0f, 1.0f - u);
        float n0[3] = {rnd(-1, 1), rnd(-1, 1), rnd(-1, 1)};
        for (int k = 0; k < 9; k++)
            l->nrm[q][k] = k < 3 ? n0[k] : rnd(-1.0f, 1.0f);
        float t = rnd(0.01f, 100.0f);
        if (mode == M_EDGE) {
            switch (checkasm_rand() % 8) {
            case 0: /* opposite vertex normals at the midpoint: degenerate */
                for (int k = 0; k < 3; k++) l->nrm[q][3 + k] = -n0[k], l->nrm[q][6 + k] = 0.0f;
                u = 0.5f, v = 0.0f;
                break;
            case 1: t = 0.0f; break; /* the hit at the eye: L = 0 */
            case 2: t = ext[checkasm_rand() % (sizeof ext / sizeof ext[0])]; break;
            case 3: u = 1.0f, v = 0.0f; break;
            case 4: for (int k = 0; k < 9; k++) l->nrm[q][k] = 0.0f; break; /* zero normals */
            default: break;
            }
        }
        l->u[q] = u, l->v[q] = v, l->t[q] = t;
        for (int k = 0; k < 3; k++) {
            l->dir[k][q] = k == 2 ? -1.0f : rnd(-1.5f, 1.5f);
            p->base[k][q] = rnd(0.0f, 1.0f);
            p->emit[k][q] = checkasm_rand() % 4 ? 0.0f : rnd(0.0f, 2.0f);
        }
        /* materials: matte (specular 0), glTF dielectric, metal, in between; rough to mirror */
        static const float metals[] = {0.0f, 1.0f, 0.5f};
        p->metal[q] = checkasm_rand() % 2 ? metals[checkasm_rand() % 3] : rnd(0.0f, 1.0f);
        p->spec[q] = checkasm_rand() % 3 ? 1.0f : checkasm_rand() % 2 ? 0.0f : rnd(0.0f, 1.0f);
        static const float roughs[] = {0.0f, FV_MIN_ROUGHNESS, 1.0f, 0.5f};
        const float r = mode == M_EDGE ? roughs[checkasm_rand() % 4] : rnd(0.0f, 1.0f);
        p->a2[q] = fv_ggx_a2(r);
        p->occl[q] = checkasm_rand() % 2 ? 1.0f : rnd(0.0f, 1.0f);
    }
    fv_shade_packet_lanes(p, l);
    for (int q = 0; q < FV_SHADE_LANES; q++)
        if (checkasm_rand() % 8 == 0)
            p->nrm_at[q] = l->nrm[checkasm_rand() % FV_SHADE_LANES];
}

static int gen_lights(fv_light_rec *l, int max, int mode)
{
    const int n = (int)(checkasm_rand() % (unsigned)(max + 1));
    for (int i = 0; i < n; i++) {
        memset(&l[i], 0, sizeof l[i]);
        l[i].l.type = (fv_light_type)(checkasm_rand() % 3);
        for (int k = 0; k < 3; k++) {
            l[i].l.color[k] = rnd(0.0f, 1.0f);
            l[i].l.pos[k] = rnd(-20.0f, 20.0f);
        }
        const float d[3] = {rnd(-1, 1), rnd(-1, 1), rnd(-1, 1)};
        const float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) + 1e-6f;
        for (int k = 0; k < 3; k++) l[i].l.dir[k] = d[k] / len;
        l[i].l.intensity = mode == M_EDGE && checkasm_rand() % 4 == 0 ? 3e38f : rnd(0.0f, 100.0f);
        l[i].l.range = checkasm_rand() % 2 ? rnd(1.0f, 40.0f) : 0.0f;
        l[i].cos_outer = rnd(0.5f, 0.9f);
        l[i].cos_inner = mode == M_EDGE && checkasm_rand() % 3 == 0 ? l[i].cos_outer : rnd(l[i].cos_outer, 1.0f);
    }
    return n;
}

static void test_tables(void **state)
{
    (void)state;
    checkasm_rng = 0x5eed05adeull;
    static const char *const names[] = {"brdf"};
    fv_shade_dsp ref;
    fv_shade_dsp_init(&ref, FV_ISA_C);
    assert_true(ref.brdf == fv_shade_brdf_c);
    CHECKASM_CHECK_ISA_TABLES("shade", fv_shade_dsp, &ref, names);
}

static void test_brdf(void **state)
{
    (void)state;
    int tested = 0;
    for (int k = 0; checkasm_isas[k]; k++) {
        const unsigned isa = checkasm_isas[k];
        if (!checkasm_cpu_runs(isa, "brdf"))
            continue;
        fv_shade_dsp d;
        fv_shade_dsp_init(&d, isa);
        if (!d.brdf || d.brdf == fv_shade_brdf_c)
            fail_msg("brdf: %s has no version of its own", fv_isa_name(isa));
        int runs = 0;
        for (int r = 0; r < 2000; r++) {
            const int mode = r % M_COUNT;
            fv_shade_packet p;
            fv_shade_lanes geo;
            fv_light_rec lights[10];
            gen_packet(&p, &geo, mode);
            /* 1 run in 10 with up to 10 lights: more than the NEON kernel prepares (it falls back to
             * the template's loop) */
            const int nl = r < 200 ? 0 : gen_lights(lights, r % 10 == 9 ? 10 : 6, mode);
            /* every third run with shadows: each light occluded on random lanes (fv_shade_env.lit) */
            float lit[10][FV_SHADE_LANES];
            for (int j = 0; j < 10; j++)
                for (int q = 0; q < FV_SHADE_LANES; q++) lit[j][q] = rnd(0, 1) < 0.4f ? 0.0f : 1.0f;
            const fv_shade_env env = {.lights = lights, .nlights = nl, .exposure = rnd(0.01f, 2.0f),
                                      .eye = {rnd(-5, 5), rnd(-5, 5), rnd(-5, 5)}, .lit = r % 3 == 2 ? &lit[0][0] : NULL};
            float ref[3][FV_SHADE_LANES];
            buf got = checkasm_out_f32(3 * FV_SHADE_LANES, r & 3);
            const unsigned dr = fv_shade_brdf_c(&p, &env, ref);
            const unsigned dg = d.brdf(&p, &env, (float(*)[FV_SHADE_LANES])got.p);
            checkasm_check_guards_f32(&got, 3 * FV_SHADE_LANES, fv_isa_name(isa), "brdf", r);
            if (dr != dg)
                fail_msg("%s brdf run %d: degenerate lanes %#x, c %#x", fv_isa_name(isa), r, dg, dr);
            /* the degenerate lanes' rgb is unspecified: compare the others */
            for (int q = 0; q < FV_SHADE_LANES; q++)
                if (dr >> q & 1u)
                    for (int c = 0; c < 3; c++) ref[c][q] = got.p[c * FV_SHADE_LANES + q] = 0.0f;
            checkasm_compare(ref, got.p, 3 * FV_SHADE_LANES, CHECKASM_F32, 1, CHECKASM_EXACT,
                             "%s brdf run %d lights %d mode %d", fv_isa_name(isa), r, nl, mode);
            free(got.base);
            runs++;
        }
        printf("[ checkasm ] brdf: %-7s == c on %d packets (bit-exact)\n", fv_isa_name(isa), runs);
        tested++;
    }
    printf("[ checkasm ] brdf: %d ISA version(s) tested\n", tested);
}

const struct CMUnitTest checkasm_shade_tests[] = {
    cmocka_unit_test(test_tables),
    cmocka_unit_test(test_brdf),
    {0},
};
