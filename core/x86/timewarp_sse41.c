/* fovea: the timewarp kernel, SSE4.1: 4 display pixels a step, the float steps in vector code,
 * the source reads per lane (SSE4.1 has no gather), the bilinear tap in 32-bit integer lanes.
 * Same IEEE steps as the reference, in its order. */
#include <smmintrin.h>
#include <string.h>

#include "timewarp_dsp.h"

typedef struct {
    __m128 t0, t1, t2, zmin, one, denmin, wscale, tol, wm1, hm1, half, k128;
    __m128i wm1i, hm1i, istride, rstride;
    const uint16_t *invd;
    const uint8_t *rgb;
} tw4;

static inline __m128 clamp4(__m128 v, __m128 hi) { return _mm_min_ps(_mm_max_ps(v, _mm_setzero_ps()), hi); }

static inline void proj4(const tw4 *c, __m128 A0, __m128 A1, __m128 A2, __m128 w, __m128 *u, __m128 *v)
{
    const __m128 nz = _mm_max_ps(_mm_add_ps(A2, _mm_mul_ps(c->t2, w)), c->zmin);
    const __m128 inv = _mm_div_ps(c->one, nz);
    *u = _mm_mul_ps(_mm_add_ps(A0, _mm_mul_ps(c->t0, w)), inv);
    *v = _mm_mul_ps(_mm_add_ps(A1, _mm_mul_ps(c->t1, w)), inv);
}

static inline __m128i gather_u16(const uint16_t *p, __m128i i)
{
    return _mm_setr_epi32(p[_mm_cvtsi128_si32(i)], p[_mm_extract_epi32(i, 1)], p[_mm_extract_epi32(i, 2)],
                          p[_mm_extract_epi32(i, 3)]);
}
static inline int32_t word_at(const uint8_t *p)
{
    int32_t v;
    memcpy(&v, p, 4);
    return v;
}
static inline __m128i gather_w32(const uint8_t *p, __m128i o)
{
    return _mm_setr_epi32(word_at(p + _mm_cvtsi128_si32(o)), word_at(p + _mm_extract_epi32(o, 1)),
                          word_at(p + _mm_extract_epi32(o, 2)), word_at(p + _mm_extract_epi32(o, 3)));
}

static inline __m128 fetch_w4(const tw4 *c, __m128 A2, __m128 u, __m128 v)
{
    const __m128i ix = _mm_cvttps_epi32(clamp4(u, c->wm1)), iy = _mm_cvttps_epi32(clamp4(v, c->hm1));
    const __m128i g = gather_u16(c->invd, _mm_add_epi32(_mm_mullo_epi32(iy, c->istride), ix));
    const __m128 ws = _mm_mul_ps(_mm_cvtepi32_ps(g), c->wscale);
    const __m128 den = _mm_max_ps(_mm_sub_ps(c->one, _mm_mul_ps(c->t2, ws)), c->denmin);
    return _mm_div_ps(_mm_mul_ps(A2, ws), den);
}

static inline __m128i chan(__m128i g, int sh) { return _mm_and_si128(_mm_srli_epi32(g, sh), _mm_set1_epi32(255)); }

static inline __m128i lerp_chan(__m128i g00, __m128i g10, __m128i g01, __m128i g11, int sh, __m128i fx, __m128i fy)
{
    const __m128i c00 = chan(g00, sh), c10 = chan(g10, sh), c01 = chan(g01, sh), c11 = chan(g11, sh);
    const __m128i top = _mm_add_epi32(_mm_slli_epi32(c00, 7), _mm_mullo_epi32(_mm_sub_epi32(c10, c00), fx));
    const __m128i bot = _mm_add_epi32(_mm_slli_epi32(c01, 7), _mm_mullo_epi32(_mm_sub_epi32(c11, c01), fx));
    const __m128i s = _mm_add_epi32(_mm_slli_epi32(top, 7), _mm_mullo_epi32(_mm_sub_epi32(bot, top), fy));
    return _mm_srli_epi32(_mm_add_epi32(s, _mm_set1_epi32(8192)), 14);
}

static inline void tap4(const tw4 *c, uint8_t *dst, __m128 u, __m128 v)
{
    const __m128 bu = clamp4(_mm_sub_ps(u, c->half), c->wm1), bv = clamp4(_mm_sub_ps(v, c->half), c->hm1);
    const __m128i x0 = _mm_cvttps_epi32(bu), y0 = _mm_cvttps_epi32(bv);
    const __m128i fx = _mm_cvttps_epi32(_mm_mul_ps(_mm_sub_ps(bu, _mm_cvtepi32_ps(x0)), c->k128));
    const __m128i fy = _mm_cvttps_epi32(_mm_mul_ps(_mm_sub_ps(bv, _mm_cvtepi32_ps(y0)), c->k128));
    const __m128i x1 = _mm_sub_epi32(x0, _mm_cmpgt_epi32(c->wm1i, x0)); /* + 1 inside */
    const __m128i y1 = _mm_sub_epi32(y0, _mm_cmpgt_epi32(c->hm1i, y0));
    const __m128i r0 = _mm_mullo_epi32(y0, c->rstride), r1 = _mm_mullo_epi32(y1, c->rstride);
    const __m128i b0 = _mm_add_epi32(x0, _mm_add_epi32(x0, x0)), b1 = _mm_add_epi32(x1, _mm_add_epi32(x1, x1));
    const __m128i g00 = gather_w32(c->rgb, _mm_add_epi32(r0, b0)), g10 = gather_w32(c->rgb, _mm_add_epi32(r0, b1));
    const __m128i g01 = gather_w32(c->rgb, _mm_add_epi32(r1, b0)), g11 = gather_w32(c->rgb, _mm_add_epi32(r1, b1));
    const __m128i px = _mm_or_si128(_mm_or_si128(lerp_chan(g00, g10, g01, g11, 0, fx, fy),
                                                 _mm_slli_epi32(lerp_chan(g00, g10, g01, g11, 8, fx, fy), 8)),
                                    _mm_slli_epi32(lerp_chan(g00, g10, g01, g11, 16, fx, fy), 16));
    const __m128i keep = _mm_setr_epi8(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1);
    const __m128i b = _mm_shuffle_epi8(px, keep);
    const int32_t t = _mm_extract_epi32(b, 2);
    _mm_storel_epi64((__m128i *)(void *)dst, b);
    memcpy(dst + 8, &t, 4);
}

static int tw_row_sse41(uint8_t *restrict dst, int x0, int y, int n, const fv_tw_map *m, const fv_tw_src *s)
{
    const float py = (float)y + 0.5f;
    const float r[3] = {m->a0[0] + py * m->ay[0], m->a0[1] + py * m->ay[1], m->a0[2] + py * m->ay[2]};
    tw4 c;
    c.t0 = _mm_set1_ps(m->t[0]), c.t1 = _mm_set1_ps(m->t[1]), c.t2 = _mm_set1_ps(m->t[2]);
    c.zmin = _mm_set1_ps(FV_TW_ZMIN), c.one = _mm_set1_ps(1.0f), c.denmin = _mm_set1_ps(FV_TW_DEN_MIN);
    c.wscale = _mm_set1_ps(m->w_scale), c.tol = _mm_set1_ps(m->tol);
    c.wm1 = _mm_set1_ps((float)(s->w - 1)), c.hm1 = _mm_set1_ps((float)(s->h - 1));
    c.half = _mm_set1_ps(0.5f), c.k128 = _mm_set1_ps(128.0f);
    c.wm1i = _mm_set1_epi32(s->w - 1), c.hm1i = _mm_set1_epi32(s->h - 1);
    c.istride = _mm_set1_epi32((int)s->invd_stride), c.rstride = _mm_set1_epi32((int)s->rgb_stride);
    c.invd = s->invd, c.rgb = s->rgb;
    const __m128 r0 = _mm_set1_ps(r[0]), r1 = _mm_set1_ps(r[1]), r2 = _mm_set1_ps(r[2]);
    const __m128 ax0 = _mm_set1_ps(m->ax[0]), ax1 = _mm_set1_ps(m->ax[1]), ax2 = _mm_set1_ps(m->ax[2]);
    const __m128 sign = _mm_set1_ps(-0.0f);
    int holes = 0, i = 0;
    /* TW_G groups of 4 a step, each stage for all before the next (see the AVX2 version) */
#define TW_G 8
    for (int g; i + 4 <= n; i += 4 * g) {
        g = (n - i) / 4 < TW_G ? (n - i) / 4 : TW_G;
        __m128 A0[TW_G], A1[TW_G], A2[TW_G], u0[TW_G], v0[TW_G], u1[TW_G], v1[TW_G], u2[TW_G], v2[TW_G];
        __m128 w1[TW_G], w2[TW_G], w3[TW_G];
        for (int k = 0; k < g; k++) {
            const __m128i xi = _mm_add_epi32(_mm_set1_epi32(x0 + i + 4 * k), _mm_setr_epi32(0, 1, 2, 3));
            const __m128 px = _mm_add_ps(_mm_cvtepi32_ps(xi), c.half);
            A0[k] = _mm_add_ps(r0, _mm_mul_ps(px, ax0)), A1[k] = _mm_add_ps(r1, _mm_mul_ps(px, ax1));
            A2[k] = _mm_add_ps(r2, _mm_mul_ps(px, ax2));
            proj4(&c, A0[k], A1[k], A2[k], _mm_setzero_ps(), &u0[k], &v0[k]);
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
            const __m128 d = _mm_andnot_ps(sign, _mm_sub_ps(w3[k], w2[k])), mx = _mm_max_ps(w3[k], w2[k]);
            const __m128 dis = _mm_cmpgt_ps(d, _mm_mul_ps(c.tol, mx));
            const __m128 first = _mm_and_ps(dis, _mm_cmplt_ps(w2[k], w3[k]));
            tap4(&c, dst + 3 * (i + 4 * k), _mm_blendv_ps(u2[k], u1[k], first), _mm_blendv_ps(v2[k], v1[k], first));
            holes += __builtin_popcount((unsigned)_mm_movemask_ps(dis));
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

/* the block warp's resample: 16 bytes a step, bytes of x and x + 3 interleaved so pmaddubsw
 * applies the horizontal weights, pmulhrsw the vertical phase and the final rounding */
static inline __m128i span16(const uint8_t *s0, const uint8_t *s1, __m128i wx, __m128i wy, __m128i k512)
{
    const __m128i a = _mm_loadu_si128((const __m128i *)(const void *)s0);
    const __m128i b = _mm_loadu_si128((const __m128i *)(const void *)(s0 + 3));
    const __m128i c = _mm_loadu_si128((const __m128i *)(const void *)s1);
    const __m128i d = _mm_loadu_si128((const __m128i *)(const void *)(s1 + 3));
    const __m128i h0l = _mm_maddubs_epi16(_mm_unpacklo_epi8(a, b), wx), h0h = _mm_maddubs_epi16(_mm_unpackhi_epi8(a, b), wx);
    const __m128i h1l = _mm_maddubs_epi16(_mm_unpacklo_epi8(c, d), wx), h1h = _mm_maddubs_epi16(_mm_unpackhi_epi8(c, d), wx);
    const __m128i vl = _mm_add_epi16(h0l, _mm_mulhrs_epi16(_mm_sub_epi16(h1l, h0l), wy));
    const __m128i vh = _mm_add_epi16(h0h, _mm_mulhrs_epi16(_mm_sub_epi16(h1h, h0h), wy));
    return _mm_packus_epi16(_mm_mulhrs_epi16(vl, k512), _mm_mulhrs_epi16(vh, k512));
}

/* one piece: n bytes at phase (fx, fy) from s0, s1 into o; pf: prefetched as the piece is read
 * (its bytes from pf on: the source a few rows below), or s0 */
static inline __attribute__((always_inline)) void span_piece(uint8_t *o, const uint8_t *s0, const uint8_t *s1, const uint8_t *pf, int n, int fx, int fy)
{
    const __m128i k512 = _mm_set1_epi16(512);
    const __m128i wx = _mm_set1_epi16((short)(fx << 8 | (64 - fx))), wy = _mm_set1_epi16((short)(fy << 9));
    int k = 0;
    for (; k + 16 <= n; k += 16) {
        if (!(k & 63))
            _mm_prefetch((const char *)(pf + k), _MM_HINT_T0);
        _mm_storeu_si128((__m128i *)(void *)(o + k), span16(s0 + k, s1 + k, wx, wy, k512));
    }
    _mm_prefetch((const char *)(pf + n + 2), _MM_HINT_T0); /* the piece's last source byte */
    if (n >= 16 && k < n) { /* the last 16 again, overlapping: the bytes are the same */
        k = n - 16;
        _mm_storeu_si128((__m128i *)(void *)(o + k), span16(s0 + k, s1 + k, wx, wy, k512));
        k = n;
    }
    for (; k < n; k++)
        o[k] = fv_tw_span_px(s0[k], s0[k + 3], s1[k], s1[k + 3], fx, fy);
}

static void tw_spans_sse41(uint8_t *restrict dst, const fv_tw_piece *pieces, int count)
{
    for (int i = 0; i < count; i++) {
        const fv_tw_piece *p = &pieces[i];
        span_piece(dst + p->dst, p->s0, p->s1, p->s0, p->n, p->fx, p->fy);
    }
}

/* tw_runs' 16-byte steps of a piece: the lower row's horizontal pass kept in h for the next
 * row (reuse: this row's upper pass is there already) */
static inline __attribute__((always_inline)) void run_steps(uint8_t *o, const uint8_t *s0, const uint8_t *s1,
                                                            const uint8_t *pf, int n16, __m128i wx, __m128i wy,
                                                            int16_t *h, int reuse)
{
    const __m128i k512 = _mm_set1_epi16(512);
    for (int k = 0; k < n16; k += 16) {
        if (!(k & 63))
            _mm_prefetch((const char *)(pf + k), _MM_HINT_T0);
        __m128i h0l, h0h;
        if (reuse) {
            h0l = _mm_loadu_si128((const __m128i *)(const void *)(h + k));
            h0h = _mm_loadu_si128((const __m128i *)(const void *)(h + k + 8));
        } else {
            const __m128i a = _mm_loadu_si128((const __m128i *)(const void *)(s0 + k));
            const __m128i b = _mm_loadu_si128((const __m128i *)(const void *)(s0 + k + 3));
            h0l = _mm_maddubs_epi16(_mm_unpacklo_epi8(a, b), wx), h0h = _mm_maddubs_epi16(_mm_unpackhi_epi8(a, b), wx);
        }
        const __m128i c = _mm_loadu_si128((const __m128i *)(const void *)(s1 + k));
        const __m128i d = _mm_loadu_si128((const __m128i *)(const void *)(s1 + k + 3));
        const __m128i h1l = _mm_maddubs_epi16(_mm_unpacklo_epi8(c, d), wx), h1h = _mm_maddubs_epi16(_mm_unpackhi_epi8(c, d), wx);
        _mm_storeu_si128((__m128i *)(void *)(h + k), h1l);
        _mm_storeu_si128((__m128i *)(void *)(h + k + 8), h1h);
        const __m128i vl = _mm_add_epi16(h0l, _mm_mulhrs_epi16(_mm_sub_epi16(h1l, h0l), wy));
        const __m128i vh = _mm_add_epi16(h0h, _mm_mulhrs_epi16(_mm_sub_epi16(h1h, h0h), wy));
        const __m128i v = _mm_packus_epi16(_mm_mulhrs_epi16(vl, k512), _mm_mulhrs_epi16(vh, k512));
        _mm_storeu_si128((__m128i *)(void *)(o + k), v);
    }
}

static void tw_runs_sse41(uint8_t *restrict dst, fv_tw_run *runs, int count, const uint8_t *rgb, ptrdiff_t stride,
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
        const __m128i wx = _mm_set1_epi16((short)(fx << 8 | (64 - fx))), wy = _mm_set1_epi16((short)(fy << 9));
        if (reuse)
            run_steps(o, s0, s1, pf, n16, wx, wy, h, 1);
        else
            run_steps(o, s0, s1, pf, n16, wx, wy, h, 0);
        r->hoff = n16 ? (fy ? off + stride : off) : -1, r->hfx = fx;
        _mm_prefetch((const char *)(pf + n + 2), _MM_HINT_T0); /* the piece's last source byte */
        int k = n16;
        if (k < n && n >= 16) { /* the last 16 again, overlapping, without the kept pass: the same bytes */
            _mm_storeu_si128((__m128i *)(void *)(o + n - 16), span16(s0 + n - 16, s1 + n - 16, wx, wy, _mm_set1_epi16(512)));
            k = n;
        }
        for (; k < n; k++)
            o[k] = fv_tw_span_px(s0[k], s0[k + 3], s1[k], s1[k + 3], fx, fy);
    }
}

static void tw_minmax_sse41(const uint16_t *p, ptrdiff_t stride, int w, int h, unsigned out[2])
{
    if (w < 8) {
        fv_tw_minmax_c(p, stride, w, h, out);
        return;
    }
    __m128i lo = _mm_set1_epi16(-1), hi = _mm_setzero_si128();
    for (int y = 0; y < h; y++) {
        const uint16_t *r = p + (ptrdiff_t)y * stride;
        for (int x = 0;; x += 8) {
            x = x + 8 <= w ? x : w - 8; /* the last 8 overlap: min and max do not mind */
            const __m128i v = _mm_loadu_si128((const __m128i *)(const void *)(r + x));
            lo = _mm_min_epu16(lo, v), hi = _mm_max_epu16(hi, v);
            if (x + 8 >= w)
                break;
        }
    }
    /* minpos gives the least of 8 u16; the greatest is the least of the complements */
    out[0] = (unsigned)_mm_cvtsi128_si32(_mm_minpos_epu16(lo)) & 0xffff;
    out[1] = 65535u - ((unsigned)_mm_cvtsi128_si32(_mm_minpos_epu16(_mm_xor_si128(hi, _mm_set1_epi16(-1)))) & 0xffff);
}

static void tw_stream_sse41(uint8_t *restrict dst, const uint8_t *restrict src, int n)
{
    if (!n) {
        _mm_sfence();
        return;
    }
    int k = (int)((16 - ((uintptr_t)dst & 15)) & 15);
    k = k < n ? k : n;
    memcpy(dst, src, (size_t)k);
    for (; k + 16 <= n; k += 16)
        _mm_stream_si128((__m128i *)(void *)(dst + k), _mm_loadu_si128((const __m128i *)(const void *)(src + k)));
    memcpy(dst + k, src + k, (size_t)(n - k));
}

void fv_timewarp_dsp_init_sse41(fv_timewarp_dsp *d)
{
    d->tw_stream = tw_stream_sse41;
    d->tw_row = tw_row_sse41;
    d->tw_spans = tw_spans_sse41;
    d->tw_runs = tw_runs_sse41;
    d->tw_minmax = tw_minmax_sse41;
}
