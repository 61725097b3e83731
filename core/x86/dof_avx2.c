/* fovea: depth-of-field kernels, AVX2 (built with -mavx2 -mfma but -ffp-contract=off and no FMA
 * intrinsics). The CoC takes 8 pixels at a time; the Gaussians 8 output pixels at a time as four
 * 256-bit accumulators of two pixels each (each 128-bit half with its own pixel's weights), the
 * rest with the 128-bit pieces of core/x86/dof_tmpl.h, which also has why the bits are the
 * references'. The combine takes 8 pixels at a time without branches (see there); the
 * up-sampling and the periphery's level blend 8 at a time as 4 pixel pairs. */
#include <immintrin.h>
#include <string.h>

#define FV_X86_W 8
#define FV_X86_FN(name) name##_avx2
#include "x86/dof_tmpl.h"

static void coc_row_avx2(float *restrict coc, const float *rgbd, int n, float K, float dn, float df)
{
    const __m256 vK = _mm256_set1_ps(K), idn = _mm256_set1_ps(1.0f / dn), idf = _mm256_set1_ps(1.0f / df);
    const __m256 vdn = _mm256_set1_ps(dn), vdf = _mm256_set1_ps(df), one = _mm256_set1_ps(1.0f);
    const __m256 lo = _mm256_set1_ps(FV_COC_MIN_DEPTH_M);
    const __m256i order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
    int x = 0;
    for (; x + 8 <= n; x += 8) {
        const float *p = rgbd + 4 * x;
        /* depths: (d0 d2 d4 d6 | d1 d3 d5 d7), then in order */
        const __m256 h0 = _mm256_unpackhi_ps(_mm256_loadu_ps(p), _mm256_loadu_ps(p + 8));
        const __m256 h1 = _mm256_unpackhi_ps(_mm256_loadu_ps(p + 16), _mm256_loadu_ps(p + 24));
        const __m256 d = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(h0, h1, _MM_SHUFFLE(3, 2, 3, 2)), order);
        const __m256 g = _mm256_max_ps(d, lo); /* d > min ? d : min */
        const __m256 ig = _mm256_div_ps(one, g);
        const __m256 nr = _mm256_mul_ps(vK, _mm256_sub_ps(idn, ig));
        const __m256 fr = _mm256_and_ps(_mm256_mul_ps(vK, _mm256_sub_ps(idf, ig)), _mm256_cmp_ps(g, vdf, _CMP_GT_OQ));
        _mm256_storeu_ps(coc + x, _mm256_blendv_ps(fr, nr, _mm256_cmp_ps(g, vdn, _CMP_LT_OQ)));
    }
    if (x + 4 <= n) {
        const dof_coc4_k k = dof_coc4_setup(K, dn, df);
        _mm_storeu_ps(coc + x, dof_coc4(dof_depth4(rgbd + 4 * x), &k));
        x += 4;
    }
    if (x < n)
        fv_dof_coc_row_c(coc + x, rgbd + 4 * x, n - x, K, dn, df);
}

/* weights of a pixel pair: wa[k] in the low half, wb[k] in the high half */
static inline __m256 wpair(const float *wa, const float *wb, int k)
{
    return _mm256_blend_ps(_mm256_broadcast_ss(wa + k), _mm256_broadcast_ss(wb + k), 0xf0);
}

/* 8 neighbouring pixels (pairs in the halves of 4 accumulators), the block's largest radius R. */
static inline void g8(__m256 a[4], const float *p, const ptrdiff_t *off, const float *const wt[8], int R)
{
    __m256 a0 = _mm256_setzero_ps(), a1 = a0, a2 = a0, a3 = a0;
    int one = 1;
    for (int k = 1; k < 8; k++)
        one &= wt[k] == wt[0];
    if (one) { /* one sigma: one broadcast a tap */
        for (int j = -R; j <= R; j++) {
            const float *q = p + off[j];
            const __m256 g = _mm256_broadcast_ss(wt[0] + (j < 0 ? -j : j));
            a0 = _mm256_add_ps(a0, _mm256_mul_ps(g, _mm256_loadu_ps(q)));
            a1 = _mm256_add_ps(a1, _mm256_mul_ps(g, _mm256_loadu_ps(q + 8)));
            a2 = _mm256_add_ps(a2, _mm256_mul_ps(g, _mm256_loadu_ps(q + 16)));
            a3 = _mm256_add_ps(a3, _mm256_mul_ps(g, _mm256_loadu_ps(q + 24)));
        }
    } else {
        for (int j = -R; j <= R; j++) {
            const int k = j < 0 ? -j : j;
            const float *q = p + off[j];
            a0 = _mm256_add_ps(a0, _mm256_mul_ps(wpair(wt[0], wt[1], k), _mm256_loadu_ps(q)));
            a1 = _mm256_add_ps(a1, _mm256_mul_ps(wpair(wt[2], wt[3], k), _mm256_loadu_ps(q + 8)));
            a2 = _mm256_add_ps(a2, _mm256_mul_ps(wpair(wt[4], wt[5], k), _mm256_loadu_ps(q + 16)));
            a3 = _mm256_add_ps(a3, _mm256_mul_ps(wpair(wt[6], wt[7], k), _mm256_loadu_ps(q + 24)));
        }
    }
    a[0] = a0, a[1] = a1, a[2] = a2, a[3] = a3;
}

/* n pixels from p (output d), 8 at a time, then 4 and 1; norm: times inv[s]. */
static inline void dof_gauss_8(float *d, const float *p, const ptrdiff_t *off, int n, const uint8_t *sig,
                               const fv_dof_gauss_tab *tab, int norm)
{
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        const uint8_t *s = sig + i;
        if (i + 16 <= n && !memcmp(s, s + 1, 15)) {
            /* 16 pixels of one sigma: 8 accumulators, so the adds' latency (4 chains of one
             * add a tap for 8 pixels) no longer bounds the loop */
            const float *wt = tab->w[s[0]], *q0 = p + 4 * i;
            const int R = tab->rad[s[0]];
            __m256 a0 = _mm256_setzero_ps(), a1 = a0, a2 = a0, a3 = a0, a4 = a0, a5 = a0, a6 = a0, a7 = a0;
            for (int j = -R; j <= R; j++) {
                const float *q = q0 + off[j];
                const __m256 g = _mm256_broadcast_ss(wt + (j < 0 ? -j : j));
                a0 = _mm256_add_ps(a0, _mm256_mul_ps(g, _mm256_loadu_ps(q)));
                a1 = _mm256_add_ps(a1, _mm256_mul_ps(g, _mm256_loadu_ps(q + 8)));
                a2 = _mm256_add_ps(a2, _mm256_mul_ps(g, _mm256_loadu_ps(q + 16)));
                a3 = _mm256_add_ps(a3, _mm256_mul_ps(g, _mm256_loadu_ps(q + 24)));
                a4 = _mm256_add_ps(a4, _mm256_mul_ps(g, _mm256_loadu_ps(q + 32)));
                a5 = _mm256_add_ps(a5, _mm256_mul_ps(g, _mm256_loadu_ps(q + 40)));
                a6 = _mm256_add_ps(a6, _mm256_mul_ps(g, _mm256_loadu_ps(q + 48)));
                a7 = _mm256_add_ps(a7, _mm256_mul_ps(g, _mm256_loadu_ps(q + 56)));
            }
            const __m256 inv = _mm256_set1_ps(tab->inv[s[0]]);
            float *o = d + 4 * i;
            _mm256_storeu_ps(o, norm ? _mm256_mul_ps(a0, inv) : a0);
            _mm256_storeu_ps(o + 8, norm ? _mm256_mul_ps(a1, inv) : a1);
            _mm256_storeu_ps(o + 16, norm ? _mm256_mul_ps(a2, inv) : a2);
            _mm256_storeu_ps(o + 24, norm ? _mm256_mul_ps(a3, inv) : a3);
            _mm256_storeu_ps(o + 32, norm ? _mm256_mul_ps(a4, inv) : a4);
            _mm256_storeu_ps(o + 40, norm ? _mm256_mul_ps(a5, inv) : a5);
            _mm256_storeu_ps(o + 48, norm ? _mm256_mul_ps(a6, inv) : a6);
            _mm256_storeu_ps(o + 56, norm ? _mm256_mul_ps(a7, inv) : a7);
            i += 8; /* and 8 by the loop */
            continue;
        }
        const float *const wt[8] = {tab->w[s[0]], tab->w[s[1]], tab->w[s[2]], tab->w[s[3]],
                                    tab->w[s[4]], tab->w[s[5]], tab->w[s[6]], tab->w[s[7]]};
        __m256 a[4];
        g8(a, p + 4 * i, off, wt, dof_span_rad(s, 8, tab));
        for (int k = 0; k < 4; k++) {
            const __m256 inv = _mm256_setr_m128(_mm_set1_ps(tab->inv[s[2 * k]]), _mm_set1_ps(tab->inv[s[2 * k + 1]]));
            _mm256_storeu_ps(d + 4 * (i + 2 * k), norm ? _mm256_mul_ps(a[k], inv) : a[k]);
        }
    }
    if (i < n)
        dof_gauss_4(d + 4 * i, p + 4 * i, off, n - i, sig + i, tab, norm);
}

/* a + s (b - a) */
static inline __m256 lerp8(__m256 a, __m256 b, __m256 s)
{
    return _mm256_add_ps(a, _mm256_mul_ps(s, _mm256_sub_ps(b, a)));
}

/* 8 pixels at a time without branches: two pixels a 256-bit vector, each step computed for both
 * and kept per pixel by a select on the reference's condition (so a pixel whose step the
 * reference skips keeps its bits; the skipped step may read and compute garbage, which the
 * select drops). The per-pixel scalars (coc, t and what follows from them) are computed for the
 * 8 pixels at once, then spread over the pairs' halves. */
static void combine_row_avx2(float *restrict out, const fv_dof_combine_args *a, int x0, int n)
{
    const __m256 one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps(), gain = _mm256_set1_ps(a->gain);
    const __m256 msign = _mm256_set1_ps(-0.0f);
    int x = x0;
    for (; x + 8 <= x0 + n; x += 8) {
        const __m256 c8 = _mm256_loadu_ps(a->coc + x), t8 = _mm256_loadu_ps(a->t + x);
        const __m256 cneg = _mm256_cmp_ps(c8, zero, _CMP_LT_OQ), tpos = _mm256_cmp_ps(t8, zero, _CMP_GT_OQ);
        /* towards the pixel's own blur by ab = c > 0 ? min(c, 1) : c < 0 && t > 0 ? t min(-c, 1) : 0 */
        const __m256 abn = _mm256_and_ps(_mm256_mul_ps(t8, _mm256_min_ps(_mm256_xor_ps(c8, msign), one)),
                                         _mm256_and_ps(cneg, tpos));
        const __m256 ab8 = _mm256_blendv_ps(abn, _mm256_min_ps(c8, one), _mm256_cmp_ps(c8, zero, _CMP_GT_OQ));
        const int anyfar = _mm256_movemask_ps(_mm256_cmp_ps(ab8, zero, _CMP_GT_OQ));
        const __m256 sc8 = _mm256_blendv_ps(one, zero, cneg); /* lnear's scale: c < 0 ? 0 : 1 */
        const int anyl = a->lnear && _mm256_movemask_ps(tpos);
        const __m256 g8 = _mm256_mul_ps(gain, t8);
        const int anyg = a->enh && _mm256_movemask_ps(_mm256_cmp_ps(g8, zero, _CMP_GT_OQ));
        for (int p = 0; p < 4; p++) {
            const int xp = x + 2 * p;
            const int l = 2 * p, h = 2 * p + 1; /* the pair's pixels within the 8 */
            const __m256i idx = _mm256_setr_epi32(l, l, l, l, h, h, h, h);
            const __m256 s = _mm256_loadu_ps(a->sharp + 4 * xp);
            __m256 o = s;
            if (anyfar) {
                const __m256 ab = _mm256_permutevar8x32_ps(ab8, idx);
                o = _mm256_blendv_ps(o, lerp8(o, _mm256_loadu_ps(a->far + 4 * xp), ab),
                                     _mm256_cmp_ps(ab, zero, _CMP_GT_OQ));
            }
            __m256 nv = a->near ? _mm256_loadu_ps(a->near + 4 * xp) : zero;
            if (anyl) {
                const __m256 t = _mm256_permutevar8x32_ps(t8, idx), sc = _mm256_permutevar8x32_ps(sc8, idx);
                const __m256 q = _mm256_mul_ps(sc, _mm256_loadu_ps(a->lnear + 4 * xp));
                nv = _mm256_blendv_ps(nv, _mm256_add_ps(nv, _mm256_mul_ps(t, _mm256_sub_ps(q, nv))),
                                      _mm256_cmp_ps(t, zero, _CMP_GT_OQ));
            }
            const __m256 n3 = _mm256_permute_ps(nv, _MM_SHUFFLE(3, 3, 3, 3));
            const __m256 pos = _mm256_cmp_ps(n3, zero, _CMP_GT_OQ);
            if (_mm256_movemask_ps(pos))
                o = _mm256_blendv_ps(o, lerp8(o, _mm256_div_ps(nv, n3), _mm256_min_ps(n3, one)), pos);
            if (anyg) {
                const __m256 g = _mm256_permutevar8x32_ps(g8, idx);
                const __m256 v = _mm256_add_ps(o, _mm256_mul_ps(g, _mm256_sub_ps(o, _mm256_loadu_ps(a->enh + 4 * xp))));
                /* max: v > 0 ? v : +0 */
                o = _mm256_blendv_ps(o, _mm256_max_ps(v, zero), _mm256_cmp_ps(g, zero, _CMP_GT_OQ));
            }
            _mm256_storeu_ps(out + 4 * xp, _mm256_blend_ps(o, s, 0x88));
        }
    }
    if (x < x0 + n)
        dof_combine_row_x86(out, a, x, x0 + n - x);
}

/* two pixels' 128-bit vectors as one */
static inline __m256 ld2(const float *lo, const float *hi)
{
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(lo)), _mm_loadu_ps(hi), 1);
}

/* lanes 2p (low half) and 2p + 1 (high half) of an 8-lane vector, each spread over its half */
#define PAIR(v, p) _mm256_permutevar8x32_ps(v, _mm256_setr_epi32(2 * (p), 2 * (p), 2 * (p), 2 * (p), 2 * (p) + 1, \
                                                                 2 * (p) + 1, 2 * (p) + 1, 2 * (p) + 1))

/* By 2 (L = 1): pixel 2k reads texels k - 1, k (weight 3/4), pixel 2k + 1 texels k, k + 1 (1/4),
 * so the pair's p0 and p1 are the two-texel loads at k - 1 and k, and the next pair's p0 is this
 * one's p1; interior pairs only (k - 1 >= 0, k + 1 < sw), the ends run by run. */
static inline void up2_avx2(float *restrict dst, const float *tmp, int k, int np)
{
    const __m256 a = _mm256_setr_ps(0.75f, 0.75f, 0.75f, 0.75f, 0.25f, 0.25f, 0.25f, 0.25f);
    const float *t = tmp + 4 * (ptrdiff_t)(k - 1);
    __m256 q0 = _mm256_loadu_ps(t);
    int p = 0;
    for (; p + 4 <= np; p += 4, t += 16, dst += 32) {
        const __m256 q1 = _mm256_loadu_ps(t + 4), q2 = _mm256_loadu_ps(t + 8), q3 = _mm256_loadu_ps(t + 12);
        const __m256 q4 = _mm256_loadu_ps(t + 16);
        _mm256_storeu_ps(dst, _mm256_add_ps(q0, _mm256_mul_ps(a, _mm256_sub_ps(q1, q0))));
        _mm256_storeu_ps(dst + 8, _mm256_add_ps(q1, _mm256_mul_ps(a, _mm256_sub_ps(q2, q1))));
        _mm256_storeu_ps(dst + 16, _mm256_add_ps(q2, _mm256_mul_ps(a, _mm256_sub_ps(q3, q2))));
        _mm256_storeu_ps(dst + 24, _mm256_add_ps(q3, _mm256_mul_ps(a, _mm256_sub_ps(q4, q3))));
        q0 = q4;
    }
    for (; p < np; p++, t += 4, dst += 8) {
        const __m256 q1 = _mm256_loadu_ps(t + 4);
        _mm256_storeu_ps(dst, _mm256_add_ps(q0, _mm256_mul_ps(a, _mm256_sub_ps(q1, q0))));
        q0 = q1;
    }
}

/* By s = 2^L >= 4: whole runs (s even pixels from s j + s/2, even), two pixels a vector: both
 * texels broadcast to the halves, one d a run, the pairs' weights (2r + 1) / 2s as constants. */
static inline __attribute__((always_inline)) void upruns_avx2(float *restrict dst, const float *tmp, int sw, int j,
                                                               int runs, const int L)
{
    const int s = 1 << L;
    for (int q = 0; q < runs; q++, j++, dst += 4 * s) {
        const __m256 p0 = _mm256_broadcast_ps((const __m128 *)(const void *)(tmp + 4 * (ptrdiff_t)fv_clampi(j, 0, sw - 1)));
        const __m256 p1 = _mm256_broadcast_ps((const __m128 *)(const void *)(tmp + 4 * (ptrdiff_t)fv_clampi(j + 1, 0, sw - 1)));
        const __m256 d = _mm256_sub_ps(p1, p0);
        for (int p = 0; p < s / 2; p++) { /* L constant: the weights fold to constants */
            const float wa = (float)(4 * p + 1) / (float)(2 * s), wb = (float)(4 * p + 3) / (float)(2 * s);
            const __m256 w = _mm256_setr_ps(wa, wa, wa, wa, wb, wb, wb, wb);
            _mm256_storeu_ps(dst + 8 * p, _mm256_add_ps(p0, _mm256_mul_ps(w, d)));
        }
    }
}

static void upsample_row_avx2(float *restrict dst, const float *tmp, int L, int sw, int x0, int n)
{
    if (L < 1 || L > DOF_UP_MAXL) {
        fv_dof_upsample_row_c(dst, tmp, L, sw, x0, n);
        return;
    }
    const int s = 1 << L, x1 = x0 + n;
    if (L == 1) { /* pairs from the first even x >= 2 to the last whose k + 1 < sw */
        const int a = x0 < 2 ? 2 : (x0 + 1) & ~1;
        const int e = x1 < 2 * sw - 2 ? x1 : 2 * sw - 2, np = (e - a) >> 1;
        if (np <= 0) {
            dof_upruns_x86(dst, tmp, L, sw, x0, n);
            return;
        }
        dof_upruns_x86(dst, tmp, L, sw, x0, a - x0);
        up2_avx2(dst + 4 * (a - x0), tmp, a >> 1, np);
        const int b = a + 2 * np;
        dof_upruns_x86(dst + 4 * (b - x0), tmp, L, sw, b, x1 - b);
        return;
    }
    /* the first run start >= x0 (x = s j + s/2), whole runs, the rest */
    const int j0 = (x0 + s / 2 - 1) / s, a = s * j0 + s / 2; /* ceil((x0 - s/2) / s), x0 >= 0 */
    const int runs = a < x1 ? (x1 - a) / s : 0;
    if (runs <= 0) {
        dof_upruns_x86(dst, tmp, L, sw, x0, n);
        return;
    }
    dof_upruns_x86(dst, tmp, L, sw, x0, a - x0);
    float *d = dst + 4 * (a - x0);
    switch (L) { /* s / 2 pairs a run, unrolled */
    case 2: upruns_avx2(d, tmp, sw, j0, runs, 2); break;
    case 3: upruns_avx2(d, tmp, sw, j0, runs, 3); break;
    case 4: upruns_avx2(d, tmp, sw, j0, runs, 4); break;
    default: upruns_avx2(d, tmp, sw, j0, runs, 5); break;
    }
    const int b = a + s * runs;
    dof_upruns_x86(dst + 4 * (b - x0), tmp, L, sw, b, x1 - b);
}

/* ---- pyrblur_row ----
 * A block's 8 per-pixel lanes are kept in pair order: lane p (low half) is pixel 2p, lane 4 + p
 * pixel 2p + 1 (one vpermps of coc and of t a block), so the AoS pair p = pixels (2p, 2p + 1)
 * spreads a lane over its 4 channels by one in-lane vpermilps (SPREAD) instead of a lane-crossing
 * vpermps per pair and value. The blend of a pair: pv = u0 + f (u1 - u0), r = mix ? b + t (pv - b)
 * : pv, b = act ? r : b (the reference's operations). mode, a constant at each call: PB_PV: all 8
 * blended, none mixing (the periphery): b = pv; PB_MIX: all 8 blended and mixing (the far part of
 * the transition ring): b = b + t (pv - b), no selects; PB_SEL: both selects. */
#define PB_ORDER _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7)
static inline __attribute__((always_inline)) __m256 SPREAD(__m256 v, int p) /* p a constant once unrolled */
{
    switch (p) {
    case 0: return _mm256_permute_ps(v, 0x00);
    case 1: return _mm256_permute_ps(v, 0x55);
    case 2: return _mm256_permute_ps(v, 0xaa);
    default: return _mm256_permute_ps(v, 0xff);
    }
}
enum { PB_PV, PB_MIX, PB_SEL };

static inline __attribute__((always_inline)) void pb_blend(float *b, __m256 u0, __m256 u1, __m256 f, __m256 t,
                                                           __m256 mix, __m256 act, int p, int mode)
{
    const __m256 pv = _mm256_add_ps(u0, _mm256_mul_ps(SPREAD(f, p), _mm256_sub_ps(u1, u0)));
    if (mode == PB_PV) {
        _mm256_storeu_ps(b, pv);
        return;
    }
    const __m256 bv = _mm256_loadu_ps(b), m = _mm256_add_ps(bv, _mm256_mul_ps(SPREAD(t, p), _mm256_sub_ps(pv, bv)));
    if (mode == PB_MIX) {
        _mm256_storeu_ps(b, m);
        return;
    }
    _mm256_storeu_ps(b, _mm256_blendv_ps(bv, _mm256_blendv_ps(pv, m, SPREAD(mix, p)), SPREAD(act, p)));
}

/* the 4 pairs of a block at pixel i whose 8 pixels share the level rows r0, r1 (+ 4 i) */
static inline __attribute__((always_inline)) void pb_rows(float *blur, const float *r0, const float *r1, __m256 f,
                                                          __m256 t, __m256 mix, __m256 act, int bits, int i, int mode)
{
    const ptrdiff_t o = 4 * (ptrdiff_t)i;
#pragma GCC unroll 4
    for (int p = 0; p < 4; p++)
        if (mode != PB_SEL || (bits & (0x11 << p)))
            pb_blend(blur + o + 8 * p, _mm256_loadu_ps(r0 + o + 8 * p), _mm256_loadu_ps(r1 + o + 8 * p), f, t, mix,
                     act, p, mode);
}

/* the 4 pairs of a block (b = blur + 4 i) whose pixels' levels are L0 = b (u0 = r0, u1 = r1) or,
 * where hi, b + 1 (u0 = r1, u1 = r2); r0..r2 at pixel i */
static inline __attribute__((always_inline)) void pb_rows2(float *b, const float *r0, const float *r1,
                                                           const float *r2, __m256 hi, __m256 f, __m256 t,
                                                           __m256 mix, __m256 act, int bits, int mode)
{
#pragma GCC unroll 4
    for (int p = 0; p < 4; p++)
        if (mode != PB_SEL || (bits & (0x11 << p))) {
            const __m256 h = SPREAD(hi, p), v1 = _mm256_loadu_ps(r1 + 8 * p);
            pb_blend(b + 8 * p, _mm256_blendv_ps(_mm256_loadu_ps(r0 + 8 * p), v1, h),
                     _mm256_blendv_ps(v1, _mm256_loadu_ps(r2 + 8 * p), h), f, t, mix, act, p, mode);
        }
}

/* the block's mode from its act and mix masks (pair order) */
static inline int pb_mode(int bits, __m256 mix)
{
    const int mb = _mm256_movemask_ps(mix);
    return bits != 255 ? PB_SEL : !mb ? PB_PV : mb == 255 ? PB_MIX : PB_SEL;
}

#define PB_DISPATCH(call)                                                                                            \
    do {                                                                                                             \
        const int mode_ = pb_mode(bits, mix);                                                                        \
        if (mode_ == PB_PV)                                                                                          \
            call(PB_PV);                                                                                             \
        else if (mode_ == PB_MIX)                                                                                    \
            call(PB_MIX);                                                                                            \
        else                                                                                                         \
            call(PB_SEL);                                                                                            \
    } while (0)

/* need == 1 (the transition disc; the half-resolution rows' level 1): L1 = 1, L0 = 0 or 1 per
 * pixel, so both levels load whole pairs and L0 is a select (no per-pixel pointers). need == 0:
 * l = min(lambda, 0) = 0 (lambda >= 0), f = 0 and L0 = L1 = 0 for every pixel: no lookup. */
static void pyrblur01_row_avx2(float *restrict blur, const fv_dof_pyrblur_args *a, int x0, int n)
{
    const __m256 steps = _mm256_set1_ps((float)a->lambda_steps), lmax = _mm256_set1_ps((float)a->lambda_max);
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), msign = _mm256_set1_ps(-0.0f);
    const __m256i order = PB_ORDER;
    const int need1 = a->need == 1;
    const float *up0 = a->up[0], *up1 = a->up[need1];
    /* The level table in registers instead of a gather: when l = min(lambda[k], 1) is 1 for every
     * k >= 32, the first 32 entries are all a lookup needs (checked 8 entries a step: a scalar
     * scan of the 513-entry table cost as much as the blend of a 640-pixel row) */
    int regs = need1 && a->lambda_max >= 31; /* (never read past a shorter table) */
    if (regs) {
        __m256 ok = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        int q = 32;
        for (; q + 8 <= a->lambda_max + 1; q += 8)
            ok = _mm256_and_ps(ok, _mm256_cmp_ps(_mm256_loadu_ps(a->lambda + q), one, _CMP_GE_OQ));
        regs = _mm256_movemask_ps(ok) == 255;
        for (; q <= a->lambda_max; q++)
            regs &= a->lambda[q] >= 1.0f;
    }
    __m256 lut[4];
    for (int q = 0; q < 4; q++)
        lut[q] = regs ? _mm256_min_ps(_mm256_loadu_ps(a->lambda + 8 * q), one) : zero;
    int i = x0;
    for (; i + 8 <= x0 + n; i += 8) {
        const __m256 c = _mm256_permutevar8x32_ps(_mm256_loadu_ps(a->coc + i), order);
        const __m256 t = _mm256_permutevar8x32_ps(_mm256_loadu_ps(a->t + i), order);
        const __m256 m = _mm256_andnot_ps(msign, c); /* |c| (-0 -> +0: skipped either way) */
        const __m256 act = _mm256_and_ps(_mm256_cmp_ps(m, zero, _CMP_GT_OQ), _mm256_cmp_ps(t, zero, _CMP_GT_OQ));
        const int bits = _mm256_movemask_ps(act);
        if (!bits)
            continue;
        const __m256 mix = _mm256_and_ps(_mm256_cmp_ps(c, zero, _CMP_GT_OQ), _mm256_cmp_ps(t, one, _CMP_LT_OQ));
        if (!need1) { /* pv = u0 + 0 (u0 - u0), as the reference */
#define PB0(md) pb_rows(blur, up0, up0, zero, t, mix, act, bits, i, md)
            PB_DISPATCH(PB0);
#undef PB0
            continue;
        }
        const __m256 v = _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(m, steps), zero), lmax); /* NaN -> 0 */
        const __m256i k = _mm256_cvttps_epi32(v);
        __m256 l;
        if (regs) {
            const __m256 b3 = _mm256_castsi256_ps(_mm256_slli_epi32(k, 28)); /* bit 3 -> sign */
            const __m256 b4 = _mm256_castsi256_ps(_mm256_slli_epi32(k, 27)); /* bit 4 -> sign */
            const __m256 lo = _mm256_blendv_ps(_mm256_permutevar8x32_ps(lut[0], k), _mm256_permutevar8x32_ps(lut[1], k), b3);
            const __m256 hi = _mm256_blendv_ps(_mm256_permutevar8x32_ps(lut[2], k), _mm256_permutevar8x32_ps(lut[3], k), b3);
            l = _mm256_blendv_ps(_mm256_blendv_ps(lo, hi, b4), one,
                                 _mm256_castsi256_ps(_mm256_cmpgt_epi32(k, _mm256_set1_epi32(31))));
        } else {
            l = _mm256_min_ps(_mm256_i32gather_ps(a->lambda, k, 4), one);
        }
        const __m256 is1 = _mm256_cmp_ps(l, one, _CMP_GE_OQ); /* L0 = int l = 1 */
        const __m256 f = _mm256_sub_ps(l, _mm256_and_ps(is1, one));
        const int all1 = _mm256_movemask_ps(is1), o4 = 4 * i;
        if (all1 == 255) { /* every pixel at level 1: pv = u1 + 0 (u1 - u1) */
#define PB1(md) pb_rows(blur, up1, up1, f, t, mix, act, bits, i, md)
            PB_DISPATCH(PB1);
#undef PB1
        } else if (!all1) { /* every pixel between levels 0 and 1 */
#define PB1(md) pb_rows(blur, up0, up1, f, t, mix, act, bits, i, md)
            PB_DISPATCH(PB1);
#undef PB1
        } else {
#pragma GCC unroll 4
            for (int p = 0; p < 4; p++)
                if (bits & (0x11 << p)) {
                    const __m256 u1 = _mm256_loadu_ps(up1 + o4 + 8 * p);
                    const __m256 u0 = _mm256_blendv_ps(_mm256_loadu_ps(up0 + o4 + 8 * p), u1, SPREAD(is1, p));
                    pb_blend(blur + o4 + 8 * p, u0, u1, f, t, mix, act, p, PB_SEL);
                }
        }
    }
    if (i < x0 + n)
        dof_pyrblur_row_x86(blur, a, i, x0 + n - i);
}

/* 8 pixels at a time: their scalars as 8 lanes in pair order (core/x86/dof_tmpl.h has why the
 * clamped LUT index gives the reference's levels and keeps skipped pixels' loads in bounds); a
 * block whose 8 pixels share a level pair (the CoC varies slowly: most) loads whole pairs from
 * the two rows, others a row pointer a pixel; the rest 128-bit. */
static void pyrblur_row_avx2(float *restrict blur, const fv_dof_pyrblur_args *a, int x0, int n)
{
    if (a->need <= 1) {
        pyrblur01_row_avx2(blur, a, x0, n);
        return;
    }
    const __m256 steps = _mm256_set1_ps((float)a->lambda_steps), lmax = _mm256_set1_ps((float)a->lambda_max);
    const __m256 need = _mm256_set1_ps((float)a->need), zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    const __m256 msign = _mm256_set1_ps(-0.0f);
    const __m256i needi = _mm256_set1_epi32(a->need), order = PB_ORDER;
    const float *const *up = a->up;
    int i = x0;
    for (; i + 8 <= x0 + n; i += 8) {
        const __m256 c = _mm256_permutevar8x32_ps(_mm256_loadu_ps(a->coc + i), order);
        const __m256 t = _mm256_permutevar8x32_ps(_mm256_loadu_ps(a->t + i), order);
        const __m256 m = _mm256_andnot_ps(msign, c); /* |c| (-0 -> +0: skipped either way) */
        const __m256 act = _mm256_and_ps(_mm256_cmp_ps(m, zero, _CMP_GT_OQ), _mm256_cmp_ps(t, zero, _CMP_GT_OQ));
        const int bits = _mm256_movemask_ps(act);
        if (!bits)
            continue;
        const __m256 v = _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(m, steps), zero), lmax); /* NaN -> 0 */
        const __m256 l = _mm256_min_ps(_mm256_i32gather_ps(a->lambda, _mm256_cvttps_epi32(v), 4), need);
        const __m256i l0 = _mm256_cvttps_epi32(l);
        const __m256 f = _mm256_sub_ps(l, _mm256_cvtepi32_ps(l0));
        const __m256 mix = _mm256_and_ps(_mm256_cmp_ps(c, zero, _CMP_GT_OQ), _mm256_cmp_ps(t, one, _CMP_LT_OQ));
        /* one level pair for all 8: rows, not pixels */
        const int l00 = _mm_cvtsi128_si32(_mm256_castsi256_si128(l0));
        if (_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(l0, _mm256_set1_epi32(l00)))) == 255) {
            const float *r0 = up[l00], *r1 = up[l00 < a->need ? l00 + 1 : l00];
#define PBR(md) pb_rows(blur, r0, r1, f, t, mix, act, bits, i, md)
            PB_DISPATCH(PBR);
#undef PBR
            continue;
        }
        /* two neighbouring level pairs (a level boundary crosses the block: about half the blocks
         * of a half-resolution row): L0 = b or b + 1, whole-pair loads of 3 rows and a select */
        const __m256i vb = _mm256_set1_epi32(l00 - (_mm256_movemask_ps(_mm256_castsi256_ps(
                                                      _mm256_cmpgt_epi32(_mm256_set1_epi32(l00), l0))) != 0));
        const __m256 hi = _mm256_castsi256_ps(_mm256_cmpeq_epi32(l0, _mm256_sub_epi32(vb, _mm256_set1_epi32(-1))));
        if (_mm256_movemask_ps(_mm256_or_ps(hi, _mm256_castsi256_ps(_mm256_cmpeq_epi32(l0, vb)))) == 255) {
            const int b0 = _mm_cvtsi128_si32(_mm256_castsi256_si128(vb)); /* b + 1 <= need: some L0 is */
            const float *r0 = up[b0] + 4 * (ptrdiff_t)i, *r1 = up[b0 + 1] + 4 * (ptrdiff_t)i;
            const float *r2 = up[b0 + 2 <= a->need ? b0 + 2 : b0 + 1] + 4 * (ptrdiff_t)i;
#define PB2(md) pb_rows2(blur + 4 * (ptrdiff_t)i, r0, r1, r2, hi, f, t, mix, act, bits, md)
            PB_DISPATCH(PB2);
#undef PB2
            continue;
        }
        _Alignas(32) int32_t L0[8], L1[8]; /* pair order: pair p's pixels at p and 4 + p */
        _mm256_store_si256((__m256i *)L0, l0);
        _mm256_store_si256((__m256i *)L1, _mm256_sub_epi32(l0, _mm256_cmpgt_epi32(needi, l0))); /* + 1 if L0 < need */
#pragma GCC unroll 4
        for (int p = 0; p < 4; p++)
            if (bits & (0x11 << p)) {
                const ptrdiff_t o = 4 * (ptrdiff_t)(i + 2 * p);
                pb_blend(blur + o, ld2(up[L0[p]] + o, up[L0[4 + p]] + o + 4), ld2(up[L1[p]] + o, up[L1[4 + p]] + o + 4),
                         f, t, mix, act, p, PB_SEL);
            }
    }
    if (i < x0 + n)
        dof_pyrblur_row_x86(blur, a, i, x0 + n - i);
}

/* 8 pixels at a time from an even x: their scalars as 8 lanes, then 4 pairs (2k, 2k + 1), whose
 * up-sampling taps are (half[k - 1], half[k + 1]) and half[k] twice: two loads and two blends */
static void periph_row_avx2(float *restrict out, const float *sharp, const float *coc, const float *half,
                            const float *lnear, int x0, int n)
{
    const __m256 one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps(), msign = _mm256_set1_ps(-0.0f);
    const __m256 slope = _mm256_set1_ps(FV_DOF_L1_SLOPE), q75 = _mm256_set1_ps(0.75f), q25 = _mm256_set1_ps(0.25f);
    int x = x0;
    if (x & 1) {
        fv_dof_periph_row_c(out, sharp, coc, half, lnear, x, 1);
        x++;
    }
    for (; x + 8 <= x0 + n; x += 8) {
        const __m256 c = _mm256_loadu_ps(coc + x), m = _mm256_andnot_ps(msign, c);
        const __m256 w = _mm256_mul_ps(_mm256_min_ps(m, one), _mm256_min_ps(_mm256_mul_ps(_mm256_mul_ps(m, m), slope), one));
        const __m256 wpos = _mm256_cmp_ps(w, zero, _CMP_GT_OQ);
        const __m256 nn = _mm256_cmp_ps(c, zero, _CMP_GE_OQ);
        const int anyn = lnear && _mm256_movemask_ps(nn);
        const float *hk = half + 2 * (ptrdiff_t)x; /* texel x / 2 */
#define PR_PAIR(p)                                                                                                   \
    do {                                                                                                             \
        const ptrdiff_t o4 = 4 * (ptrdiff_t)(x + 2 * (p));                                                           \
        const __m256 a = _mm256_loadu_ps(hk + 4 * (p) - 4), b = _mm256_loadu_ps(hk + 4 * (p));                      \
        const __m256 u = _mm256_add_ps(_mm256_mul_ps(q75, _mm256_blend_ps(b, a, 0xf0)),                              \
                                       _mm256_mul_ps(q25, _mm256_blend_ps(a, b, 0xf0)));                             \
        const __m256 sv = _mm256_loadu_ps(sharp + o4);                                                               \
        __m256 o = _mm256_blendv_ps(sv, _mm256_add_ps(sv, _mm256_mul_ps(PAIR(w, p), _mm256_sub_ps(u, sv))),          \
                                    PAIR(wpos, p));                                                                  \
        if (anyn) {                                                                                                  \
            const __m256 q = _mm256_loadu_ps(lnear + o4), q3 = _mm256_permute_ps(q, _MM_SHUFFLE(3, 3, 3, 3));       \
            const __m256 pos = _mm256_and_ps(_mm256_cmp_ps(q3, zero, _CMP_GT_OQ), PAIR(nn, p));                      \
            o = _mm256_blendv_ps(o, _mm256_add_ps(o, _mm256_mul_ps(_mm256_min_ps(q3, one), _mm256_sub_ps(_mm256_div_ps(q, q3), o))), pos); \
        }                                                                                                            \
        _mm256_storeu_ps(out + o4, _mm256_blend_ps(o, sv, 0x88));                                                   \
    } while (0)
        PR_PAIR(0);
        PR_PAIR(1);
        PR_PAIR(2);
        PR_PAIR(3);
#undef PR_PAIR
    }
    if (x < x0 + n)
        dof_periph_row_x86(out, sharp, coc, half, lnear, x, x0 + n - x);
}

/* two blocks (8 pixels): pixel pairs as vectors, the pairs of a block added crosswise so that
 * each half holds (q0 + q2) / (q1 + q3) as the reference; min / max within each 128-bit half */
static void nearblk_row_avx2(float *restrict sum, float *restrict ext, const float *coc, const float *rgbd, int n)
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    int b = 0;
    for (; 4 * b + 8 <= n; b += 2) {
        const float *p = rgbd + 16 * b;
        const __m256 c = _mm256_loadu_ps(coc + 4 * b), m = _mm256_cmp_ps(c, zero, _CMP_LT_OQ);
#define NB_Q(k) _mm256_and_ps(_mm256_blend_ps(_mm256_loadu_ps(p + 8 * (k)), one, 0x88), PAIR(m, k))
        const __m256 t0 = _mm256_add_ps(NB_Q(0), NB_Q(1)), t1 = _mm256_add_ps(NB_Q(2), NB_Q(3));
#undef NB_Q
        const __m256 s = _mm256_add_ps(_mm256_permute2f128_ps(t0, t1, 0x20), _mm256_permute2f128_ps(t0, t1, 0x31));
        _mm256_storeu_ps(sum + 4 * b, _mm256_add_ps(_mm256_loadu_ps(sum + 4 * b), s));
        __m256 lo = _mm256_min_ps(c, _mm256_shuffle_ps(c, c, 0xb1)), hi = _mm256_max_ps(c, _mm256_shuffle_ps(c, c, 0xb1));
        lo = _mm256_min_ps(lo, _mm256_shuffle_ps(lo, lo, 0x4e)), hi = _mm256_max_ps(hi, _mm256_shuffle_ps(hi, hi, 0x4e));
        /* (lo, hi) of block 0 in lanes 0, 1, of block 1 in lanes 2, 3 */
        const __m128 v = _mm256_castps256_ps128(
            _mm256_permutevar8x32_ps(_mm256_unpacklo_ps(lo, hi), _mm256_setr_epi32(0, 1, 4, 5, 0, 1, 4, 5)));
        const __m128 e = _mm_loadu_ps(ext + 2 * b);
        _mm_storeu_ps(ext + 2 * b, _mm_add_ps(_mm_blend_ps(_mm_min_ps(v, e), _mm_max_ps(v, e), 10), _mm_setzero_ps()));
    }
    for (; 4 * b + 4 <= n; b++)
        dof_nearblk4(sum + 4 * b, ext + 2 * b, coc + 4 * b, rgbd + 16 * b);
    if (4 * b < n)
        fv_dof_nearblk_row_c(sum + 4 * b, ext + 2 * b, coc + 4 * b, rgbd + 16 * b, n - 4 * b);
}

/* 8 outputs a step whose taps all lie in the row: per tap the 8 radii / weights as one vector
 * (masked to +0 where the tap does not reach), spread over the 4 pixel pairs */
static void nearbox_row_avx2(float *restrict out, float *restrict out_r, float *restrict out_w, const float *src,
                             const float *r, const float *wgt, int w, int x0, int n, int reach)
{
    const __m256 one = _mm256_set1_ps(1.0f);
    int i = x0;
    while (i < x0 + n) {
        if (i >= reach && i + 7 + reach < w && i + 8 <= x0 + n) {
            __m256 a0 = _mm256_setzero_ps(), a1 = a0, a2 = a0, a3 = a0, rm = a0;
            for (int j = -reach; j <= reach; j++) {
                const __m256 r8 = _mm256_loadu_ps(r + i + j);
                const __m256 m = _mm256_cmp_ps(r8, _mm256_set1_ps((float)(j < 0 ? -j : j)), _CMP_GE_OQ);
                const __m256 w8 = _mm256_and_ps(_mm256_loadu_ps(wgt + i + j), m);
                rm = _mm256_max_ps(_mm256_and_ps(r8, m), rm);
                const float *p = src + 4 * (ptrdiff_t)(i + j);
                a0 = _mm256_add_ps(a0, _mm256_mul_ps(PAIR(w8, 0), _mm256_loadu_ps(p)));
                a1 = _mm256_add_ps(a1, _mm256_mul_ps(PAIR(w8, 1), _mm256_loadu_ps(p + 8)));
                a2 = _mm256_add_ps(a2, _mm256_mul_ps(PAIR(w8, 2), _mm256_loadu_ps(p + 16)));
                a3 = _mm256_add_ps(a3, _mm256_mul_ps(PAIR(w8, 3), _mm256_loadu_ps(p + 24)));
            }
            float *o = out + 4 * (ptrdiff_t)i;
            _mm256_storeu_ps(o, a0), _mm256_storeu_ps(o + 8, a1), _mm256_storeu_ps(o + 16, a2);
            _mm256_storeu_ps(o + 24, a3);
            _mm256_storeu_ps(out_r + i, rm);
            _mm256_storeu_ps(out_w + i, _mm256_div_ps(one, _mm256_add_ps(_mm256_add_ps(rm, rm), one)));
            i += 8;
        } else if (i >= reach && i + 3 + reach < w && i + 4 <= x0 + n) {
            dof_nearbox4(out, out_r, out_w, src, r, wgt, i, reach), i += 4;
        } else { /* the row's ends */
            fv_dof_nearbox_row_c(out, out_r, out_w, src, r, wgt, w, i, 1, reach), i++;
        }
    }
}

/* 8 texels a step: the pair sums as even + odd lanes per 128-bit half (a0+a1 a2+a3 b0+b1 b2+b3 |
 * a4+a5 a6+a7 b4+b5 b6+b7 with a, b the two 8-float loads: the reference's additions; shuffles
 * are cheaper than hadd), the 64-bit permute puts them in order */
static inline __m256 hcoc_pairs8(const float *c, __m256 abs)
{
    const __m256 a = _mm256_and_ps(_mm256_loadu_ps(c), abs), b = _mm256_and_ps(_mm256_loadu_ps(c + 8), abs);
    return _mm256_add_ps(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0)),
                         _mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1)));
}

static void hcoc_row_avx2(float *restrict hc, const float *ca, const float *cb, int n)
{
    const __m256 abs = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff)), q = _mm256_set1_ps(0.25f);
    int u = 0;
    for (; u + 8 <= n; u += 8) {
        const __m256 s = _mm256_mul_ps(q, _mm256_add_ps(hcoc_pairs8(ca + 2 * u, abs), hcoc_pairs8(cb + 2 * u, abs)));
        _mm256_storeu_ps(hc + u, _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(s), _MM_SHUFFLE(3, 1, 2, 0))));
    }
    if (u < n)
        fv_dof_hcoc_row_c(hc + u, ca + 2 * u, cb + 2 * u, n - u);
}

/* 8 blocks a step, as the SSE4.1 version (core/x86/dof_sse41.c); the shuffles work per 128-bit
 * half, the permutes put the blocks in order */
static void nearfin_row_avx2(float *restrict rad, float *restrict rb, float *restrict wgt, float *restrict sum,
                             const float *ext, int n, float inv)
{
    const __m256 half = _mm256_set1_ps(0.5f), rmax = _mm256_set1_ps((float)FV_DOF_RMAX), q = _mm256_set1_ps(0.25f);
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), two = _mm256_set1_ps(2.0f);
    const __m256 m1 = _mm256_set1_ps(-1.0f), vinv = _mm256_set1_ps(inv), sgn = _mm256_set1_ps(-0.0f);
    const __m256i order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        /* (b0 b1 b4 b5 | b2 b3 b6 b7) -> in order by 64-bit pieces */
        const __m256 e2 = _mm256_shuffle_ps(_mm256_loadu_ps(ext + 2 * i), _mm256_loadu_ps(ext + 2 * i + 8),
                                            _MM_SHUFFLE(2, 0, 2, 0));
        const __m256 e = _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(e2), _MM_SHUFFLE(3, 1, 2, 0)));
        float *s = sum + 4 * i;
        const __m256 s0 = _mm256_loadu_ps(s), s1 = _mm256_loadu_ps(s + 8), s2 = _mm256_loadu_ps(s + 16),
                     s3 = _mm256_loadu_ps(s + 24);
        /* counts: (b0 b2 b4 b6 | b1 b3 b5 b7), then in order */
        const __m256 c2 = _mm256_shuffle_ps(_mm256_shuffle_ps(s0, s1, _MM_SHUFFLE(3, 3, 3, 3)),
                                            _mm256_shuffle_ps(s2, s3, _MM_SHUFFLE(3, 3, 3, 3)), _MM_SHUFFLE(2, 0, 2, 0));
        const __m256 cnt = _mm256_permutevar8x32_ps(c2, order);
        /* -e 0.5 as the reference: the sign flipped exactly, then the multiply; r / 4 = r 0.25
         * exactly (r is a whole number or -0) */
        const __m256 r = _mm256_min_ps(_mm256_floor_ps(_mm256_mul_ps(_mm256_xor_ps(e, sgn), half)), rmax);
        const __m256 b = _mm256_blendv_ps(m1, _mm256_floor_ps(_mm256_mul_ps(r, q)), _mm256_cmp_ps(cnt, zero, _CMP_GT_OQ));
        _mm256_storeu_ps(rad + i, r);
        _mm256_storeu_ps(rb + i, b);
        _mm256_storeu_ps(wgt + i, _mm256_div_ps(one, _mm256_add_ps(_mm256_mul_ps(two, _mm256_max_ps(b, zero)), one)));
        _mm256_storeu_ps(s, _mm256_mul_ps(s0, vinv));
        _mm256_storeu_ps(s + 8, _mm256_mul_ps(s1, vinv));
        _mm256_storeu_ps(s + 16, _mm256_mul_ps(s2, vinv));
        _mm256_storeu_ps(s + 24, _mm256_mul_ps(s3, vinv));
    }
    if (i < n)
        fv_dof_nearfin_row_c(rad + i, rb + i, wgt + i, sum + 4 * i, ext + 2 * i, n - i, inv);
}

void fv_dof_dsp_init_avx2(fv_dof_dsp *d)
{
    d->dof_hcoc_row = hcoc_row_avx2;
    d->dof_nearfin_row = nearfin_row_avx2;
    d->dof_periph_row = periph_row_avx2;
    d->dof_nearbox_row = nearbox_row_avx2;
    d->dof_nearblk_row = nearblk_row_avx2;
    d->dof_upsample_row = upsample_row_avx2;
    d->dof_pyrblur_row = pyrblur_row_avx2;
    d->dof_coc_row = coc_row_avx2;
    d->dof_hgauss_row = hgauss_row_avx2;
    d->dof_vgauss_row = vgauss_row_avx2;
    d->dof_combine_row = combine_row_avx2;
}
