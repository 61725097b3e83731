/* Bright spots: reflections inpainted out of the search and refine images, corneal glints near
 * the pupil (4-connected blobs of the raw image, dsp->et_thresh_row), and the crop mode's most
 * prominent small reflection (bright_spot). */
#include <math.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <string.h>

#include "base/util.h"
#include "eyetrack/track_impl.h"

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

int fv_et_inpaint_reflections(const fv_eyetrack_dsp *d, uint8_t *img, int w, int h, int grow_px, uint8_t *mask, int *idx,
                              int *fr, fv_et_levels *lv)
{
    uint32_t hist[256];
    histogram(img, w, h, w, hist);
    const uint32_t n = (uint32_t)(w * h);
    lv->median = percentile(hist, n, 0.5);
    lv->dark = percentile(hist, n, 0.01);
    const int thr = fv_maxi(lv->median + 40, lv->median + (255 - lv->median) / 2);
    if (percentile(hist, n, 0.995) < thr)
        return 0;
    inpaint_bright(d, img, w, h, thr, grow_px, mask, idx, fr, (uint8_t)lv->median);
    return 1;
}

int fv_et_find_glints(const fv_eyetrack_dsp *d, const uint8_t *luma, int w, int h, ptrdiff_t stride, const fv_et_pupil *pp,
                      int max_glints, uint8_t *lab, int *stack, fv_eye_glint *g)
{
    const float rad = fmaxf(2.2f * pp->r, 6.0f);
    const int x0 = fv_maxi(0, (int)(pp->x - rad)), x1 = fv_mini(w, (int)(pp->x + rad) + 1);
    const int y0 = fv_maxi(0, (int)(pp->y - rad)), y1 = fv_mini(h, (int)(pp->y + rad) + 1);
    const int ww = x1 - x0, wh = y1 - y0;
    if (ww < 1 || wh < 1)
        return 0;
    const int thr = fv_maxi((int)pp->ring + 40, (int)(pp->ring + 0.5f * (255.0f - pp->ring)));
    /* a corneal glint is the LED's tiny virtual image in a 7.8 mm convex mirror (~0.4 mm across,
     * under a tenth of the pupil's area); a reflection on spectacles (a nearly flat mirror) shows
     * the LED at full size and is several times larger: refused by area */
    const float max_area = fmaxf(12.0f, 0.2f * pp->r * pp->r);
    /* lab: 255 bright and not yet in a blob, 1 in one, 0 dark (thr above 255: none bright) */
    int n = 0, nc = 0;
    enum { MAX_CAND = 32 };
    fv_eye_glint cand[MAX_CAND];
    for (int y = 0; y < wh; y++)
        d->et_thresh_row(lab + y * ww, luma + (y + y0) * stride + x0, ww, fv_mini(thr, 256));
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
            if (dd > rad || nc == MAX_CAND)
                continue;
            cand[nc++] = gl;
        }
    /* corneal glints are images of the same LEDs in the same mirror: about equally small. A
     * reflection on spectacles is a larger image of an LED: refused when more than 3x the median
     * candidate's area (the corneal glints are the majority near the pupil) */
    float area[MAX_CAND];
    for (int i = 0; i < nc; i++) { /* insertion sort of the areas */
        int j = i;
        for (; j > 0 && area[j - 1] > cand[i].area_px; j--)
            area[j] = area[j - 1];
        area[j] = cand[i].area_px;
    }
    const float amed = nc ? area[nc / 2] : 0.0f;
    for (int i = 0; i < nc; i++) {
        const fv_eye_glint gl = cand[i];
        if (nc >= 3 && gl.area_px > fmaxf(3.0f * amed, 12.0f))
            continue;
        const float dd = hypotf(gl.x - pp->x, gl.y - pp->y);
        /* insertion by distance to the pupil centre */
        int j = n < FV_EYE_MAX_GLINTS ? n++ : n - 1;
        if (j == FV_EYE_MAX_GLINTS - 1 && n == FV_EYE_MAX_GLINTS && hypotf(g[j].x - pp->x, g[j].y - pp->y) <= dd &&
            j > 0)
            continue; /* full, and farther than all kept */
        while (j > 0 && hypotf(g[j - 1].x - pp->x, g[j - 1].y - pp->y) > dd) {
            g[j] = g[j - 1];
            j--;
        }
        g[j] = gl;
    }
    return fv_mini(n, max_glints);
}

/* The median of the 24 pixels of the square ring 3 px around q (insertion sort). */
static int ring3_median(const uint8_t *q, ptrdiff_t stride)
{
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
    return (ring[11] + ring[12] + 1) / 2;
}

static inline int local_max3(const uint8_t *q, ptrdiff_t stride)
{
    const int v = q[0];
    return !(v < q[-1] || v < q[1] || v < q[-stride] || v < q[stride] || v < q[-stride - 1] || v < q[-stride + 1] ||
             v < q[stride - 1] || v < q[stride + 1]);
}

/* The most prominent small reflection within r of (cx, cy) in a small crop: a 3x3 local maximum
 * at least min_grey grey levels above the median of the square ring 3 px around it (weaker and
 * smaller than what find_glints accepts: at these sizes the reflection is a few pixels of
 * a blurred spot). 1 and its pixel centre, or 0. */
int fv_et_bright_spot(const uint8_t *img, int w, int h, ptrdiff_t stride, float cx, float cy, float r,
                      int min_grey, float *ox, float *oy)
{
    const int x0 = fv_maxi(3, (int)floorf(cx - r)), x1 = fv_mini(w - 4, (int)floorf(cx + r));
    const int y0 = fv_maxi(3, (int)floorf(cy - r)), y1 = fv_mini(h - 4, (int)floorf(cy + r));
    int best = min_grey - 1, bx = -1, by = -1;
    for (int y = y0; y <= y1; y++)
        for (int x = x0; x <= x1; x++) {
            const uint8_t *q = img + y * stride + x;
            if (q[0] - best <= 0 || !local_max3(q, stride))
                continue;
            const int con = q[0] - ring3_median(q, stride);
            if (con > best)
                best = con, bx = x, by = y;
        }
    if (bx < 0)
        return 0;
    *ox = bx + 0.5f, *oy = by + 0.5f;
    return 1;
}

int fv_et_dark_spots(const uint8_t *img, int w, int h, ptrdiff_t stride, float cx, float cy, float r, int min_grey,
                     int max_ring_grey, int max_n, int *xs, int *ys)
{
    const int x0 = fv_maxi(3, (int)floorf(cx - r)), x1 = fv_mini(w - 4, (int)floorf(cx + r));
    const int y0 = fv_maxi(3, (int)floorf(cy - r)), y1 = fv_mini(h - 4, (int)floorf(cy + r));
    int n = 0;
    for (int y = y0; y <= y1 && n < max_n; y++)
        for (int x = x0; x <= x1 && n < max_n; x++) {
            const uint8_t *q = img + y * stride + x;
            if (q[0] < min_grey || !local_max3(q, stride))
                continue;
            const int ring = ring3_median(q, stride);
            if (q[0] - ring >= min_grey && ring <= max_ring_grey)
                xs[n] = x, ys[n] = y, n++;
        }
    return n;
}
