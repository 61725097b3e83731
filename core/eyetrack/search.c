/* Coarse search for the pupil: the darkest compact blob that contrasts with its ring.
 *
 * The frame is halved (dsp->et_down2_row) until min(w, h) <= 160 (F), reflections on F are
 * inpainted from their surroundings (glints.c) so a glint inside the pupil does not make it look
 * bright; F is halved again to <= 64 (C). Over integral images (dsp->et_integral_row) every
 * centre and box size of C is scored by contrast with its ring, darkness and a weak centre prior
 * (box_search); the best is refined in position and size on F. Contrast, not darkness alone,
 * rejects brows, lashes and shadows (as dark around as inside). In crop mode the search image
 * is first clipped at its median + search_clip_grey: a spectacle frame's bright rim under a dark
 * brow would otherwise give the brow the brightest ring in the crop. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/util.h"
#include "eyetrack/track_impl.h"

#define SEARCH_C_SIDE 64 /* exhaustive search image C: min side at most this */

static inline uint32_t box_sum(const uint32_t *ii, int iw, int x0, int y0, int x1, int y1)
{
    /* sum over [x0, x1) x [y0, y1); ii has a zero first row and column, row length iw */
    return ii[y1 * iw + x1] - ii[y0 * iw + x1] - ii[y1 * iw + x0] + ii[y0 * iw + x0];
}

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
    int sides; /* only boxes that pass sides_ok */
    float sides_frac, sides_min_grey;
} box_ctx;

static int sides_ok(const box_ctx *b, int x, int y, int k, float inner, float ring);

static inline void box_offer(const box_ctx *b, box_hit *best, float score, float mi, float mo, int x, int y, int k)
{
    if (score <= best->score) /* the prior only lowers it */
        return;
    if (b->prior > 0) {
        const float ddx = (float)x - b->cxm, ddy = (float)y - b->cym;
        score -= b->prior * sqrtf(ddx * ddx + ddy * ddy);
    }
    if (score > best->score && (!b->sides || sides_ok(b, x, y, k, mi, mo)))
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
                       int x1, int y0, int y1, float dark, float mu, const fv_eye_mode_settings *sides, box_hit *best)
{
    const float rf = 1.5f;
    const box_ctx b = { ii, sw + 1, sw, sh, dark, mu / (float)(sw < sh ? sw : sh), 0.5f * (sw - 1), 0.5f * (sh - 1),
                        sides != NULL, sides ? sides->sides_frac : 0.0f, sides ? sides->sides_min_grey : 0.0f };
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

/* A pupil is surrounded by brighter iris on every side; a band (a spectacle frame's rim, a lid
 * margin, a brow) is as dark as the box along itself. Each of the ring's four side strips must be
 * brighter than the box by sides_frac of the ring's contrast and sides_min_grey grey levels
 * (headset 0.5 and 10; crop 0.3 and 3, a tinted lens leaving crops 6-15 levels of contrast), but
 * one side may fail (a pupil under the lashes of a lowered lid, a crop's rim). */
static int sides_ok(const box_ctx *b, int x, int y, int k, float inner, float ring)
{
    const uint32_t *ii = b->ii;
    const int sw = b->sw, sh = b->sh, iw = sw + 1, ko = (int)lrintf(1.5f * k);
    const int ox0 = fv_maxi(0, x - ko), ox1 = fv_mini(sw, x + ko + 1), oy0 = fv_maxi(0, y - ko), oy1 = fv_mini(sh, y + ko + 1);
    const int bx0 = x - k, bx1 = x + k + 1, by0 = y - k, by1 = y + k + 1;
    const int side[4][4] = {{ox0, oy0, ox1, by0}, {ox0, by1, ox1, oy1}, {ox0, by0, bx0, by1}, {bx1, by0, ox1, by1}};
    /* grey levels: a box inside a uniform band has no contrast at all */
    const float need = fmaxf((ring - inner) * b->sides_frac, b->sides_min_grey);
    int fails = 0;
    for (int i = 0; i < 4; i++) {
        const int a = (side[i][2] - side[i][0]) * (side[i][3] - side[i][1]);
        if (a <= 0)
            continue; /* clipped away by the image edge: no evidence either way */
        const float m = (float)box_sum(ii, iw, side[i][0], side[i][1], side[i][2], side[i][3]) / (float)a;
        fails += m - inner < need;
    }
    return fails <= 1;
}

/* Crop mode: a corneal reflection marks the eye. When no bright spot (spot_min_grey above its
 * ring) lies within the best box's half-size, each spot within twice that on the dark eye (its
 * ring's median at most the image's: not skin, not a spectacle rim) proposes the best box whose
 * centre is within the best's half-size of it; the best proposal wins if it scores within
 * spot_margin_grey of b. Without it the box settles on the darkest part of a wide dark region
 * (the iris's shadowed side, a tinted lens's darker patch) beside the pupil that carries the
 * reflection. u: full-resolution pixels per pixel of C, whose integral image is ii. */
static box_hit spot_alternative(const fv_eyetrack_dsp *d, const fv_eye_params *p, const fv_eye_mode_settings *set,
                                const uint8_t *luma, int w, int h, ptrdiff_t stride, float u, int median,
                                const uint32_t *ii, int cw, int ch, int kmin, int kmax, int mx, float dark, box_hit b)
{
    enum { MAX_SPOTS = 16 };
    const float cx = (b.x + 0.5f) * u, cy = (b.y + 0.5f) * u, r = (b.k + 0.5f) * u;
    float gx, gy;
    if (fv_et_bright_spot(luma, w, h, stride, cx, cy, r, set->spot_min_grey, &gx, &gy))
        return b; /* the best box has its reflection */
    int xs[MAX_SPOTS], ys[MAX_SPOTS];
    const int n = fv_et_dark_spots(luma, w, h, stride, cx, cy, 2.0f * r, set->spot_min_grey, median, MAX_SPOTS, xs, ys);
    box_hit alt = { -1e30f, 0, 0, 0, 0, 0 };
    for (int i = 0; i < n; i++) {
        const int sx = (int)((xs[i] + 0.5f) / u), sy = (int)((ys[i] + 0.5f) / u);
        box_search(d, ii, cw, ch, kmin, kmax, 0, fv_maxi(mx, sx - b.k), fv_mini(cw - mx, sx + b.k + 1), fv_maxi(mx, sy - b.k),
                   fv_mini(ch - mx, sy + b.k + 1), dark, p->centre_prior, set->search_sides ? set : NULL, &alt);
    }
    return alt.score > -1e30f && alt.score >= b.score - set->spot_margin_grey ? alt : b;
}

/* Two levels: F (halved until min side <= SEARCH_MAX_SIDE; reflections inpainted there) and C
 * (F halved again until min side <= SEARCH_C_SIDE). The exhaustive search runs on C;
 * F only refines position and size around C's answer, which costs ~25x less than searching F. */
fv_et_candidate fv_et_search(const fv_eyetrack_dsp *d, const fv_eye_params *p, const uint8_t *luma, int w, int h,
                             ptrdiff_t stride, const fv_et_scratch *s, const fv_eye_mode_settings *set)
{
    fv_et_candidate c = { 0 };
    uint8_t *work = s->work, *mask = s->mask, *small = s->lowres;
    uint32_t *ii = s->ii;
    int sw = w, sh = h, scale = 1;
    const uint8_t *src = luma;
    ptrdiff_t sst = stride;
    while (fv_mini(sw, sh) > FV_ET_SEARCH_MAX_SIDE) { /* halve straight from the input, then in place-free ping-pong */
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
    fv_et_levels lv;
    /* ii: free until the integral below */
    fv_et_inpaint_reflections(d, work, sw, sh, 1, mask, s->stack, (int *)ii, &lv);
    const float dark = (float)lv.dark;
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
    const int kmin = fv_maxi(1, (int)lrintf(p->min_radius_frac * side));
    const int kmax = fv_maxi(kmin, (int)lrintf(p->max_radius_frac * side));
    box_hit b = { -1e30f, 0, 0, 0, 0, 0 };
    if (set->search_clip_grey > 0) { /* bright rims, halos and skin count as the median + clip */
        uint8_t *dst = cs == small ? mask : small;
        const int cap = fv_mini(255, lv.median + set->search_clip_grey);
        for (int i = 0; i < cw * ch; i++)
            dst[i] = cs[i] > cap ? (uint8_t)cap : cs[i];
        cs = dst;
    }
    integral(d, cs, cw, ch, ii);
    /* centres no nearer the border than border_frac of the side: vignetted corners and image
     * edges are dark, and a pupil there is cut anyway */
    const int mx = (int)lrintf(p->border_frac * side);
    /* the best box whose four sides all (but one) contrast with it (a band-shaped box is
     * refused); only if there is none, the best box */
    for (int sides = set->search_sides; sides >= 0; sides--) {
        b = (box_hit){ -1e30f, 0, 0, 0, 0, 0 };
        box_search(d, ii, cw, ch, kmin, kmax, 0, mx, cw - mx, mx, ch - mx, dark, p->centre_prior, sides ? set : NULL, &b);
        if (b.score > -1e30f)
            break;
    }
    if (b.score <= -1e30f)
        return c;
    if (set->spot_margin_grey > 0)
        b = spot_alternative(d, p, set, luma, w, h, stride, (float)(f * scale), lv.median, ii, cw, ch, kmin, kmax, mx,
                             dark, b);
    if (f > 1) { /* refine on F around C's answer */
        const int fx = b.x * f + f / 2, fy = b.y * f + f / 2, fk = b.k * f + f / 2;
        box_hit bf = { -1e30f, 0, 0, 0, 0, 0 };
        integral(d, work, sw, sh, ii);
        box_search(d, ii, sw, sh, fv_maxi(1, fk - f), fk + f, 1, fx - f - 1, fx + f + 2, fy - f - 1, fy + f + 2, dark, 0.0f,
                   NULL, &bf); /* no prior: it would bias the position */
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
    c.sw = sw, c.sh = sh;
    return c;
}
