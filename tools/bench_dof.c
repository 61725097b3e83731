/* bench_dof: times the layered depth-of-field kernels (dsp.h dof_*) of every ISA this CPU runs on
 * production-sized rows (1280 pixels; far CoCs of 2..16 px, so Gaussian sigmas of 0.5..4 px and
 * radii 2..12), single thread, data in cache as in the pipeline's bands, the Gaussians called on
 * spans of 128 pixels as core/dof/weier.c calls them. Prints ns per output pixel (the median of
 * --reps runs) and the speed-up over the C reference; the kernels' outputs are also compared
 * with the reference's (bit-identity, as tests/test_kernels_dof checks in depth).
 * A developer tool for the kernels; on a shared machine take the ratios, not the times.
 *
 *   build/tools/bench_dof [--reps N] [--width W]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dof/weier_impl.h"
#include "dsp.h"
#include "pipeline.h"
#include "pullpush.h"

#define SPAN 128 /* TILE * 8, the span of core/dof/weier.c's Gaussian calls */
#define ROWS 8   /* rows cycled through per timed pass (in cache) */
#define VROWS 48 /* rows of the vertical pass's source plane */

static uint64_t rng = 0xbe4c4d0full;
static float rnd(void)
{
    uint64_t z = (rng += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return (float)((z ^ (z >> 31)) >> 40) * (1.0f / 16777216.0f);
}

static uint8_t sig_index(float sigma) /* as core/dof/weier.c */
{
    const float s = sigma * FV_DOF_SIG_STEPS + 0.5f;
    return (uint8_t)(s < (float)(FV_DOF_NSIG - 1) ? (s > 0.0f ? (int)s : 0) : FV_DOF_NSIG - 1);
}

static int cmp_d(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

typedef struct {
    int W, reps;
    fv_dof_gauss_tab tab;
    float *rgbd, *coc;              /* ROWS rows of level 0 and their CoCs */
    uint8_t *sig;                   /* ROWS rows of sigma indices (far CoC / 4) */
    float *plane;                   /* VROWS rows of far_h */
    float *dst;                     /* ROWS output rows */
    fv_pyramid pyr;
    float *near, *far, *enh;        /* one row each */
} bench;

enum { K_COC, K_HG, K_VG, K_COMB, K_N };
static const char *kname[K_N] = {"coc_row", "hgauss_row", "vgauss_row", "combine_row"};

/* One timed pass of kernel k over ROWS rows; returns ns per output pixel. */
static double pass(const bench *b, const fv_dsp *d, int k)
{
    const int W = b->W;
    const int64_t t0 = fv_time_ns();
    for (int r = 0; r < ROWS; r++) {
        const float *rgbd = b->rgbd + 4 * (size_t)W * (size_t)r, *coc = b->coc + (size_t)W * (size_t)r;
        const uint8_t *sig = b->sig + (size_t)W * (size_t)r;
        float *dst = b->dst + 4 * (size_t)W * (size_t)r;
        switch (k) {
        case K_COC: d->dof_coc_row(dst, rgbd, W, 20.0f, 1.0f, 1.5f); break;
        case K_HG:
            for (int xs = 0; xs < W; xs += SPAN)
                d->dof_hgauss_row(dst, rgbd, coc, W, xs, W - xs < SPAN ? W - xs : SPAN, sig + xs, &b->tab);
            break;
        case K_VG:
            for (int xs = 0; xs < W; xs += SPAN)
                d->dof_vgauss_row(dst, b->plane, W, 16 + r, 0, VROWS, xs, W - xs < SPAN ? W - xs : SPAN, sig + xs,
                                  &b->tab);
            break;
        default: {
            /* gaze in the row's middle: centre (far layer) within 200 px, periphery (pyramid
             * taps and contrast enhancement) beyond 320 px, the blend between */
            const fv_dof_combine_args a = {
                .pyr = &b->pyr, .y = r, .sharp = b->pyr.lv[0].rgbd + 4 * (ptrdiff_t)r * b->pyr.lv[0].stride,
                .coc = coc, .far = b->far, .far_x0 = W / 2 - 240, .far_x1 = W / 2 + 240, .near = b->near,
                .has_near = r & 1, .gx = 0.5f * (float)W, .gy = (float)r, .r0 = 200.0f, .inv_tr = 1.0f / 120.0f,
                .gain = 0.5f, .enh = b->enh,
            };
            for (int xs = 0; xs < W; xs += 16)
                d->dof_combine_row(dst, &a, xs, W - xs < 16 ? W - xs : 16);
        }
        }
    }
    return (double)(fv_time_ns() - t0) / ((double)ROWS * W);
}

static double median_ns(const bench *b, const fv_dsp *d, int k)
{
    double *t = malloc(sizeof(double) * (size_t)b->reps);
    if (!t)
        exit(1);
    pass(b, d, k); /* warm */
    for (int i = 0; i < b->reps; i++) {
        double s = 0.0;
        for (int j = 0; j < 4; j++)
            s += pass(b, d, k);
        t[i] = s / 4;
    }
    qsort(t, (size_t)b->reps, sizeof(double), cmp_d);
    const double m = t[b->reps / 2];
    free(t);
    return m;
}

/* CoC profile: smooth (ramps of 2..16 px along the row, some in-focus and near pixels) or noisy
 * (every pixel its own far CoC of 2..16 px: the Gaussians' blocks run to their largest radius) */
static void fill_coc(bench *b, int noisy)
{
    const int W = b->W;
    for (int r = 0; r < ROWS; r++)
        for (int x = 0; x < W; x++) {
            const size_t i = (size_t)r * (size_t)W + (size_t)x;
            float c = noisy ? 2.0f + 14.0f * rnd() : 9.0f + 7.0f * sinf((float)x * 0.01f + (float)r);
            const float u = rnd();
            if (!noisy && u < 0.1f)
                c = u < 0.05f ? 0.0f : -4.0f * rnd();
            b->coc[i] = c;
            /* the far sigma; in-focus / near pixels carry a tile's far sigma as weier.c does */
            b->sig[i] = sig_index(c > 0.0f ? c * 0.25f : 2.0f);
        }
}

int main(int argc, char **argv)
{
    bench b = {.W = 1280, .reps = 9};
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--reps") && i + 1 < argc)
            b.reps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--width") && i + 1 < argc)
            b.W = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: bench_dof [--reps N] [--width W]\n");
            return strcmp(argv[i], "--help") ? 2 : 0;
        }
    }
    if (b.reps < 1 || b.W < 16 || b.W > 16384) {
        fprintf(stderr, "bench_dof: --reps must be >= 1 and --width within 16..16384\n");
        return 2;
    }
    const int W = b.W;
    fv_dof_gauss_tab_init(&b.tab);
    b.rgbd = malloc(4 * sizeof(float) * (size_t)W * ROWS);
    b.coc = malloc(sizeof(float) * (size_t)W * ROWS);
    b.sig = malloc((size_t)W * ROWS);
    b.plane = malloc(4 * sizeof(float) * (size_t)W * VROWS);
    b.dst = malloc(4 * sizeof(float) * (size_t)W * ROWS);
    float *ref = malloc(4 * sizeof(float) * (size_t)W * ROWS);
    b.near = malloc(4 * sizeof(float) * (size_t)W);
    b.far = malloc(4 * sizeof(float) * (size_t)W);
    b.enh = malloc(4 * sizeof(float) * (size_t)W);
    if (!b.rgbd || !b.coc || !b.sig || !b.plane || !b.dst || !ref || !b.near || !b.far || !b.enh ||
        fv_pyramid_init(&b.pyr, W, ROWS)) {
        fprintf(stderr, "bench_dof: out of memory\n");
        return 1;
    }
    for (size_t i = 0; i < (size_t)W * ROWS; i++) {
        for (int c = 0; c < 3; c++)
            b.rgbd[4 * i + (size_t)c] = rnd();
        b.rgbd[4 * i + 3] = 0.3f + 10.0f * rnd();
    }
    for (size_t i = 0; i < 4 * (size_t)W * VROWS; i++)
        b.plane[i] = rnd();
    for (int x = 0; x < W; x++) {
        const float nw = rnd() < 0.7f ? 0.0f : rnd(), fw = 0.2f + rnd();
        for (int c = 0; c < 3; c++) {
            b.near[4 * x + c] = nw * rnd();
            b.far[4 * x + c] = fw * rnd();
            b.enh[4 * x + c] = rnd();
        }
        b.near[4 * x + 3] = nw, b.far[4 * x + 3] = fw, b.enh[4 * x + 3] = rnd();
    }
    fv_pyr_level *l0 = &b.pyr.lv[0];
    for (int y = 0; y < ROWS; y++)
        for (int x = 0; x < W; x++) {
            const ptrdiff_t o = (ptrdiff_t)y * l0->stride + x;
            memcpy(l0->rgbd + 4 * o, b.rgbd + 4 * ((size_t)y * (size_t)W + (size_t)x), 4 * sizeof(float));
            l0->wgt[o] = rnd() < 0.5f ? 1.0f : 0.0f;
        }
    fv_dsp c;
    fv_dsp_init(&c, FV_ISA_C);
    fv_pullpush(&b.pyr, &c, NULL);

    const unsigned isas[] = {FV_ISA_C, FV_ISA_SSE41, FV_ISA_SSE41 | FV_ISA_AVX2, FV_ISA_NEON};
    printf("bench_dof: %d-pixel rows, median of %d runs, one thread; ns per output pixel (x the C reference's speed)\n",
           W, b.reps);
    int bad = 0;
    for (int noisy = 0; noisy < 2; noisy++) {
        fill_coc(&b, noisy);
        printf("CoC profile: %s\n", noisy ? "noisy (far 2..16 px, every pixel its own)"
                                          : "smooth (far 2..16 px ramps, 10% focused / near)");
        printf("  %-12s", "kernel");
        for (int k = 0; k < 4; k++) {
            fv_dsp d;
            fv_dsp_init(&d, isas[k]);
            if (k == 0 || d.isa != FV_ISA_C)
                printf(" %16s", fv_isa_name(d.isa));
        }
        printf("\n");
        for (int kk = 0; kk < K_N; kk++) {
            if (noisy && kk == K_COC)
                continue; /* the CoC does not depend on the profile */
            printf("  %-12s", kname[kk]);
            double cns = 0.0;
            for (int k = 0; k < 4; k++) {
                fv_dsp d;
                fv_dsp_init(&d, isas[k]);
                if (k > 0 && d.isa == FV_ISA_C)
                    continue; /* that ISA is not on this CPU */
                memset(b.dst, 0, 4 * sizeof(float) * (size_t)W * ROWS);
                const double ns = median_ns(&b, &d, kk);
                if (k == 0) {
                    cns = ns;
                    memcpy(ref, b.dst, 4 * sizeof(float) * (size_t)W * ROWS);
                    printf(" %7.2f         ", ns);
                } else {
                    const int same = !memcmp(ref, b.dst, 4 * sizeof(float) * (size_t)W * ROWS);
                    bad |= !same;
                    printf(" %7.2f (%4.2fx)%s", ns, cns / ns, same ? "" : "!");
                }
            }
            printf("\n");
        }
    }
    if (bad)
        printf("bench_dof: ! marks an ISA whose output differs from the C reference's\n");
    fv_pyramid_free(&b.pyr);
    free(b.rgbd), free(b.coc), free(b.sig), free(b.plane), free(b.dst), free(ref), free(b.near), free(b.far),
        free(b.enh);
    return bad;
}
