/* mrl_pairs: how consistent are the MRL pupil labels? Finds pairs of near-identical images in a
 * labelled image list (same subject folder, image numbers at most --gap apart, same size, mean
 * absolute difference at most --mad grey levels after the best whole-pixel shift of up to +-4
 * px) and compares their labels (the second image's label moved by that shift): two labels of
 * the same picture should agree. With --track (a fovea-track CSV of the same list) it does the
 * same for the detections, and reports the detections' error on the pairs whose labels agree
 * (the figures in docs/eyetrack.md are from fovea-track's default --mode auto).
 *
 *   build/tools/mrl_pairs ../shared/assets/eyes/mrl-dev/pupil.txt [--track out.csv]
 *
 * Per sensor (the file name's last field): pairs, median label difference, shares above 2 and 3
 * px, the per-label noise this implies (sigma per axis, assuming independent Gaussian label
 * errors: median difference / (1.1774 sqrt 2)) and what even a detector at the annotators' mean
 * would then score (share within 3 and 5 px of a label: 1 - exp(-d^2 / (2 sigma^2))).
 * Exit status: 0, 2 on bad usage or input. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "eyesrc.h"

typedef struct {
    char name[160], subj[64];
    int num, sensor; /* sensor: the last '_' field (1, 2, ...) */
    int w, h;
    uint8_t *px;
    float lx, ly;
    int has_det;
    float dx, dy;
} entry;

static int cmp_entry(const void *a, const void *b)
{
    const entry *x = a, *y = b;
    const int c = strcmp(x->subj, y->subj);
    return c ? c : (x->num > y->num) - (x->num < y->num);
}

static int cmp_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Mean |a(q + s) - b(q)| over the overlap for the shift s = (sx, sy). */
static double shifted_mad(const entry *a, const entry *b, int sx, int sy)
{
    const int w = a->w, h = a->h;
    long sum = 0, n = 0;
    for (int y = sy < 0 ? -sy : 0; y < (sy > 0 ? h - sy : h); y++)
        for (int x = sx < 0 ? -sx : 0; x < (sx > 0 ? w - sx : w); x++) {
            sum += abs((int)a->px[(y + sy) * w + x + sx] - (int)b->px[y * w + x]);
            n++;
        }
    return n ? (double)sum / (double)n : 1e9;
}

static float median(float *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_float);
    return n ? v[n / 2] : NAN;
}

static double share_above(const float *v, int n, float t)
{
    int k = 0;
    for (int i = 0; i < n; i++)
        k += v[i] > t;
    return n ? 100.0 * k / n : NAN;
}

int main(int argc, char **argv)
{
    const char *list = NULL, *track = NULL;
    double mad_max = 3.0;
    int gap = 3;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--track") && i + 1 < argc)
            track = argv[++i];
        else if (!strcmp(argv[i], "--mad") && i + 1 < argc)
            mad_max = atof(argv[++i]);
        else if (!strcmp(argv[i], "--gap") && i + 1 < argc)
            gap = atoi(argv[++i]);
        else if (argv[i][0] != '-' && !list)
            list = argv[i];
        else {
            fprintf(stderr, "usage: mrl_pairs LIST [--track FOVEA_TRACK.csv] [--mad GREY] [--gap N]\n");
            return 2;
        }
    }
    if (!list || !(mad_max > 0) || gap < 1) {
        fprintf(stderr, "usage: mrl_pairs LIST [--track FOVEA_TRACK.csv] [--mad GREY] [--gap N]\n");
        return 2;
    }
    char err[512];
    fv_eyesrc *src;
    if (fv_eyesrc_open_list(&src, list, err, sizeof err)) {
        fprintf(stderr, "mrl_pairs: %s\n", err);
        return 2;
    }
    const long cnt = fv_eyesrc_count(src);
    entry *e = calloc((size_t)cnt, sizeof *e);
    int n = 0;
    fv_eye_frame f;
    int rc;
    while (e && (rc = fv_eyesrc_next(src, &f, err, sizeof err)) == 1) {
        entry *x = &e[n];
        const char *slash = strrchr(f.name, '/'), *base = slash ? slash + 1 : f.name;
        snprintf(x->name, sizeof x->name, "%s", f.name);
        snprintf(x->subj, sizeof x->subj, "%.*s", slash ? (int)(slash - f.name) : 0, f.name);
        const char *u1 = strchr(base, '_'), *ul = strrchr(base, '_');
        if (!f.has_label || !u1 || !ul)
            continue; /* not an MRL-style labelled name */
        x->num = atoi(u1 + 1);
        x->sensor = atoi(ul + 1);
        x->w = f.w, x->h = f.h;
        x->lx = f.label_x, x->ly = f.label_y;
        x->px = malloc((size_t)f.w * (size_t)f.h);
        if (!x->px)
            break;
        for (int y = 0; y < f.h; y++)
            memcpy(x->px + (size_t)y * f.w, f.luma + y * f.stride, (size_t)f.w);
        n++;
    }
    fv_eyesrc_close(src);
    if (!e || rc < 0) {
        fprintf(stderr, "mrl_pairs: %s\n", e ? err : "out of memory");
        return 2;
    }
    if (track) {
        FILE *fp = fopen(track, "r");
        if (!fp) {
            fprintf(stderr, "mrl_pairs: %s: cannot open\n", track);
            return 2;
        }
        char line[512];
        while (fgets(line, sizeof line, fp)) {
            char *c1 = strchr(line, ',');
            if (!c1)
                continue;
            *c1 = 0;
            float x, y;
            if (sscanf(c1 + 1, "%f,%f", &x, &y) != 2)
                continue;
            for (int i = 0; i < n; i++) /* lists are small: a linear search will do */
                if (!strcmp(e[i].name, line)) {
                    e[i].has_det = 1, e[i].dx = x, e[i].dy = y;
                    break;
                }
        }
        fclose(fp);
    }
    qsort(e, (size_t)n, sizeof *e, cmp_entry);
    float *ld = malloc(sizeof(float) * (size_t)n * (size_t)gap), *dd = malloc(sizeof(float) * (size_t)n * (size_t)gap);
    float *de = malloc(sizeof(float) * (size_t)n * (size_t)gap * 2);
    int *sen = malloc(sizeof(int) * (size_t)n * (size_t)gap);
    float *ldd = malloc(sizeof(float) * (size_t)n * (size_t)gap);
    if (!ld || !dd || !de || !sen || !ldd)
        return 1;
    int np = 0;
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n && !strcmp(e[j].subj, e[i].subj) && e[j].num - e[i].num <= gap; j++) {
            if (e[j].w != e[i].w || e[j].h != e[i].h)
                continue;
            double best = 1e9;
            int bx = 0, by = 0;
            for (int sy = -4; sy <= 4; sy++)
                for (int sx = -4; sx <= 4; sx++) {
                    const double m = shifted_mad(&e[i], &e[j], sx, sy);
                    if (m < best)
                        best = m, bx = sx, by = sy;
                }
            if (best > mad_max)
                continue;
            /* b's point q shows what a shows at q + s */
            ld[np] = hypotf(e[j].lx + bx - e[i].lx, e[j].ly + by - e[i].ly);
            dd[np] = e[i].has_det && e[j].has_det ? hypotf(e[j].dx + bx - e[i].dx, e[j].dy + by - e[i].dy) : NAN;
            de[2 * np] = e[i].has_det ? hypotf(e[i].dx - e[i].lx, e[i].dy - e[i].ly) : NAN;
            de[2 * np + 1] = e[j].has_det ? hypotf(e[j].dx - e[j].lx, e[j].dy - e[j].ly) : NAN;
            sen[np] = e[i].sensor;
            np++;
        }
    printf("mrl_pairs: %d labelled images, %d near-identical pairs (mean |difference| <= %.1f grey levels after "
           "a shift of <= 4 px, numbers <= %d apart)\n",
           n, np, mad_max, gap);
    for (int s = 0; s <= 9; s++) {
        int k = 0, kd = 0, ka = 0;
        float *dv = malloc(sizeof(float) * (size_t)(np + 1)), *ea = malloc(sizeof(float) * (size_t)(2 * np + 1));
        if (!dv || !ea)
            return 1;
        for (int i = 0; i < np; i++)
            if (s == 0 || sen[i] == s) {
                ldd[k++] = ld[i];
                if (!isnan(dd[i]))
                    dv[kd++] = dd[i];
                if (ld[i] <= 1.0f && !isnan(de[2 * i]) && !isnan(de[2 * i + 1]))
                    ea[ka++] = de[2 * i], ea[ka++] = de[2 * i + 1];
            }
        if (!k) {
            free(dv), free(ea);
            continue;
        }
        const float med = median(ldd, k);
        const double sigma = med / (1.1774 * sqrt(2.0));
        if (s)
            printf("  sensor %02d", s);
        else
            printf("  all      ");
        printf("  %4d pairs: labels differ by median %.2f px, > 2 px %.0f%%, > 3 px %.0f%%; label noise ~%.2f px "
               "per axis; a detector at the annotators' mean would score ~%.0f%% within 3 px, ~%.0f%% within 5 px\n",
               k, (double)med, share_above(ldd, k, 2.0f), share_above(ldd, k, 3.0f), sigma,
               100.0 * (1.0 - exp(-9.0 / (2.0 * sigma * sigma))), 100.0 * (1.0 - exp(-25.0 / (2.0 * sigma * sigma))));
        if (kd)
            printf("             detections differ by median %.2f px, > 3 px %.0f%%", (double)median(dv, kd),
                   share_above(dv, kd, 3.0f));
        if (ka)
            printf("; on the %d images of pairs whose labels agree within 1 px: detection within 3 px %.0f%%, "
                   "within 5 px %.0f%%",
                   ka, 100.0 - share_above(ea, ka, 3.0f), 100.0 - share_above(ea, ka, 5.0f));
        if (kd || ka)
            printf("\n");
        free(dv), free(ea);
    }
    for (int i = 0; i < n; i++)
        free(e[i].px);
    free(e), free(ld), free(dd), free(de), free(sen), free(ldd);
    return 0;
}
