/* fovea: Liu et al.'s polar-space acuity sampling (see sampling_liu.h for the model).
 *
 * One bit table per phase, centred on the gaze like Weier's S_in but reaching every pixel from
 * every gaze pixel: offsets -(w-1)..w-1 by -(h-1)..h-1, 0.92 MB per phase at 1280x1440 (4.6 MB
 * for the 5 phases of the default rotation). A row is then one bit extraction, as cheap as
 * S_out's, and the pattern moves with the gaze by whole pixels (no flicker from sub-pixel gaze
 * motion). A hash per polar cell evaluated per pixel would need no table but an eccentricity,
 * an angle and a hash for each of the 1.8 M pixels every frame. */
#include "sampling_liu.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI_D 3.14159265358979323846
#define LIU_A 14.98 /* eq. 1's numerator coefficient */
#define LIU_B 0.3   /* eq. 1's eccentricity scale */

double fv_liu_ring_density(double a)
{
    if (a <= FV_LIU_ALPHA_F)
        return 2.0 * PI_D * a;
    const double u = LIU_B * a + 1.0;
    return LIU_A * PI_D * a / (u * u);
}

double fv_liu_relative_density(double a)
{
    if (a <= FV_LIU_ALPHA_F)
        return 1.0;
    const double u = LIU_B * a + 1.0;
    return 0.5 * LIU_A / (u * u);
}

/* eq. 2 without its constant: 14.98 pi / 0.3^2 (1/u + ln u), u = 0.3 alpha + 1 */
static double eq2_raw(double a)
{
    const double u = LIU_B * a + 1.0;
    return LIU_A * PI_D / (LIU_B * LIU_B) * (1.0 / u + log(u));
}

double fv_liu_cdf(double a)
{
    if (a <= FV_LIU_ALPHA_F)
        return PI_D * a * a;
    return eq2_raw(a) - eq2_raw(FV_LIU_ALPHA_F) + PI_D * FV_LIU_ALPHA_F * FV_LIU_ALPHA_F;
}

double fv_liu_cdf_inv(double rho)
{
    if (!(rho > 0.0))
        return 0.0;
    if (rho <= PI_D * FV_LIU_ALPHA_F * FV_LIU_ALPHA_F)
        return sqrt(rho / PI_D);
    double lo = FV_LIU_ALPHA_F, hi = 2.0 * FV_LIU_ALPHA_F;
    while (fv_liu_cdf(hi) < rho)
        hi *= 2.0;
    for (int i = 0; i < 60; i++) { /* eq. 2 is increasing: bisection to double precision */
        const double m = 0.5 * (lo + hi);
        if (fv_liu_cdf(m) < rho)
            lo = m;
        else
            hi = m;
    }
    return 0.5 * (lo + hi);
}

double fv_liu_eq3(double r)
{
    return (((25.09 * r + 0.1680) * r + 27.61) * r + 23.87) * r + 3.232;
}

/* the polar grid for a fovea density lambda_0 */
typedef struct liu_geom {
    double ppd, l0, drho, sat_px;
    int nphi;
} liu_geom;

static void geom_set(liu_geom *g, double ppd, double l0)
{
    g->ppd = ppd;
    g->l0 = l0;
    /* Cells square (in pixels) far out, where alpha g(alpha) -> 14.98 pi / 0.3^2 and most rays
     * go: width 2 pi alpha / n_phi = height drho / g(alpha) there. With lambda_0 = n_phi /
     * (drho ppd^2) that gives n_phi = pi ppd sqrt(2 * 14.98 lambda_0) / 0.3. */
    double n = PI_D * ppd * sqrt(2.0 * LIU_A * l0) / LIU_B;
    g->nphi = n < 8.0 ? 8 : (int)lround(n);
    g->drho = (double)g->nphi / (l0 * ppd * ppd);
    /* lambda = lambda_0 * 7.49 / (0.3 alpha + 1)^2 reaches 1 at sat (every pixel inside) */
    g->sat_px = l0 >= 1.0 ? (sqrt(0.5 * LIU_A * l0) - 1.0) / LIU_B * ppd : 0.0;
}

static inline void set_bit(uint64_t *row, int x) { row[x >> 6] |= 1ull << (x & 63); }

void fv_liu_phase_offset(int k, double *u, double *v)
{
    const double a = 0.5 + 0.7548776662466927 * k, b = 0.5 + 0.5698402909980532 * k;
    *u = a - floor(a);
    *v = b - floor(b);
}

/* Sets the pattern's pixels for the cell offsets (u, v) in a bw x bh bit image (stride words a
 * row) whose gaze pixel is (cx, cy). */
static void raster(const liu_geom *g, double u, double v, uint64_t *bits, int stride, int cx, int cy, int bw, int bh)
{
    const double sat2 = g->sat_px * g->sat_px;
    for (int y = 0; y < bh; y++) { /* the saturated disc: every pixel */
        const double dy = y - cy, rem = sat2 - dy * dy;
        if (rem <= 0.0)
            continue;
        int h = (int)floor(sqrt(rem));
        while (h >= 0 && (double)h * h + dy * dy >= sat2) /* strict <, as the probability */
            h--;
        const int lo = cx - h < 0 ? 0 : cx - h, hi = cx + h >= bw ? bw - 1 : cx + h;
        for (int x = lo; x <= hi; x++)
            set_bit(bits + (size_t)y * stride, x);
    }
    const double fx = cx > bw - 1 - cx ? cx : bw - 1 - cx, fy = cy > bh - 1 - cy ? cy : bh - 1 - cy;
    const double rmax = sqrt(fx * fx + fy * fy) + 1.0;
    const double step = 2.0 * PI_D / g->nphi, cstep = cos(step), sstep = sin(step);
    long i = (long)floor(fv_liu_cdf(g->sat_px / g->ppd) / g->drho - u);
    for (i = i < 0 ? 0 : i;; i++) {
        const double r = fv_liu_cdf_inv(((double)i + u) * g->drho) * g->ppd;
        if (r < g->sat_px)
            continue;
        if (r > rmax)
            break;
        /* each ring starts at its own angle (golden-ratio stagger): no radial spokes */
        double st = (double)i * 0.6180339887498949;
        st -= floor(st);
        double c = cos(step * (v + st)), s = sin(step * (v + st));
        for (int j = 0; j < g->nphi; j++) {
            const int x = cx + (int)floor(r * c + 0.5), y = cy + (int)floor(r * s + 0.5);
            if ((unsigned)x < (unsigned)bw && (unsigned)y < (unsigned)bh)
                set_bit(bits + (size_t)y * stride, x);
            const double c2 = c * cstep - s * sstep; /* rotate by one step */
            s = s * cstep + c * sstep;
            c = c2;
        }
    }
}

/* Rays of phase 0 for the gaze at the image centre. */
static long centre_count(const liu_geom *g, int w, int h, uint64_t *bits)
{
    const int stride = (w + 63) / 64;
    memset(bits, 0, (size_t)h * stride * sizeof *bits);
    double u, v;
    fv_liu_phase_offset(0, &u, &v);
    raster(g, u, v, bits, stride, w / 2, h / 2, w, h);
    long n = 0;
    for (size_t i = 0; i < (size_t)h * stride; i++)
        n += __builtin_popcountll(bits[i]);
    return n;
}

/* lambda_0 whose pattern casts `target` rays for the centred gaze: bisection on the expected
 * count sum(min(1, lambda)) over the pixels (a radial histogram), then a few corrections on the
 * real count (rounding to pixels makes polar samples collide). */
static double match_count(double ppd, int w, int h, long target)
{
    const int cx = w / 2, cy = h / 2;
    const double q = 4.0; /* histogram bins per pixel of radius */
    const int nb = (int)(q * sqrt((double)cx * cx + (double)cy * cy)) + 2; /* cx >= w - 1 - cx */
    long *hist = calloc((size_t)nb, sizeof *hist);
    double *rel = malloc((size_t)nb * sizeof *rel);
    uint64_t *bits = malloc((size_t)h * ((w + 63) / 64) * sizeof *bits);
    double l0 = -1.0;
    if (!hist || !rel || !bits)
        goto out;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            hist[(int)(q * sqrt((double)(x - cx) * (x - cx) + (double)(y - cy) * (y - cy)))]++;
    for (int b = 0; b < nb; b++)
        rel[b] = fv_liu_relative_density((b + 0.5) / q / ppd);
    double lo = log(1e-3), hi = log(1e4);
    for (int it = 0; it < 60; it++) {
        const double m = 0.5 * (lo + hi), l = exp(m);
        double e = 0.0;
        for (int b = 0; b < nb; b++)
            e += (double)hist[b] * (l * rel[b] < 1.0 ? l * rel[b] : 1.0);
        if (e < (double)target)
            lo = m;
        else
            hi = m;
    }
    l0 = exp(0.5 * (lo + hi));
    for (int it = 0; it < 6; it++) {
        liu_geom g;
        geom_set(&g, ppd, l0);
        const long n = centre_count(&g, w, h, bits);
        if (labs(n - target) <= target / 500 + 1)
            break;
        l0 *= (double)target / (double)n;
    }
out:
    free(hist);
    free(rel);
    free(bits);
    return l0;
}

int fv_sampler_liu_init(fv_sampler *s, float focal_px)
{
    const fv_sampling_params *p = &s->prm;
    /* below lambda_0 = 1 eq. 1's fovea itself would be undersampled (and there the polar grid's
     * rings are pixels apart: it does not resolve a density below one sample per pixel) */
    if (!(p->liu_density == 0.0f || (p->liu_density >= 1.0f && p->liu_density <= 1e4f)))
        return -1;
    if (p->full)
        return 0;
    const int w = s->width, h = s->height;
    double l0 = p->liu_density;
    if (l0 == 0.0) { /* equal ray counts: Weier's static pattern with the same r0, r1, p_min */
        fv_sampling_params wp = *p;
        wp.kind = FV_SAMPLER_WEIER;
        wp.rotate = 0;
        fv_sampler ws;
        if (fv_sampler_init(&ws, w, h, focal_px, &wp))
            return -1;
        long n = 0;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x += 64)
                n += __builtin_popcountll(fv_sampler_row(&ws, x, y, w - x < 64 ? w - x : 64, w / 2, h / 2, 0));
        fv_sampler_free(&ws);
        s->liu_target = n;
        l0 = match_count(s->ppd, w, h, n);
        if (l0 < 0.0)
            return -1;
        l0 = l0 < 1.0 ? 1.0 : l0; /* a budget below a full fovea: the fovea wins */
    }
    liu_geom g;
    geom_set(&g, s->ppd, l0);
    s->liu_l0 = l0;
    s->liu_nphi = g.nphi;
    s->liu_drho = g.drho;
    s->liu_sat_px = g.sat_px;
    const int bw = 2 * w - 1, bh = 2 * h - 1;
    s->in_stride = (bw + 63) / 64;
    const size_t words = (size_t)bh * s->in_stride;
    s->s_in = calloc((size_t)s->phases * words, sizeof(uint64_t));
    if (!s->s_in)
        return -1;
    for (int k = 0; k < s->phases; k++) {
        double u, v;
        fv_liu_phase_offset(k, &u, &v);
        raster(&g, u, v, s->s_in + k * words, s->in_stride, w - 1, h - 1, bw, bh);
    }
    return 0;
}

float fv_sampler_liu_probability(const fv_sampler *s, float dx_px, float dy_px)
{
    const double a = sqrt((double)dx_px * dx_px + (double)dy_px * dy_px) / s->ppd;
    const double l = s->liu_l0 * fv_liu_relative_density(a);
    return l < 1.0 ? (float)l : 1.0f;
}
