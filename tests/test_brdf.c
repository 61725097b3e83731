/* BRDF tests: core/brdf.h against the glTF 2.0 specification's appendix B. Hand-computed values
 * at chosen points (worked out in the comments), then a sweep against the appendix's formulas
 * written out here again in double precision, in the appendix's own form (mix of a dielectric
 * and a metal BRDF), over metal, dielectric, rough, smooth and grazing configurations. */
#include "testutil.h"

#include "brdf.h"

#include <math.h>
#include <string.h>

#define PI 3.14159265358979323846

static void assert_rel(double got, double want, double rel, const char *what, int line)
{
    if (!(fabs(got - want) <= rel * fmax(fabs(want), 1e-3))) {
        print_error("line %d: %s = %.9g, expected %.9g (rel %g)\n", line, what, got, want, rel);
        fail();
    }
}
#define ASSERT_REL(got, want, rel) assert_rel((got), (want), (rel), #got, __LINE__)

static fv_brdf_mat mat(float base, float metallic, float roughness, float specular)
{
    const fv_brdf_mat m = {{base, base, base}, metallic, fv_ggx_a2(roughness), specular};
    return m;
}

/* Head-on (n = l = v = h: every cosine 1, Schlick weight 0):
 *   roughness 0.5: a = 0.25, a2 = 1/16, D = 1/(pi a2) = 16/pi, V = 0.5/(1 + 1) = 1/4, pi V D = 4.
 *   dielectric base 0.5: (1 - 0.04) 0.5 + 0.04 x 4 = 0.64; metal base 0.5: 4 x 0.5 = 2;
 *   metallic 0.5: (0.64 + 2)/2 = 1.32.
 *   roughness 1: a2 = 1, D = 1/pi, V = 1/4, pi V D = 1/4; white dielectric: 0.96 + 0.01 = 0.97.
 *   matte (specular 0): base x n.l, whatever the roughness. */
static void test_head_on_values(void **state)
{
    (void)state;
    float f[3];
    fv_brdf_mat m = mat(0.5f, 0.0f, 0.5f, 1.0f);
    ASSERT_REL(fv_ggx_a2(0.5f), 0.0625, 1e-7);
    ASSERT_REL(fv_ggx_d(m.a2, 1.0f), 16.0 / PI, 1e-6);
    ASSERT_REL(fv_smith_v(m.a2, 1.0f, 1.0f), 0.25, 1e-7);
    ASSERT_REL(fv_schlick_w(1.0f), 0.0, 0);
    fv_brdf_cos(&m, 1, 1, 1, 1, f);
    ASSERT_REL(f[0], 0.64, 1e-6);
    m = mat(0.5f, 1.0f, 0.5f, 1.0f);
    fv_brdf_cos(&m, 1, 1, 1, 1, f);
    ASSERT_REL(f[1], 2.0, 1e-6);
    m = mat(0.5f, 0.5f, 0.5f, 1.0f);
    fv_brdf_cos(&m, 1, 1, 1, 1, f);
    ASSERT_REL(f[2], 1.32, 1e-6);
    m = mat(1.0f, 0.0f, 1.0f, 1.0f);
    fv_brdf_cos(&m, 1, 1, 1, 1, f);
    ASSERT_REL(f[0], 0.97, 1e-6);
    m = mat(0.7f, 0.0f, 0.2f, 0.0f);
    fv_brdf_cos(&m, 0.3f, 0.9f, 0.8f, 0.6f, f);
    ASSERT_REL(f[0], 0.7 * 0.3, 1e-6);
}

/* Grazing: l and v at 89 degrees from n on opposite sides, so h = n, n.h = 1 and
 * v.h = cos 89 deg: the Schlick weight (1 - 0.017452)^5 = 0.91574 takes the dielectric Fresnel
 * to 0.04 + 0.96 x 0.91574 = 0.91911 and a metal's towards white: a black metal reflects
 * 0.91574 of its specular lobe. Rough (a2 = 1): D = 1/pi, V = 0.5/(2 cos 89), pi V D n.l = 1/4. */
static void test_grazing_fresnel(void **state)
{
    (void)state;
    const double c = cos(89.0 * PI / 180.0), w = pow(1.0 - c, 5.0);
    ASSERT_REL(fv_schlick_w((float)c), w, 1e-5);
    ASSERT_REL(w, 0.91574, 1e-4);
    float f[3];
    fv_brdf_mat m = mat(0.0f, 1.0f, 1.0f, 1.0f); /* black metal */
    fv_brdf_cos(&m, (float)c, (float)c, 1.0f, (float)c, f);
    ASSERT_REL(f[0], 0.25 * w, 1e-5);
    m = mat(0.0f, 0.0f, 1.0f, 1.0f); /* black dielectric: only the Fresnel-weighted lobe */
    fv_brdf_cos(&m, (float)c, (float)c, 1.0f, (float)c, f);
    ASSERT_REL(f[0], 0.25 * (0.04 + 0.96 * w), 1e-5);
}

/* The ambient term: a uniform surround of radiance 0.15: dielectric base 0.5 reflects
 * 0.15 (0.96 x 0.5 + 0.04) = 0.078, a metal 0.15 x 0.5 = 0.075, matte 0.15 x 0.5. */
static void test_ambient(void **state)
{
    (void)state;
    float a[3];
    fv_brdf_mat m = mat(0.5f, 0.0f, 0.3f, 1.0f);
    fv_brdf_ambient(&m, 0.15f, a);
    ASSERT_REL(a[0], 0.078, 1e-6);
    m = mat(0.5f, 1.0f, 0.3f, 1.0f);
    fv_brdf_ambient(&m, 0.15f, a);
    ASSERT_REL(a[0], 0.075, 1e-6);
    m = mat(0.5f, 0.0f, 0.3f, 0.0f);
    fv_brdf_ambient(&m, 0.15f, a);
    ASSERT_REL(a[0], 0.075, 1e-6);
}

/* Appendix B in double, in its own form: material = mix(dielectric_brdf, metal_brdf, metallic),
 * dielectric_brdf = fresnel_mix(ior 1.5, diffuse_brdf, specular_brdf) (the mix weighted by
 * KHR_materials_specular's factor), metal_brdf = conductor_fresnel(baseColor, specular_brdf). */
static double spec_pi_f_cos(double base, double metallic, double roughness, double specular, double nl, double nv,
                            double nh, double vh)
{
    const double alpha = roughness * roughness, a2 = alpha * alpha;
    const double D = a2 / (PI * pow(nh * nh * (a2 - 1.0) + 1.0, 2.0)); /* nh > 0 here */
    const double V = 0.5 / (nl * sqrt(nv * nv * (1.0 - a2) + a2) + nv * sqrt(nl * nl * (1.0 - a2) + a2));
    const double specular_brdf = V * D, diffuse_brdf = base / PI;
    const double f0 = pow((1.0 - 1.5) / (1.0 + 1.5), 2.0);
    const double fr = f0 + (1.0 - f0) * pow(1.0 - fabs(vh), 5.0);
    const double dielectric = diffuse_brdf + (specular_brdf - diffuse_brdf) * (specular * fr);
    const double metal = specular_brdf * (base + (1.0 - base) * pow(1.0 - fabs(vh), 5.0));
    return PI * (dielectric + (metal - dielectric) * metallic) * nl;
}

/* Random unit l, v in the upper hemisphere of n = z, every material: float within 2e-5 relative
 * (the float formulas' rounding; worst near the mirror floor where D ~ 1e4). */
static void test_sweep_against_appendix(void **state)
{
    (void)state;
    uint64_t seed = 17;
    int n = 0;
    for (int it = 0; it < 20000; it++) {
        double l[3], v[3];
        for (int pass = 0; pass < 2; pass++) {
            double *d = pass ? v : l;
            const double ct = 0.02 + 0.98 * fv_test_randf(&seed), ph = 2.0 * PI * fv_test_randf(&seed);
            const double st = sqrt(1.0 - ct * ct);
            d[0] = st * cos(ph), d[1] = st * sin(ph), d[2] = ct;
        }
        double h[3] = {l[0] + v[0], l[1] + v[1], l[2] + v[2]};
        const double hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        for (int k = 0; k < 3; k++) h[k] /= hl;
        const double nl = l[2], nv = v[2], nh = h[2], vh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
        const double base = fv_test_randf(&seed);
        const double metallic = it % 3 == 0 ? 0.0 : it % 3 == 1 ? 1.0 : fv_test_randf(&seed);
        const double roughness = 0.1 + 0.9 * fv_test_randf(&seed);
        const double specular = it % 5 == 0 ? fv_test_randf(&seed) : 1.0;
        const fv_brdf_mat m = mat((float)base, (float)metallic, (float)roughness, (float)specular);
        float f[3];
        fv_brdf_cos(&m, (float)nl, (float)nv, (float)nh, (float)vh, f);
        const double want = spec_pi_f_cos((float)base, (float)metallic, (float)roughness, (float)specular, (float)nl,
                                          (float)nv, (float)nh, (float)vh);
        if (!(fabs(f[0] - want) <= 2e-5 * fmax(want, 1e-2))) {
            print_error("it %d base %g metallic %g roughness %g specular %g nl %g nv %g nh %g vh %g: %.9g vs %.9g\n", it,
                        base, metallic, roughness, specular, nl, nv, nh, vh, (double)f[0], want);
            fail();
        }
        n++;
    }
    assert_int_equal(n, 20000);
}

/* Roughness 0 is clamped to the floor: D stays finite at the mirror direction, and equals the
 * formula at roughness FV_MIN_ROUGHNESS; out-of-range cosines are clamped, NaN gives 0. */
static void test_clamps(void **state)
{
    (void)state;
    ASSERT_REL(fv_ggx_a2(0.0f), pow(FV_MIN_ROUGHNESS, 4.0), 1e-6);
    ASSERT_REL(fv_ggx_a2(2.0f), 1.0, 0);
    const float d = fv_ggx_d(fv_ggx_a2(0.0f), 1.0f);
    assert_true(isfinite(d));
    ASSERT_REL(d, 1.0 / (PI * pow(FV_MIN_ROUGHNESS, 4.0)), 1e-5);
    assert_true(fv_clamp01(NAN) == 0.0f && fv_clamp01(-1.0f) == 0.0f && fv_clamp01(1.5f) == 1.0f);
    float f[3];
    const fv_brdf_mat m = mat(0.5f, 1.0f, 0.0f, 1.0f);
    fv_brdf_cos(&m, 1.0f, 1.0f, 1.00001f, 1.0f, f); /* n.h a hair above 1 by rounding */
    assert_true(isfinite(f[0]) && f[0] > 0.0f);
}

/* The head light's shortcut (l = v) is the general BRDF at n.l = n.h = n.v, v.h = 1, bit for
 * bit, for every material and n.v in (0, 1]; and the hand-worked head-on value above. */
static void test_head_light(void **state)
{
    (void)state;
    uint64_t seed = 0x4ead11647ull;
    for (int it = 0; it < 20000; it++) {
        const float nv = it == 0 ? 1.0f : it == 1 ? 1e-20f : 1e-6f + (1.0f - 1e-6f) * (float)fv_test_randf(&seed);
        const float roughness = it % 7 == 0 ? 0.0f : (float)fv_test_randf(&seed);
        const float metallic = it % 3 == 0 ? 0.0f : it % 3 == 1 ? 1.0f : (float)fv_test_randf(&seed);
        const float specular = it % 5 == 0 ? 0.0f : 1.0f;
        fv_brdf_mat m = mat((float)fv_test_randf(&seed), metallic, roughness, specular);
        m.base[1] = (float)fv_test_randf(&seed), m.base[2] = (float)fv_test_randf(&seed);
        float want[3], got[3];
        fv_brdf_cos(&m, nv, nv, nv, 1.0f, want);
        fv_brdf_cos_head(&m, nv, got);
        for (int k = 0; k < 3; k++)
            if (memcmp(&want[k], &got[k], sizeof(float))) {
                print_error("it %d nv %.9g channel %d: head %.9g, general %.9g\n", it, (double)nv, k, (double)got[k],
                            (double)want[k]);
                fail();
            }
    }
    const fv_brdf_mat half = mat(0.5f, 0.5f, 0.5f, 1.0f);
    float f[3];
    fv_brdf_cos_head(&half, 1.0f, f);
    ASSERT_REL(f[0], 1.32, 1e-6); /* test_head_on_values */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_head_on_values),  cmocka_unit_test(test_grazing_fresnel),
        cmocka_unit_test(test_ambient),         cmocka_unit_test(test_sweep_against_appendix),
        cmocka_unit_test(test_clamps),          cmocka_unit_test(test_head_light),
    };
    return cmocka_run_group_tests_name("brdf", tests, NULL, NULL);
}
