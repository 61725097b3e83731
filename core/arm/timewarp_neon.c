/* fovea: the timewarp kernel, NEON: 4 display pixels a step, the float steps in vector code,
 * the source reads per lane (NEON has no gather), the bilinear tap on bytes in output order
 * (tap4).
 * Same IEEE steps as the reference, in its order. Its selects (a > b ? a : b) against a constant
 * bound are FMAXNM / FMINNM: they return the number where the other operand is a (quiet) NaN,
 * as the select does (FMAX would propagate it); the two operands variable (mx) stay compares. */
#include <arm_neon.h>
#include <string.h>

#include "timewarp_dsp.h"

typedef struct {
    float32x4_t t0, t1, t2, zmin, one, denmin, wscale, tol, wm1, hm1, half, k128;
    int32x4_t hm1i, istride, rstride;
    const uint16_t *invd;
    const uint8_t *rgb;
} tw4;

static inline float32x4_t gt_sel(float32x4_t a, float32x4_t b) { return vbslq_f32(vcgtq_f32(a, b), a, b); }
/* a > b ? a : b for a constant b > 0 (the operands come out of arithmetic: never a signalling
 * NaN, which FMAXNM would not drop) */
static inline float32x4_t max_bound(float32x4_t a, float32x4_t b) { return vmaxnmq_f32(a, b); }
/* the reference's clamp: v > 0 ? v : 0 (NaN -> 0; -0 -> +0, as FMAXNM(-0, +0) = +0), then
 * v < hi ? v : hi on a number */
static inline float32x4_t clamp4(float32x4_t v, float32x4_t hi) { return vminnmq_f32(vmaxnmq_f32(v, vdupq_n_f32(0.0f)), hi); }

static inline void proj4(const tw4 *c, float32x4_t A0, float32x4_t A1, float32x4_t A2, float32x4_t w, float32x4_t *u,
                         float32x4_t *v)
{
    const float32x4_t nz = max_bound(vaddq_f32(A2, vmulq_f32(c->t2, w)), c->zmin);
    const float32x4_t inv = vdivq_f32(c->one, nz);
    *u = vmulq_f32(vaddq_f32(A0, vmulq_f32(c->t0, w)), inv);
    *v = vmulq_f32(vaddq_f32(A1, vmulq_f32(c->t1, w)), inv);
}

static inline int32x4_t gather_u16(const uint16_t *p, int32x4_t i)
{
    const int32_t v[4] = {p[vgetq_lane_s32(i, 0)], p[vgetq_lane_s32(i, 1)], p[vgetq_lane_s32(i, 2)],
                          p[vgetq_lane_s32(i, 3)]};
    return vld1q_s32(v);
}
static inline float32x4_t fetch_w4(const tw4 *c, float32x4_t A2, float32x4_t u, float32x4_t v)
{
    const int32x4_t ix = vcvtq_s32_f32(clamp4(u, c->wm1)), iy = vcvtq_s32_f32(clamp4(v, c->hm1));
    const int32x4_t g = gather_u16(c->invd, vaddq_s32(vmulq_s32(iy, c->istride), ix));
    const float32x4_t ws = vmulq_f32(vcvtq_f32_s32(g), c->wscale);
    const float32x4_t den = max_bound(vsubq_f32(c->one, vmulq_f32(c->t2, ws)), c->denmin);
    return vdivq_f32(vmulq_f32(A2, ws), den);
}

/* the bilinear tap of 4 pixels, 12 output bytes. Each lane's corners come from one 8-byte load
 * a row at its x0 (bytes x0's RGB, then x0 + 1's: at the right edge x0 + 1 is past the row, but
 * there fx = 0 and the reference reads x0 twice, so the byte is weighted by 0; 5 bytes past the
 * last pixel at most, inside FV_TW_RGB_PAD). Byte shuffles put the corners in output byte order,
 * then the reference's integer sums as c00 (128 - fx) + c10 fx (u16) and top (128 - fy) +
 * bot fy (u32): the same integers, all non-negative, so (s + 8192) >> 14 is a rounding narrow. */
static inline void tap4(const tw4 *c, uint8_t *dst, float32x4_t u, float32x4_t v)
{
    static const uint8_t k_c0[16] = {0, 1, 2, 8, 9, 10, 16, 17, 18, 24, 25, 26, 255, 255, 255, 255};
    static const uint8_t k_c1[16] = {3, 4, 5, 11, 12, 13, 19, 20, 21, 27, 28, 29, 255, 255, 255, 255};
    static const uint8_t k_fx[16] = {0, 0, 0, 4, 4, 4, 8, 8, 8, 12, 12, 12, 255, 255, 255, 255};
    static const uint8_t k_fy0[16] = {0, 255, 0, 255, 0, 255, 4, 255, 4, 255, 4, 255, 8, 255, 8, 255};
    static const uint8_t k_fy1[16] = {8, 255, 12, 255, 12, 255, 12, 255, 255, 255, 255, 255, 255, 255, 255, 255};
    const float32x4_t bu = clamp4(vsubq_f32(u, c->half), c->wm1), bv = clamp4(vsubq_f32(v, c->half), c->hm1);
    const int32x4_t x0 = vcvtq_s32_f32(bu), y0 = vcvtq_s32_f32(bv);
    const int32x4_t fx = vcvtq_s32_f32(vmulq_f32(vsubq_f32(bu, vcvtq_f32_s32(x0)), c->k128));
    const int32x4_t fy = vcvtq_s32_f32(vmulq_f32(vsubq_f32(bv, vcvtq_f32_s32(y0)), c->k128));
    const int32x4_t y1 = vsubq_s32(y0, vreinterpretq_s32_u32(vcgtq_s32(c->hm1i, y0))); /* + 1 inside */
    const int32x4_t b0 = vmulq_n_s32(x0, 3);
    const int32x4_t o0 = vmlaq_s32(b0, y0, c->rstride), o1 = vmlaq_s32(b0, y1, c->rstride);
    const uint8_t *p = c->rgb;
    const uint8x16x2_t w0 = {{vcombine_u8(vld1_u8(p + vgetq_lane_s32(o0, 0)), vld1_u8(p + vgetq_lane_s32(o0, 1))),
                              vcombine_u8(vld1_u8(p + vgetq_lane_s32(o0, 2)), vld1_u8(p + vgetq_lane_s32(o0, 3)))}};
    const uint8x16x2_t w1 = {{vcombine_u8(vld1_u8(p + vgetq_lane_s32(o1, 0)), vld1_u8(p + vgetq_lane_s32(o1, 1))),
                              vcombine_u8(vld1_u8(p + vgetq_lane_s32(o1, 2)), vld1_u8(p + vgetq_lane_s32(o1, 3)))}};
    const uint8x16_t i0 = vld1q_u8(k_c0), i1 = vld1q_u8(k_c1);
    const uint8x16_t c00 = vqtbl2q_u8(w0, i0), c10 = vqtbl2q_u8(w0, i1);
    const uint8x16_t c01 = vqtbl2q_u8(w1, i0), c11 = vqtbl2q_u8(w1, i1);
    const uint8x16_t wx1 = vqtbl1q_u8(vreinterpretq_u8_s32(fx), vld1q_u8(k_fx)), wx0 = vsubq_u8(vdupq_n_u8(128), wx1);
    const uint16x8_t top_l = vmlal_u8(vmull_u8(vget_low_u8(c00), vget_low_u8(wx0)), vget_low_u8(c10), vget_low_u8(wx1));
    const uint16x8_t top_h = vmlal_high_u8(vmull_high_u8(c00, wx0), c10, wx1);
    const uint16x8_t bot_l = vmlal_u8(vmull_u8(vget_low_u8(c01), vget_low_u8(wx0)), vget_low_u8(c11), vget_low_u8(wx1));
    const uint16x8_t bot_h = vmlal_high_u8(vmull_high_u8(c01, wx0), c11, wx1);
    /* fy per output byte as u16: bytes 0-7, then 8-11 */
    const uint16x8_t wy1l = vreinterpretq_u16_u8(vqtbl1q_u8(vreinterpretq_u8_s32(fy), vld1q_u8(k_fy0)));
    const uint16x8_t wy1h = vreinterpretq_u16_u8(vqtbl1q_u8(vreinterpretq_u8_s32(fy), vld1q_u8(k_fy1)));
    const uint16x8_t k128 = vdupq_n_u16(128), wy0l = vsubq_u16(k128, wy1l);
    const uint16x4_t wy0h = vsub_u16(vget_low_u16(k128), vget_low_u16(wy1h));
    const uint32x4_t s0 = vmlal_u16(vmull_u16(vget_low_u16(top_l), vget_low_u16(wy0l)), vget_low_u16(bot_l), vget_low_u16(wy1l));
    const uint32x4_t s1 = vmlal_high_u16(vmull_high_u16(top_l, wy0l), bot_l, wy1l);
    const uint32x4_t s2 = vmlal_u16(vmull_u16(vget_low_u16(top_h), wy0h), vget_low_u16(bot_h), vget_low_u16(wy1h));
    const uint8x8_t b01 = vmovn_u16(vrshrn_high_n_u32(vrshrn_n_u32(s0, 14), s1, 14));
    const uint16x4_t n2 = vrshrn_n_u32(s2, 14);
    const uint8x8_t b2 = vmovn_u16(vcombine_u16(n2, n2));
    vst1_u8(dst, b01);
    const uint32_t tail = vget_lane_u32(vreinterpret_u32_u8(b2), 0);
    memcpy(dst + 8, &tail, 4);
}

static int tw_row_neon(uint8_t *restrict dst, int x0, int y, int n, const fv_tw_map *m, const fv_tw_src *s)
{
    const float py = (float)y + 0.5f;
    const float r[3] = {m->a0[0] + py * m->ay[0], m->a0[1] + py * m->ay[1], m->a0[2] + py * m->ay[2]};
    tw4 c;
    c.t0 = vdupq_n_f32(m->t[0]), c.t1 = vdupq_n_f32(m->t[1]), c.t2 = vdupq_n_f32(m->t[2]);
    c.zmin = vdupq_n_f32(FV_TW_ZMIN), c.one = vdupq_n_f32(1.0f), c.denmin = vdupq_n_f32(FV_TW_DEN_MIN);
    c.wscale = vdupq_n_f32(m->w_scale), c.tol = vdupq_n_f32(m->tol);
    c.wm1 = vdupq_n_f32((float)(s->w - 1)), c.hm1 = vdupq_n_f32((float)(s->h - 1));
    c.half = vdupq_n_f32(0.5f), c.k128 = vdupq_n_f32(128.0f);
    c.hm1i = vdupq_n_s32(s->h - 1);
    c.istride = vdupq_n_s32((int32_t)s->invd_stride), c.rstride = vdupq_n_s32((int32_t)s->rgb_stride);
    c.invd = s->invd, c.rgb = s->rgb;
    const float32x4_t r0 = vdupq_n_f32(r[0]), r1 = vdupq_n_f32(r[1]), r2 = vdupq_n_f32(r[2]);
    const float32x4_t ax0 = vdupq_n_f32(m->ax[0]), ax1 = vdupq_n_f32(m->ax[1]), ax2 = vdupq_n_f32(m->ax[2]);
    static const int32_t lanes[4] = {0, 1, 2, 3};
    int holes = 0, i = 0;
    /* TW_G groups of 4 a step, each stage for all before the next (see the AVX2 version) */
#define TW_G 8
    for (int g; i + 4 <= n; i += 4 * g) {
        g = (n - i) / 4 < TW_G ? (n - i) / 4 : TW_G;
        float32x4_t A0[TW_G], A1[TW_G], A2[TW_G], u0[TW_G], v0[TW_G], u1[TW_G], v1[TW_G], u2[TW_G], v2[TW_G];
        float32x4_t w1[TW_G], w2[TW_G], w3[TW_G];
        for (int k = 0; k < g; k++) {
            const int32x4_t xi = vaddq_s32(vdupq_n_s32(x0 + i + 4 * k), vld1q_s32(lanes));
            const float32x4_t px = vaddq_f32(vcvtq_f32_s32(xi), c.half);
            A0[k] = vaddq_f32(r0, vmulq_f32(px, ax0)), A1[k] = vaddq_f32(r1, vmulq_f32(px, ax1));
            A2[k] = vaddq_f32(r2, vmulq_f32(px, ax2));
            proj4(&c, A0[k], A1[k], A2[k], vdupq_n_f32(0.0f), &u0[k], &v0[k]);
        }
        for (int k = 0; k < g; k++)
            w1[k] = fetch_w4(&c, A2[k], u0[k], v0[k]);
        for (int k = 0; k < g; k++)
            proj4(&c, A0[k], A1[k], A2[k], w1[k], &u1[k], &v1[k]);
        for (int k = 0; k < g; k++)
            w2[k] = fetch_w4(&c, A2[k], u1[k], v1[k]);
        for (int k = 0; k < g; k++)
            proj4(&c, A0[k], A1[k], A2[k], w2[k], &u2[k], &v2[k]);
        for (int k = 0; k < g; k++)
            w3[k] = fetch_w4(&c, A2[k], u2[k], v2[k]);
        for (int k = 0; k < g; k++) {
            const float32x4_t d = vabsq_f32(vsubq_f32(w3[k], w2[k])), mx = gt_sel(w3[k], w2[k]);
            const uint32x4_t dis = vcgtq_f32(d, vmulq_f32(c.tol, mx));
            const uint32x4_t first = vandq_u32(dis, vcltq_f32(w2[k], w3[k]));
            tap4(&c, dst + 3 * (i + 4 * k), vbslq_f32(first, u1[k], u2[k]), vbslq_f32(first, v1[k], v2[k]));
            holes += (int)vaddvq_u32(vshrq_n_u32(dis, 31));
        }
    }
#undef TW_G
    for (; i < n; i++) {
        const float px = (float)(x0 + i) + 0.5f;
        const float A[3] = {r[0] + px * m->ax[0], r[1] + px * m->ax[1], r[2] + px * m->ax[2]};
        holes += fv_tw_pixel(dst + 3 * i, m, s, A);
    }
    return holes;
}

/* the block warp's resample: 16 bytes a step; vqrdmulh is pmulhrsw's rounding (it saturates
 * only -32768 x -32768, which the operands never reach), the last step overlapping */
static inline uint8x16_t span16(const uint8_t *s0, const uint8_t *s1, uint8x8_t w0, uint8x8_t w1, int16x8_t wy)
{
    const uint8x16_t a = vld1q_u8(s0), b = vld1q_u8(s0 + 3), c = vld1q_u8(s1), d = vld1q_u8(s1 + 3);
    const int16x8_t h0l = vreinterpretq_s16_u16(vmlal_u8(vmull_u8(vget_low_u8(a), w0), vget_low_u8(b), w1));
    const int16x8_t h0h = vreinterpretq_s16_u16(vmlal_u8(vmull_u8(vget_high_u8(a), w0), vget_high_u8(b), w1));
    const int16x8_t h1l = vreinterpretq_s16_u16(vmlal_u8(vmull_u8(vget_low_u8(c), w0), vget_low_u8(d), w1));
    const int16x8_t h1h = vreinterpretq_s16_u16(vmlal_u8(vmull_u8(vget_high_u8(c), w0), vget_high_u8(d), w1));
    const int16x8_t vl = vaddq_s16(h0l, vqrdmulhq_s16(vsubq_s16(h1l, h0l), wy));
    const int16x8_t vh = vaddq_s16(h0h, vqrdmulhq_s16(vsubq_s16(h1h, h0h), wy));
    /* (v + 32) >> 6, v in [0, 16320] */
    return vcombine_u8(vqrshrun_n_s16(vl, 6), vqrshrun_n_s16(vh, 6));
}

/* one piece: n bytes at phase (fx, fy) from s0, s1 into o; pf: prefetched as the piece is read
 * (its bytes from pf on: the source a few rows below), or s0 */
static inline __attribute__((always_inline)) void span_piece(uint8_t *o, const uint8_t *s0, const uint8_t *s1, const uint8_t *pf, int n, int fx, int fy)
{
    const uint8x8_t w0 = vdup_n_u8((uint8_t)(64 - fx)), w1 = vdup_n_u8((uint8_t)fx);
    const int16x8_t wy = vdupq_n_s16((int16_t)(fy << 9));
    int k = 0;
    for (; k + 16 <= n; k += 16) {
        if (!(k & 63))
            __builtin_prefetch(pf + k);
        vst1q_u8(o + k, span16(s0 + k, s1 + k, w0, w1, wy));
    }
    __builtin_prefetch(pf + n + 2); /* the piece's last source byte */
    if (k < n && n >= 16) {
        vst1q_u8(o + n - 16, span16(s0 + n - 16, s1 + n - 16, w0, w1, wy));
        k = n;
    }
    for (; k < n; k++)
        o[k] = fv_tw_span_px(s0[k], s0[k + 3], s1[k], s1[k + 3], fx, fy);
}

static void tw_spans_neon(uint8_t *restrict dst, const fv_tw_piece *pieces, int count)
{
    for (int i = 0; i < count; i++) {
        const fv_tw_piece *p = &pieces[i];
        span_piece(dst + p->dst, p->s0, p->s1, p->s0, p->n, p->fx, p->fy);
    }
}

/* tw_runs' 16-byte steps of a piece: the lower row's horizontal pass kept in h for the next
 * row (reuse: this row's upper pass is there already) */
static inline __attribute__((always_inline)) void run_steps(uint8_t *o, const uint8_t *s0, const uint8_t *s1,
                                                            const uint8_t *pf, int n16, uint8x8_t w0, uint8x8_t w1,
                                                            int16x8_t wy, int16_t *h, int reuse)
{
    for (int k = 0; k < n16; k += 16) {
        if (!(k & 63))
            __builtin_prefetch(pf + k);
        int16x8_t h0l, h0h;
        if (reuse) {
            h0l = vld1q_s16(h + k), h0h = vld1q_s16(h + k + 8);
        } else {
            const uint8x16_t a = vld1q_u8(s0 + k), b = vld1q_u8(s0 + k + 3);
            h0l = vreinterpretq_s16_u16(vmlal_u8(vmull_u8(vget_low_u8(a), w0), vget_low_u8(b), w1));
            h0h = vreinterpretq_s16_u16(vmlal_u8(vmull_u8(vget_high_u8(a), w0), vget_high_u8(b), w1));
        }
        const uint8x16_t c = vld1q_u8(s1 + k), d = vld1q_u8(s1 + k + 3);
        const int16x8_t h1l = vreinterpretq_s16_u16(vmlal_u8(vmull_u8(vget_low_u8(c), w0), vget_low_u8(d), w1));
        const int16x8_t h1h = vreinterpretq_s16_u16(vmlal_u8(vmull_u8(vget_high_u8(c), w0), vget_high_u8(d), w1));
        vst1q_s16(h + k, h1l), vst1q_s16(h + k + 8, h1h);
        const int16x8_t vl = vaddq_s16(h0l, vqrdmulhq_s16(vsubq_s16(h1l, h0l), wy));
        const int16x8_t vh = vaddq_s16(h0h, vqrdmulhq_s16(vsubq_s16(h1h, h0h), wy));
        vst1q_u8(o + k, vcombine_u8(vqrshrun_n_s16(vl, 6), vqrshrun_n_s16(vh, 6)));
    }
}

/* plain stores: the intrinsics have no non-temporal store (as tw_stream_neon) */
static void tw_runs_neon(uint8_t *restrict dst, fv_tw_run *runs, int count, const uint8_t *rgb, ptrdiff_t stride,
                         ptrdiff_t pf_end, int16_t *hbuf)
{
    for (int i = 0; i < count; i++) {
        fv_tw_run *r = &runs[i];
        int fx, fy;
        int64_t off;
        const uint8_t *s0 = fv_tw_run_piece(r, rgb, stride, &fx, &fy, &off), *s1 = fy ? s0 + stride : s0;
        const uint8_t *pf = off + 4 * stride < pf_end ? s0 + 3 * stride : s0;
        const int n = r->n, n16 = n & ~15, reuse = r->hoff == off && r->hfx == fx;
        uint8_t *o = dst + r->dst;
        int16_t *h = hbuf + r->dst;
        const uint8x8_t w0 = vdup_n_u8((uint8_t)(64 - fx)), w1 = vdup_n_u8((uint8_t)fx);
        const int16x8_t wy = vdupq_n_s16((int16_t)(fy << 9));
        if (reuse)
            run_steps(o, s0, s1, pf, n16, w0, w1, wy, h, 1);
        else
            run_steps(o, s0, s1, pf, n16, w0, w1, wy, h, 0);
        r->hoff = n16 ? (fy ? off + stride : off) : -1, r->hfx = fx;
        __builtin_prefetch(pf + n + 2); /* the piece's last source byte */
        int k = n16;
        if (k < n && n >= 16) { /* the last 16 again, overlapping, without the kept pass: the same bytes */
            vst1q_u8(o + n - 16, span16(s0 + n - 16, s1 + n - 16, w0, w1, wy));
            k = n;
        }
        for (; k < n; k++)
            o[k] = fv_tw_span_px(s0[k], s0[k + 3], s1[k], s1[k + 3], fx, fy);
    }
}

static void tw_minmax_neon(const uint16_t *p, ptrdiff_t stride, int w, int h, unsigned out[2])
{
    if (w < 8) {
        fv_tw_minmax_c(p, stride, w, h, out);
        return;
    }
    uint16x8_t lo = vdupq_n_u16(65535), hi = vdupq_n_u16(0);
    for (int y = 0; y < h; y++) {
        const uint16_t *r = p + (ptrdiff_t)y * stride;
        for (int x = 0;; x += 8) {
            x = x + 8 <= w ? x : w - 8; /* the last 8 overlap: min and max do not mind */
            const uint16x8_t v = vld1q_u16(r + x);
            lo = vminq_u16(lo, v), hi = vmaxq_u16(hi, v);
            if (x + 8 >= w)
                break;
        }
    }
    out[0] = vminvq_u16(lo), out[1] = vmaxvq_u16(hi);
}

/* plain stores: the intrinsics have no non-temporal store (STNP would need assembly); n = 0
 * (the fence call) has nothing to order */
static void tw_stream_neon(uint8_t *restrict dst, const uint8_t *restrict src, int n)
{
    if (!n)
        return;
    int k = 0;
    for (; k + 16 <= n; k += 16)
        vst1q_u8(dst + k, vld1q_u8(src + k));
    memcpy(dst + k, src + k, (size_t)(n - k));
}

void fv_timewarp_dsp_init_neon(fv_timewarp_dsp *d)
{
    d->tw_stream = tw_stream_neon;
    d->tw_row = tw_row_neon;
    d->tw_spans = tw_spans_neon;
    d->tw_runs = tw_runs_neon;
    d->tw_minmax = tw_minmax_neon;
}
