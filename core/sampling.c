#include "sampling.h"
#include "sampling_liu.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI_D 3.14159265358979323846

const char *const fv_sampler_names[FV_SAMPLER_KIND_COUNT] = {"weier", "liu"};

int fv_sampler_kind_parse(const char *name, int *kind)
{
    for (int k = 0; k < FV_SAMPLER_KIND_COUNT; k++)
        if (!strcmp(name, fv_sampler_names[k])) {
            *kind = k;
            return 0;
        }
    return -1;
}

void fv_sampling_params_default(fv_sampling_params *p)
{
    p->r0_deg = 10.0f;
    p->r1_deg = 20.0f;
    p->p_min = 0.2f;
    p->full = 0;
    p->rotate = 0;
    p->kind = FV_SAMPLER_WEIER;
    p->liu_density = 0.0f;
}

float fv_sampling_radius(const fv_sampling_params *p, float u)
{
    double pm = p->p_min, r0 = p->r0_deg, r1 = p->r1_deg;
    if (fabs(pm - 1.0) < 1e-6) /* f(x) is flat: uniform in r */
        return (float)(r0 + (r1 - r0) * u);
    double x = (sqrt((pm * pm - 1.0) * u + 1.0) - 1.0) / (pm - 1.0);
    return (float)(r0 + (r1 - r0) * x);
}

/* Eq. (1) draws r with pdf c*f(x)/(r1-r0), f(x) = 1 - x(1 - p_min), c = 2/(1 + p_min). Spread
 * over the ring 2*pi*r, N points give an areal density N*c*f(x)/((r1-r0)*2*pi*r). N is chosen so
 * the density meets S_out's p_min at r1 (no seam), which gives (r1/r)*f(x): 2 at r0 for the
 * defaults, saturating to full coverage there, falling to p_min at r1. */
float fv_sampling_transition_density(const fv_sampling_params *p, float r_deg)
{
    double x = (r_deg - p->r0_deg) / (p->r1_deg - p->r0_deg);
    double f = 1.0 - x * (1.0 - p->p_min);
    return (float)(p->r1_deg / r_deg * f);
}

static double halton(uint32_t i, uint32_t base)
{
    double f = 1.0, r = 0.0;
    while (i > 0) {
        f /= base;
        r += f * (i % base);
        i /= base;
    }
    return r;
}

static inline void set_bit(uint64_t *row, int x) { row[x >> 6] |= 1ull << (x & 63); }

int fv_sampler_init(fv_sampler *s, int width, int height, float focal_px, const fv_sampling_params *p)
{
    memset(s, 0, sizeof *s);
    if (width < 1 || height < 1 || !(focal_px > 0.0f))
        return -1;
    if (!(p->r0_deg > 0.0f && p->r0_deg <= p->r1_deg && p->r1_deg <= 90.0f && p->p_min > 0.0f && p->p_min <= 1.0f) ||
        (unsigned)p->kind >= FV_SAMPLER_KIND_COUNT)
        return -1;
    s->prm = *p;
    s->width = width;
    s->height = height;
    s->ppd = focal_px * (float)(PI_D / 180.0);
    s->r0_px = p->r0_deg * s->ppd;
    s->r1_px = p->r1_deg * s->ppd;
    s->rin = (int)ceilf(s->r1_px);
    /* K phases shifted by 1/K <= p_min tile the lattice's [0, 1) range: every pixel is sampled
     * at least once per K frames. */
    int K = 1;
    if (p->rotate && !p->full) {
        K = (int)ceil(1.0 / (double)p->p_min - 1e-6);
        K = K < 1 ? 1 : K > FV_SAMPLER_MAX_PHASES ? FV_SAMPLER_MAX_PHASES : K;
    }
    s->phases = K;
    if (p->kind == FV_SAMPLER_LIU) {
        if (fv_sampler_liu_init(s, focal_px)) {
            fv_sampler_free(s);
            return -1;
        }
        return 0;
    }
    int side = 2 * s->rin + 1;
    s->in_stride = (side + 63) / 64;
    s->out_stride = (width + 63) / 64;
    s->s_in = calloc((size_t)K * (size_t)side * (size_t)s->in_stride, sizeof(uint64_t));
    s->s_out = calloc((size_t)K * (size_t)height * (size_t)s->out_stride, sizeof(uint64_t));
    if (!s->s_in || !s->s_out) {
        fv_sampler_free(s);
        return -1;
    }

    /* S_out: rank-1 lattice dither (the R2 sequence, Roberts 2018): a pixel is sampled when
     * frac(a1 x + a2 y + k/K) < p_min. Exact density p_min with evenly spread samples and no
     * clumps or large holes, unlike white noise. */
    for (int k = 0; k < K; k++)
        for (int y = 0; y < height; y++) {
            uint64_t *row = s->s_out + ((size_t)k * height + y) * s->out_stride;
            for (int x = 0; x < width; x++)
                if (fv_sampler_lattice(s, x, y, k) < p->p_min)
                    set_bit(row, x);
        }

    /* S_in: every offset inside r0, then Halton (2, 3) points placed with eq. (1)-(2); phase k
     * takes the k-th block of points, so the phases together are one longer Halton sequence. */
    int c = s->rin;
    double r0sq = (double)s->r0_px * s->r0_px;
    const size_t in_words = (size_t)side * s->in_stride;
    for (int dy = -c; dy <= c; dy++) {
        uint64_t *row = s->s_in + (size_t)(dy + c) * s->in_stride;
        for (int dx = -c; dx <= c; dx++)
            if ((double)dx * dx + (double)dy * dy < r0sq)
                set_bit(row, dx + c);
    }
    for (int k = 1; k < K; k++)
        memcpy(s->s_in + k * in_words, s->s_in, in_words * sizeof(uint64_t));
    if (p->r1_deg > p->r0_deg) {
        double cnorm = 2.0 / (1.0 + p->p_min);
        double n = (p->r1_deg - p->r0_deg) * 2.0 * PI_D * p->r1_deg / cnorm * (double)s->ppd * s->ppd;
        s->transition_points = (long)ceil(n);
        double r1sq = (double)s->r1_px * s->r1_px;
        for (int k = 0; k < K; k++)
            for (long i = 1; i <= s->transition_points; i++) {
                uint32_t h = (uint32_t)(k * s->transition_points + i);
                double r = fv_sampling_radius(p, (float)halton(h, 2)) * (double)s->ppd;
                double phi = 2.0 * PI_D * halton(h, 3);
                int dx = (int)floor(r * cos(phi) + 0.5), dy = (int)floor(r * sin(phi) + 0.5);
                double d2 = (double)dx * dx + (double)dy * dy;
                if (d2 < r0sq || d2 >= r1sq) /* rounding pushed it out of the ring */
                    continue;
                set_bit(s->s_in + k * in_words + (size_t)(dy + c) * s->in_stride, dx + c);
            }
    }
    return 0;
}

double fv_sampler_lattice(const fv_sampler *s, int x, int y, int phase)
{
    const int k = (phase % s->phases + s->phases) % s->phases;
    return fv_sampler_lattice_at(x, y, (double)k / s->phases);
}

float fv_sampler_probability(const fv_sampler *s, float dx_px, float dy_px)
{
    if (s->prm.full)
        return 1.0f;
    if (s->prm.kind == FV_SAMPLER_LIU)
        return fv_sampler_liu_probability(s, dx_px, dy_px);
    float r_px = sqrtf(dx_px * dx_px + dy_px * dy_px);
    if (r_px < s->r0_px)
        return 1.0f;
    if (!(r_px < s->r1_px))
        return s->prm.p_min;
    float l = fv_sampling_transition_density(&s->prm, r_px / s->ppd);
    return l > 1.0f ? 1.0f : l < s->prm.p_min ? s->prm.p_min : l;
}

void fv_sampling_jitter(uint32_t frame, float *ox, float *oy)
{
    const double x = 0.5 + halton(frame, 2), y = 0.5 + halton(frame, 3);
    *ox = (float)(x < 1.0 ? x : x - 1.0);
    *oy = (float)(y < 1.0 ? y : y - 1.0);
    /* (float) may round 0.99999999 up to 1: keep the position inside the pixel */
    *ox = *ox < 1.0f ? *ox : 0.99999994f;
    *oy = *oy < 1.0f ? *oy : 0.99999994f;
}

void fv_sampler_free(fv_sampler *s)
{
    free(s->s_in);
    free(s->s_out);
    s->s_in = s->s_out = NULL;
}

/* n <= 64 bits starting at bit x of a bit row (bits past the row's end read as 0). */
static inline uint64_t get_bits(const uint64_t *row, int words, int x, int n)
{
    int w = x >> 6, b = x & 63;
    uint64_t v = w < words ? row[w] >> b : 0;
    if (b && w + 1 < words)
        v |= row[w + 1] << (64 - b);
    return n == 64 ? v : v & ((1ull << n) - 1);
}

uint64_t fv_sampler_row(const fv_sampler *s, int x0, int y, int n, int gx, int gy, int phase)
{
    uint64_t all = n == 64 ? ~0ull : (1ull << n) - 1;
    if (s->prm.full)
        return all;
    const int k = (phase % s->phases + s->phases) % s->phases;
    if (s->prm.kind == FV_SAMPLER_LIU) { /* one table around the gaze (sampling_liu.c) */
        const int cx = gx < 0 ? 0 : gx >= s->width ? s->width - 1 : gx;
        const int cy = gy < 0 ? 0 : gy >= s->height ? s->height - 1 : gy;
        const uint64_t *row = s->s_in + ((size_t)k * (2 * s->height - 1) + (size_t)(y - cy + s->height - 1)) * s->in_stride;
        return get_bits(row, s->in_stride, x0 - cx + s->width - 1, n);
    }
    uint64_t out = get_bits(s->s_out + ((size_t)k * s->height + y) * s->out_stride, s->out_stride, x0, n);
    int dy = y - gy;
    if (dy < -s->rin || dy > s->rin)
        return out;
    /* Pixels with dx^2 + dy^2 < r1^2 take S_in, the rest S_out. The span of this row inside
     * the r1 disc is [gx - h, gx + h]. */
    double r1sq = (double)s->r1_px * s->r1_px, rem = r1sq - (double)dy * dy;
    if (rem <= 0.0)
        return out;
    int h = (int)floor(sqrt(rem));
    while ((double)h * h + (double)dy * dy >= r1sq) /* keep the strict < of the disc test */
        h--;
    if (h < 0)
        return out;
    int lo = gx - h, hi = gx + h; /* inclusive */
    if (hi < x0 || lo > x0 + n - 1)
        return out;
    if (lo < x0)
        lo = x0;
    if (hi > x0 + n - 1)
        hi = x0 + n - 1;
    int len = hi - lo + 1;
    uint64_t span = (len == 64 ? ~0ull : (1ull << len) - 1) << (lo - x0);
    const uint64_t *inrow = s->s_in + ((size_t)k * (2 * s->rin + 1) + (size_t)(dy + s->rin)) * s->in_stride;
    uint64_t in = get_bits(inrow, s->in_stride, lo - gx + s->rin, len) << (lo - x0);
    return (out & ~span) | (in & span);
}

void fv_sampler_rows(const fv_sampler *s, int x0, int y0, int n, int count, int gx, int gy, int phase, uint32_t *rows)
{
    /* a tile beyond the r1 disc's bounding box (most tiles): S_out's bits alone, the phase taken
     * once (a row's own call divides twice for it and tests the disc) */
    if (!s->prm.full && s->prm.kind != FV_SAMPLER_LIU) {
        const int r1c = (int)floor((double)s->r1_px) + 1; /* > every half-span h of a row */
        if (y0 + count - 1 < gy - s->rin || y0 > gy + s->rin || x0 + n - 1 < gx - r1c || x0 > gx + r1c) {
            const int k = (phase % s->phases + s->phases) % s->phases;
            const uint64_t *row = s->s_out + ((size_t)k * s->height + y0) * s->out_stride;
            for (int y = 0; y < count; y++, row += s->out_stride)
                rows[y] = (uint32_t)get_bits(row, s->out_stride, x0, n);
            return;
        }
    }
    for (int y = 0; y < count; y++)
        rows[y] = (uint32_t)fv_sampler_row(s, x0, y0 + y, n, gx, gy, phase);
}
