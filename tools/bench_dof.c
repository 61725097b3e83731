/* bench_dof: times the layered depth-of-field kernels (dsp.h dof_*) of every ISA this CPU runs on
 * production-sized rows (1280 pixels; far CoCs of 2..16 px, so Gaussian sigmas of 0.5..4 px and
 * radii 2..12), single thread, data in cache as in the pipeline's bands, the Gaussians called on
 * spans of 128 pixels and the combine, the up-sampling and the periphery's level blend on whole
 * rows as core/dof/weier.c calls them. Each run times one pass of every ISA back
 * to back in this thread's CPU time; printed: ns per output pixel (the median of --reps runs, at
 * most 256) and the speed-up over C (the median of the runs' ratios). The outputs are also
 * compared with the C reference's (bit-identity; tests/test_kernels_dof checks it in depth).
 * A developer tool for the kernels; on a shared machine trust the ratios more than the times.
 *
 *   build/tools/bench_dof [--reps N] [--width W]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dof/weier_impl.h"
#include "dsp.h"

#define SPAN 128 /* TILE * 8, the span of core/dof/weier.c's Gaussian calls */
#define ROWS 8   /* rows cycled through per timed pass (in cache) */
#define VROWS 48 /* rows of the vertical pass's source plane */
#define UPL 5    /* pyramid levels up-sampled (MAX_UP_LEVEL of core/dof/weier.c) */
#define LSTEPS 8 /* the level LUT's steps per pixel of CoC (LAMBDA_STEPS) */

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

/* this thread's CPU time: time slices other processes of a loaded machine take do not count */
static int64_t cpu_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
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
    uint8_t *sigh, *sigv;           /* ROWS rows of sigma indices of the two passes */
    float *plane;                   /* VROWS rows of far_h */
    float *dst;                     /* ROWS output rows */
    float *near, *lnear, *far, *enh, *t; /* one row each */
    float *tmp;                     /* a row of level-1 texels (the up-sampling's source) */
    int32_t *i0[UPL + 1], *i1[UPL + 1]; /* up-sampling taps by 2^L, L = 1..UPL */
    float *ax[UPL + 1];
    float *up[UPL + 1];             /* up-sampled level rows (up[0] = the row's level 0) */
    float lambda[LSTEPS * 64 + 1];  /* CoC -> continuous level, as core/dof/weier.c */
} bench;

enum { K_COC, K_HG, K_VG, K_COMB, K_UP, K_PB, K_N };
static const char *kname[K_N] = {"coc_row", "hgauss_row", "vgauss_row", "combine_row", "upsample_row", "pyrblur_row"};

/* One timed pass of kernel k over ROWS rows; returns ns per output pixel. */
static double pass(const bench *b, const fv_dsp *d, int k)
{
    const int W = b->W;
    const int64_t t0 = cpu_ns();
    for (int r = 0; r < ROWS; r++) {
        const float *rgbd = b->rgbd + 4 * (size_t)W * (size_t)r, *coc = b->coc + (size_t)W * (size_t)r;
        const uint8_t *sigh = b->sigh + (size_t)W * (size_t)r, *sigv = b->sigv + (size_t)W * (size_t)r;
        float *dst = b->dst + 4 * (size_t)W * (size_t)r;
        switch (k) {
        case K_COC: d->dof_coc_row(dst, rgbd, W, 20.0f, 1.0f, 1.5f); break;
        case K_HG:
            for (int xs = 0; xs < W; xs += SPAN)
                d->dof_hgauss_row(dst, rgbd, coc, W, xs, W - xs < SPAN ? W - xs : SPAN, sigh + xs, &b->tab);
            break;
        case K_VG:
            for (int xs = 0; xs < W; xs += SPAN)
                d->dof_vgauss_row(dst, b->plane, W, 16 + r, 0, VROWS, xs, W - xs < SPAN ? W - xs : SPAN, sigv + xs,
                                  &b->tab);
            break;
        case K_UP: /* levels 1..4 by turns */
            d->dof_upsample_row(dst, b->tmp, b->i0[1 + r % 4], b->i1[1 + r % 4], b->ax[1 + r % 4], W);
            break;
        case K_PB: {
            /* the row's own CoCs and t (the periphery beyond 320 px of the middle), all 5 levels */
            const float *ups[UPL + 1] = {rgbd, b->up[1], b->up[2], b->up[3], b->up[4], b->up[5]};
            const fv_dof_pyrblur_args pa = {.coc = coc, .t = b->t, .up = ups, .need = UPL, .lambda = b->lambda,
                                            .lambda_steps = LSTEPS, .lambda_max = 64 * LSTEPS};
            d->dof_pyrblur_row(dst, &pa, 0, W);
            break;
        }
        default: {
            /* as core/dof/weier.c: the whole row at once; near layers and enhancement on
             * odd rows only (tiles no near sample reaches; contrast enhancement off by default) */
            const fv_dof_combine_args a = {
                .sharp = rgbd, .coc = coc, .far = b->far, .near = r & 1 ? b->near : NULL,
                .lnear = r & 1 ? b->lnear : NULL, .t = b->t, .enh = r & 1 ? b->enh : NULL, .gain = 0.5f,
            };
            d->dof_combine_row(dst, &a, 0, W);
        }
        }
    }
    return (double)(cpu_ns() - t0) / ((double)ROWS * W);
}

static double median(double *t, int n)
{
    qsort(t, (size_t)n, sizeof(double), cmp_d);
    return t[n / 2];
}

/* CoC profile: smooth (ramps of 2..16 px along the row, with an in-focus and a near segment
 * of 40..120 px, as objects in front of a far background) or noisy (every pixel its own far CoC
 * of 2..16 px: the Gaussians' blocks run to their largest radius). The sigma indices as
 * core/dof/weier.c makes them: the far sigma c / 4; in the horizontal pass in-focus and near
 * pixels carry their tile's largest far sigma (here the row's), in the vertical pass 0. */
static void fill_coc(bench *b, int noisy)
{
    const int W = b->W;
    for (int r = 0; r < ROWS; r++) {
        const int f0 = (int)(rnd() * (float)W), f1 = f0 + 40 + (int)(80.0f * rnd());
        const int n0 = (int)(rnd() * (float)W), n1 = n0 + 40 + (int)(80.0f * rnd());
        float cmax = 0.0f;
        for (int x = 0; x < W; x++) {
            const size_t i = (size_t)r * (size_t)W + (size_t)x;
            float c = noisy ? 2.0f + 14.0f * rnd() : 9.0f + 7.0f * sinf((float)x * 0.01f + (float)r);
            if (!noisy && x >= f0 && x < f1)
                c = 0.0f;
            if (!noisy && x >= n0 && x < n1)
                c = -3.0f - 3.0f * rnd();
            b->coc[i] = c;
            cmax = c > cmax ? c : cmax;
        }
        for (int x = 0; x < W; x++) {
            const size_t i = (size_t)r * (size_t)W + (size_t)x;
            const float c = b->coc[i];
            b->sigh[i] = sig_index(c > 0.0f ? c * 0.25f : cmax * 0.25f);
            b->sigv[i] = sig_index(c > 0.0f ? c * 0.25f : 0.0f);
        }
    }
}

int main(int argc, char **argv)
{
    bench b = {.W = 1280, .reps = 31};
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
    b.sigh = malloc((size_t)W * ROWS);
    b.sigv = malloc((size_t)W * ROWS);
    b.plane = malloc(4 * sizeof(float) * (size_t)W * VROWS);
    b.dst = malloc(4 * sizeof(float) * (size_t)W * ROWS);
    float *ref = malloc(4 * sizeof(float) * (size_t)W * ROWS);
    b.near = malloc(4 * sizeof(float) * (size_t)W);
    b.far = malloc(4 * sizeof(float) * (size_t)W);
    b.enh = malloc(4 * sizeof(float) * (size_t)W);
    b.lnear = malloc(4 * sizeof(float) * (size_t)W);
    b.t = malloc(sizeof(float) * (size_t)W);
    b.tmp = malloc(4 * sizeof(float) * (size_t)W);
    int oom = !b.tmp;
    for (int L = 0; L <= UPL; L++) {
        b.i0[L] = malloc(sizeof(int32_t) * (size_t)W), b.i1[L] = malloc(sizeof(int32_t) * (size_t)W);
        b.ax[L] = malloc(sizeof(float) * (size_t)W), b.up[L] = malloc(4 * sizeof(float) * (size_t)W);
        oom |= !b.i0[L] || !b.i1[L] || !b.ax[L] || !b.up[L];
    }
    if (oom || !b.rgbd || !b.coc || !b.sigh || !b.sigv || !b.plane || !b.dst || !ref || !b.near || !b.far ||
        !b.enh || !b.lnear || !b.t) {
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
    for (size_t i = 0; i < 4 * (size_t)W; i++) {
        b.tmp[i] = rnd();
        for (int L = 0; L <= UPL; L++)
            b.up[L][i] = rnd();
    }
    for (int L = 1; L <= UPL; L++) /* taps as core/dof/weier.c's xtaps_init, level L of width W >> L */
        for (int x = 0; x < W; x++) {
            const int sw = (W + (1 << L) - 1) >> L;
            const float u = ((float)x + 0.5f) / (float)(1 << L) - 0.5f, fu = floorf(u);
            b.i0[L][x] = (int)fu < 0 ? 0 : (int)fu > sw - 1 ? sw - 1 : (int)fu;
            b.i1[L][x] = (int)fu + 1 > sw - 1 ? sw - 1 : (int)fu + 1;
            b.ax[L][x] = u - fu;
        }
    for (int i = 0; i <= 64 * LSTEPS; i++) { /* as core/dof/weier.c */
        const float c = (float)i / LSTEPS, var = c * c * (1.0f / 16.0f);
        float lo = 0.0f, l = 0.0f;
        for (int L = 1; L <= UPL; L++) {
            const float hi = (3.0f * (float)(1 << (2 * L)) - 1.0f) / 12.0f;
            if (var < hi) {
                l = (float)(L - 1) + (var - lo) / (hi - lo);
                break;
            }
            lo = hi, l = (float)L;
        }
        b.lambda[i] = l;
    }
    /* near layer in runs (objects), t: 0 within 200 px of the row's middle (the fovea), 1
     * beyond 320 px (the periphery), the transition between */
    float nw = 0.0f;
    for (int x = 0; x < W; x++) {
        if (rnd() < 0.02f)
            nw = rnd() < 0.6f ? 0.0f : 0.2f + rnd();
        const float fw = 0.2f + rnd(), lw = rnd() < 0.5f ? 0.0f : rnd();
        for (int c = 0; c < 3; c++) {
            b.near[4 * x + c] = nw * rnd();
            b.lnear[4 * x + c] = lw * rnd();
            b.far[4 * x + c] = rnd();
            b.enh[4 * x + c] = rnd();
        }
        b.near[4 * x + 3] = nw, b.lnear[4 * x + 3] = lw, b.far[4 * x + 3] = fw, b.enh[4 * x + 3] = rnd();
        const float e = fabsf((float)x + 0.5f - 0.5f * (float)W), tt = (e - 200.0f) / 120.0f;
        b.t[x] = tt > 0.0f ? (tt < 1.0f ? tt : 1.0f) : 0.0f;
    }
    const unsigned isas[] = {FV_ISA_C, FV_ISA_SSE41, FV_ISA_SSE41 | FV_ISA_AVX2, FV_ISA_NEON};
    printf("bench_dof: %d-pixel rows, median of %d runs, one thread, CPU time;\n"
           "ns per output pixel (x the C reference's speed, the median of the runs' ratios)\n",
           W, b.reps);
    int bad = 0;
    for (int noisy = 0; noisy < 2; noisy++) {
        fill_coc(&b, noisy);
        printf("CoC profile: %s\n", noisy ? "noisy (far 2..16 px, every pixel its own)"
                                          : "smooth (far 2..16 px ramps, in-focus and near segments)");
        printf("  %-12s", "kernel");
        for (int k = 0; k < 4; k++) {
            fv_dsp d;
            fv_dsp_init(&d, isas[k]);
            if (k == 0 || d.isa != FV_ISA_C)
                printf(" %16s", fv_isa_name(d.isa));
        }
        printf("\n");
        fv_dsp d[4];
        int nd = 0;
        for (int k = 0; k < 4; k++) {
            fv_dsp_init(&d[nd], isas[k]);
            if (k == 0 || d[nd].isa != FV_ISA_C) /* else that ISA is not on this CPU */
                nd++;
        }
        for (int kk = 0; kk < K_N; kk++) {
            if (noisy && (kk == K_COC || kk == K_UP))
                continue; /* the CoC and the up-sampling do not depend on the profile */
            /* each run times every ISA back to back, so a ratio compares runs under the same load */
            double ns[4][256], ratio[4][256];
            const int reps = b.reps < 256 ? b.reps : 256;
            for (int k = 0; k < nd; k++)
                pass(&b, &d[k], kk); /* warm */
            for (int r = 0; r < reps; r++)
                for (int k = 0; k < nd; k++) {
                    ns[k][r] = pass(&b, &d[k], kk);
                    ratio[k][r] = ns[0][r] / ns[k][r];
                }
            printf("  %-12s", kname[kk]);
            for (int k = 0; k < nd; k++) {
                memset(b.dst, 0, 4 * sizeof(float) * (size_t)W * ROWS);
                pass(&b, &d[k], kk);
                if (k == 0) {
                    memcpy(ref, b.dst, 4 * sizeof(float) * (size_t)W * ROWS);
                    printf(" %7.2f         ", median(ns[k], reps));
                } else {
                    const int same = !memcmp(ref, b.dst, 4 * sizeof(float) * (size_t)W * ROWS);
                    bad |= !same;
                    printf(" %7.2f (%4.2fx)%s", median(ns[k], reps), median(ratio[k], reps), same ? "" : "!");
                }
            }
            printf("\n");
        }
    }
    if (bad)
        printf("bench_dof: ! marks an ISA whose output differs from the C reference's\n");
    free(b.rgbd), free(b.coc), free(b.sigh), free(b.sigv), free(b.plane), free(b.dst), free(ref);
    free(b.near), free(b.far), free(b.enh), free(b.lnear), free(b.t), free(b.tmp);
    for (int L = 0; L <= UPL; L++)
        free(b.i0[L]), free(b.i1[L]), free(b.ax[L]), free(b.up[L]);
    return bad;
}
