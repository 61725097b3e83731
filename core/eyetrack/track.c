/* fovea eye tracker: dark-pupil detection, sub-pixel centre, glints, confidence, blinks
 * (docs/eyetrack.md has the measurements behind the choices).
 *
 * 1. Search (coarse_search): the frame is halved (dsp->et_down2_row) until min(w, h) <= 160
 *    (F), reflections on F (dsp->et_thresh_row) are masked and inpainted from their
 *    surroundings so a glint inside the pupil does not make it look bright; F is halved again
 *    to <= 64 (C). Over integral images (dsp->et_integral_row) every centre and box size of C
 *    is scored by contrast with its ring, darkness and a weak centre prior (box_search); the
 *    best is refined in position and size on F. Contrast, not darkness alone, rejects brows,
 *    lashes and shadows (as dark around as inside).
 * 2. Refinement at full resolution in a window around it: threshold half way between the blob
 *    and its surround, iterated weighted centroid of the darker pixels, then rays from there
 *    give sub-pixel edge points for a direct ellipse fit with outlier rejection. Headset-sized
 *    frames report the ellipse centre; small remote-camera crops report the search's box centre.
 * 3. Glints: small bright blobs of the raw image close to the pupil.
 * 4. Confidence from the contrast and the fit; blinks from darkness / contrast / size drops
 *    against the tracker's running reference. */
#include <math.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <stdlib.h>
#include <string.h>

#include "eyetrack/eyetrack_dsp.h"
#include "base/util.h"
#include "eyetrack/eyetrack.h"

#define SEARCH_MAX_SIDE 160 /* search image F: min side at most this */
#define SEARCH_C_SIDE 64    /* exhaustive search image C: min side at most this */
#define REFINE_MAX_SIDE 320 /* headset frames: pupil refined on the frame halved down to this */
#define NRAYS 48
#define EDGE_SEARCH_PX 3.0f /* headset frames: steepest rise looked for this far either side of the crossing */
/* RANSAC support on headset-sized pupils: an edge point counts only if its gradient is within
 * 32 deg of the candidate ellipse's outward normal */
#define GRAD_MINCOS 0.85
#define SPOT_MIN 20 /* bright_spot: grey levels above the median of its surround */

struct fv_eye_tracker {
    fv_eye_params p;
    fv_eyetrack_dsp dsp;
    uint8_t *mem;
    size_t cap;
    /* history for blink detection (fv_track_frame only) */
    int nref;
    float ref_contrast, ref_radius, ref_inner, ref_ring;
};

void fv_eye_default_params(fv_eye_params *p)
{
    p->isa_mask = ~0u;
    p->min_radius_frac = 0.035f;
    p->max_radius_frac = 0.17f;
    p->border_frac = 0.1f;
    p->centre_prior = 20.0f;
    /* both chosen on the even-numbered MRL images (docs/eyetrack.md) */
    p->crop_centre_weight = 0.05f;
    p->glint_weight = 0.3f;
    p->max_glints = FV_EYE_MAX_GLINTS;
}

fv_eye_tracker *fv_eye_create(const fv_eye_params *p)
{
    fv_eye_tracker *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    if (p)
        t->p = *p;
    else
        fv_eye_default_params(&t->p);
    if (t->p.max_glints < 0 || t->p.max_glints > FV_EYE_MAX_GLINTS)
        t->p.max_glints = FV_EYE_MAX_GLINTS;
    fv_eyetrack_dsp_init(&t->dsp, t->p.isa_mask);
    return t;
}

void fv_eye_destroy(fv_eye_tracker *t)
{
    if (!t)
        return;
    free(t->mem);
    free(t);
}

void fv_eye_reset(fv_eye_tracker *t)
{
    t->nref = 0;
    t->ref_contrast = t->ref_radius = t->ref_inner = t->ref_ring = 0;
}

static void *scratch(fv_eye_tracker *t, size_t bytes)
{
    if (bytes > t->cap) {
        void *m = realloc(t->mem, bytes);
        if (!m)
            return NULL;
        t->mem = m;
        t->cap = bytes;
    }
    return t->mem;
}

/* ---------------------------------------------------------------- helpers */

/* Grey level below which a fraction q of the pixels lie. */
static int percentile(const uint32_t hist[256], uint32_t total, double q)
{
    const uint32_t want = (uint32_t)(q * total);
    uint32_t acc = 0;
    for (int v = 0; v < 256; v++) {
        acc += hist[v];
        if (acc > want)
            return v;
    }
    return 255;
}

static void histogram(const uint8_t *img, int w, int h, ptrdiff_t stride, uint32_t hist[256])
{
    /* four sub-histograms break the store-to-load dependency on runs of equal pixels */
    uint32_t hs[4][256];
    memset(hs, 0, sizeof hs);
    for (int y = 0; y < h; y++) {
        const uint8_t *r = img + y * stride;
        int x = 0;
        for (; x + 4 <= w; x += 4) {
            hs[0][r[x]]++, hs[1][r[x + 1]]++, hs[2][r[x + 2]]++, hs[3][r[x + 3]]++;
        }
        for (; x < w; x++)
            hs[0][r[x]]++;
    }
    for (int v = 0; v < 256; v++)
        hist[v] = hs[0][v] + hs[1][v] + hs[2][v] + hs[3][v];
}

/* Pixel lists hold y << 16 | x (sides are at most 8192): the column and row without a
 * division, the neighbours by adding +-1 and +-ROW. */
#define PK(x, y) ((y) << 16 | (x))
#define PK_X(p) ((p)&0xffff)
#define PK_Y(p) ((p) >> 16)
enum { ROW = 1 << 16 };

/* Appends the nonzero bytes of row y (m, w bytes) to list[n...]; the new count. */
static int list_nonzero(const uint8_t *m, int w, int y, int *list, int n)
{
    int x = 0;
    for (; x + 8 <= w; x += 8) { /* mostly zero: eight at a time */
        uint64_t v;
        memcpy(&v, m + x, sizeof v);
        if (v)
            for (int j = x; j < x + 8; j++)
                if (m[j])
                    list[n++] = PK(j, y);
    }
    for (; x < w; x++)
        if (m[x])
            list[n++] = PK(x, y);
    return n;
}

/* Reflections: pixels >= thr, grown by `grow` pixels (a glint's halo is brighter than its
 * background too), replaced by the mean of their unmasked 4-neighbours, ring by ring from the
 * outside in. mask is w*h bytes of scratch, idx and fr w*h ints each; the work is proportional
 * to the masked area, not the image. */
static void inpaint_bright(const fv_eyetrack_dsp *dsp, uint8_t *img, int w, int h, int thr, int grow, uint8_t *mask, int *idx,
                           int *fr, uint8_t fallback)
{
    int n = 0;
    for (int y = 0; y < h; y++)
        if (dsp->et_thresh_row(mask + y * w, img + y * w, w, thr))
            n = list_nonzero(mask + y * w, w, y, idx, n);
    if (!n)
        return;
    for (int j = 0; j < n; j++)
        mask[PK_Y(idx[j]) * w + PK_X(idx[j])] = 1;
    int from = 0; /* idx[from, n): the last ring; the only pixels with unmasked neighbours */
    for (int g = 0; g < grow; g++) {
        const int to = n;
        for (int j = from; j < to; j++) {
            const int p = idx[j], x = PK_X(p), y = PK_Y(p), i = y * w + x;
#define GROW(cond, di, dp)                                                                                              \
    if ((cond) && !mask[i + (di)])                                                                                     \
        mask[i + (di)] = 1, idx[n++] = p + (dp);
            GROW(x > 0, -1, -1)
            GROW(x + 1 < w, 1, 1)
            GROW(y > 0, -w, -ROW)
            GROW(y + 1 < h, w, ROW)
#undef GROW
        }
        from = to;
    }
    /* mask: 0 source, 1 to fill, 2 + p filled in pass p (a source from pass p + 1 on), QUEUED
     * in the next pass's frontier. Pass p fills exactly the pixels 4-adjacent to a source, i.e.
     * (p = 0) to an unmasked pixel or (p > 0) to one filled in pass p - 1, each from sources
     * only, so a pass's order does not matter and only that frontier needs visiting (for
     * pass 0, the last ring): the pixels no pass reaches are not seen again until the end. */
    enum { QUEUED = 255 };
    const int passes = 3 + 2 * grow; /* enough for a grown glint; big bright areas get the fallback */
    int b0 = 0, b1 = 0;              /* fr[b0, b1): the pixels filled in the last pass */
    for (int pass = 0; pass < passes; pass++) {
        const uint8_t lim = (uint8_t)(2 + pass);
        if (pass > 0) { /* this pass's frontier: unfilled neighbours of the last pass's pixels */
            const int e0 = b1;
            for (int j = b0; j < e0; j++) {
                const int p = fr[j], x = PK_X(p), y = PK_Y(p), i = y * w + x;
#define QUEUE(cond, di, dp)                                                                                             \
    if ((cond) && mask[i + (di)] == 1)                                                                                 \
        mask[i + (di)] = QUEUED, fr[b1++] = p + (dp);
                QUEUE(x > 0, -1, -1)
                QUEUE(x + 1 < w, 1, 1)
                QUEUE(y > 0, -w, -ROW)
                QUEUE(y + 1 < h, w, ROW)
#undef QUEUE
            }
            b0 = e0;
            if (b0 == b1)
                break;
        }
        const int *list = pass ? fr + b0 : idx + from, len = pass ? b1 - b0 : n - from;
        int e = b1;
        for (int j = 0; j < len; j++) {
            const int p = list[j], x = PK_X(p), y = PK_Y(p), i = y * w + x;
            int s = 0, c = 0;
#define SRC(cond, di)                                                                                                   \
    if ((cond) && (mask[i + (di)] == 0 || (mask[i + (di)] >= 2 && mask[i + (di)] < lim)))                              \
        s += img[i + (di)], c++;
            SRC(x > 0, -1)
            SRC(x + 1 < w, 1)
            SRC(y > 0, -w)
            SRC(y + 1 < h, w)
#undef SRC
            if (c) { /* always, past pass 0 */
                /* (s + c / 2) / c, with constant divisors */
                img[i] = (uint8_t)(c == 1 ? s : c == 2 ? (s + 1) / 2 : c == 3 ? (s + 1) / 3 : (s + 2) / 4);
                mask[i] = lim;
                if (!pass)
                    fr[e++] = p;
            }
        }
        if (!pass) {
            b0 = 0, b1 = e;
            if (!e)
                break;
        }
    }
    for (int j = 0; j < n; j++) {
        const int i = PK_Y(idx[j]) * w + PK_X(idx[j]);
        if (mask[i] == 1)
            img[i] = fallback;
    }
}

static inline uint32_t box_sum(const uint32_t *ii, int iw, int x0, int y0, int x1, int y1)
{
    /* sum over [x0, x1) x [y0, y1); ii has a zero first row and column, row length iw */
    return ii[y1 * iw + x1] - ii[y0 * iw + x1] - ii[y1 * iw + x0] + ii[y0 * iw + x0];
}


/* Bilinear sample, pixel centres at +0.5 (clamped to the image). */
static inline float sample(const uint8_t *img, int w, int h, float x, float y)
{
    x -= 0.5f, y -= 0.5f;
    x = fv_clampf(x, 0.0f, (float)w - 1.001f);
    y = fv_clampf(y, 0.0f, (float)h - 1.001f);
    const int ix = (int)x, iy = (int)y;
    const float fx = x - ix, fy = y - iy;
    const uint8_t *r = img + iy * w + ix;
    const int x1 = ix + 1 < w ? 1 : 0, y1 = iy + 1 < h ? w : 0;
    const float a = r[0] + fx * (r[x1] - r[0]), b = r[y1] + fx * (r[y1 + x1] - r[y1]);
    return a + fy * (b - a);
}

/* Distance along the ray (cx, cy) + d (dx, dy) of the steepest rise within +-span of d0:
 * central differences 1 px wide every 0.5 px, the peak refined by a parabola through the
 * differences 1 px either side of it. */
static float steepest_rise(const uint8_t *img, int w, int h, float cx, float cy, float dx, float dy, float d0,
                           float span)
{
#define AT(q) sample(img, w, h, cx + (q) * dx, cy + (q) * dy)
    float best = -1e30f, bq = d0;
    for (float q = fmaxf(0.5f, d0 - span); q <= d0 + span; q += 0.5f) {
        const float g = AT(q + 0.5f) - AT(q - 0.5f);
        if (g > best)
            best = g, bq = q;
    }
    const float gm = AT(bq) - AT(bq - 1.0f), gp = AT(bq + 1.0f) - AT(bq);
    const float den = gm - 2.0f * best + gp;
    /* vertex of the parabola through (-1, gm), (0, best), (1, gp), in units of 1 px; the
     * samples of the search were 0.5 px apart, so at most a quarter pixel either way */
    return bq + (den < 0 ? fv_clampf(0.5f * (gm - gp) / den, -0.25f, 0.25f) : 0.0f);
#undef AT
}

/* The ray stays at or above th for len pixels past dist (a pupil edge, not a glint's halo or
 * a stray bright pixel inside the pupil). */
static int sustained(const uint8_t *win, int ww, int wh, float cx, float cy, float dx, float dy, float dist, float len,
                     float th)
{
    for (float d = dist + 0.5f; d <= dist + len; d += 0.5f) {
        const float px = cx + d * dx, py = cy + d * dy;
        if (px < 0.5f || py < 0.5f || px > ww - 0.5f || py > wh - 0.5f)
            return 1;
        if (sample(win, ww, wh, px, py) < th)
            return 0;
    }
    return 1;
}

/* ---------------------------------------------------------------- coarse search */

typedef struct {
    float x, y, r; /* full-resolution pixels (corner origin) */
    float inner, ring;
    int scale; /* of the search image */
    int ok;
} candidate;

static void integral(const fv_eyetrack_dsp *d, const uint8_t *img, int w, int h, uint32_t *ii)
{
    /* zero first row and column */
    const int iw = w + 1;
    memset(ii, 0, (size_t)iw * sizeof *ii);
    for (int y = 0; y < h; y++) {
        ii[(size_t)(y + 1) * iw] = 0;
        d->et_integral_row(ii + (size_t)(y + 1) * iw + 1, ii + (size_t)y * iw + 1, img + (size_t)y * w, w);
    }
}

typedef struct {
    float score, inner, ring;
    int x, y, k;
} box_hit;

/* Best contrast box over centres [x0, x1) x [y0, y1) and half-sizes k in [kmin, kmax]
 * (every k when step1, else a geometric-ish ladder). Score = mean(ring k..1.5k) - mean(box k)
 * - (mean(box) - dark) - mu * (distance from the image centre) / min side: the darkness term
 * prefers the darker of two contrasting blobs (the pupil in the iris); a 1.5k ring beat 2k and
 * 3k on the MRL images (less lid and brow in it); mu (grey levels per image side) is a weak
 * prior for the eye being roughly centred in its camera, which keeps dark brows, hair and
 * vignetted corners from winning in dim images. Centres are visited k, y, x in order, and
 * a later one wins only with a strictly higher score. */
typedef struct {
    const uint32_t *ii;
    int iw, sw, sh;
    float dark, prior, cxm, cym;
} box_ctx;

static inline void box_offer(const box_ctx *b, box_hit *best, float score, float mi, float mo, int x, int y, int k)
{
    if (score <= best->score) /* the prior only lowers it */
        return;
    if (b->prior > 0) {
        const float ddx = (float)x - b->cxm, ddy = (float)y - b->cym;
        score -= b->prior * sqrtf(ddx * ddx + ddy * ddy);
    }
    if (score > best->score)
        *best = (box_hit){ score, mi, mo, x, y, k };
}

/* Centres [xa, xb) of row y whose box or ring the image clips. */
static void box_clipped(const box_ctx *b, box_hit *best, int k, int ko, int y, int xa, int xb)
{
    /* the box inside the image, most of the ring too: vignetted corners and image edges are
     * dark and half a ring is no surround */
    if (y - k < 0 || y + k + 1 > b->sh)
        return;
    xa = fv_maxi(xa, k), xb = fv_mini(xb, b->sw - k);
    const int na = (2 * k + 1) * (2 * k + 1), no_full = (2 * ko + 1) * (2 * ko + 1);
    const int oy0 = fv_maxi(0, y - ko), oy1 = fv_mini(b->sh, y + ko + 1);
    for (int x = xa; x < xb; x++) {
        const int ox0 = fv_maxi(0, x - ko), ox1 = fv_mini(b->sw, x + ko + 1);
        const int no = (ox1 - ox0) * (oy1 - oy0);
        if (10 * (no - na) < 6 * (no_full - na))
            continue;
        const uint32_t si = box_sum(b->ii, b->iw, x - k, y - k, x + k + 1, y + k + 1);
        const uint32_t so = box_sum(b->ii, b->iw, ox0, oy0, ox1, oy1) - si;
        const float mi = (float)si / na, mo = (float)so / (no - na);
        box_offer(b, best, mo - mi - (mi - b->dark), mi, mo, x, y, k);
    }
}

static void box_search(const fv_eyetrack_dsp *d, const uint32_t *ii, int sw, int sh, int kmin, int kmax, int step1, int x0,
                       int x1, int y0, int y1, float dark, float mu, box_hit *best)
{
    const float rf = 1.5f;
    const box_ctx b = { ii, sw + 1, sw, sh, dark, mu / (float)(sw < sh ? sw : sh), 0.5f * (sw - 1), 0.5f * (sh - 1) };
    const int iw = sw + 1, xs = fv_maxi(0, x0), xe = fv_mini(sw, x1);
    enum { CHUNK = 256 };
    float sc[CHUNK];
    for (int k = kmin; k <= kmax; k += (step1 || k < 4 ? 1 : k / 4)) {
        const int ko = (int)lrintf(rf * k);
        const int na_full = (2 * k + 1) * (2 * k + 1), no_full = (2 * ko + 1) * (2 * ko + 1);
        const float inv_a = 1.0f / (float)na_full, inv_r = 1.0f / (float)(no_full - na_full);
        /* centres [xa, xb) of rows [ko, sh - ko) have their ring inside the image: no
         * divisions, one row kernel call per chunk */
        const int xa = fv_maxi(xs, ko), xb = fv_mini(xe, sw - ko);
        for (int y = fv_maxi(0, y0); y < fv_mini(sh, y1); y++) {
            if (y < ko || y >= sh - ko || xa >= xb) {
                box_clipped(&b, best, k, ko, y, xs, xe);
                continue;
            }
            box_clipped(&b, best, k, ko, y, xs, xa);
            for (int c0 = xa; c0 < xb; c0 += CHUNK) {
                const int cn = fv_mini(CHUNK, xb - c0);
                const uint32_t *it = ii + (y - k) * iw + c0 - k, *ib = ii + (y + k + 1) * iw + c0 - k;
                const uint32_t *ot = ii + (y - ko) * iw + c0 - ko, *ob = ii + (y + ko + 1) * iw + c0 - ko;
                if (!(d->et_box_score_row(sc, it, ib, 2 * k + 1, ot, ob, 2 * ko + 1, cn, inv_a, inv_r, dark) >
                      best->score))
                    continue; /* nothing in the chunk beats the best */
                for (int j = 0; j < cn; j++) {
                    if (sc[j] <= best->score)
                        continue;
                    const int x = c0 + j;
                    const uint32_t si = box_sum(ii, iw, x - k, y - k, x + k + 1, y + k + 1);
                    const uint32_t so = box_sum(ii, iw, x - ko, y - ko, x + ko + 1, y + ko + 1) - si;
                    box_offer(&b, best, sc[j], (float)si * inv_a, (float)so * inv_r, x, y, k);
                }
            }
            box_clipped(&b, best, k, ko, y, xb, xe);
        }
    }
}

/* Two levels: F (halved until min side <= SEARCH_MAX_SIDE; reflections inpainted there) and C
 * (F halved again until min side <= SEARCH_C_SIDE). The exhaustive search runs on C;
 * F only refines position and size around C's answer, which costs ~25x less than searching F. */
static candidate coarse_search(fv_eye_tracker *t, const uint8_t *luma, int w, int h, ptrdiff_t stride,
                               uint8_t *work, uint8_t *mask, uint8_t *small, uint32_t *ii, int *idx)
{
    candidate c = { 0 };
    const fv_eyetrack_dsp *d = &t->dsp;
    int sw = w, sh = h, scale = 1;
    const uint8_t *src = luma;
    ptrdiff_t sst = stride;
    while (fv_mini(sw, sh) > SEARCH_MAX_SIDE) { /* halve straight from the input, then in place-free ping-pong */
        const int nw = sw / 2, nh = sh / 2;
        uint8_t *dst = src == work ? mask : work;
        for (int y = 0; y < nh; y++)
            d->et_down2_row(dst + (size_t)y * nw, src + (2 * y) * sst, src + (2 * y + 1) * sst, nw);
        src = dst, sst = nw;
        sw = nw, sh = nh, scale *= 2;
    }
    if (src != work)
        for (int y = 0; y < sh; y++)
            memcpy(work + (size_t)y * sw, src + y * sst, (size_t)sw);
    uint32_t hist[256];
    histogram(work, sw, sh, sw, hist);
    const int med = percentile(hist, (uint32_t)(sw * sh), 0.5);
    const int hi = percentile(hist, (uint32_t)(sw * sh), 0.995);
    const int thr = fv_maxi(med + 40, med + (255 - med) / 2);
    if (hi >= thr)
        inpaint_bright(d, work, sw, sh, thr, 1, mask, idx, (int *)ii, (uint8_t)med); /* ii: free until the integral below */
    const float dark = (float)percentile(hist, (uint32_t)(sw * sh), 0.01);
    /* level C */
    int cw = sw, ch = sh, f = 1;
    const uint8_t *cs = work;
    while (fv_mini(cw, ch) > SEARCH_C_SIDE) {
        const int nw = cw / 2, nh = ch / 2;
        uint8_t *dst = cs == small ? mask : small;
        for (int y = 0; y < nh; y++)
            d->et_down2_row(dst + (size_t)y * nw, cs + (size_t)(2 * y) * cw, cs + (size_t)(2 * y + 1) * cw, nw);
        cs = dst;
        cw = nw, ch = nh, f *= 2;
    }
    const float side = (float)fv_mini(cw, ch);
    const int kmin = fv_maxi(1, (int)lrintf(t->p.min_radius_frac * side));
    const int kmax = fv_maxi(kmin, (int)lrintf(t->p.max_radius_frac * side));
    box_hit b = { -1e30f, 0, 0, 0, 0, 0 };
    integral(d, cs, cw, ch, ii);
    /* centres no nearer the border than margin_frac of the side: vignetted corners and image
     * edges are dark, and a pupil there is cut anyway */
    const int mx = (int)lrintf(t->p.border_frac * side);
    box_search(d, ii, cw, ch, kmin, kmax, 0, mx, cw - mx, mx, ch - mx, dark, t->p.centre_prior, &b);
    if (b.score <= -1e30f)
        return c;
    if (f > 1) { /* refine on F around C's answer */
        const int fx = b.x * f + f / 2, fy = b.y * f + f / 2, fk = b.k * f + f / 2;
        box_hit bf = { -1e30f, 0, 0, 0, 0, 0 };
        integral(d, work, sw, sh, ii);
        box_search(d, ii, sw, sh, fv_maxi(1, fk - f), fk + f, 1, fx - f - 1, fx + f + 2, fy - f - 1, fy + f + 2, dark, 0.0f, &bf); /* no prior: it would bias the position */
        if (bf.score > -1e30f)
            b = bf;
        else
            b.x = fx, b.y = fy, b.k = fk;
    }
    c.x = (b.x + 0.5f) * scale;
    c.y = (b.y + 0.5f) * scale;
    c.r = (b.k + 0.5f) * scale;
    c.inner = b.inner;
    c.ring = b.ring;
    c.ok = 1;
    c.scale = scale;
    return c;
}

/* ---------------------------------------------------------------- refinement */

/* Points within tol of e (fv_ellipse_distance with the rotation computed once). */
/* Points within tol of the ellipse; with gradients (gx, gy not NULL), only those whose image
 * gradient points along the ellipse's outward normal (cos >= mincos): a lash or lid edge that
 * happens to lie on a candidate ellipse runs across it, not along it. */
static int count_near(const fv_ellipse *e, const float *x, const float *y, const float *gx, const float *gy, int n,
                      double tol, double mincos)
{
    const double c = cos(e->angle), s = sin(e->angle), ia = 1.0 / e->a, ib = 1.0 / e->b;
    int k = 0;
    for (int i = 0; i < n; i++) {
        const double u = (x[i] - e->cx) * c + (y[i] - e->cy) * s, v = -(x[i] - e->cx) * s + (y[i] - e->cy) * c;
        const double rho = sqrt((u * ia) * (u * ia) + (v * ib) * (v * ib));
        const double d = rho < 1e-12 ? e->b : fabs(rho - 1.0) * sqrt(u * u + v * v) / rho;
        if (d > tol)
            continue;
        if (gx) {
            const double nu = u * ia * ia, nv = v * ib * ib;
            const double nx = nu * c - nv * s, ny = nu * s + nv * c;
            const double dot = nx * gx[i] + ny * gy[i], nn = sqrt((nx * nx + ny * ny) * (gx[i] * gx[i] + gy[i] * gy[i]));
            if (!(dot >= mincos * nn))
                continue;
        }
        k++;
    }
    return k;
}

typedef struct {
    float x, y, r;
    float inner, ring;
    int fit;
    fv_ellipse e;
    float inliers; /* fraction of rays giving inlier edge points */
} pupil;

/* A lid across the pupil puts a run of edge points on a nearly straight line (its radius of
 * curvature is several times the pupil's). Find the best line through pairs of points 2-8 rays
 * apart (the points come in ray order, and a lid's are neighbours); if at least 5 points lie
 * within tol of it, spread over >= 1.2 r along it (an arc of the pupil's own outline that long
 * bends away from any line by more than tol even at b/a = 0.6), it runs within 40 deg of
 * horizontal and it cuts the pupil, drop those points and everything beyond it (lashes).
 * Returns the number of points kept (ex, ey, egx, egy compacted). */
static int drop_lid_line(float *ex, float *ey, float *egx, float *egy, int ne, float cx, float cy, float r)
{
    const float tol = fmaxf(0.5f, 0.025f * r);
    int best = 0;
    float bnx = 0, bny = 0, bd = 0;
    for (int i = 0; i < ne; i++)
        for (int dj = 2; dj <= fv_mini(8, ne - 1); dj++) {
            const int j = (i + dj) % ne;
            const float dx = ex[j] - ex[i], dy = ey[j] - ey[i], len = hypotf(dx, dy);
            if (len < 0.3f * r || fabsf(dy) > 0.643f * len) /* sin 40 deg */
                continue;
            const float nx = -dy / len, ny = dx / len, d = nx * ex[i] + ny * ey[i];
            if (fabsf(nx * cx + ny * cy - d) > 0.95f * r)
                continue;
            int cnt = 0;
            float tmin = 1e30f, tmax = -1e30f;
            for (int k = 0; k < ne; k++)
                if (fabsf(nx * ex[k] + ny * ey[k] - d) <= tol) {
                    const float tt = ny * ex[k] - nx * ey[k];
                    cnt++, tmin = fminf(tmin, tt), tmax = fmaxf(tmax, tt);
                }
            if (cnt >= 5 && tmax - tmin >= 1.2f * r && cnt > best)
                best = cnt, bnx = nx, bny = ny, bd = d;
        }
    if (!best)
        return ne;
    /* side of the line the centre is on: keep points on it, beyond tol */
    const float sc = bnx * cx + bny * cy - bd > 0 ? 1.0f : -1.0f;
    int m = 0;
    for (int k = 0; k < ne; k++)
        if (sc * (bnx * ex[k] + bny * ey[k] - bd) > tol)
            ex[m] = ex[k], ey[m] = ey[k], egx[m] = egx[k], egy[m] = egy[k], m++;
    return m;
}

/* Scratch: win, mask w*h bytes, idx, fr w*h ints (fr: the search's integral image buffer, free
 * by now), dxx w floats. */
static int refine(fv_eye_tracker *t, const uint8_t *luma, int w, int h, ptrdiff_t stride, const candidate *c,
                  int inpainted, uint8_t *win, uint8_t *mask, int *idx, int *fr, float *dxx, pupil *out)
{
    /* window around the candidate, reflections inpainted */
    /* headset-sized frames: the search's box can be much smaller than the pupil (the darkest
     * part of it), and rays must reach the pupil's far edge inside the window */
    const int half = fv_maxi((int)ceilf(3.0f * c->r), inpainted ? 0 : fv_mini(w, h) / 4) + 2;
    const int x0 = fv_maxi(0, (int)c->x - half), y0 = fv_maxi(0, (int)c->y - half);
    const int x1 = fv_mini(w, (int)c->x + half), y1 = fv_mini(h, (int)c->y + half);
    const int ww = x1 - x0, wh = y1 - y0;
    if (ww < 4 || wh < 4)
        return -1;
    for (int y = 0; y < wh; y++)
        memcpy(win + (size_t)y * ww, luma + (y + y0) * stride + x0, (size_t)ww);
    int med = 0, masked = 0;
    if (!inpainted) { /* small frames: the search image, inpainted already; nothing else needs these levels */
        uint32_t hist[256];
        histogram(win, ww, wh, ww, hist);
        med = percentile(hist, (uint32_t)(ww * wh), 0.5);
        const int thr = fv_maxi(med + 40, med + (255 - med) / 2);
        if (percentile(hist, (uint32_t)(ww * wh), 0.995) >= thr) {
            inpaint_bright(&t->dsp, win, ww, wh, thr, c->scale > 1 ? 3 : 1, mask, idx, fr, (uint8_t)med);
            masked = 1;
        }
    }

    float cx = c->x - x0, cy = c->y - y0, r = c->r;
    float inner = c->inner, ring = c->ring;
    /* small frames only need the levels and size from this (their centre is the search's) */
    const int iters = inpainted ? 2 : 6;
    int grown = 0;
    for (int it = 0; it < iters; it++) {
        /* blob and surround levels around the current estimate */
        const float ri = 0.7f * r, ro0 = 1.2f * r, ro1 = 1.7f * r, rr = 1.5f * r;
        const float ri2 = ri * ri, ro02 = ro0 * ro0, ro12 = ro1 * ro1, rr2 = rr * rr;
        const int bx0 = fv_maxi(0, (int)(cx - ro1)), bx1 = fv_mini(ww, (int)(cx + ro1) + 1);
        const int by0 = fv_maxi(0, (int)(cy - ro1)), by1 = fv_mini(wh, (int)(cy + ro1) + 1);
        const int ax0 = fv_maxi(0, (int)(cx - rr)), ax1 = fv_mini(ww, (int)(cx + rr) + 1);
        const int ay0 = fv_maxi(0, (int)(cy - rr)), ay1 = fv_mini(wh, (int)(cy + rr) + 1);
        /* dx * dx of every column either loop visits (the same float operations as per pixel) */
        const int qx0 = fv_mini(ax0, bx0), qx1 = fv_maxi(ax1, bx1);
        for (int x = qx0; x < qx1; x++) {
            const float dx = x + 0.5f - cx;
            dxx[x - qx0] = dx * dx;
        }
        /* integer sums: exact, as the double sums were */
        int64_t si = 0, so = 0;
        int ni = 0, no = 0;
        for (int y = by0; y < by1; y++) {
            const float dy = y + 0.5f - cy, dyy = dy * dy;
            const uint8_t *row = win + y * ww;
            for (int x = bx0; x < bx1; x++) {
                const float d2 = dxx[x - qx0] + dyy;
                const int v = row[x];
                if (d2 <= ri2)
                    si += v, ni++;
                else if (d2 >= ro02 && d2 <= ro12)
                    so += v, no++;
            }
        }
        if (ni)
            inner = (float)((double)si / ni);
        if (no)
            ring = (float)((double)so / no);
        /* Headset-sized frames: the search's box can sit between reflections inside a much
         * bigger pupil, with pupil all around it too; grow it until its surround is not pupil */
        if (!inpainted && grown < 4 && ring < inner + 0.25f * (med - inner) && 1.7f * 1.4f * r < half) {
            r *= 1.4f, grown++, it--;
            continue;
        }
        if (!(ring > inner))
            return -1;
        const float th = 0.5f * (inner + ring);
        /* weighted centroid of the dark pixels near the estimate */
        double sw = 0, sx = 0, sy = 0;
        int area = 0;
        for (int y = ay0; y < ay1; y++) {
            const float dy = y + 0.5f - cy, dyy = dy * dy;
            const uint8_t *row = win + y * ww;
            for (int x = ax0; x < ax1; x++) {
                if (dxx[x - qx0] + dyy > rr2)
                    continue;
                const float v = row[x];
                if (v < th) {
                    const double wt = th - v;
                    sw += wt, sx += wt * (x + 0.5f), sy += wt * (y + 0.5f);
                    area++;
                }
            }
        }
        if (sw <= 0)
            return -1;
        const float nx = (float)(sx / sw), ny = (float)(sy / sw);
        const float nr = fv_clampf(sqrtf(area / (float)M_PI), 0.6f * r, 1.4f * r);
        const int settled = fabsf(nx - cx) < 0.02f * r && fabsf(ny - cy) < 0.02f * r && fabsf(nr - r) < 0.02f * r;
        cx = nx, cy = ny, r = nr;
        if (settled)
            break;
    }
    out->x = cx + x0;
    out->y = cy + y0;
    out->r = r;
    out->inner = inner;
    out->ring = ring;
    out->fit = 0;
    out->inliers = 0;

    /* edge points along rays: first outward crossing of the mid level */
    const float th = 0.5f * (inner + ring);
    const uint8_t *ew = win;
    if (!inpainted) {
        /* 3x3 box: sensor noise would otherwise break the sustained-crossing rule near the
         * true edge and push crossings out into a dark iris (idx is free once inpainted) */
        uint8_t *bl = (uint8_t *)idx;
        for (int y = 0; y < wh; y++)
            t->dsp.et_box3_row(bl + y * ww, win + fv_maxi(0, y - 1) * ww, win + y * ww, win + fv_mini(wh - 1, y + 1) * ww, ww);
        ew = bl;
    }
    float ex[NRAYS], ey[NRAYS];
    int ne = 0;
    const float step = fmaxf(0.25f, r / 24.0f);
    const int nrays = r < 12.0f ? NRAYS / 2 : NRAYS; /* small pupils: fewer edge pixels anyway */
    float evo[NRAYS], egx[NRAYS], egy[NRAYS];
    const float lidf = 0.35f;
    for (int k = 0; k < nrays; k++) {
        const float a = (float)(2.0 * M_PI * k / nrays), dx = cosf(a), dy = sinf(a);
        float prev = sample(ew, ww, wh, cx, cy), pd = 0;
        for (float dist = step; dist < 2.2f * r; dist += step) {
            const float px = cx + dist * dx, py = cy + dist * dy;
            if (px < 0.5f || py < 0.5f || px > ww - 0.5f || py > wh - 0.5f)
                break;
            const float v = sample(ew, ww, wh, px, py);
            if (v >= th && prev < th && sustained(ew, ww, wh, cx, cy, dx, dy, dist, fmaxf(1.5f, 0.2f * r), th)) {
                const float f = (th - prev) / (v - prev);
                float de = pd + f * (dist - pd);
                if (!inpainted) /* the level's crossing moves with the levels; the edge does not */
                    de = steepest_rise(ew, ww, wh, cx, cy, dx, dy, de, EDGE_SEARCH_PX);
                /* beyond a pupil edge lies iris; beyond a lid edge, much brighter skin: a ray
                 * that meets the lid gives no point (it would drag the fit) */
                const float po = de + fmaxf(2.0f, 0.15f * r);
                const float vo = sample(ew, ww, wh, cx + po * dx, cy + po * dy);
                float vmax = vo;
                if (!inpainted) {
                    /* the brightest of the profile beyond: iris for a pupil edge, skin between
                     * the lashes for a lid edge */
                    const float pe = de + fmaxf(4.0f, 0.5f * r);
                    for (float q = po + 1.0f; q <= pe; q += 1.0f) {
                        const float qx = cx + q * dx, qy = cy + q * dy;
                        if (qx < 0.5f || qy < 0.5f || qx > ww - 0.5f || qy > wh - 0.5f)
                            break;
                        vmax = fmaxf(vmax, sample(ew, ww, wh, qx, qy));
                    }
                }
                /* an edge next to an inpainted reflection is made up, not seen */
                const int ix = (int)(cx + de * dx), iy = (int)(cy + de * dy);
                int near_mask = 0;
                if (masked)
                    for (int qy = fv_maxi(0, iy - 1); qy <= fv_mini(wh - 1, iy + 1); qy++)
                        for (int qx = fv_maxi(0, ix - 1); qx <= fv_mini(ww - 1, ix + 1); qx++)
                            near_mask |= mask[qy * ww + qx] != 0;
                if (!near_mask && vo <= ring + 0.6f * (ring - inner)) {
                    ex[ne] = cx + de * dx + x0;
                    ey[ne] = cy + de * dy + y0;
                    evo[ne] = vmax;
                    /* Sobel gradient at the edge point (bilinear samples 1 px apart), for the
                     * RANSAC support test */
                    const float qx = cx + de * dx, qy = cy + de * dy;
                    float g[3][3];
                    for (int j = 0; j < 3; j++)
                        for (int i = 0; i < 3; i++)
                            g[j][i] = sample(ew, ww, wh, qx + (float)(i - 1), qy + (float)(j - 1));
                    egx[ne] = (g[0][2] + 2.0f * g[1][2] + g[2][2]) - (g[0][0] + 2.0f * g[1][0] + g[2][0]);
                    egy[ne] = (g[2][0] + 2.0f * g[2][1] + g[2][2]) - (g[0][0] + 2.0f * g[0][1] + g[0][2]);
                    ne++;
                }
                break;
            }
            prev = v, pd = dist;
        }
    }
    if (!inpainted && ne >= 8) {
        /* What lies beyond most edge points (evo: the brightest of the profile up to 0.5 r out)
         * is iris; points with something clearly brighter beyond them (the lid margin, skin
         * between the lashes) are dropped. The median is the iris level as long as the lid
         * hides less than half of the outline. */
        float srt[NRAYS];
        memcpy(srt, evo, sizeof(float) * (size_t)ne);
        for (int i = 1; i < ne; i++)
            for (int j = i; j > 0 && srt[j - 1] > srt[j]; j--) {
                const float tmp = srt[j];
                srt[j] = srt[j - 1], srt[j - 1] = tmp;
            }
        const float iris = srt[ne / 2], lim = iris + lidf * (iris - inner);
        int m = 0;
        for (int i = 0; i < ne; i++)
            if (evo[i] <= lim)
                ex[m] = ex[i], ey[m] = ey[i], evo[m] = evo[i], egx[m] = egx[i], egy[m] = egy[i], m++;
        ne = m;
    }
    int lid = 0;
    if (!inpainted && ne >= 12) {
        const int kept = drop_lid_line(ex, ey, egx, egy, ne, cx + x0, cy + y0, r);
        lid = kept < ne;
        ne = kept;
    }
    if (ne < 8)
        return 0;
    /* headset-sized pupils: aspect b/a >= 0.6 (gaze up to ~50 deg off the camera axis); flatter
     * fits are lid-line consensus */
    const double minab = 0.6;
    int n = 0;
    if (!inpainted) {
        /* Headset-sized pupils: RANSAC over 6-point fits (a lid can hide a third of the outline
         * and put its own edge in the middle of the points, which moves a least-squares fit),
         * then the least-squares refit below on the consensus. Deterministic sampling. */
        uint64_t st = 0x5eedu;
        int best = 0;
        fv_ellipse be;
        for (int it = 0; it < 64; it++) {
            float sx[6], sy[6];
            int pick[6], k = 0;
            while (k < 6) {
                st += 0x9e3779b97f4a7c15ull;
                uint64_t z = st;
                z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
                z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
                const int j = (int)((z ^ (z >> 31)) % (uint64_t)ne);
                int dup = 0;
                for (int q = 0; q < k; q++)
                    dup |= pick[q] == j;
                if (!dup)
                    pick[k] = j, sx[k] = ex[j], sy[k] = ey[j], k++;
            }
            fv_ellipse e;
            if (fv_ellipse_fit(sx, sy, 6, &e) || e.a < 0.5 * r || e.a > 2.5 * r || e.b < minab * e.a ||
                hypot(e.cx - (cx + x0), e.cy - (cy + y0)) > r)
                continue;
            const int cnt = count_near(&e, ex, ey, egx, egy, ne, fmax(1.0, 0.06 * e.a), GRAD_MINCOS);
            if (cnt > best)
                best = cnt, be = e;
        }
        if (best >= 8) {
            const double tol = fmax(1.0, 0.06 * be.a);
            for (int i = 0; i < ne; i++)
                if (count_near(&be, ex + i, ey + i, egx + i, egy + i, 1, tol, GRAD_MINCOS))
                    ex[n] = ex[i], ey[n] = ey[i], n++;
        }
    }
    if (n < 8) {
    /* first cut: points much nearer or farther than the median radius (glints, lids, lashes) */
    float rad[NRAYS];
    for (int i = 0; i < ne; i++)
        rad[i] = hypotf(ex[i] - (cx + x0), ey[i] - (cy + y0));
    float sorted[NRAYS];
    memcpy(sorted, rad, sizeof(float) * (size_t)ne);
    for (int i = 1; i < ne; i++) /* insertion sort: 48 values */
        for (int j = i; j > 0 && sorted[j - 1] > sorted[j]; j--) {
            const float tmp = sorted[j];
            sorted[j] = sorted[j - 1], sorted[j - 1] = tmp;
        }
    const float rmed = sorted[ne / 2];
    n = 0;
    for (int i = 0; i < ne; i++)
        if (fabsf(rad[i] - rmed) <= fmaxf(1.5f, 0.25f * rmed))
            ex[n] = ex[i], ey[n] = ey[i], n++;
    }
    if (n < 8)
        return 0;
    fv_ellipse e;
    for (int round = 0; round < 3; round++) {
        if (fv_ellipse_fit(ex, ey, n, &e))
            return 0;
        /* drop points far from the fit (lashes, lids, leftover reflections), refit */
        const double tol = fmax(0.75, 0.08 * e.a);
        int m = 0;
        for (int i = 0; i < n; i++)
            if (fv_ellipse_distance(&e, ex[i], ey[i]) <= tol)
                ex[m] = ex[i], ey[m] = ey[i], m++;
        if (m == n)
            break;
        if (m < 6)
            return 0;
        n = m;
    }
    if (fv_ellipse_fit(ex, ey, n, &e))
        return 0;
    const double dc = hypot(e.cx - out->x, e.cy - out->y);
    if (e.a < 0.5 * r || e.a > 2.5 * r || e.b < (inpainted ? 0.3 : minab) * e.a || dc > (lid ? 1.0 : 0.6) * r)
        return 0;
    out->fit = 1;
    out->e = e;
    out->inliers = (float)n / nrays;
    return 0;
}

/* ---------------------------------------------------------------- glints */

static int find_glints(const fv_eye_tracker *t, const uint8_t *luma, int w, int h, ptrdiff_t stride, const pupil *pp,
                       uint8_t *lab, int *stack, fv_eye_glint *g)
{
    const float rad = fmaxf(2.2f * pp->r, 6.0f);
    const int x0 = fv_maxi(0, (int)(pp->x - rad)), x1 = fv_mini(w, (int)(pp->x + rad) + 1);
    const int y0 = fv_maxi(0, (int)(pp->y - rad)), y1 = fv_mini(h, (int)(pp->y + rad) + 1);
    const int ww = x1 - x0, wh = y1 - y0;
    if (ww < 1 || wh < 1)
        return 0;
    const int thr = fv_maxi((int)pp->ring + 40, (int)(pp->ring + 0.5f * (255.0f - pp->ring)));
    const float max_area = fmaxf(4.0f, 0.8f * pp->r * pp->r);
    /* lab: 255 bright and not yet in a blob, 1 in one, 0 dark (thr above 255: none bright) */
    int n = 0;
    for (int y = 0; y < wh; y++)
        t->dsp.et_thresh_row(lab + y * ww, luma + (y + y0) * stride + x0, ww, fv_mini(thr, 256));
    for (int y = 0; y < wh; y++)
        for (int x = 0; x < ww; x++) {
            if (x + 8 <= ww) { /* mostly dark: skip eight at a time */
                uint64_t v;
                memcpy(&v, lab + y * ww + x, sizeof v);
                if (!v) {
                    x += 7;
                    continue;
                }
            }
            if (lab[y * ww + x] != 255)
                continue;
            /* flood fill one 4-connected blob */
            int sp = 0, area = 0, touches = 0, peak = 0;
            double sw = 0, sx = 0, sy = 0;
            stack[sp++] = PK(x, y);
            lab[y * ww + x] = 1;
            while (sp) {
                const int q = stack[--sp], px = PK_X(q), py = PK_Y(q), i = py * ww + px;
                const int v = luma[(py + y0) * stride + px + x0];
                const double wt = v - thr + 1;
                peak = fv_maxi(peak, v);
                sw += wt, sx += wt * (px + 0.5), sy += wt * (py + 0.5);
                area++;
                if (px == 0 || py == 0 || px == ww - 1 || py == wh - 1)
                    touches = 1;
#define PUSH(cond, di, dq)                                                                                              \
    if ((cond) && lab[i + (di)] == 255)                                                                                \
        lab[i + (di)] = 1, stack[sp++] = q + (dq);
                PUSH(px > 0, -1, -1)
                PUSH(px + 1 < ww, 1, 1)
                PUSH(py > 0, -ww, -ROW)
                PUSH(py + 1 < wh, ww, ROW)
#undef PUSH
            }
            if (touches || area > max_area)
                continue;
            fv_eye_glint gl = { (float)(sx / sw) + x0, (float)(sy / sw) + y0, (float)area };
            /* a reflection is a small spot much brighter than what is right around it (bright
             * skin or sclera above the threshold is not) */
            const float rb = sqrtf(area / (float)M_PI) + 2.5f;
            float bg = 0;
            for (int k = 0; k < 8; k++) {
                const int bx = fv_mini(w - 1, fv_maxi(0, (int)floorf(gl.x + rb * cosf(k * (float)M_PI / 4)))),
                          by = fv_mini(h - 1, fv_maxi(0, (int)floorf(gl.y + rb * sinf(k * (float)M_PI / 4))));
                bg += luma[by * stride + bx];
            }
            if (peak - bg / 8 < 50)
                continue;
            const float dd = hypotf(gl.x - pp->x, gl.y - pp->y);
            if (dd > rad)
                continue;
            /* insertion by distance to the pupil centre */
            int j = n < FV_EYE_MAX_GLINTS ? n++ : n - 1;
            if (j == FV_EYE_MAX_GLINTS - 1 && n == FV_EYE_MAX_GLINTS &&
                hypotf(g[j].x - pp->x, g[j].y - pp->y) <= dd && j > 0)
                continue; /* full, and farther than all kept */
            while (j > 0 && hypotf(g[j - 1].x - pp->x, g[j - 1].y - pp->y) > dd) {
                g[j] = g[j - 1];
                j--;
            }
            g[j] = gl;
        }
    return fv_mini(n, t->p.max_glints);
}

/* ---------------------------------------------------------------- frame */

/* The most prominent small reflection within r of (cx, cy) in a small crop: a 3x3 local maximum
 * at least SPOT_MIN grey levels above the median of the square ring 3 px around it (weaker and
 * smaller than what find_glints accepts: at these sizes the reflection is a few pixels of
 * a blurred spot). 1 and its pixel centre, or 0. */
static int bright_spot(const uint8_t *img, int w, int h, ptrdiff_t stride, float cx, float cy, float r, float *ox,
                       float *oy)
{
    const int x0 = fv_maxi(3, (int)floorf(cx - r)), x1 = fv_mini(w - 4, (int)floorf(cx + r));
    const int y0 = fv_maxi(3, (int)floorf(cy - r)), y1 = fv_mini(h - 4, (int)floorf(cy + r));
    int best = SPOT_MIN - 1, bx = -1, by = -1;
    for (int y = y0; y <= y1; y++)
        for (int x = x0; x <= x1; x++) {
            const uint8_t *q = img + y * stride + x;
            const int v = q[0];
            if (v - best <= 0 || v < q[-1] || v < q[1] || v < q[-stride] || v < q[stride] || v < q[-stride - 1] ||
                v < q[-stride + 1] || v < q[stride - 1] || v < q[stride + 1])
                continue;
            /* median of the 24 ring pixels (insertion sort) */
            uint8_t ring[24];
            int n = 0;
            for (int k = -3; k <= 3; k++) {
                ring[n++] = q[-3 * stride + k], ring[n++] = q[3 * stride + k];
                if (k > -3 && k < 3)
                    ring[n++] = q[k * stride - 3], ring[n++] = q[k * stride + 3];
            }
            for (int i = 1; i < n; i++)
                for (int j = i; j > 0 && ring[j - 1] > ring[j]; j--) {
                    const uint8_t tmp = ring[j];
                    ring[j] = ring[j - 1], ring[j - 1] = tmp;
                }
            const int con = v - (ring[11] + ring[12] + 1) / 2;
            if (con > best)
                best = con, bx = x, by = y;
        }
    if (bx < 0)
        return 0;
    *ox = bx + 0.5f, *oy = by + 0.5f;
    return 1;
}

static int track(fv_eye_tracker *t, const uint8_t *luma, int w, int h, ptrdiff_t stride, fv_eye_result *r,
                 int history)
{
    if (!t || !luma || !r || w < 8 || h < 8 || w > 8192 || h > 8192 || stride < w)
        return -1;
    memset(r, 0, sizeof *r);
    r->status = FV_EYE_LOST;
    const size_t px = (size_t)w * h;
    const size_t ii_bytes = ((size_t)(w + 1) * (h + 1)) * sizeof(uint32_t);
    const size_t row_bytes = (size_t)w * sizeof(float);
    uint8_t *m = scratch(t, 3 * px + ii_bytes + px * sizeof(int) + row_bytes + 64 +
                                2 * FV_EYE_MAX_GLINTS * sizeof(fv_eye_glint));
    if (!m)
        return -1;
    uint32_t *ii = (uint32_t *)m;
    int *stack = (int *)(m + ii_bytes);
    float *rowf = (float *)(m + ii_bytes + px * sizeof(int));
    fv_eye_glint *gl = (fv_eye_glint *)(m + ii_bytes + px * sizeof(int) + row_bytes);
    uint8_t *work = m + ii_bytes + px * sizeof(int) + row_bytes + 2 * FV_EYE_MAX_GLINTS * sizeof(fv_eye_glint),
            *mask = work + px, *lowres = mask + px;

    const candidate c = coarse_search(t, luma, w, h, stride, work, mask, lowres, ii, stack);
    if (!c.ok)
        return 0;
    pupil p;
    /* small images: the search image is the full-resolution frame, already inpainted; refine
     * from it (into another buffer) rather than inpainting the window again */
    const int reuse = c.scale == 1;
    /* Frames bigger than REFINE_MAX_SIDE: refined on the frame halved (lowres is free after the
     * search). The ellipse keeps sub-pixel precision from the edge points, the sensor noise that
     * pushes crossings outward halves, and the work quarters. */
    const uint8_t *rsrc = reuse ? work : luma;
    int rw = w, rh = h, rs = 1;
    ptrdiff_t rst = reuse ? w : stride;
    while (!reuse && fv_mini(rw, rh) > REFINE_MAX_SIDE && rs < c.scale) {
        uint8_t *dst = rsrc == lowres ? lowres + px / 2 : lowres;
        const int nw = rw / 2, nh = rh / 2;
        for (int y = 0; y < nh; y++)
            t->dsp.et_down2_row(dst + (size_t)y * nw, rsrc + (2 * y) * rst, rsrc + (2 * y + 1) * rst, nw);
        rsrc = dst, rst = nw, rw = nw, rh = nh, rs *= 2;
    }
    candidate rc = c;
    rc.x /= (float)rs, rc.y /= (float)rs, rc.r /= (float)rs, rc.scale /= rs;
    if (refine(t, rsrc, rw, rh, rst, &rc, reuse, reuse ? lowres : work, mask, stack, (int *)ii, rowf, &p)) {
        /* no dark region stands out in the window: keep the search's answer, flagged low */
        p.x = c.x, p.y = c.y, p.r = c.r, p.inner = c.inner, p.ring = c.ring, p.fit = 0, p.inliers = 0;
    } else if (rs > 1) {
        const float f = (float)rs;
        p.x *= f, p.y *= f, p.r *= f;
        p.e.cx *= f, p.e.cy *= f, p.e.a *= f, p.e.b *= f;
    }
    /* Small images (min side <= SEARCH_MAX_SIDE: remote-camera crops, ~10 px pupils inside an
     * often equally dark iris): the best contrast box's centre beat the refined centroid and the
     * ellipse on the MRL images (lids, lashes and iris pull them). Headset-sized eyes: the ellipse
     * centre, else the dark-region centroid. */
    const int small = c.scale == 1;
    const int ng = find_glints(t, luma, w, h, stride, &p, work, stack, gl);
    if (small) {
        /* The box centre, moved toward the crop's centre (the crop is the eye detector's own
         * estimate: on MRL the labels sit ~8% of the way from the detection to the centre)
         * and toward a corneal reflection inside the box (it hides part of the pupil, and its
         * inpainted area looks less dark than the pupil, which pushes the box away from it),
         * then on a pixel centre again like the box it came from. */
        const float a = fv_clampf(t->p.crop_centre_weight, 0.0f, 1.0f), gw = fv_clampf(t->p.glint_weight, 0.0f, 1.0f);
        float px = c.x + a * (0.5f * (float)w - c.x), py = c.y + a * (0.5f * (float)h - c.y);
        float gx, gy;
        if (gw > 0 && bright_spot(luma, w, h, stride, c.x, c.y, c.r, &gx, &gy))
            px += gw * (gx - c.x), py += gw * (gy - c.y);
        r->pupil_x = floorf(px) + 0.5f;
        r->pupil_y = floorf(py) + 0.5f;
    } else if (p.fit) {
        r->pupil_x = (float)p.e.cx;
        r->pupil_y = (float)p.e.cy;
        r->ellipse_fit = 1;
    } else {
        r->pupil_x = p.x;
        r->pupil_y = p.y;
    }
    if (p.fit) {
        r->pupil_a_px = (float)p.e.a;
        r->pupil_b_px = (float)p.e.b;
        r->pupil_angle_rad = (float)p.e.angle;
    } else {
        r->pupil_a_px = r->pupil_b_px = p.r;
    }
    r->contrast = p.ring - p.inner;
    r->found = 1;
    r->status = FV_EYE_OK;

    r->n_glints = ng;
    memcpy(r->glints, gl, (size_t)r->n_glints * sizeof *gl);
    if (r->n_glints) {
        float gx = 0, gy = 0;
        for (int i = 0; i < r->n_glints; i++)
            gx += r->glints[i].x, gy += r->glints[i].y;
        r->has_pg = 1;
        r->pg_x = r->pupil_x - gx / r->n_glints;
        r->pg_y = r->pupil_y - gy / r->n_glints;
    }

    /* confidence: contrast (grey levels) and how much of the outline the fit explains */
    const float cc = fv_clampf((r->contrast - 4.0f) / 24.0f, 0.0f, 1.0f);
    const float fit = p.fit ? fv_clampf(p.inliers / 0.6f, 0.0f, 1.0f) : 0.5f;
    r->confidence = cc * (0.4f + 0.6f * fit);

    if (r->contrast < 3.0f) {
        r->status = FV_EYE_LOST;
        r->found = 0;
    }
    if (history && r->status == FV_EYE_OK) {
        /* a blink: what is found is not the pupil the tracker has been seeing: much less dark
         * (lashes, lid crease), much less contrast, much smaller, or a sliver */
        const float flat = p.fit ? (float)(p.e.b / p.e.a) : 1.0f;
        const float span = t->ref_ring - t->ref_inner;
        if (t->nref >= 3 && (p.inner > t->ref_inner + 0.4f * span || r->contrast < 0.45f * t->ref_contrast ||
                             p.r < 0.45f * t->ref_radius || flat < 0.3f)) {
            r->status = FV_EYE_BLINK; /* what was found is not a pupil: no position */
            r->found = 0;
            r->has_pg = 0;
            r->confidence *= 0.25f;
        } else {
            const float a = t->nref < 10 ? 1.0f / (t->nref + 1) : 0.1f;
            t->ref_contrast += a * (r->contrast - t->ref_contrast);
            t->ref_radius += a * (p.r - t->ref_radius);
            t->ref_inner += a * (p.inner - t->ref_inner);
            t->ref_ring += a * (p.ring - t->ref_ring);
            t->nref++;
        }
    } else if (history && r->status == FV_EYE_LOST && t->nref >= 3) {
        r->status = FV_EYE_BLINK;
    }
    return 0;
}

int fv_track_frame(fv_eye_tracker *t, const uint8_t *luma, int w, int h, ptrdiff_t stride, fv_eye_result *r)
{
    return track(t, luma, w, h, stride, r, 1);
}

int fv_track_image(fv_eye_tracker *t, const uint8_t *luma, int w, int h, ptrdiff_t stride, fv_eye_result *r)
{
    return track(t, luma, w, h, stride, r, 0);
}
