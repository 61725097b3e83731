/* fovea: anti-aliasing in the fovea (reproject.h, fv_taa_aa_*): the fully sampled tiles' rays
 * go through a different point of their pixels every frame (fv_sampling_jitter) and each pixel
 * accumulates them in its history, so a still view converges to the pixel's box-filtered
 * value. It runs on the fovea's tiles only (about 140 of 7200 at 1280x1440). fv_taa_aa_tile_c below
 * is the plain-C reference of the dsp table's taa_aa (reproject_dsp.h); the SIMD versions share
 * core/reproject_aa_tmpl.h.
 *
 * Per pixel of an AA tile (every pixel has this frame's sample s, depth d):
 *   1. The pixel centre's place in the previous frame: the sample's world point (its ray through
 *      (x + ox, y + oy) at depth d) projected into the previous camera, moved back by the jitter
 *      (ox - 1/2, oy - 1/2) (exact for a translation of the image; with the head still, the
 *      centre itself).
 *   2. Disocclusion: the history counts only if one of the 3x3 history texels around that place
 *      has a depth within the reprojection's tolerance of the sample's previous view depth. Not a
 *      per-texel depth weight as in the periphery's blend: a jittered pixel on an edge holds
 *      either surface's depth from frame to frame, and per-texel rejection would drop exactly
 *      the edges' history.
 *   3. History h: a bilinear tap of level 0 weighted by the texels' confidence (with the head
 *      moving and the 4x4 texels around all real samples: Catmull-Rom instead, whose sharpness
 *      keeps the per-frame resampling from blurring the accumulated image), clamped to the
 *      min / max of this frame's samples in the pixel's 3x3 neighbourhood inside the tile (the
 *      usual rectification: what the history holds beyond what the neighbourhood shows now is
 *      a ghost or a disocclusion). Only the tile's own samples: a neighbour tile may not be
 *      traced yet, and reading it would make the image depend on the thread count.
 *   4. Weight: n = the history's sample count at the nearest texel (0 without history) + 1,
 *      capped at FV_TAA_AA_MAX_N; out = h + (s - h) / n. A still view is the plain mean of its
 *      first FV_TAA_AA_MAX_N jittered samples, then an exponential window of that length.
 * The depth stays the sample's. Counts live in a plane of their own (one byte a pixel, two per
 * eye, swapped with the pyramids); every other tile writes 0 there, so a pixel that joins the
 * fovea starts afresh from its first jittered sample (today's behaviour) and counts never go
 * stale. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "reproject.h"
#include "reproject_dsp.h"
#include "sampling.h"

int fv_taa_aa_tile_eligible(const struct fv_sampler *smp, int gx, int gy, int x0, int y0, int tw, int th,
                            const uint32_t *rows)
{
    const uint32_t full = tw >= 32 ? ~0u : (1u << tw) - 1u;
    for (int y = 0; y < th; y++)
        if ((rows[y] & full) != full)
            return 0;
    /* every pixel sampled every frame: the acuity model's probability 1 at the pixel centres of
     * the tile's corners (the region is a disc around the gaze, so convex) */
    const float xs[2] = {(float)x0 + 0.5f - (float)gx, (float)(x0 + tw - 1) + 0.5f - (float)gx};
    const float ys[2] = {(float)y0 + 0.5f - (float)gy, (float)(y0 + th - 1) + 0.5f - (float)gy};
    for (int i = 0; i < 2; i++)
        for (int k = 0; k < 2; k++)
            if (!(fv_sampler_probability(smp, xs[i], ys[k]) >= 1.0f))
                return 0;
    return 1;
}

int fv_taa_aa_snapshot(fv_taa_aa_frame *a, const fv_pyr_level *h0, const struct fv_sampler *smp, int gx, int gy,
                       int tile, float **buf, size_t *cap)
{
    a->h_rgbd = a->h_wgt = NULL;
    const int w = h0->w, h = h0->h, tx_n = (w + tile - 1) / tile, ty_n = (h + tile - 1) / tile;
    /* Weier's model samples every pixel only inside r1 (p_min < 1): scan the tiles near it;
     * otherwise (Liu's tables, p_min 1) every tile */
    int tx_a = 0, tx_b = tx_n - 1, ty_a = 0, ty_b = ty_n - 1;
    if (smp->prm.kind != FV_SAMPLER_LIU && smp->prm.p_min < 1.0f && !smp->prm.full) {
        const int R = (int)ceilf(smp->r1_px) + 1;
        tx_a = (gx - R) / tile - 1, tx_b = (gx + R) / tile + 1, ty_a = (gy - R) / tile - 1, ty_b = (gy + R) / tile + 1;
        tx_a = tx_a < 0 ? 0 : tx_a, ty_a = ty_a < 0 ? 0 : ty_a;
        tx_b = tx_b < tx_n - 1 ? tx_b : tx_n - 1, ty_b = ty_b < ty_n - 1 ? ty_b : ty_n - 1;
    }
    int xa = w, xb = -1, ya = h, yb = -1; /* the candidates' pixel box */
    for (int ty = ty_a; ty <= ty_b; ty++)
        for (int tx = tx_a; tx <= tx_b; tx++) {
            const int x0 = tx * tile, y0 = ty * tile;
            const int tw = w - x0 < tile ? w - x0 : tile, th = h - y0 < tile ? h - y0 : tile;
            const float xs[2] = {(float)x0 + 0.5f - (float)gx, (float)(x0 + tw - 1) + 0.5f - (float)gx};
            const float ys[2] = {(float)y0 + 0.5f - (float)gy, (float)(y0 + th - 1) + 0.5f - (float)gy};
            int full = 1;
            for (int i = 0; i < 2 && full; i++)
                for (int k = 0; k < 2 && full; k++)
                    full = fv_sampler_probability(smp, xs[i], ys[k]) >= 1.0f;
            if (!full)
                continue;
            xa = x0 < xa ? x0 : xa, ya = y0 < ya ? y0 : ya;
            xb = x0 + tw - 1 > xb ? x0 + tw - 1 : xb, yb = y0 + th - 1 > yb ? y0 + th - 1 : yb;
        }
    if (xb < xa)
        return 0; /* no tile can take the AA: nothing reads the history's level 0 there */
    /* the ring the AA reads (3x3 around each pixel's place), within the level's border */
    xa = xa - 1 < -1 ? -1 : xa - 1, ya = ya - 1 < -1 ? -1 : ya - 1;
    xb = xb + 1 > w ? w : xb + 1, yb = yb + 1 > h ? h : yb + 1;
    const int bw = xb - xa + 1, bh = yb - ya + 1;
    const size_t need = (size_t)bw * (size_t)bh * 5;
    if (need > *cap) {
        float *nb = realloc(*buf, need * sizeof(float));
        if (!nb)
            return -1;
        *buf = nb, *cap = need;
    }
    float *rgbd = *buf, *wg = *buf + (size_t)bw * (size_t)bh * 4;
    for (int y = ya; y <= yb; y++) {
        const ptrdiff_t o = (ptrdiff_t)y * h0->stride + xa, r = (ptrdiff_t)(y - ya) * bw;
        memcpy(rgbd + 4 * r, h0->rgbd + 4 * o, (size_t)bw * 4 * sizeof(float));
        memcpy(wg + r, h0->wgt + o, (size_t)bw * sizeof(float));
    }
    a->h_rgbd = rgbd, a->h_wgt = wg, a->h_stride = bw, a->h_x0 = xa, a->h_y0 = ya;
    return 0;
}

void fv_taa_aa_clear(const fv_taa_aa_frame *a, int x0, int y0, int tw, int th)
{
    for (int y = 0; y < th; y++)
        memset(a->n_cur + (ptrdiff_t)(y0 + y) * a->stride + x0, 0, (size_t)tw);
}

static inline float minf(float a, float b) { return a < b ? a : b; }
static inline float maxf(float a, float b) { return a > b ? a : b; }

/* Catmull-Rom resampling of level 0 at texels i0-1 .. i0+2, j0-1 .. j0+2 (fractions fx, fy), into
 * h when all 16 texels have weight 1 (else h stays). */
static void catmull_rom(const fv_pyr_level *H, int i0, int j0, float fx, float fy, float h[3])
{
    float wx[4], wy[4];
    const float t[2] = {fx, fy};
    float *w[2] = {wx, wy};
    for (int k = 0; k < 2; k++) {
        const float q = t[k];
        w[k][0] = q * (-0.5f + q * (1.0f - 0.5f * q));
        w[k][1] = 1.0f + q * q * (-2.5f + 1.5f * q);
        w[k][2] = q * (0.5f + q * (2.0f - 1.5f * q));
        w[k][3] = q * q * (-0.5f + 0.5f * q);
    }
    /* the weights first (any hole: no Catmull-Rom), then the sums in scalars: an array kept them
     * in memory, each += a store-to-load round trip (the same additions in the same order) */
    for (int j = 0; j < 4; j++) {
        const float *wr = H->wgt + (ptrdiff_t)(j0 - 1 + j) * H->stride + i0 - 1;
        if (wr[0] != 1.0f || wr[1] != 1.0f || wr[2] != 1.0f || wr[3] != 1.0f)
            return;
    }
    float a0 = 0.0f, a1 = 0.0f, a2 = 0.0f;
    for (int j = 0; j < 4; j++) {
        const float *r = H->rgbd + 4 * ((ptrdiff_t)(j0 - 1 + j) * H->stride + i0 - 1);
        for (int i = 0; i < 4; i++) {
            const float ww = wx[i] * wy[j];
            a0 += ww * r[4 * i];
            a1 += ww * r[4 * i + 1];
            a2 += ww * r[4 * i + 2];
        }
    }
    h[0] = a0, h[1] = a1, h[2] = a2;
}

void fv_taa_aa_tile_c(const fv_taa_frame *f, const fv_taa_aa_frame *a, const fv_pyr_level *l0, int x0, int y0, int tw,
                    int th)
{
    enum { T = 16 };
    /* the tile's samples before any is changed: the neighbourhoods read this frame's samples only */
    float s[T][T][4];
    for (int y = 0; y < th; y++)
        memcpy(s[y], l0->rgbd + 4 * ((ptrdiff_t)(y0 + y) * l0->stride + x0), (size_t)tw * 4 * sizeof(float));
    const int hist = f && a->n_prev;
    const fv_pyr_level *H = hist ? &f->hist->lv[0] : NULL;
    /* the history's level 0 as read below: the pyramid, or the still head's snapshot */
    const float *Hrgbd = H ? H->rgbd : NULL, *Hw = H ? H->wgt : NULL;
    ptrdiff_t Hs = H ? H->stride : 0;
    int hx0 = 0, hy0 = 0;
    if (hist && a->h_rgbd) {
        Hrgbd = a->h_rgbd, Hw = a->h_wgt, Hs = a->h_stride, hx0 = a->h_x0, hy0 = a->h_y0;
    }
    const float jx = a->ox - 0.5f, jy = a->oy - 0.5f;
    for (int y = 0; y < th; y++) {
        uint8_t *ncur = a->n_cur + (ptrdiff_t)(y0 + y) * a->stride + x0;
        for (int x = 0; x < tw; x++) {
            float *px = l0->rgbd + 4 * ((ptrdiff_t)(y0 + y) * l0->stride + x0 + x);
            int n = 0;
            float h[3] = {0.0f, 0.0f, 0.0f};
            if (hist) {
                const float d = s[y][x][3];
                float u, v, z;
                if (f->identity) {
                    u = (float)(x0 + x) + 0.5f;
                    v = (float)(y0 + y) + 0.5f;
                    z = d;
                } else {
                    z = fv_taa_project(f, (float)(x0 + x) + a->ox, (float)(y0 + y) + a->oy, d, &u, &v);
                    u -= jx;
                    v -= jy;
                }
                if (z > 1e-4f && u >= 0.0f && u < f->prev_w && v >= 0.0f && v < f->prev_h) {
                    /* 2. some history texel near the place is on the sample's surface */
                    const int ni = (int)u, nj = (int)v; /* u, v >= 0: truncation is floor */
                    const float tol = z / f->inv_depth_tol;
                    int near = 0;
                    for (int j = nj - 1; j <= nj + 1 && !near; j++)
                        for (int i = ni - 1; i <= ni + 1; i++) {
                            const ptrdiff_t o = (ptrdiff_t)(j - hy0) * Hs + (i - hx0);
                            if (Hw[o] > 0.0f && fabsf(Hrgbd[4 * o + 3] - z) <= tol) {
                                near = 1;
                                break;
                            }
                        }
                    /* 3. bilinear history, weighted by confidence */
                    const float sx = u - 0.5f, sy = v - 0.5f, fx0 = floorf(sx), fy0 = floorf(sy);
                    const int i0 = (int)fx0, j0 = (int)fy0;
                    const float fx = sx - fx0, fy = sy - fy0;
                    const float b[4] = {(1.0f - fx) * (1.0f - fy), fx * (1.0f - fy), (1.0f - fx) * fy, fx * fy};
                    float acc[3] = {0.0f, 0.0f, 0.0f}, accw = 0.0f; /* the sums in scalars (as above) */
                    for (int k = 0; k < 4; k++) {
                        const ptrdiff_t o = (ptrdiff_t)(j0 + (k >> 1) - hy0) * Hs + i0 + (k & 1) - hx0;
                        const float w = b[k] * Hw[o];
                        acc[0] += w * Hrgbd[4 * o];
                        acc[1] += w * Hrgbd[4 * o + 1];
                        acc[2] += w * Hrgbd[4 * o + 2];
                        accw += w;
                    }
                    if (near && accw > 1e-6f) {
                        n = a->n_prev[(ptrdiff_t)(int)v * a->stride + (int)u];
                        for (int c = 0; c < 3; c++)
                            h[c] = acc[c] / accw;
                        /* moving: Catmull-Rom over the 4x4 texels where all are real samples
                         * inside the image (the fovea's history), sharper than the bilinear
                         * tap, whose blur compounds frame after frame; the clamp below takes
                         * its overshoot */
                        if (!f->identity && !a->h_rgbd && i0 >= 1 && j0 >= 1 && (float)(i0 + 2) < f->prev_w &&
                            (float)(j0 + 2) < f->prev_h)
                            catmull_rom(H, i0, j0, fx, fy, h);
                    }
                }
            }
            n = n + 1 < FV_TAA_AA_MAX_N ? n + 1 : FV_TAA_AA_MAX_N;
            ncur[x] = (uint8_t)n;
            if (n == 1)
                continue; /* no history: the sample as traced */
            const float alpha = 1.0f / (float)n;
            if (f->identity) { /* head still, scene static: the history is exact, nothing to rectify */
                for (int c = 0; c < 3; c++)
                    px[c] = h[c] + alpha * (s[y][x][c] - h[c]);
                continue;
            }
            /* rectification: the 3x3 neighbourhood of this frame's samples, inside the tile */
            /* in scalars: arrays were kept in memory, a store-to-load round trip per min / max */
            float lo0 = s[y][x][0], lo1 = s[y][x][1], lo2 = s[y][x][2], hi0 = lo0, hi1 = lo1, hi2 = lo2;
            for (int j = y > 0 ? y - 1 : 0; j <= (y + 1 < th ? y + 1 : th - 1); j++)
                for (int i = x > 0 ? x - 1 : 0; i <= (x + 1 < tw ? x + 1 : tw - 1); i++) {
                    const float *q = s[j][i];
                    lo0 = minf(lo0, q[0]), lo1 = minf(lo1, q[1]), lo2 = minf(lo2, q[2]);
                    hi0 = maxf(hi0, q[0]), hi1 = maxf(hi1, q[1]), hi2 = maxf(hi2, q[2]);
                }
            const float lo[3] = {lo0, lo1, lo2}, hi[3] = {hi0, hi1, hi2};
            for (int c = 0; c < 3; c++) {
                const float hc = minf(maxf(h[c], lo[c]), hi[c]);
                px[c] = hc + alpha * (s[y][x][c] - hc);
            }
        }
    }
}
