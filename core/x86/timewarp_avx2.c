/* fovea: the timewarp kernel, AVX2: 8 display pixels a step, the bilinear tap in 32-bit integer
 * lanes, the bytes packed with shuffles. Same IEEE steps as the reference, in its order.
 * Source reads: gathers are slow (about 40 cycles for 8 dwords on the EPYC the project measures
 * on), and a warp's 8 neighbouring pixels mostly read neighbouring source pixels of one row, so
 * each read first tries a window: the inverse depths of 16 pixels from the first lane's, picked
 * with permutes, and the colours of 2 x 5 pixels (from the first and the fifth lane's) per row,
 * picked with byte shuffles; the gathers only where the lanes spread wider or over two rows. The
 * windows read past a row's end (into the next row, or the planes' padding: timewarp_dsp.h), so
 * the values picked are the gathers' own. */
#include <immintrin.h>
#include <string.h>

#include "timewarp_dsp.h"

typedef struct {
    __m256 t0, t1, t2, zmin, one, denmin, wscale, tol, wm1, hm1, half, k128;
    __m256i wm1i, hm1i, istride, rstride;
    const int *invd, *rgb;
    const uint8_t *rgb8;
} tw8;

static inline __m256 clamp8(__m256 v, __m256 hi) { return _mm256_min_ps(_mm256_max_ps(v, _mm256_setzero_ps()), hi); }

static inline void proj8(const tw8 *c, __m256 A0, __m256 A1, __m256 A2, __m256 w, __m256 *u, __m256 *v)
{
    const __m256 nz = _mm256_max_ps(_mm256_add_ps(A2, _mm256_mul_ps(c->t2, w)), c->zmin);
    const __m256 inv = _mm256_div_ps(c->one, nz);
    *u = _mm256_mul_ps(_mm256_add_ps(A0, _mm256_mul_ps(c->t0, w)), inv);
    *v = _mm256_mul_ps(_mm256_add_ps(A1, _mm256_mul_ps(c->t1, w)), inv);
}

static inline __m256i lane0(__m256i v) { return _mm256_broadcastd_epi32(_mm256_castsi256_si128(v)); }
static inline int all_set(__m256i m) { return _mm256_movemask_ps(_mm256_castsi256_ps(m)) == 0xff; }

/* the 16-bit inverse depths at (ix, iy) */
static inline __m256i invd8(const tw8 *c, __m256i ix, __m256i iy)
{
    const __m256i idx = _mm256_add_epi32(_mm256_mullo_epi32(iy, c->istride), ix);
    const __m256i d = _mm256_sub_epi32(ix, lane0(ix));
    const __m256i in = _mm256_and_si256(_mm256_cmpgt_epi32(d, _mm256_set1_epi32(-1)),
                                        _mm256_cmpgt_epi32(_mm256_set1_epi32(16), d));
    if (all_set(_mm256_and_si256(in, _mm256_cmpeq_epi32(iy, lane0(iy))))) {
        const uint16_t *p = (const uint16_t *)(const void *)c->invd + _mm256_cvtsi256_si32(idx);
        const __m256i w = _mm256_loadu_si256((const __m256i *)(const void *)p); /* 16 depths from lane 0's */
        const __m256i lo = _mm256_cvtepu16_epi32(_mm256_castsi256_si128(w));
        const __m256i hi = _mm256_cvtepu16_epi32(_mm256_extracti128_si256(w, 1));
        return _mm256_blendv_epi8(_mm256_permutevar8x32_epi32(lo, d), _mm256_permutevar8x32_epi32(hi, d),
                                  _mm256_cmpgt_epi32(d, _mm256_set1_epi32(7)));
    }
    return _mm256_and_si256(_mm256_i32gather_epi32(c->invd, idx, 2), _mm256_set1_epi32(0xffff));
}

static inline __m256 fetch_w8(const tw8 *c, __m256 A2, __m256 u, __m256 v)
{
    const __m256i ix = _mm256_cvttps_epi32(clamp8(u, c->wm1)), iy = _mm256_cvttps_epi32(clamp8(v, c->hm1));
    const __m256i g = invd8(c, ix, iy);
    const __m256 ws = _mm256_mul_ps(_mm256_cvtepi32_ps(g), c->wscale);
    const __m256 den = _mm256_max_ps(_mm256_sub_ps(c->one, _mm256_mul_ps(c->t2, ws)), c->denmin);
    return _mm256_div_ps(_mm256_mul_ps(A2, ws), den);
}

static inline __m256i chan(__m256i g, int sh) { return _mm256_and_si256(_mm256_srli_epi32(g, sh), _mm256_set1_epi32(255)); }

static inline __m256i lerp_chan(__m256i g00, __m256i g10, __m256i g01, __m256i g11, int sh, __m256i fx, __m256i fy)
{
    const __m256i c00 = chan(g00, sh), c10 = chan(g10, sh), c01 = chan(g01, sh), c11 = chan(g11, sh);
    const __m256i top = _mm256_add_epi32(_mm256_slli_epi32(c00, 7), _mm256_mullo_epi32(_mm256_sub_epi32(c10, c00), fx));
    const __m256i bot = _mm256_add_epi32(_mm256_slli_epi32(c01, 7), _mm256_mullo_epi32(_mm256_sub_epi32(c11, c01), fx));
    const __m256i s = _mm256_add_epi32(_mm256_slli_epi32(top, 7), _mm256_mullo_epi32(_mm256_sub_epi32(bot, top), fy));
    return _mm256_srli_epi32(_mm256_add_epi32(s, _mm256_set1_epi32(8192)), 14);
}

static inline void tap8(const tw8 *c, uint8_t *dst, __m256 u, __m256 v)
{
    const __m256 bu = clamp8(_mm256_sub_ps(u, c->half), c->wm1), bv = clamp8(_mm256_sub_ps(v, c->half), c->hm1);
    const __m256i x0 = _mm256_cvttps_epi32(bu), y0 = _mm256_cvttps_epi32(bv);
    const __m256i fx = _mm256_cvttps_epi32(_mm256_mul_ps(_mm256_sub_ps(bu, _mm256_cvtepi32_ps(x0)), c->k128));
    const __m256i fy = _mm256_cvttps_epi32(_mm256_mul_ps(_mm256_sub_ps(bv, _mm256_cvtepi32_ps(y0)), c->k128));
    const __m256i x1 = _mm256_sub_epi32(x0, _mm256_cmpgt_epi32(c->wm1i, x0)); /* + 1 inside */
    const __m256i y1 = _mm256_sub_epi32(y0, _mm256_cmpgt_epi32(c->hm1i, y0));
    __m256i g00, g10, g01, g11;
    /* the window: lanes 0-3 within 3 pixels right of lane 0's x0, lanes 4-7 of lane 4's, one row */
    const __m256i base = _mm256_permutevar8x32_epi32(x0, _mm256_setr_epi32(0, 0, 0, 0, 4, 4, 4, 4));
    const __m256i d = _mm256_sub_epi32(x0, base);
    const __m256i in = _mm256_and_si256(_mm256_cmpgt_epi32(_mm256_set1_epi32(4), d), _mm256_cmpeq_epi32(y0, lane0(y0)));
    if (all_set(in)) { /* d >= 0: lanes 0-3 and 4-7 are in order (monotonic x0) or fail below */
        const __m256i nonneg = _mm256_cmpgt_epi32(d, _mm256_set1_epi32(-1));
        if (!all_set(nonneg))
            goto gather;
        const int y = _mm256_cvtsi256_si32(y0), yb = y + (y < _mm256_cvtsi256_si32(c->hm1i));
        const int xa = _mm256_cvtsi256_si32(base), xb = _mm256_extract_epi32(base, 4);
        const uint8_t *p0 = c->rgb8 + (ptrdiff_t)y * _mm256_cvtsi256_si32(c->rstride);
        const uint8_t *p1 = c->rgb8 + (ptrdiff_t)yb * _mm256_cvtsi256_si32(c->rstride);
        const __m256i w0 = _mm256_loadu2_m128i((const __m128i *)(const void *)(p0 + 3 * xb),
                                               (const __m128i *)(const void *)(p0 + 3 * xa));
        const __m256i w1 = _mm256_loadu2_m128i((const __m128i *)(const void *)(p1 + 3 * xb),
                                               (const __m128i *)(const void *)(p1 + 3 * xa));
        /* bytes 3d .. 3d + 3 of the window for x0, 3d + 3 .. 3d + 6 for x0 + 1 */
        const __m256i d3 = _mm256_add_epi32(d, _mm256_add_epi32(d, d));
        const __m256i k0 = _mm256_add_epi32(_mm256_mullo_epi32(d3, _mm256_set1_epi32(0x01010101)),
                                            _mm256_set1_epi32(0x03020100));
        const __m256i k1 = _mm256_add_epi32(k0, _mm256_set1_epi32(0x03030303));
        g00 = _mm256_shuffle_epi8(w0, k0), g10 = _mm256_shuffle_epi8(w0, k1);
        g01 = _mm256_shuffle_epi8(w1, k0), g11 = _mm256_shuffle_epi8(w1, k1);
    } else {
    gather:;
        const __m256i r0 = _mm256_mullo_epi32(y0, c->rstride), r1 = _mm256_mullo_epi32(y1, c->rstride);
        const __m256i b0 = _mm256_add_epi32(x0, _mm256_add_epi32(x0, x0)), b1 = _mm256_add_epi32(x1, _mm256_add_epi32(x1, x1));
        g00 = _mm256_i32gather_epi32(c->rgb, _mm256_add_epi32(r0, b0), 1);
        g10 = _mm256_i32gather_epi32(c->rgb, _mm256_add_epi32(r0, b1), 1);
        g01 = _mm256_i32gather_epi32(c->rgb, _mm256_add_epi32(r1, b0), 1);
        g11 = _mm256_i32gather_epi32(c->rgb, _mm256_add_epi32(r1, b1), 1);
    }
    const __m256i px = _mm256_or_si256(
        _mm256_or_si256(lerp_chan(g00, g10, g01, g11, 0, fx, fy),
                        _mm256_slli_epi32(lerp_chan(g00, g10, g01, g11, 8, fx, fy), 8)),
        _mm256_slli_epi32(lerp_chan(g00, g10, g01, g11, 16, fx, fy), 16));
    const __m128i keep = _mm_setr_epi8(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1);
    const __m128i lo = _mm_shuffle_epi8(_mm256_castsi256_si128(px), keep);
    const __m128i hi = _mm_shuffle_epi8(_mm256_extracti128_si256(px, 1), keep);
    const int32_t tl = _mm_extract_epi32(lo, 2), th = _mm_extract_epi32(hi, 2);
    _mm_storel_epi64((__m128i *)(void *)dst, lo);
    memcpy(dst + 8, &tl, 4);
    _mm_storel_epi64((__m128i *)(void *)(dst + 12), hi);
    memcpy(dst + 20, &th, 4);
}

static int tw_row_avx2(uint8_t *restrict dst, int x0, int y, int n, const fv_tw_map *m, const fv_tw_src *s)
{
    const float py = (float)y + 0.5f;
    const float r[3] = {m->a0[0] + py * m->ay[0], m->a0[1] + py * m->ay[1], m->a0[2] + py * m->ay[2]};
    tw8 c;
    c.t0 = _mm256_set1_ps(m->t[0]), c.t1 = _mm256_set1_ps(m->t[1]), c.t2 = _mm256_set1_ps(m->t[2]);
    c.zmin = _mm256_set1_ps(FV_TW_ZMIN), c.one = _mm256_set1_ps(1.0f), c.denmin = _mm256_set1_ps(FV_TW_DEN_MIN);
    c.wscale = _mm256_set1_ps(m->w_scale), c.tol = _mm256_set1_ps(m->tol);
    c.wm1 = _mm256_set1_ps((float)(s->w - 1)), c.hm1 = _mm256_set1_ps((float)(s->h - 1));
    c.half = _mm256_set1_ps(0.5f), c.k128 = _mm256_set1_ps(128.0f);
    c.wm1i = _mm256_set1_epi32(s->w - 1), c.hm1i = _mm256_set1_epi32(s->h - 1);
    c.istride = _mm256_set1_epi32((int)s->invd_stride), c.rstride = _mm256_set1_epi32((int)s->rgb_stride);
    c.invd = (const int *)(const void *)s->invd, c.rgb = (const int *)(const void *)s->rgb, c.rgb8 = s->rgb;
    const __m256 r0 = _mm256_set1_ps(r[0]), r1 = _mm256_set1_ps(r[1]), r2 = _mm256_set1_ps(r[2]);
    const __m256 ax0 = _mm256_set1_ps(m->ax[0]), ax1 = _mm256_set1_ps(m->ax[1]), ax2 = _mm256_set1_ps(m->ax[2]);
    const __m256 sign = _mm256_set1_ps(-0.0f);
    int holes = 0, i = 0;
    /* TW_G groups of 8 a step, each stage for all before the next: one group is a chain of
     * dependent steps (three fetches, each needing the one before) too long for the core to
     * overlap with the next group's on its own */
#define TW_G 8 /* 2: 22.5 -> 16.7 ms an eye, 4: 11.4, 8: 10.5 */
    for (int g; i + 8 <= n; i += 8 * g) {
        g = (n - i) / 8 < TW_G ? (n - i) / 8 : TW_G;
        __m256 A0[TW_G], A1[TW_G], A2[TW_G], u0[TW_G], v0[TW_G], u1[TW_G], v1[TW_G], u2[TW_G], v2[TW_G];
        __m256 w1[TW_G], w2[TW_G], w3[TW_G];
        for (int k = 0; k < g; k++) {
            const __m256i xi = _mm256_add_epi32(_mm256_set1_epi32(x0 + i + 8 * k), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
            const __m256 px = _mm256_add_ps(_mm256_cvtepi32_ps(xi), c.half);
            A0[k] = _mm256_add_ps(r0, _mm256_mul_ps(px, ax0)), A1[k] = _mm256_add_ps(r1, _mm256_mul_ps(px, ax1));
            A2[k] = _mm256_add_ps(r2, _mm256_mul_ps(px, ax2));
            proj8(&c, A0[k], A1[k], A2[k], _mm256_setzero_ps(), &u0[k], &v0[k]);
        }
        for (int k = 0; k < g; k++)
            w1[k] = fetch_w8(&c, A2[k], u0[k], v0[k]);
        for (int k = 0; k < g; k++)
            proj8(&c, A0[k], A1[k], A2[k], w1[k], &u1[k], &v1[k]);
        for (int k = 0; k < g; k++)
            w2[k] = fetch_w8(&c, A2[k], u1[k], v1[k]);
        for (int k = 0; k < g; k++)
            proj8(&c, A0[k], A1[k], A2[k], w2[k], &u2[k], &v2[k]);
        for (int k = 0; k < g; k++)
            w3[k] = fetch_w8(&c, A2[k], u2[k], v2[k]);
        for (int k = 0; k < g; k++) {
            const __m256 d = _mm256_andnot_ps(sign, _mm256_sub_ps(w3[k], w2[k])), mx = _mm256_max_ps(w3[k], w2[k]);
            const __m256 dis = _mm256_cmp_ps(d, _mm256_mul_ps(c.tol, mx), _CMP_GT_OQ);
            const __m256 first = _mm256_and_ps(dis, _mm256_cmp_ps(w2[k], w3[k], _CMP_LT_OQ));
            tap8(&c, dst + 3 * (i + 8 * k), _mm256_blendv_ps(u2[k], u1[k], first), _mm256_blendv_ps(v2[k], v1[k], first));
            holes += __builtin_popcount((unsigned)_mm256_movemask_ps(dis));
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

/* the block warp's resample: 32 bytes a step (the in-lane unpacks and packs keep the order),
 * bytes of x and x + 3 interleaved so pmaddubsw applies the horizontal weights, pmulhrsw the
 * vertical phase and the final rounding; the rest in 16-byte steps, the last one overlapping */
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

/* bytes [k, n) of a piece in 16-byte steps, the last one overlapping (n >= 16), else one by one */
static inline __attribute__((always_inline)) void span_tail(uint8_t *o, const uint8_t *s0, const uint8_t *s1, int k,
                                                            int n, int fx, int fy)
{
    const __m128i wx = _mm_set1_epi16((short)(fx << 8 | (64 - fx))), wy = _mm_set1_epi16((short)(fy << 9));
    const __m128i k512 = _mm_set1_epi16(512);
    for (; k + 16 <= n; k += 16)
        _mm_storeu_si128((__m128i *)(void *)(o + k), span16(s0 + k, s1 + k, wx, wy, k512));
    if (k < n && n >= 16) { /* the last 16 again, overlapping: the same bytes */
        _mm_storeu_si128((__m128i *)(void *)(o + n - 16), span16(s0 + n - 16, s1 + n - 16, wx, wy, k512));
        k = n;
    }
    for (; k < n; k++)
        o[k] = fv_tw_span_px(s0[k], s0[k + 3], s1[k], s1[k + 3], fx, fy);
}

/* one piece: n bytes at phase (fx, fy) from s0, s1 into o; pf: prefetched as the piece is read
 * (its bytes from pf on: the source a few rows below), or s0 */
static inline __attribute__((always_inline)) void span_piece(uint8_t *o, const uint8_t *s0, const uint8_t *s1, const uint8_t *pf, int n, int fx, int fy)
{
    const __m256i k512 = _mm256_set1_epi16(512);
    const __m256i wx = _mm256_set1_epi16((short)(fx << 8 | (64 - fx))), wy = _mm256_set1_epi16((short)(fy << 9));
    int k = 0;
    for (; k + 32 <= n; k += 32) {
        _mm_prefetch((const char *)(pf + k), _MM_HINT_T0);
        const __m256i a = _mm256_loadu_si256((const __m256i *)(const void *)(s0 + k));
        const __m256i b = _mm256_loadu_si256((const __m256i *)(const void *)(s0 + k + 3));
        const __m256i c = _mm256_loadu_si256((const __m256i *)(const void *)(s1 + k));
        const __m256i e = _mm256_loadu_si256((const __m256i *)(const void *)(s1 + k + 3));
        const __m256i h0l = _mm256_maddubs_epi16(_mm256_unpacklo_epi8(a, b), wx);
        const __m256i h0h = _mm256_maddubs_epi16(_mm256_unpackhi_epi8(a, b), wx);
        const __m256i h1l = _mm256_maddubs_epi16(_mm256_unpacklo_epi8(c, e), wx);
        const __m256i h1h = _mm256_maddubs_epi16(_mm256_unpackhi_epi8(c, e), wx);
        const __m256i vl = _mm256_add_epi16(h0l, _mm256_mulhrs_epi16(_mm256_sub_epi16(h1l, h0l), wy));
        const __m256i vh = _mm256_add_epi16(h0h, _mm256_mulhrs_epi16(_mm256_sub_epi16(h1h, h0h), wy));
        _mm256_storeu_si256((__m256i *)(void *)(o + k),
                            _mm256_packus_epi16(_mm256_mulhrs_epi16(vl, k512), _mm256_mulhrs_epi16(vh, k512)));
    }
    _mm_prefetch((const char *)(pf + n + 2), _MM_HINT_T0); /* the piece's last source byte */
    if (k < n)
        span_tail(o, s0, s1, k, n, fx, fy);
}

static void tw_spans_avx2(uint8_t *restrict dst, const fv_tw_piece *pieces, int count)
{
    for (int i = 0; i < count; i++) {
        const fv_tw_piece *p = &pieces[i];
        span_piece(dst + p->dst, p->s0, p->s1, p->s0, p->n, p->fx, p->fy);
    }
}

/* tw_runs' 32-byte steps of a piece: the lower row's horizontal pass kept in h for the next
 * row (reuse: this row's upper pass is there already) */
static inline __attribute__((always_inline)) void run_steps(uint8_t *o, const uint8_t *s0, const uint8_t *s1,
                                                            const uint8_t *pf, int n32, __m256i wx, __m256i wy,
                                                            int16_t *h, int reuse)
{
    const __m256i k512 = _mm256_set1_epi16(512);
    for (int k = 0; k < n32; k += 32) {
        _mm_prefetch((const char *)(pf + k), _MM_HINT_T0);
        __m256i h0l, h0h;
        if (reuse) {
            h0l = _mm256_loadu_si256((const __m256i *)(const void *)(h + k));
            h0h = _mm256_loadu_si256((const __m256i *)(const void *)(h + k + 16));
        } else {
            const __m256i a = _mm256_loadu_si256((const __m256i *)(const void *)(s0 + k));
            const __m256i b = _mm256_loadu_si256((const __m256i *)(const void *)(s0 + k + 3));
            h0l = _mm256_maddubs_epi16(_mm256_unpacklo_epi8(a, b), wx);
            h0h = _mm256_maddubs_epi16(_mm256_unpackhi_epi8(a, b), wx);
        }
        const __m256i c = _mm256_loadu_si256((const __m256i *)(const void *)(s1 + k));
        const __m256i e = _mm256_loadu_si256((const __m256i *)(const void *)(s1 + k + 3));
        const __m256i h1l = _mm256_maddubs_epi16(_mm256_unpacklo_epi8(c, e), wx);
        const __m256i h1h = _mm256_maddubs_epi16(_mm256_unpackhi_epi8(c, e), wx);
        _mm256_storeu_si256((__m256i *)(void *)(h + k), h1l);
        _mm256_storeu_si256((__m256i *)(void *)(h + k + 16), h1h);
        const __m256i vl = _mm256_add_epi16(h0l, _mm256_mulhrs_epi16(_mm256_sub_epi16(h1l, h0l), wy));
        const __m256i vh = _mm256_add_epi16(h0h, _mm256_mulhrs_epi16(_mm256_sub_epi16(h1h, h0h), wy));
        const __m256i v = _mm256_packus_epi16(_mm256_mulhrs_epi16(vl, k512), _mm256_mulhrs_epi16(vh, k512));
        _mm256_storeu_si256((__m256i *)(void *)(o + k), v);
    }
}

/* one 16-byte step at k, as run_steps (a grid cell's 48 bytes: 32 + 16) */
static inline __attribute__((always_inline)) void run_step16(uint8_t *o, const uint8_t *s0, const uint8_t *s1, int k,
                                                             __m256i wx, __m256i wy, int16_t *h, int reuse)
{
    const __m128i wx4 = _mm256_castsi256_si128(wx), wy4 = _mm256_castsi256_si128(wy), k512 = _mm_set1_epi16(512);
    __m128i h0l, h0h;
    if (reuse) {
        h0l = _mm_loadu_si128((const __m128i *)(const void *)(h + k));
        h0h = _mm_loadu_si128((const __m128i *)(const void *)(h + k + 8));
    } else {
        const __m128i a = _mm_loadu_si128((const __m128i *)(const void *)(s0 + k));
        const __m128i b = _mm_loadu_si128((const __m128i *)(const void *)(s0 + k + 3));
        h0l = _mm_maddubs_epi16(_mm_unpacklo_epi8(a, b), wx4), h0h = _mm_maddubs_epi16(_mm_unpackhi_epi8(a, b), wx4);
    }
    const __m128i c = _mm_loadu_si128((const __m128i *)(const void *)(s1 + k));
    const __m128i d = _mm_loadu_si128((const __m128i *)(const void *)(s1 + k + 3));
    const __m128i h1l = _mm_maddubs_epi16(_mm_unpacklo_epi8(c, d), wx4), h1h = _mm_maddubs_epi16(_mm_unpackhi_epi8(c, d), wx4);
    _mm_storeu_si128((__m128i *)(void *)(h + k), h1l);
    _mm_storeu_si128((__m128i *)(void *)(h + k + 8), h1h);
    const __m128i vl = _mm_add_epi16(h0l, _mm_mulhrs_epi16(_mm_sub_epi16(h1l, h0l), wy4));
    const __m128i vh = _mm_add_epi16(h0h, _mm_mulhrs_epi16(_mm_sub_epi16(h1h, h0h), wy4));
    _mm_storeu_si128((__m128i *)(void *)(o + k), _mm_packus_epi16(_mm_mulhrs_epi16(vl, k512), _mm_mulhrs_epi16(vh, k512)));
}

/* the last bytes of a run's piece (off the 16-byte steps: rare, out of the loop's registers) */
static __attribute__((noinline)) void run_tail(uint8_t *o, const uint8_t *s0, const uint8_t *s1, int k, int n, int fx,
                                               int fy)
{
    span_tail(o, s0, s1, k, n, fx, fy);
}

static void tw_runs_avx2(uint8_t *restrict dst, fv_tw_run *runs, int count, const uint8_t *rgb, ptrdiff_t stride,
                         ptrdiff_t pf_end, int16_t *hbuf)
{
    const int64_t pf_lim = (int64_t)pf_end - 4 * (int64_t)stride, pf_d = 3 * (int64_t)stride;
    for (fv_tw_run *r = runs, *e = runs + count; r < e; r++) {
        int fx, fy;
        int64_t off;
        const uint8_t *s0 = fv_tw_run_piece(r, rgb, stride, &fx, &fy, &off), *s1 = s0 + (fy ? stride : 0);
        const uint8_t *pf = s0 + (off < pf_lim ? pf_d : 0);
        const int n = r->n, n32 = n & ~31, n16 = n & ~15, reuse = (r->hoff == off) & (r->hfx == fx);
        r->hoff = n16 ? off + (fy ? stride : 0) : -1, r->hfx = fx;
        uint8_t *o = dst + r->dst;
        int16_t *h = hbuf + r->dst;
        const __m256i wx = _mm256_set1_epi16((short)(fx * 255 + 64)), wy = _mm256_set1_epi16((short)(fy << 9));
        if (reuse) {
            run_steps(o, s0, s1, pf, n32, wx, wy, h, 1);
            if (n16 > n32)
                run_step16(o, s0, s1, n32, wx, wy, h, 1);
        } else {
            run_steps(o, s0, s1, pf, n32, wx, wy, h, 0);
            if (n16 > n32)
                run_step16(o, s0, s1, n32, wx, wy, h, 0);
        }
        _mm_prefetch((const char *)(pf + n + 2), _MM_HINT_T0); /* the piece's last source byte */
        if (n16 < n)
            run_tail(o, s0, s1, n16, n, fx, fy);
    }
}

static void tw_minmax_avx2(const uint16_t *p, ptrdiff_t stride, int w, int h, unsigned out[2])
{
    if (w < 16) {
        fv_tw_minmax_c(p, stride, w, h, out);
        return;
    }
    __m256i lo = _mm256_set1_epi16(-1), hi = _mm256_setzero_si256();
    for (int y = 0; y < h; y++) {
        const uint16_t *r = p + (ptrdiff_t)y * stride;
        for (int x = 0;; x += 16) {
            x = x + 16 <= w ? x : w - 16; /* the last 16 overlap: min and max do not mind */
            const __m256i v = _mm256_loadu_si256((const __m256i *)(const void *)(r + x));
            lo = _mm256_min_epu16(lo, v), hi = _mm256_max_epu16(hi, v);
            if (x + 16 >= w)
                break;
        }
    }
    const __m128i l = _mm_min_epu16(_mm256_castsi256_si128(lo), _mm256_extracti128_si256(lo, 1));
    const __m128i g = _mm_max_epu16(_mm256_castsi256_si128(hi), _mm256_extracti128_si256(hi, 1));
    out[0] = (unsigned)_mm_cvtsi128_si32(_mm_minpos_epu16(l)) & 0xffff;
    out[1] = 65535u - ((unsigned)_mm_cvtsi128_si32(_mm_minpos_epu16(_mm_xor_si128(g, _mm_set1_epi16(-1)))) & 0xffff);
}

static void tw_stream_avx2(uint8_t *restrict dst, const uint8_t *restrict src, int n)
{
    if (!n) {
        _mm_sfence();
        return;
    }
    int k = (int)((32 - ((uintptr_t)dst & 31)) & 31);
    k = k < n ? k : n;
    memcpy(dst, src, (size_t)k);
    for (; k + 32 <= n; k += 32)
        _mm256_stream_si256((__m256i *)(void *)(dst + k), _mm256_loadu_si256((const __m256i *)(const void *)(src + k)));
    memcpy(dst + k, src + k, (size_t)(n - k));
}

void fv_timewarp_dsp_init_avx2(fv_timewarp_dsp *d)
{
    d->tw_stream = tw_stream_avx2;
    d->tw_row = tw_row_avx2;
    d->tw_spans = tw_spans_avx2;
    d->tw_runs = tw_runs_avx2;
    d->tw_minmax = tw_minmax_avx2;
}
