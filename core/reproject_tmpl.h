/* fovea: the temporal reprojection kernels' shared parts (see reproject.h), used by the C
 * reference and every ISA version (dav1d-style template). Included once per ISA file after it
 * defines:
 *   TAA_FN(name)   the ISA's function name
 *   acc4           a 4-channel accumulator (r, g, b, depth)
 *   acc_zero()     an accumulator of +0
 *   tap(L, s, t, zexp, inv_tol, &acc, &accw)
 *                  adds one bilinear tap of level L at level coordinates (s, t) (texel centres
 *                  at integers; s, t >= -0.5): texels (i, j), (i, j+1), (i+1, j), (i+1, j+1)
 *                  with i = floor(s), j = floor(t), fx = s - i, fy = t - j, bilinear weights
 *                  b00 = (1-fx)(1-fy), b01 = (1-fx) fy, b10 = fx (1-fy), b11 = fx fy, and
 *                    wt  = (b * conf) * max(0, 1 - |depth - zexp| * inv_tol)
 *                    acc = acc + ((wt00 c00 + wt01 c01) + (wt10 c10 + wt11 c11))
 *                    accw = accw + ((wt00 + wt01) + (wt10 + wt11))
 *   out_blend(px, acc, accw, alpha)   h = acc / accw; px.rgb = h + alpha (px.rgb - h)
 *   sample_mask(wgt, n)               bit i set where wgt[i] == 1 (n <= 64)
 * (an ISA that defines TAA_OWN_BLEND writes its own blend and may hand samples its vector path
 * does not take to taa_taps, which needs tap, acc4 and out_blend).
 * The blend's per-sample arithmetic is scalar IEEE code here, identical for all ISAs; the fill
 * has a scalar form here (the reference, and the ISAs' row edges) that the ISA files vectorise
 * across pixels with the same operations per lane. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "reproject.h"
#include "base/util.h"

/* Footprint (previous-frame pixels) -> pyramid level: floor(log2 f) from the exponent bits. */
static inline int taa_level(float f, int max_level)
{
    if (!(f >= 2.0f))
        return 0; /* also NaN */
    uint32_t b;
    memcpy(&b, &f, 4);
    int e = (int)(b >> 23) - 127;
    return e < max_level ? e : max_level;
}


/* 2^l and 2^-l: exact, without a division on the sample's dependency chain */
static const float taa_pow2[8] = {1.0f, 2.0f, 4.0f, 8.0f, 16.0f, 32.0f, 64.0f, 128.0f};
static const float taa_inv_pow2[8] = {1.0f, 0.5f, 0.25f, 0.125f, 0.0625f, 0.03125f, 0.015625f, 0.0078125f};

/* A sample between its projection and its taps (the blend's two halves, below; an ISA that
 * blends several samples per step sends the samples its vector path does not take here). */
typedef struct {
    float *px;          /* the sample (r, g, b, depth) */
    float u, v, z;      /* its previous pixel and view depth */
    float inv_tol, o;   /* 1 / (tol z); quincunx half extent (taps when >= 1/8) */
    int l;              /* pyramid level of the footprint */
} taa_pending;

/* Projected samples wait this many samples for their taps, so the history lines prefetched at the
 * projection arrive meanwhile: one sample's chain (project, load, weigh, blend) is ~100
 * instructions, too long for the out-of-order window to overlap more than two or three samples'
 * misses. checkasm --bench taa_blend+taa_fill (AVX2, one thread, cold history): distance 0 (one
 * pass) 21.2 ms, 8: 17.1, 16: 16.5, 24: 16.5. */
#define TAA_PREFETCH_DIST 16
#define TAA_RING 32 /* a power of two > TAA_PREFETCH_DIST */

static inline __attribute__((always_inline)) void taa_taps(const struct fv_taa_frame *f, const struct fv_taa_tile *t, const taa_pending *q)
{
    const float umax = f->prev_w - 0.015625f, vmax = f->prev_h - 0.015625f; /* taps stay inside */
    const fv_pyr_level *L = &f->hist->lv[q->l];
    const float inv_ts = taa_inv_pow2[q->l]; /* l <= max_level <= 5 */
    const float u = q->u, v = q->v, o = q->o;
    acc4 acc = acc_zero();
    float accw = 0.0f;
    int taps = 1;
    tap(L, u * inv_ts - 0.5f, v * inv_ts - 0.5f, q->z, q->inv_tol, &acc, &accw);
    if (o >= 0.125f) { /* quincunx: the footprint's four corners at half extent */
        const float ul = fv_clampf(u - o, 0.0f, umax), ur = fv_clampf(u + o, 0.0f, umax);
        const float vt = fv_clampf(v - o, 0.0f, vmax), vb = fv_clampf(v + o, 0.0f, vmax);
        tap(L, ul * inv_ts - 0.5f, vt * inv_ts - 0.5f, q->z, q->inv_tol, &acc, &accw);
        tap(L, ur * inv_ts - 0.5f, vt * inv_ts - 0.5f, q->z, q->inv_tol, &acc, &accw);
        tap(L, ul * inv_ts - 0.5f, vb * inv_ts - 0.5f, q->z, q->inv_tol, &acc, &accw);
        tap(L, ur * inv_ts - 0.5f, vb * inv_ts - 0.5f, q->z, q->inv_tol, &acc, &accw);
        taps = 5;
    }
    if (!(accw > 0.0f))
        return; /* no valid history: the sample stands alone */
    const float a1 = 1.0f - (taps == 1 ? accw : accw / 5.0f); /* accw / 1 is accw */
    out_blend(q->px, acc, accw, a1 > t->alpha ? a1 : t->alpha);
}

/* The blend's per-sample footprint: pyramid level and quincunx half extent (taps when >= 1/8). */
static inline int taa_footprint(const struct fv_taa_frame *f, float fp, float *o_out)
{
    const int l = taa_level(fp, f->max_level);
    const float ts = taa_pow2[l];
    float o = (fp - ts) * 0.5f;
    *o_out = o < 0.5f * ts ? o : 0.5f * ts;
    return l;
}

#ifndef TAA_OWN_BLEND /* an ISA may vectorise the blend across samples instead */
static void TAA_FN(taa_blend)(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd_blk,
                              const float *wgt_blk, ptrdiff_t stride, int x0, int y0, int w, int h,
                              struct fv_taa_flow *flow)
{
    float fdx = flow->dx, fdy = flow->dy, fn = flow->n;
    /* a new sample's weight of 1 (the fovea, where every pixel is traced every frame): only the
     * flow sums are wanted, for the tile's fill; h + 1 (px - h) would only round px */
    const int keep_sample = t->alpha >= 1.0f;
    /* Samples are projected (and their flow summed) in row-major order; their taps run
     * TAA_PREFETCH_DIST samples later. A blend changes only its own sample's colour, never a
     * depth another projection reads, so the result is the one-pass loop's, bit for bit. */
    taa_pending ring[TAA_RING];
    unsigned head = 0, tail = 0;
    for (int r = 0; r < h; r++) {
        const int y = y0 + r;
        float *rgbd = rgbd_blk + 4 * r * stride;
        const float py = (float)y + 0.5f;
        const float b0 = f->M0[0] + py * f->MY[0], b1 = f->M0[1] + py * f->MY[1], b2 = f->M0[2] + py * f->MY[2];
        /* iterate over the samples' bits: no branch on the (dithered) pattern per pixel */
        uint64_t m = sample_mask(wgt_blk + r * stride, w);
        while (m) {
            const int i = __builtin_ctzll(m);
            m &= m - 1;
            float *px = rgbd + 4 * i;
            const float d = px[3], pxc = (float)(x0 + i) + 0.5f;
            float u, v, z, rz;
            if (f->identity) {
                u = pxc;
                v = py;
                z = d;
                rz = 1.0f / z;
            } else {
                const float U = f->T[0] + d * (b0 + pxc * f->MX[0]);
                const float V = f->T[1] + d * (b1 + pxc * f->MX[1]);
                z = f->T[2] + d * (b2 + pxc * f->MX[2]);
                if (!(z > 1e-4f))
                    continue; /* behind the previous eye: no history */
                rz = 1.0f / z;
                u = U * rz;
                v = V * rz;
            }
            if (!(u >= 0.0f && u < f->prev_w && v >= 0.0f && v < f->prev_h))
                continue; /* outside the previous image */
            fdx = fdx + (u - pxc);
            fdy = fdy + (v - py);
            fn = fn + 1.0f;
            if (keep_sample)
                continue; /* history has no weight here: the sample stays exactly as traced */
            const float fp = (d * rz) * t->widen;
            float o;
            const int l = taa_footprint(f, fp, &o);
            const float inv_ts = taa_inv_pow2[l];
            taa_pending *q = &ring[head++ % TAA_RING];
            q->px = px;
            q->u = u;
            q->v = v;
            q->z = z;
            q->inv_tol = rz * f->inv_depth_tol;
            q->o = o;
            q->l = l;
            { /* the centre tap's two texel rows (2 x 32 bytes) and their weights */
                const fv_pyr_level *L = &f->hist->lv[l];
                const ptrdiff_t o00 = (ptrdiff_t)floorf(v * inv_ts - 0.5f) * L->stride +
                                      (ptrdiff_t)floorf(u * inv_ts - 0.5f);
                const float *c = L->rgbd + 4 * o00;
                __builtin_prefetch(c);
                __builtin_prefetch(c + 7);
                __builtin_prefetch(c + 4 * L->stride);
                __builtin_prefetch(c + 4 * L->stride + 7);
                __builtin_prefetch(L->wgt + o00);
                __builtin_prefetch(L->wgt + o00 + L->stride);
            }
            if (head - tail > TAA_PREFETCH_DIST)
                taa_taps(f, t, &ring[tail++ % TAA_RING]);
        }
    }
    while (tail != head)
        taa_taps(f, t, &ring[tail++ % TAA_RING]);
    flow->dx = fdx;
    flow->dy = fdy;
    flow->n = fn;
}
#endif

/* The fill for pixels i in [i0, i1) of the row (the whole row in the reference). hrow / hw point
 * at pixel 0 of history row y + flow_y of level 0; B = N0 + vc * NY for that row's centre vc. */
static inline void taa_fill_px(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, float *wgt,
                               const float *hrow, const float *hw, const float B[3], int x0, float py, int i0, int i1)
{
    for (int i = i0; i < i1; i++) {
        const int sx = x0 + i + t->flow_x;
        if (!(wgt[i] == 0.0f && sx >= 0 && (float)sx < f->prev_w))
            continue;
        const float ws = hw[sx];
        if (!(ws > 0.0f))
            continue;
        const float *src = hrow + 4 * sx;
        const float D = src[3];
        float z = D;
        if (!f->identity) {
            /* the history texel's world point must land on this pixel (within half a pixel) */
            const float uc = (float)sx + 0.5f, pxc = (float)(x0 + i) + 0.5f;
            const float U = f->T2[0] + D * (B[0] + uc * f->NX[0]);
            const float V = f->T2[1] + D * (B[1] + uc * f->NX[1]);
            z = f->T2[2] + D * (B[2] + uc * f->NX[2]);
            if (!(z > 1e-4f))
                continue;
            const float rz = 1.0f / z;
            const float ex = U * rz - pxc, ey = V * rz - py;
            if (!(ex <= 0.5f && ex >= -0.5f && ey <= 0.5f && ey >= -0.5f))
                continue;
        }
        float *o = rgbd + 4 * i;
        o[0] = src[0];
        o[1] = src[1];
        o[2] = src[2];
        o[3] = z;
        wgt[i] = ws;
    }
}

/* The pixels [*ilo, *ihi) of a fill row whose history texels x0 + i + flow_x lie inside the
 * previous row (contiguous runs the ISA versions load whole; the rest goes pixel by pixel). */
static inline void taa_fill_span(const struct fv_taa_frame *f, const struct fv_taa_tile *t, int x0, int n, int *ilo,
                                 int *ihi)
{
    const int sx0 = x0 + t->flow_x, W = (int)f->prev_w;
    int lo = sx0 < 0 ? -sx0 : 0, hi = W - sx0 < n ? W - sx0 : n;
    lo = lo > n ? n : lo;
    *ilo = lo;
    *ihi = hi < lo ? lo : hi;
}

/* Row set-up of the fill: NULL when the history row is outside the previous image. */
static inline const float *taa_fill_setup(const struct fv_taa_frame *f, const struct fv_taa_tile *t, int y,
                                          const float **hw, float B[3])
{
    const int sy = y + t->flow_y;
    if (!(sy >= 0 && (float)sy < f->prev_h))
        return NULL;
    const fv_pyr_level *L = &f->hist->lv[0];
    const float vc = (float)sy + 0.5f;
    for (int k = 0; k < 3; k++)
        B[k] = f->N0[k] + vc * f->NY[k];
    const ptrdiff_t o = (ptrdiff_t)sy * L->stride;
    *hw = L->wgt + o;
    return L->rgbd + 4 * o;
}

/* The fill of a block from a vector body (the C reference's, with none; the ISA files now write
 * their own per-block fill instead, with the row-independent set-up hoisted: branch taa9)
 *   int vec(f, t, rgbd, wgt, hrow, hw, B, x0, py, ilo, ihi)
 * which fills pixels ilo, ilo + step, ... of the contiguous span [ilo, ihi) (taa_fill_span) and
 * returns the first pixel it did not do; the scalar form does the row's edges and the rest. */
#define TAA_FILL_BLOCK(name, vec)                                                                         \
    static void name(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd_blk,          \
                     float *wgt_blk, ptrdiff_t stride, int x0, int y0, int w, int h)                     \
    {                                                                                                     \
        for (int r = 0; r < h; r++) {                                                                     \
            float *rgbd = rgbd_blk + 4 * r * stride, *wgt = wgt_blk + r * stride;                          \
            const float *hw, *hrow;                                                                       \
            float B[3];                                                                                   \
            if (!(hrow = taa_fill_setup(f, t, y0 + r, &hw, B)))                                           \
                continue;                                                                                 \
            const float py = (float)(y0 + r) + 0.5f;                                                      \
            int ilo, ihi;                                                                                 \
            taa_fill_span(f, t, x0, w, &ilo, &ihi);                                                       \
            taa_fill_px(f, t, rgbd, wgt, hrow, hw, B, x0, py, 0, ilo);                                    \
            const int i = vec(f, t, rgbd, wgt, hrow, hw, B, x0, py, ilo, ihi);                            \
            taa_fill_px(f, t, rgbd, wgt, hrow, hw, B, x0, py, i, w);                                      \
        }                                                                                                 \
    }
