/* fovea: timewarp set-up (the kernel: timewarp_dsp.h, timewarp_ref.c). */
#include "timewarp.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "metrics.h"
#include "pipeline.h"
#include "reproject.h"

void fv_tw_setup(fv_tw_map *m, const fv_camera *display, const fv_camera *source, float tol)
{
    /* the reprojection's mapping (fv_taa_frame_setup, core/reproject.c) from the current camera
     * to the previous one is exactly this: source (U, V, Z) = z_d (M0 + px MX + py MY) + T for
     * display pixel coordinates (px, py) at display depth z_d; its history pyramid is not read
     * beyond its level count */
    fv_pyramid none;
    memset(&none, 0, sizeof none);
    none.levels = 1;
    fv_taa_frame f;
    fv_taa_frame_setup(&f, display, source, &none, 0.03f);
    memset(m, 0, sizeof *m);
    for (int k = 0; k < 3; k++) {
        m->a0[k] = f.M0[k];
        m->ax[k] = f.MX[k];
        m->ay[k] = f.MY[k];
        m->t[k] = f.T[k];
    }
    m->tol = tol;
    m->w_scale = 1.0f / FV_TW_INVD_PER_M;
}

void fv_tw_map_set_lens(fv_tw_map *m, const fv_lens_map *l) { m->lens = l; }

void fv_tw_cell_map(const fv_tw_map *m, const fv_tw_src *src, int X0, int X1, int Y0, int Y1, fv_tw_map *out)
{
    *out = *m;
    out->lens = NULL;
    /* F at the centre; F^-1 where the centre lands at the depth the source shows there (two of the
     * kernel's fixed-point steps through the exact lens) */
    const float p0x = 0.5f * (float)(X0 + X1), p0y = 0.5f * (float)(Y0 + Y1);
    float qx, qy;
    fv_lens_map_fwd(m->lens, p0x, p0y, &qx, &qy);
    const float A[3] = {(m->a0[0] + qy * m->ay[0]) + qx * m->ax[0], (m->a0[1] + qy * m->ay[1]) + qx * m->ax[1],
                        (m->a0[2] + qy * m->ay[2]) + qx * m->ax[2]};
    float w = 0.0f;
    for (int it = 0; it < 2; it++) {
        float u, v;
        fv_tw_proj(A, m->t, w, &u, &v);
        fv_lens_map_inv(m->lens, u, v, &u, &v);
        w = fv_tw_fetch_w(m, src, A[2], u, v);
    }
    fv_lens_map_fold(m->lens, m->t, m->a0, m->ax, m->ay, p0x, p0y, w, out->t, out->a0, out->ax, out->ay);
}

void fv_tw_pack_invd(uint16_t *dst, ptrdiff_t dst_stride, const float *rgbd, ptrdiff_t rgbd_stride, int w, int h)
{
    for (int y = 0; y < h; y++) {
        const float *s = rgbd + (ptrdiff_t)y * rgbd_stride;
        uint16_t *o = dst + (ptrdiff_t)y * dst_stride;
        for (int x = 0; x < w; x++) {
            const float z = s[4 * x + 3];
            const float q = z > 0.0f ? FV_TW_INVD_PER_M / z + 0.5f : 65535.0f; /* NaN, <= 0: nearest */
            o[x] = (uint16_t)(q < 65535.0f ? q : 65535.0f);
        }
    }
}

long fv_tw_warp_rows_pixel(const fv_timewarp_dsp *d, uint8_t *dst, ptrdiff_t dst_stride, int y0, int y1,
                           const fv_tw_map *m, const fv_tw_src *src)
{
    long holes = 0;
    if (m->lens) { /* each cell with its map */
        const int C = FV_TW_LENS_CELL;
        for (int cy = y0 / C * C; cy < y1; cy += C)
            for (int cx = 0; cx < src->w; cx += C) {
                const int x1 = cx + C < src->w ? cx + C : src->w, ya = cy > y0 ? cy : y0;
                const int yb = cy + C < y1 ? cy + C : y1;
                fv_tw_map cm;
                fv_tw_cell_map(m, src, cx, x1, cy, cy + C < src->h ? cy + C : src->h, &cm);
                for (int y = ya; y < yb; y++)
                    holes += d->tw_row(dst + (ptrdiff_t)y * dst_stride + 3 * cx, cx, y, x1 - cx, &cm, src);
            }
        return holes;
    }
    for (int y = y0; y < y1; y++)
        holes += d->tw_row(dst + (ptrdiff_t)y * dst_stride, 0, y, src->w, m, src);
    return holes;
}

static inline float minf(float a, float b) { return a < b ? a : b; }
static inline float maxf(float a, float b) { return a > b ? a : b; }
static inline int mini(int a, int b) { return a < b ? a : b; }
/* the reference's nearest-pixel index of a coordinate (fv_tw_fetch_w) */
static inline int tw_index(float u, int n) { return (int)fv_tw_clampf(u, (float)(n - 1)); }

void fv_tw_tiles_build(const fv_timewarp_dsp *d, fv_tw_tiles *t, const fv_tw_src *src)
{
    const int T = FV_TW_TILE;
    t->tw = (src->w + T - 1) / T, t->th = (src->h + T - 1) / T;
    for (int ty = 0; ty < t->th; ty++)
        for (int tx = 0; tx < t->tw; tx++) {
            unsigned mm[2];
            d->tw_minmax(src->invd + (ptrdiff_t)ty * T * src->invd_stride + tx * T, src->invd_stride,
                         mini(T, src->w - tx * T), mini(T, src->h - ty * T), mm);
            t->lohi[2 * ((size_t)ty * t->tw + tx)] = (uint16_t)mm[0];
            t->lohi[2 * ((size_t)ty * t->tw + tx) + 1] = (uint16_t)mm[1];
        }
    t->tw4 = (t->tw + 3) / 4, t->th4 = (t->th + 3) / 4;
    for (int ty = 0; ty < t->th4; ty++)
        for (int tx = 0; tx < t->tw4; tx++) {
            unsigned lo = 65535, hi = 0;
            for (int j = 4 * ty; j < 4 * ty + 4 && j < t->th; j++)
                for (int i = 4 * tx; i < 4 * tx + 4 && i < t->tw; i++) {
                    const uint16_t *e = t->lohi + 2 * ((size_t)j * t->tw + i);
                    lo = e[0] < lo ? e[0] : lo, hi = e[1] > hi ? e[1] : hi;
                }
            t->lohi4[2 * ((size_t)ty * t->tw4 + tx)] = (uint16_t)lo;
            t->lohi4[2 * ((size_t)ty * t->tw4 + tx) + 1] = (uint16_t)hi;
        }
}

/* the least and greatest depth code over source pixels [ix0, ix1] x [iy0, iy1] (or a superset) */
static void depth_range(const fv_timewarp_dsp *d, const fv_tw_src *s, const fv_tw_tiles *tiles, int ix0, int ix1,
                        int iy0, int iy1, unsigned mm[2])
{
    if (!tiles) {
        d->tw_minmax(s->invd + (ptrdiff_t)iy0 * s->invd_stride + ix0, s->invd_stride, ix1 - ix0 + 1, iy1 - iy0 + 1, mm);
        return;
    }
    /* a footprint wider than 6 tiles reads the coarse level (a superset: fewer reads) */
    const int T = ix1 - ix0 > 6 * FV_TW_TILE || iy1 - iy0 > 6 * FV_TW_TILE ? 4 * FV_TW_TILE : FV_TW_TILE;
    const uint16_t *l = T == FV_TW_TILE ? tiles->lohi : tiles->lohi4;
    const int tw = T == FV_TW_TILE ? tiles->tw : tiles->tw4;
    unsigned lo = 65535, hi = 0;
    for (int ty = iy0 / T; ty <= iy1 / T; ty++) {
        const uint16_t *r = l + 2 * (size_t)ty * tw;
        for (int tx = ix0 / T; tx <= ix1 / T; tx++) {
            lo = r[2 * tx] < lo ? r[2 * tx] : lo;
            hi = r[2 * tx + 1] > hi ? r[2 * tx + 1] : hi;
        }
    }
    mm[0] = lo, mm[1] = hi;
}

/* Row translations in fixed point: 1/64 px with 16 more bits, offset by a multiple of 2^22 that
 * keeps them positive (shifts of negatives are the compiler's choice in C) */
#define TW_QBIAS (FV_TW_RUN_BIAS << 22)
static inline void row_offsets(int64_t qu, int64_t qv, int *ox, int *oy, int *fx, int *fy)
{
    const int64_t u = (qu + TW_QBIAS + 32768) >> 16, v = (qv + TW_QBIAS + 32768) >> 16; /* 1/64 px, rounded */
    *ox = (int)(u >> 6) - (int)(TW_QBIAS >> 22), *oy = (int)(v >> 6) - (int)(TW_QBIAS >> 22);
    *fx = (int)(u & 63), *fy = (int)(v & 63);
}

/* b's rows from its first and last row's translation (u0, v0, u1, v1): the fixed-point start and
 * step, fast, inner. 0 when they are not finite. */
static int block_rows(fv_tw_block *b, const fv_tw_src *s)
{
    const int X0 = b->x0, X1 = b->x1, Y0 = b->y0, Y1 = b->y1;
    if (!(fabsf(b->u0) < 1e6f && fabsf(b->v0) < 1e6f && fabsf(b->u1) < 1e6f && fabsf(b->v1) < 1e6f))
        return 0;
    /* the rows' translations in 1/64 px with 16 more bits, stepped per row (no float per row) */
    const double rows = Y1 - Y0 > 1 ? (double)(Y1 - Y0 - 1) : 1.0, k = 64.0 * 65536.0;
    b->qu = (int64_t)((double)b->u0 * k + (b->u0 < 0 ? -0.5 : 0.5));
    b->qv = (int64_t)((double)b->v0 * k + (b->v0 < 0 ? -0.5 : 0.5));
    const double su = ((double)b->u1 - b->u0) / rows * k, sv = ((double)b->v1 - b->v0) / rows * k;
    b->dqu = (int64_t)(su + (su < 0 ? -0.5 : 0.5)), b->dqv = (int64_t)(sv + (sv < 0 ? -0.5 : 0.5));
    b->fast = 1;
    /* inner: no row clamps (fv_tw_warp_rows' block_row). The rows' offsets are roundings of a
     * linear function of y, so the source rows y + oy and columns x + ox are monotonic in y:
     * the first and the last row bound them all. */
    int ox0, oy0, ox1, oy1, f0, f1;
    row_offsets(b->qu, b->qv, &ox0, &oy0, &f0, &f1);
    row_offsets(b->qu + (int64_t)(Y1 - 1 - Y0) * b->dqu, b->qv + (int64_t)(Y1 - 1 - Y0) * b->dqv, &ox1, &oy1, &f0, &f1);
    const int sy0 = Y0 + oy0, sy1 = Y1 - 1 + oy1;
    b->inner = (sy0 < sy1 ? sy0 : sy1) >= 0 && (sy0 > sy1 ? sy0 : sy1) <= s->h - 2 && X0 + (ox0 < ox1 ? ox0 : ox1) >= 0 &&
               X1 + (ox0 > ox1 ? ox0 : ox1) <= s->w - 1;
    return 1;
}

/* one block (the proof: timewarp.h); 1 when translated */
static int plan_block(const fv_timewarp_dsp *d, const fv_tw_map *m, const fv_tw_src *s, const fv_tw_tiles *tiles,
                      int X0, int X1, int Y0, int Y1, float *guess, fv_tw_block *b)
{
    memset(b, 0, sizeof *b);
    b->x0 = X0, b->x1 = X1, b->y0 = Y0, b->y1 = Y1;
    const float cx[4] = {(float)X0 + 0.5f, (float)X1 - 0.5f, (float)X0 + 0.5f, (float)X1 - 0.5f};
    const float cy[4] = {(float)Y0 + 0.5f, (float)Y0 + 0.5f, (float)Y1 - 0.5f, (float)Y1 - 0.5f};
    float A[3][4];
    for (int j = 0; j < 3; j++)
        for (int k = 0; k < 4; k++)
            A[j][k] = (m->a0[j] + cy[k] * m->ay[j]) + cx[k] * m->ax[j]; /* the reference's order */
    const float *t = m->t, eps = 1.0f / 64.0f; /* eps: float rounding of a projection, px */
    float G = *guess, lo = 0.0f, hi = 0.0f;
    for (int it = 0;; it++) {
        if (it == 3)
            return 0;
        float umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY, zmin = INFINITY;
        for (int e = 0; e < 2; e++) {
            const float w = e ? G : 0.0f;
            for (int k = 0; k < 4; k++) {
                const float nz = A[2][k] + t[2] * w, r = 1.0f / nz;
                const float u = (A[0][k] + t[0] * w) * r, v = (A[1][k] + t[1] * w) * r;
                umin = minf(umin, u), umax = maxf(umax, u), vmin = minf(vmin, v), vmax = maxf(vmax, v);
                zmin = minf(zmin, nz);
            }
        }
        if (!(zmin > 2.0f * FV_TW_ZMIN)) /* behind the eye (or NaN): no clamp-free proof */
            return 0;
        if (!(umax - umin < 4096.0f && vmax - vmin < 4096.0f))
            return 0;
        unsigned mm[2];
        depth_range(d, s, tiles, tw_index(umin - eps, s->w), tw_index(umax + eps, s->w), tw_index(vmin - eps, s->h),
                    tw_index(vmax + eps, s->h), mm);
        const float wl = (float)mm[0] * m->w_scale, wh = (float)mm[1] * m->w_scale;
        const float dl = 1.0f - t[2] * wl, dh = 1.0f - t[2] * wh;
        if (!(dl > FV_TW_DEN_MIN && dh > FV_TW_DEN_MIN)) /* the conversion's floor: not monotonic there */
            return 0;
        const float azmin = minf(minf(A[2][0], A[2][1]), minf(A[2][2], A[2][3]));
        const float azmax = maxf(maxf(A[2][0], A[2][1]), maxf(A[2][2], A[2][3]));
        /* w_d = A_z w_s / den: increasing in w_s, linear in A_z > 0 */
        lo = (azmin * wl) / dl * (1.0f - 1e-5f), hi = (azmax * wh) / dh * (1.0f + 1e-5f); /* + the interior's rounding */
        if (hi <= G)
            break;
        G = hi * 1.0625f;
    }
    *guess = hi * 1.0625f;
    /* the offsets q(c, w) - c at the corners for w = lo, hi: ranges along the top edge (k = 0, 1)
     * and the bottom edge (k = 2, 3) */
    float fu[2][2] = {{INFINITY, -INFINITY}, {INFINITY, -INFINITY}}, fv[2][2] = {{INFINITY, -INFINITY}, {INFINITY, -INFINITY}};
    float qu = 0, qv = 0, dmin = INFINITY;
    for (int e = 0; e < 2; e++) {
        const float w = e ? hi : lo;
        for (int k = 0; k < 4; k++) {
            const float nz = A[2][k] + t[2] * w, r = 1.0f / nz; /* > 0: w in [0, G] */
            const float u = (A[0][k] + t[0] * w) * r, v = (A[1][k] + t[1] * w) * r;
            const int edge = k >> 1;
            fu[edge][0] = minf(fu[edge][0], u - cx[k]), fu[edge][1] = maxf(fu[edge][1], u - cx[k]);
            fv[edge][0] = minf(fv[edge][0], v - cy[k]), fv[edge][1] = maxf(fv[edge][1], v - cy[k]);
            qu = maxf(qu, fabsf(u)), qv = maxf(qv, fabsf(v)), dmin = minf(dmin, nz);
        }
    }
    /* the homography's curvature: bilinear interpolation of the corners is off by at most
     * hx^2 / 8 |q_xx| + hy^2 / 8 |q_yy| */
    const float hx = (float)(X1 - X0 - 1), hy = (float)(Y1 - Y0 - 1), d2 = dmin * dmin;
    const float ax2 = fabsf(m->ax[2]), ay2 = fabsf(m->ay[2]);
    const float cu = hx * hx / 8.0f * 2.0f * ax2 * (fabsf(m->ax[0]) + qu * ax2) / d2 +
                     hy * hy / 8.0f * 2.0f * ay2 * (fabsf(m->ay[0]) + qu * ay2) / d2;
    const float cv = hx * hx / 8.0f * 2.0f * ax2 * (fabsf(m->ax[1]) + qv * ax2) / d2 +
                     hy * hy / 8.0f * 2.0f * ay2 * (fabsf(m->ay[1]) + qv * ay2) / d2;
    /* a row's translation interpolates the edges' middles, so a pixel is off by at most the
     * larger half spread of the two edges (in between: their blend) */
    const float eu = maxf(fu[0][1] - fu[0][0], fu[1][1] - fu[1][0]) * 0.5f + cu;
    const float ev = maxf(fv[0][1] - fv[0][0], fv[1][1] - fv[1][0]) * 0.5f + cv;
    const float err = maxf(eu, ev) + 1.0f / 128.0f; /* + a row's rounding to 1/64 */
    b->err_px = err;
    if (!(err + 1e-3f <= FV_TW_BLOCK_POS_PX)) /* 1e-3: this computation's own rounding */
        return 0;
    b->u0 = (fu[0][0] + fu[0][1]) * 0.5f, b->v0 = (fv[0][0] + fv[0][1]) * 0.5f;
    b->u1 = (fu[1][0] + fu[1][1]) * 0.5f, b->v1 = (fv[1][0] + fv[1][1]) * 0.5f;
    return block_rows(b, s);
}

void fv_tw_block_row(const fv_tw_block *b, int y, int *ox, int *oy, int *fx, int *fy)
{
    row_offsets(b->qu + (int64_t)(y - b->y0) * b->dqu, b->qv + (int64_t)(y - b->y0) * b->dqv, ox, oy, fx, fy);
}

/* a block, else its quarters (halves where a side is down to FV_TW_BLOCK_MIN), depth first:
 * the entries that cover a row come in column order; returns the entries written. A block
 * whose bound is more than its side / FV_TW_BLOCK_MIN times too large is not cut: halving the
 * side halves the spread of a smooth mapping, so even its smallest parts would fail (a frame
 * warped far: planning 85 parts a block would cost more than the per-pixel warp saves). */
static int plan_split(const fv_timewarp_dsp *d, const fv_tw_map *m, const fv_tw_src *src, const fv_tw_tiles *tiles,
                      int X0, int X1, int Y0, int Y1, float *guess, fv_tw_block *out, int MIN)
{
    const int side = X1 - X0 > Y1 - Y0 ? X1 - X0 : Y1 - Y0;
    if (plan_block(d, m, src, tiles, X0, X1, Y0, Y1, guess, out) || side <= MIN ||
        out->err_px > FV_TW_BLOCK_POS_PX * (float)side / (float)MIN)
        return 1;
    const int Xm = X1 - X0 > MIN ? X0 + (X1 - X0 + 1) / 2 : X1, Ym = Y1 - Y0 > MIN ? Y0 + (Y1 - Y0 + 1) / 2 : Y1;
    int n = plan_split(d, m, src, tiles, X0, Xm, Y0, Ym, guess, out, MIN);
    if (Xm < X1)
        n += plan_split(d, m, src, tiles, Xm, X1, Y0, Ym, guess, out + n, MIN);
    if (Ym < Y1) {
        n += plan_split(d, m, src, tiles, X0, Xm, Ym, Y1, guess, out + n, MIN);
        if (Xm < X1)
            n += plan_split(d, m, src, tiles, Xm, X1, Ym, Y1, guess, out + n, MIN);
    }
    return n;
}

/* A block, else its left and right halves, else each half's quarters (plan_split). Most of a
 * block's bound is the spread of the offsets along its rows (a turn's homography stretches rows;
 * the rows' blend of the top and bottom edges follows the vertical change), so halving the width
 * usually proves both halves: two plans instead of the quarters' four, and the same pieces a row. */
static int plan_halves(const fv_timewarp_dsp *d, const fv_tw_map *m, const fv_tw_src *src, const fv_tw_tiles *tiles,
                       int X0, int X1, int Y0, int Y1, float *guess, fv_tw_block *out, int MIN)
{
    const int side = X1 - X0 > Y1 - Y0 ? X1 - X0 : Y1 - Y0;
    if (X1 - X0 <= MIN || Y1 - Y0 <= MIN)
        return plan_split(d, m, src, tiles, X0, X1, Y0, Y1, guess, out, MIN);
    if (plan_block(d, m, src, tiles, X0, X1, Y0, Y1, guess, out) || out->err_px > FV_TW_BLOCK_POS_PX * (float)side / (float)MIN)
        return 1;
    const int Xm = X0 + (X1 - X0 + 1) / 2, Ym = Y0 + (Y1 - Y0 + 1) / 2;
    int n = 0;
    for (int h = 0; h < 2; h++) {
        const int xa = h ? Xm : X0, xb = h ? X1 : Xm;
        if (plan_block(d, m, src, tiles, xa, xb, Y0, Y1, guess, out + n)) {
            n++;
            continue;
        }
        n += plan_split(d, m, src, tiles, xa, xb, Y0, Ym, guess, out + n, MIN);
        n += plan_split(d, m, src, tiles, xa, xb, Ym, Y1, guess, out + n, MIN);
    }
    return n;
}

/* fv_tw_plan_blocks, and each entry's map in pmap: m, or with a lens its cell's, kept in cells
 * (at most nb (FV_TW_BLOCK_W / FV_TW_LENS_CELL)^2 of them) */
static int plan_blocks(const fv_timewarp_dsp *d, const fv_tw_map *m, const fv_tw_src *src, const fv_tw_tiles *tiles,
                       int by, int bx0, int nb, fv_tw_block *out, float *guess, fv_tw_map *cells,
                       const fv_tw_map **pmap, int min)
{
    const int BW = FV_TW_BLOCK_W, Y0 = by * FV_TW_BLOCK_H, Y1 = mini(Y0 + FV_TW_BLOCK_H, src->h);
    int n = 0, nc = 0;
    for (int i = 0; i < nb; i++) {
        const int X0 = (bx0 + i) * BW, X1 = mini(X0 + BW, src->w);
        if (X0 >= X1)
            break;
        if (!m->lens) {
            const int k = plan_halves(d, m, src, tiles, X0, X1, Y0, Y1, guess, out + n, min);
            for (int j = 0; j < k; j++)
                pmap[n + j] = m;
            n += k;
            continue;
        }
        /* the block's cells in rows, each planned on its own map: the entries covering a row
         * still come in column order */
        const int C = FV_TW_LENS_CELL;
        for (int cy = Y0; cy < Y1; cy += C)
            for (int cx = X0; cx < X1; cx += C) {
                const int cx1 = mini(cx + C, X1), cy1 = mini(cy + C, Y1);
                fv_tw_cell_map(m, src, cx, cx1, cy, cy1, &cells[nc]);
                const int k = plan_halves(d, &cells[nc], src, tiles, cx, cx1, cy, cy1, guess, out + n, min);
                for (int j = 0; j < k; j++)
                    pmap[n + j] = &cells[nc];
                n += k, nc++;
            }
    }
    return n;
}

enum { TW_CELLS = (FV_TW_BLOCK_W / FV_TW_LENS_CELL) * (FV_TW_BLOCK_H / FV_TW_LENS_CELL) };

int fv_tw_plan_blocks(const fv_timewarp_dsp *d, const fv_tw_map *m, const fv_tw_src *src, const fv_tw_tiles *tiles,
                      int by, int bx0, int nb, fv_tw_block *out, float *guess)
{
    enum { NB = 64 };
    fv_tw_map cells[TW_CELLS * NB];
    const fv_tw_map *pmap[FV_TW_BLOCK_SPLIT * NB];
    int n = 0;
    for (int i = 0; i < nb; i += NB) /* in groups that fit the arrays: the same entries as in one */
        n += plan_blocks(d, m, src, tiles, by, bx0 + i, mini(NB, nb - i), out + n, guess, cells, pmap, FV_TW_BLOCK_MIN);
    return n;
}

/* ---- the bounded warp's grid fallback (timewarp.h) ---- */

/* the reference's tap offsets (source minus display position) at n display points (px, py):
 * three fixed-point steps; where the last two disagree, the farther surface (the smaller inverse
 * depth). The points' steps go in lockstep, each depth prefetched a stage ahead (the fetches
 * miss the cache: a part's taps are scattered over the plane). 0 when a point lands behind the
 * source camera or off the float range. */
enum { TW_GRID_TAPS = (FV_TW_BLOCK_W / FV_TW_GRID_W + 1) * (FV_TW_BLOCK_H / FV_TW_GRID_H + 1) };
static int grid_taps(const fv_tw_map *m, const fv_tw_src *s, int n, const float *px, const float *py, float *du,
                     float *dv)
{
    float A[TW_GRID_TAPS][3], u[TW_GRID_TAPS], v[TW_GRID_TAPS], w[TW_GRID_TAPS], wp[TW_GRID_TAPS];
    for (int i = 0; i < n; i++) {
        for (int k = 0; k < 3; k++)
            A[i][k] = (m->a0[k] + py[i] * m->ay[k]) + px[i] * m->ax[k];
        w[i] = wp[i] = 0.0f;
    }
    for (int it = 0; it < 3; it++) {
        for (int i = 0; i < n; i++) {
            fv_tw_proj(A[i], m->t, w[i], &u[i], &v[i]);
            const int ix = (int)fv_tw_clampf(u[i], (float)(s->w - 1)), iy = (int)fv_tw_clampf(v[i], (float)(s->h - 1));
            __builtin_prefetch(s->invd + (ptrdiff_t)iy * s->invd_stride + ix);
        }
        for (int i = 0; i < n; i++)
            wp[i] = w[i], w[i] = fv_tw_fetch_w(m, s, A[i][2], u[i], v[i]);
    }
    for (int i = 0; i < n; i++) {
        float wi = w[i];
        const float dw = wi > wp[i] ? wi - wp[i] : wp[i] - wi;
        if (dw > m->tol * (wi > wp[i] ? wi : wp[i]))
            wi = wi < wp[i] ? wi : wp[i];
        if (!(A[i][2] + m->t[2] * wi > 2.0f * FV_TW_ZMIN))
            return 0;
        float uu, vv;
        fv_tw_proj(A[i], m->t, wi, &uu, &vv);
        du[i] = uu - px[i], dv[i] = vv - py[i];
        if (!(fabsf(du[i]) < 1e6f && fabsf(dv[i]) < 1e6f))
            return 0;
    }
    return 1;
}

/* the part b (failed) as grid cells into out (at most ceil(w / FV_TW_GRID_W) ceil(h / FV_TW_GRID_H)
 * entries, in rows: those covering a row in column order); the taps at the cells' top and bottom
 * edges (shared by the cells above and below), each cell's first and last row's translation
 * interpolated between them. 0 when a tap cannot be placed (the part then stays per pixel). */
static int grid_cells(const fv_tw_map *m, const fv_tw_src *s, const fv_tw_block *b, fv_tw_block *out)
{
    enum { GW = FV_TW_GRID_W, GH = FV_TW_GRID_H, NX = FV_TW_BLOCK_W / GW + 1, NY = FV_TW_BLOCK_H / GH + 1 };
    float px[TW_GRID_TAPS], py[TW_GRID_TAPS], tu[TW_GRID_TAPS], tv[TW_GRID_TAPS];
    const int nx = (b->x1 - b->x0 + GW - 1) / GW, ny = (b->y1 - b->y0 + GH - 1) / GH;
    if (nx > NX - 1 || ny > NY - 1)
        return 0;
    for (int j = 0; j <= ny; j++)
        for (int i = 0; i < nx; i++) {
            px[j * nx + i] = 0.5f * (float)(b->x0 + i * GW + mini(b->x0 + (i + 1) * GW, b->x1));
            py[j * nx + i] = (float)mini(b->y0 + j * GH, b->y1);
        }
    if (!grid_taps(m, s, (ny + 1) * nx, px, py, tu, tv))
        return 0;
    int n = 0;
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            fv_tw_block *c = &out[n++];
            memset(c, 0, sizeof *c);
            c->x0 = b->x0 + i * GW, c->x1 = mini(c->x0 + GW, b->x1);
            c->y0 = b->y0 + j * GH, c->y1 = mini(c->y0 + GH, b->y1);
            const int t = j * nx + i, l = t + nx; /* the taps at its top and bottom edge */
            const float h = (float)(c->y1 - c->y0), f0 = 0.5f / h, f1 = (h - 0.5f) / h;
            c->u0 = tu[t] + (tu[l] - tu[t]) * f0, c->v0 = tv[t] + (tv[l] - tv[t]) * f0;
            c->u1 = tu[t] + (tu[l] - tu[t]) * f1, c->v1 = tv[t] + (tv[l] - tv[t]) * f1;
            if (!block_rows(c, s))
                return 0;
            c->grid = 1;
        }
    return n;
}

/* The bounded warp's share-out within a group of planned entries (plan, pmap: n of them, at
 * most MAXE after): the failed parts, largest bound first, run per pixel while *allow lasts; the
 * others become grid cells. Returns the new count. */
static int bound_entries(const fv_tw_src *src, fv_tw_block *plan, const fv_tw_map **pmap, int n, int maxe, long *allow,
                         fv_tw_warp_stats *st)
{
    enum { MAXF = FV_TW_BLOCK_SPLIT * 8 };
    int fail[MAXF], nf = 0;
    long need = 0;
    for (int i = 0; i < n && nf < MAXF; i++)
        if (!plan[i].fast) {
            fail[nf++] = i;
            need += (long)(plan[i].x1 - plan[i].x0) * (plan[i].y1 - plan[i].y0);
        }
    if (need <= *allow) {
        *allow -= need;
        if (st)
            st->pixel_px += need;
        return n;
    }
    /* largest bound first (insertion sort: a few dozen entries); a part the planner gave up on
     * before bounding it (err_px 0) counts as unbounded */
    for (int i = 1; i < nf; i++)
        for (int j = i; j > 0; j--) {
            const float ea = plan[fail[j - 1]].err_px, eb = plan[fail[j]].err_px;
            if ((ea > 0.0f ? ea : INFINITY) >= (eb > 0.0f ? eb : INFINITY))
                break;
            const int t = fail[j - 1];
            fail[j - 1] = fail[j], fail[j] = t;
        }
    char keep[FV_TW_BLOCK_SPLIT * 8];
    memset(keep, 0, sizeof keep);
    for (int k = 0; k < nf; k++) {
        const fv_tw_block *b = &plan[fail[k]];
        const long px = (long)(b->x1 - b->x0) * (b->y1 - b->y0);
        if (px <= *allow) {
            *allow -= px;
            keep[fail[k]] = 1;
            if (st)
                st->pixel_px += px;
        }
    }
    /* rebuild: each entry to grid becomes its cells where it stood (a row's entries stay in
     * column order); a part of s x s has at most ceil(s / 16)^2 <= s^2 / 64 cells for s >= 8 */
    fv_tw_block tmp[FV_TW_BLOCK_SPLIT * 8];
    const fv_tw_map *tmap[FV_TW_BLOCK_SPLIT * 8];
    int k = 0;
    for (int i = 0; i < n; i++) {
        if (plan[i].fast || keep[i]) {
            tmp[k] = plan[i], tmap[k++] = pmap[i];
            continue;
        }
        const fv_tw_block b = plan[i];
        const int cells = ((b.x1 - b.x0 + FV_TW_GRID_W - 1) / FV_TW_GRID_W) * ((b.y1 - b.y0 + FV_TW_GRID_H - 1) / FV_TW_GRID_H);
        const int c = k + cells + (n - 1 - i) <= maxe ? grid_cells(pmap[i], src, &b, tmp + k) : 0;
        if (!c) { /* cannot be placed (or no room): per pixel, over the budget */
            tmp[k] = b, tmap[k++] = pmap[i];
            if (st)
                st->pixel_px += (long)(b.x1 - b.x0) * (b.y1 - b.y0);
            continue;
        }
        for (int j = 0; j < c; j++)
            tmap[k + j] = pmap[i];
        k += c;
        if (st)
            st->grid_px += (long)(b.x1 - b.x0) * (b.y1 - b.y0);
    }
    memcpy(plan, tmp, sizeof *tmp * (size_t)k);
    memcpy(pmap, tmap, sizeof *tmap * (size_t)k);
    return k;
}

#define FV_TW_PREFETCH_ROWS 3

/* one row of a translated block: its clamped columns written here, the rest as a piece for
 * tw_spans; the source position is clamped to the source as the reference's. o holds columns
 * from xo on. 1 when a piece. */
static inline int block_row(fv_tw_piece *pc, uint8_t *o, int xo, int y, const fv_tw_block *b, const int64_t q[2],
                            const fv_tw_src *s)
{
    int ox, oy, fx, fy;
    row_offsets(q[0], q[1], &ox, &oy, &fx, &fy);
    int sy = y + oy;
    if (sy < 0) /* above the first row: it, with no vertical weight */
        sy = 0, fy = 0;
    else if (sy >= s->h - 1)
        sy = s->h - 1, fy = 0;
    const uint8_t *r0 = s->rgb + (ptrdiff_t)sy * s->rgb_stride, *r1 = fy ? r0 + s->rgb_stride : r0;
    /* columns whose tap is left of the first column or right of the last take that column */
    const int xa = b->x0 + ox < 0 ? mini(-ox, b->x1) : b->x0;
    const int xb = b->x1 + ox > s->w - 1 ? (s->w - 1 - ox > xa ? s->w - 1 - ox : xa) : b->x1;
    if (xa > b->x0 || xb < b->x1) {
        uint8_t e0[3], e1[3];
        for (int c = 0; c < 3; c++) {
            e0[c] = fv_tw_span_px(r0[c], r0[c], r1[c], r1[c], 0, fy);
            const int l = 3 * (s->w - 1) + c;
            e1[c] = fv_tw_span_px(r0[l], r0[l], r1[l], r1[l], 0, fy);
        }
        for (int x = b->x0; x < xa; x++)
            memcpy(o + 3 * (x - xo), e0, 3);
        for (int x = xb; x < b->x1; x++)
            memcpy(o + 3 * (x - xo), e1, 3);
    }
    if (xa >= xb)
        return 0;
    pc->s0 = r0 + 3 * (ptrdiff_t)(xa + ox), pc->s1 = r1 + 3 * (ptrdiff_t)(xa + ox);
    pc->dst = 3 * (xa - xo), pc->n = 3 * (xb - xa), pc->fx = fx, pc->fy = fy;
    /* a display row reads pieces of ten or so source rows (the homography's tilt), too many
     * short streams for the hardware prefetcher: fetch this piece's source a few rows ahead */
    if (sy + FV_TW_PREFETCH_ROWS + 1 < s->h)
        for (int k = 0; k < pc->n + 3; k += 64)
            __builtin_prefetch(pc->s0 + FV_TW_PREFETCH_ROWS * s->rgb_stride + k);
    return 1;
}

long fv_tw_warp_rows(const fv_timewarp_dsp *d, uint8_t *dst, ptrdiff_t dst_stride, int y0, int y1, const fv_tw_map *m,
                     const fv_tw_src *src, const fv_tw_tiles *tiles)
{
    return fv_tw_warp_rows_bounded(d, dst, dst_stride, y0, y1, m, src, tiles, LONG_MAX, NULL);
}

long fv_tw_warp_rows_bounded(const fv_timewarp_dsp *d, uint8_t *dst, ptrdiff_t dst_stride, int y0, int y1,
                             const fv_tw_map *m, const fv_tw_src *src, const fv_tw_tiles *tiles, long budget_px,
                             fv_tw_warp_stats *stats)
{
    enum { CHUNK = 8, MAXE = FV_TW_BLOCK_SPLIT * CHUNK }; /* blocks planned at a time, their entries */
    const int BW = FV_TW_BLOCK_W, BH = FV_TW_BLOCK_H, nbx = (src->w + BW - 1) / BW;
    fv_tw_block plan[MAXE];
    fv_tw_piece pc[MAXE];
    /* the entries covering the row, rebuilt where that set changes: the inner translated blocks
     * as runners (tw_runs steps their translation a row at a time and keeps each one's
     * lower-row horizontal pass for the next row), the
     * others as items (a clamped translated block, or a run of per-pixel parts in one call: the
     * kernel interleaves 64 pixels) */
    fv_tw_run run[MAXE];
    /* a row's columns composed in cache, then streamed (tw_stream); tw_runs' kept passes */
    _Alignas(32) uint8_t row[3 * CHUNK * FV_TW_BLOCK_W];
    _Alignas(32) int16_t hbuf[3 * CHUNK * FV_TW_BLOCK_W];
    struct { const fv_tw_block *b; const fv_tw_map *m; int xa, xb; } item[MAXE]; /* b NULL: per-pixel columns [xa, xb) */
    fv_tw_map cells[TW_CELLS * CHUNK]; /* with a lens: the cells' maps */
    const fv_tw_map *pmap[MAXE];       /* each plan entry's map */
    const ptrdiff_t stride = src->rgb_stride;
    long holes = 0, budget_left = budget_px, rem_px = (long)(y1 - y0) * src->w;
    for (int by = y0 / BH; by * BH < y1; by++) {
        const int ya = by * BH > y0 ? by * BH : y0, yb = mini(by * BH + BH, y1);
        float guess = 0.0f;
        for (int bx0 = 0; bx0 < nbx; bx0 += CHUNK) {
            /* bounded: parts no smaller than a grid cell (a failed part is cells of that size anyway;
             * proving 8x8 parts costs more planning and twice the pieces a row) */
            int n = plan_blocks(d, m, src, tiles, by, bx0, mini(CHUNK, nbx - bx0), plan, &guess, cells, pmap,
                                budget_px == LONG_MAX ? FV_TW_BLOCK_MIN : FV_TW_GRID_MIN);
            const int x0 = bx0 * BW, x1 = mini((bx0 + CHUNK) * BW, src->w);
            if (budget_px != LONG_MAX) { /* this group's share of what is left, in proportion to its pixels */
                const long px = (long)(x1 - x0) * (yb - ya);
                long allow = rem_px > px ? (long)((double)budget_left * (double)px / (double)rem_px) : budget_left;
                const long given = allow;
                n = bound_entries(src, plan, pmap, n, MAXE, &allow, stats);
                budget_left -= given - allow;
                rem_px -= px;
            } else if (stats)
                for (int i = 0; i < n; i++)
                    stats->pixel_px += plan[i].fast ? 0 : (long)(plan[i].x1 - plan[i].x0) * (plan[i].y1 - plan[i].y0);
            int nr = 0, ni = 0, next = ya; /* the entries covering the row change on row next */
            for (int y = ya; y < yb; y++) {
                if (y == next) {
                    nr = ni = 0, next = yb;
                    int prev_slow = 0;
                    for (int i = 0; i < n; i++) {
                        const fv_tw_block *b = &plan[i];
                        const int c = b->y0 > y ? b->y0 : b->y1;
                        next = c > y && c < next ? c : next;
                        if (!(b->y0 <= y && y < b->y1))
                            continue;
                        if (b->inner) { /* block_row without its clamps: the same pieces (TW_QBIAS is
                                         * FV_TW_RUN_BIAS in 1/2^22 px) */
                            fv_tw_run *r = &run[nr++];
                            r->qu = b->qu + (int64_t)(y - b->y0) * b->dqu + TW_QBIAS + 32768;
                            r->qv = b->qv + (int64_t)(y - b->y0) * b->dqv + TW_QBIAS + 32768;
                            r->dqu = b->dqu, r->dqv = b->dqv;
                            r->off = (int64_t)y * stride + 3 * b->x0 - FV_TW_RUN_BIAS * ((int64_t)stride + 3);
                            r->dst = 3 * (b->x0 - x0), r->n = 3 * (b->x1 - b->x0);
                            r->hoff = -1, r->hfx = 0;
                        } else if (b->fast)
                            item[ni].b = b, item[ni++].xa = 0;
                        else if (prev_slow && item[ni - 1].m == pmap[i])
                            item[ni - 1].xb = b->x1;
                        else
                            item[ni].b = NULL, item[ni].m = pmap[i], item[ni].xa = b->x0, item[ni++].xb = b->x1;
                        prev_slow = !b->fast;
                    }
                }
                d->tw_runs(row, run, nr, src->rgb, stride, (ptrdiff_t)src->h * stride, hbuf);
                int np = 0;
                for (int k = 0; k < ni; k++) {
                    const fv_tw_block *b = item[k].b;
                    if (b) {
                        const int64_t q[2] = {b->qu + (int64_t)(y - b->y0) * b->dqu, b->qv + (int64_t)(y - b->y0) * b->dqv};
                        np += block_row(&pc[np], row, x0, y, b, q, src);
                    } else
                        holes += d->tw_row(row + 3 * (item[k].xa - x0), item[k].xa, y, item[k].xb - item[k].xa, item[k].m,
                                           src);
                }
                d->tw_spans(row, pc, np);
                d->tw_stream(dst + (ptrdiff_t)y * dst_stride + 3 * x0, row, 3 * (x1 - x0));
            }
        }
    }
    d->tw_stream(NULL, NULL, 0); /* the fence: the rows are visible to the thread that shows them */
    return holes;
}

int fv_tw_frame_alloc(fv_tw_frame *f, int w, int h)
{
    memset(f, 0, sizeof *f);
    f->w = w, f->h = h;
    for (int e = 0; e < 2; e++) {
        f->rgb[e] = calloc((size_t)w * h * 3 + FV_TW_RGB_PAD, 1);
        f->invd[e] = calloc((size_t)w * h * 2 + FV_TW_INVD_PAD, 1);
        const int tw = (w + FV_TW_TILE - 1) / FV_TW_TILE, th = (h + FV_TW_TILE - 1) / FV_TW_TILE;
        f->tiles[e].lohi = calloc(2 * (size_t)tw * th, sizeof(uint16_t));
        f->tiles[e].lohi4 = calloc(2 * (size_t)((tw + 3) / 4) * ((th + 3) / 4), sizeof(uint16_t));
        if (!f->rgb[e] || !f->invd[e] || !f->tiles[e].lohi || !f->tiles[e].lohi4) {
            fv_tw_frame_free(f);
            return -1;
        }
    }
    return 0;
}

void fv_tw_frame_free(fv_tw_frame *f)
{
    for (int e = 0; e < 2; e++) {
        free(f->rgb[e]);
        free(f->invd[e]);
        free(f->tiles[e].lohi);
        free(f->tiles[e].lohi4);
        f->rgb[e] = NULL;
        f->invd[e] = NULL;
        f->tiles[e].lohi = f->tiles[e].lohi4 = NULL;
    }
}

void fv_tw_frame_capture(fv_tw_frame *f, const fv_pipeline *pl, int e)
{
    const fv_eye eye = e ? FV_EYE_RIGHT : FV_EYE_LEFT;
    fv_pipeline_to_rgb8(pl, eye, f->rgb[e], (ptrdiff_t)f->w * 3);
    ptrdiff_t stride;
    const float *img = fv_pipeline_depth(pl, eye, &stride); /* the final image's depth */
    fv_tw_pack_invd(f->invd[e], f->w, img, stride * 4, f->w, f->h);
    /* the depth's tiles, here on the renderer's thread, not on the display's; exact on any ISA */
    fv_timewarp_dsp d;
    fv_timewarp_dsp_init(&d, ~0u);
    const fv_tw_src s = {f->rgb[e], (ptrdiff_t)f->w * 3, f->invd[e], f->w, f->w, f->h};
    fv_tw_tiles_build(&d, &f->tiles[e], &s);
    const fv_camera *c = fv_pipeline_camera(pl, eye);
    if (c->lens_on) /* ~50 us: cheaper than telling whether the lens changed */
        fv_lens_map_init(&f->lmap[e], c);
    f->cam[e] = *c;
}

long fv_tw_frame_warp(const fv_timewarp_dsp *d, const fv_tw_frame *f, int e, const fv_camera *display, uint8_t *dst,
                      ptrdiff_t dst_stride, float tol)
{
    fv_tw_map m;
    fv_tw_setup(&m, display, &f->cam[e], tol);
    if (f->cam[e].lens_on)
        fv_tw_map_set_lens(&m, &f->lmap[e]);
    const fv_tw_src s = {f->rgb[e], (ptrdiff_t)f->w * 3, f->invd[e], f->w, f->w, f->h};
    return fv_tw_warp_rows(d, dst, dst_stride, 0, f->h, &m, &s, &f->tiles[e]);
}

long fv_tw_frame_warp_bounded(const fv_timewarp_dsp *d, const fv_tw_frame *f, int e, const fv_camera *display,
                              uint8_t *dst, ptrdiff_t dst_stride, float tol, long budget_px, fv_tw_warp_stats *stats)
{
    fv_tw_map m;
    fv_tw_setup(&m, display, &f->cam[e], tol);
    if (f->cam[e].lens_on)
        fv_tw_map_set_lens(&m, &f->lmap[e]);
    const fv_tw_src s = {f->rgb[e], (ptrdiff_t)f->w * 3, f->invd[e], f->w, f->w, f->h};
    return fv_tw_warp_rows_bounded(d, dst, dst_stride, 0, f->h, &m, &s, &f->tiles[e], budget_px, stats);
}

double fv_tw_psnr_outside_holes(const uint8_t *warped, const uint8_t *ref, const fv_tw_map *m, const fv_tw_src *src,
                                double *disocc_frac)
{
    const int w = src->w, h = src->h;
    float *err = malloc((size_t)w * h * sizeof *err);
    *disocc_frac = NAN;
    if (!err)
        return NAN;
    fv_luma_error(ref, warped, w, h, (ptrdiff_t)w * 3, err);
    double se = 0;
    long n = 0, holes = 0;
    const int C = FV_TW_LENS_CELL;
    fv_tw_map cm = *m;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            uint8_t px[3];
            if (m->lens && (x % C == 0)) /* with a lens: the cell's map */
                fv_tw_cell_map(m, src, x, mini(x + C, w), y / C * C, mini(y / C * C + C, h), &cm);
            if (fv_tw_row_c(px, x, y, 1, &cm, src)) { /* the reference's verdict for this pixel */
                holes++;
                continue;
            }
            const double e = err[(size_t)y * w + x];
            se += e * e;
            n++;
        }
    free(err);
    *disocc_frac = (double)holes / ((double)w * h);
    if (!n)
        return NAN;
    return se > 0 ? 10.0 * log10(255.0 * 255.0 * (double)n / se) : INFINITY;
}
