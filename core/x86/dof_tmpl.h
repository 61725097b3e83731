/* fovea: the depth-of-field kernels' code shared by the SSE4.1 and AVX2 versions (x86 template:
 * core/x86/dof_sse41.c and dof_avx2.c each include it once after defining FV_X86_W, their vector
 * width in floats (4 or 8), and FV_X86_FN(name), their function names; each is built with its
 * own ISA flags). The 128-bit pieces, and the Gaussian rows around the ISA's block routine. One pixel = one __m128
 * (r, g, b, depth or weight): the references (core/dof/dof_ref.c) add channel by channel in the
 * same order, so a vector of 4 channel accumulators gives their bits.
 *
 * The Gaussians take blocks of pixels with different sigmas through one loop over the block's
 * largest radius R: a pixel whose own radius is smaller adds w[s][|j|] * v = +-0 for |j| beyond
 * it (the table holds 0 there, core/dof/weier_impl.h), and an accumulator that starts at +0 is
 * never -0 (x + y is -0 only if both are -0), so adding +-0 leaves its bits unchanged. The same
 * argument lets the horizontal pass add +0 (a masked tap) for a near sample instead of skipping
 * it. The values read for those extra taps lie in the rows / columns the call covers and must be
 * finite (they are: level 0 and far_h are finite everywhere the pass reads). */
#if !defined(FV_X86_W) || !defined(FV_X86_FN)
#error "define FV_X86_W and FV_X86_FN before including x86/dof_tmpl.h"
#endif

#include <smmintrin.h>
#include <stddef.h>
#include <stdint.h>

#include "dof/weier_impl.h"
#include "base/util.h"
#include "dof/dof_dsp.h"

#define DOF_CH 128 /* output pixels per chunk of the horizontal pass's masked row (TILE * 8) */


/* ---- nearblk_row: one block of 4 pixels (q, the +0 of skipped pixels, as the reference) ---- */
static inline void dof_nearblk4(float *sum, float *ext, const float *coc, const float *rgbd)
{
    const __m128 c = _mm_loadu_ps(coc), m = _mm_cmplt_ps(c, _mm_setzero_ps()), one = _mm_set1_ps(1.0f);
#define DOF_NB_Q(k) _mm_and_ps(_mm_blend_ps(_mm_loadu_ps(rgbd + 4 * (k)), one, 8), _mm_shuffle_ps(m, m, (k) * 0x55))
    const __m128 s = _mm_add_ps(_mm_add_ps(DOF_NB_Q(0), DOF_NB_Q(2)), _mm_add_ps(DOF_NB_Q(1), DOF_NB_Q(3)));
#undef DOF_NB_Q
    _mm_storeu_ps(sum, _mm_add_ps(_mm_loadu_ps(sum), s));
    __m128 lo = _mm_min_ps(c, _mm_shuffle_ps(c, c, 0xb1)), hi = _mm_max_ps(c, _mm_shuffle_ps(c, c, 0xb1));
    lo = _mm_min_ps(lo, _mm_shuffle_ps(lo, lo, 0x4e)), hi = _mm_max_ps(hi, _mm_shuffle_ps(hi, hi, 0x4e));
    const __m128 e = _mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(const void *)ext));
    const __m128 r = _mm_add_ps(_mm_blend_ps(_mm_min_ps(lo, e), _mm_max_ps(hi, e), 2), _mm_setzero_ps());
    _mm_storel_epi64((__m128i *)(void *)ext, _mm_castps_si128(r));
}

/* ---- nearbox_row: 4 outputs i.. i+3 whose taps all lie in the row (i >= reach, i + 3 + reach
 * < w): per tap the 4 radii / weights as one vector, masked to +0 where the tap does not reach
 * (the reference skips it; + (+0 x finite) leaves a sum that started at +0 unchanged) ---- */
static inline void dof_nearbox4(float *out, float *out_r, float *out_w, const float *src, const float *r,
                                const float *wgt, int i, int reach)
{
    __m128 a0 = _mm_setzero_ps(), a1 = a0, a2 = a0, a3 = a0, rm = a0;
    for (int j = -reach; j <= reach; j++) {
        const __m128 r4 = _mm_loadu_ps(r + i + j), m = _mm_cmpge_ps(r4, _mm_set1_ps((float)(j < 0 ? -j : j)));
        const __m128 w4 = _mm_and_ps(_mm_loadu_ps(wgt + i + j), m);
        rm = _mm_max_ps(_mm_and_ps(r4, m), rm);
        const float *p = src + 4 * (ptrdiff_t)(i + j);
        a0 = _mm_add_ps(a0, _mm_mul_ps(_mm_shuffle_ps(w4, w4, 0x00), _mm_loadu_ps(p)));
        a1 = _mm_add_ps(a1, _mm_mul_ps(_mm_shuffle_ps(w4, w4, 0x55), _mm_loadu_ps(p + 4)));
        a2 = _mm_add_ps(a2, _mm_mul_ps(_mm_shuffle_ps(w4, w4, 0xaa), _mm_loadu_ps(p + 8)));
        a3 = _mm_add_ps(a3, _mm_mul_ps(_mm_shuffle_ps(w4, w4, 0xff), _mm_loadu_ps(p + 12)));
    }
    float *o = out + 4 * (ptrdiff_t)i;
    _mm_storeu_ps(o, a0), _mm_storeu_ps(o + 4, a1), _mm_storeu_ps(o + 8, a2), _mm_storeu_ps(o + 12, a3);
    _mm_storeu_ps(out_r + i, rm);
    const __m128 one = _mm_set1_ps(1.0f);
    _mm_storeu_ps(out_w + i, _mm_div_ps(one, _mm_add_ps(_mm_add_ps(rm, rm), one)));
}

/* ---- coc_row: 4 pixels ---- */
typedef struct {
    __m128 K, idn, idf, dn, df;
} dof_coc4_k;

static inline dof_coc4_k dof_coc4_setup(float K, float dn, float df)
{
    dof_coc4_k k;
    k.K = _mm_set1_ps(K);
    k.idn = _mm_set1_ps(1.0f / dn);
    k.idf = _mm_set1_ps(1.0f / df);
    k.dn = _mm_set1_ps(dn);
    k.df = _mm_set1_ps(df);
    return k;
}

/* depths of 4 pixels -> their CoCs: g < dn ? K (1/dn - 1/g) : g > df ? K (1/df - 1/g) : 0 */
static inline __m128 dof_coc4(__m128 d, const dof_coc4_k *k)
{
    const __m128 g = _mm_max_ps(d, _mm_set1_ps(FV_COC_MIN_DEPTH_M)); /* d > min ? d : min */
    const __m128 ig = _mm_div_ps(_mm_set1_ps(1.0f), g);
    const __m128 nr = _mm_mul_ps(k->K, _mm_sub_ps(k->idn, ig));
    const __m128 fr = _mm_and_ps(_mm_mul_ps(k->K, _mm_sub_ps(k->idf, ig)), _mm_cmpgt_ps(g, k->df));
    return _mm_blendv_ps(fr, nr, _mm_cmplt_ps(g, k->dn));
}

/* lane 3 of 4 consecutive pixels */
static inline __m128 dof_depth4(const float *rgbd)
{
    const __m128 h01 = _mm_unpackhi_ps(_mm_loadu_ps(rgbd), _mm_loadu_ps(rgbd + 4));       /* z0 z1 d0 d1 */
    const __m128 h23 = _mm_unpackhi_ps(_mm_loadu_ps(rgbd + 8), _mm_loadu_ps(rgbd + 12));  /* z2 z3 d2 d3 */
    return _mm_movehl_ps(h23, h01);
}

/* ---- hgauss_row ---- */

/* The row as the far layer sees it, positions base .. base+len-1 clamped into [0, w):
 * (r, g, b, 1) for a far sample (coc > 0), +0 otherwise (so g * m adds exactly what the
 * reference adds, or +-0 for a skipped tap). 16-byte aligned m. */
static inline void dof_mask_row(float *restrict m, const float *rgbd, const float *coc, int w, int base, int len)
{
    const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
    for (int k = 0; k < len; k++) {
        const int q = fv_clampi(base + k, 0, w - 1);
        const __m128 p = _mm_blend_ps(_mm_loadu_ps(rgbd + 4 * q), one, 8);
        _mm_store_ps(m + 4 * k, _mm_and_ps(p, _mm_cmpgt_ps(_mm_set1_ps(coc[q]), zero)));
    }
}

/* ---- the Gaussians' taps: tap j of the pixel at p is at p + off[j] (off points at the entry of
 * j = 0 and holds the span's largest radius either way): the masked row's neighbours for the
 * horizontal pass, the clamped rows for the vertical one. Pixel k of a block is at p + 4 k. */

/* One pixel, its own radius. */
static inline __m128 dof_g1(const float *p, const ptrdiff_t *off, const float *wt, int R)
{
    __m128 a = _mm_setzero_ps();
    for (int j = -R; j <= R; j++)
        a = _mm_add_ps(a, _mm_mul_ps(_mm_set1_ps(wt[j < 0 ? -j : j]), _mm_loadu_ps(p + off[j])));
    return a;
}

/* Four neighbouring pixels, the block's largest radius R (see the top of this file). */
static inline void dof_g4(__m128 a[4], const float *p, const ptrdiff_t *off, const float *const wt[4], int R)
{
    __m128 a0 = _mm_setzero_ps(), a1 = a0, a2 = a0, a3 = a0;
    if (wt[0] == wt[1] && wt[0] == wt[2] && wt[0] == wt[3]) { /* one sigma: one broadcast a tap */
        for (int j = -R; j <= R; j++) {
            const float *q = p + off[j];
            const __m128 g = _mm_set1_ps(wt[0][j < 0 ? -j : j]);
            a0 = _mm_add_ps(a0, _mm_mul_ps(g, _mm_loadu_ps(q)));
            a1 = _mm_add_ps(a1, _mm_mul_ps(g, _mm_loadu_ps(q + 4)));
            a2 = _mm_add_ps(a2, _mm_mul_ps(g, _mm_loadu_ps(q + 8)));
            a3 = _mm_add_ps(a3, _mm_mul_ps(g, _mm_loadu_ps(q + 12)));
        }
    } else {
        for (int j = -R; j <= R; j++) {
            const int k = j < 0 ? -j : j;
            const float *q = p + off[j];
            a0 = _mm_add_ps(a0, _mm_mul_ps(_mm_set1_ps(wt[0][k]), _mm_loadu_ps(q)));
            a1 = _mm_add_ps(a1, _mm_mul_ps(_mm_set1_ps(wt[1][k]), _mm_loadu_ps(q + 4)));
            a2 = _mm_add_ps(a2, _mm_mul_ps(_mm_set1_ps(wt[2][k]), _mm_loadu_ps(q + 8)));
            a3 = _mm_add_ps(a3, _mm_mul_ps(_mm_set1_ps(wt[3][k]), _mm_loadu_ps(q + 12)));
        }
    }
    a[0] = a0, a[1] = a1, a[2] = a2, a[3] = a3;
}

/* n pixels from p (output d), 4 at a time; norm: times inv[s] (the horizontal pass). */
static inline void dof_gauss_4(float *d, const float *p, const ptrdiff_t *off, int n, const uint8_t *sig,
                               const fv_dof_gauss_tab *tab, int norm)
{
    int i = 0;
    for (; i + 4 <= n; i += 4) {
        const uint8_t *s = sig + i;
        const float *const wt[4] = {tab->w[s[0]], tab->w[s[1]], tab->w[s[2]], tab->w[s[3]]};
        const int R = fv_maxi(fv_maxi(tab->rad[s[0]], tab->rad[s[1]]), fv_maxi(tab->rad[s[2]], tab->rad[s[3]]));
        __m128 a[4];
        dof_g4(a, p + 4 * i, off, wt, R);
        for (int k = 0; k < 4; k++)
            _mm_storeu_ps(d + 4 * (i + k), norm ? _mm_mul_ps(a[k], _mm_set1_ps(tab->inv[s[k]])) : a[k]);
    }
    for (; i < n; i++) {
        const __m128 a = dof_g1(p + 4 * i, off, tab->w[sig[i]], tab->rad[sig[i]]);
        _mm_storeu_ps(d + 4 * i, norm ? _mm_mul_ps(a, _mm_set1_ps(tab->inv[sig[i]])) : a);
    }
}

/* The offsets of the taps j in [-R, R]: the horizontal pass's (neighbours in the masked row)
 * and the vertical pass's (rows clamped into [ylo, yhi), relative to row 0). off points at j = 0. */
static inline void dof_offsets_h(ptrdiff_t *off, int R)
{
    for (int j = -R; j <= R; j++)
        off[j] = 4 * (ptrdiff_t)j;
}
static inline void dof_offsets_v(ptrdiff_t *off, int R, ptrdiff_t stride, int y, int ylo, int yhi)
{
    for (int j = -R; j <= R; j++)
        off[j] = 4 * (ptrdiff_t)fv_clampi(y + j, ylo, yhi - 1) * stride;
}

static inline int dof_span_rad(const uint8_t *sig, int n, const fv_dof_gauss_tab *tab)
{
    int R = 0;
    for (int i = 0; i < n; i++)
        R = fv_maxi(R, tab->rad[sig[i]]);
    return R;
}

/* ---- combine_row, one pixel at a time: the reference's control flow, colours as vectors (the
 * SSE4.1 version; the AVX2 one's tail) ---- */

static inline __m128 dof_bcast3(__m128 v) { return _mm_shuffle_ps(v, v, _MM_SHUFFLE(3, 3, 3, 3)); }

/* a + s (b - a), s broadcast */
static inline __m128 dof_lerp(__m128 a, __m128 b, float s)
{
    return _mm_add_ps(a, _mm_mul_ps(_mm_set1_ps(s), _mm_sub_ps(b, a)));
}

static inline void dof_combine_row_x86(float *restrict out, const fv_dof_combine_args *a, int x0, int n)
{
    for (int x = x0; x < x0 + n; x++) {
        const __m128 s = _mm_loadu_ps(a->sharp + 4 * x);
        __m128 o = s; /* lane 3 is carried along unused and replaced by the depth at the end */
        const float c = a->coc[x], t = a->t[x];
        float ab = 0.0f;
        if (c > 0.0f)
            ab = c < 1.0f ? c : 1.0f;
        else if (c < 0.0f && t > 0.0f)
            ab = t * (-c < 1.0f ? -c : 1.0f);
        if (ab > 0.0f)
            o = dof_lerp(o, _mm_loadu_ps(a->far + 4 * x), ab);
        __m128 nv = a->near ? _mm_loadu_ps(a->near + 4 * x) : _mm_setzero_ps();
        if (a->lnear && t > 0.0f) {
            const float sc = c < 0.0f ? 0.0f : 1.0f;
            const __m128 q = _mm_mul_ps(_mm_set1_ps(sc), _mm_loadu_ps(a->lnear + 4 * x));
            nv = _mm_add_ps(nv, _mm_mul_ps(_mm_set1_ps(t), _mm_sub_ps(q, nv)));
        }
        const float n3 = _mm_cvtss_f32(dof_bcast3(nv));
        if (n3 > 0.0f)
            o = dof_lerp(o, _mm_div_ps(nv, dof_bcast3(nv)), n3 < 1.0f ? n3 : 1.0f);
        if (a->enh) {
            const float g = a->gain * t;
            if (g > 0.0f) {
                const __m128 b = _mm_loadu_ps(a->enh + 4 * x);
                const __m128 v = _mm_add_ps(o, _mm_mul_ps(_mm_set1_ps(g), _mm_sub_ps(o, b)));
                o = _mm_max_ps(v, _mm_setzero_ps()); /* v > 0 ? v : +0 */
            }
        }
        _mm_storeu_ps(out + 4 * x, _mm_blend_ps(o, s, 8));
    }
}

/* ---- periph_row: 4 pixels' scalars (w, the masks) as 4 lanes, then one pixel a vector ---- */
#define DOF_BCK(v, k) _mm_shuffle_ps(v, v, _MM_SHUFFLE(k, k, k, k))
static inline void dof_periph4(float *out, const float *sharp, const float *coc, const float *half, const float *lnear,
                               int x)
{
    const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps(), c4 = _mm_loadu_ps(coc + x);
    const __m128 m = _mm_andnot_ps(_mm_set1_ps(-0.0f), c4);
    const __m128 w4 = _mm_mul_ps(_mm_min_ps(m, one), _mm_min_ps(_mm_mul_ps(_mm_mul_ps(m, m), _mm_set1_ps(FV_DOF_L1_SLOPE)), one));
    const __m128 wpos = _mm_cmpgt_ps(w4, zero);
    const __m128 nn = _mm_cmpge_ps(c4, zero); /* !(c < 0), c finite */
    const __m128 q75 = _mm_set1_ps(0.75f), q25 = _mm_set1_ps(0.25f);
#define DOF_PX(k)                                                                                                    \
    do {                                                                                                             \
        const int xi = x + (k);                                                                                      \
        const float *h0 = half + 4 * (ptrdiff_t)(xi >> 1), *h1 = h0 + ((xi & 1) ? 4 : -4);                          \
        const __m128 sv = _mm_loadu_ps(sharp + 4 * (ptrdiff_t)xi);                                                   \
        const __m128 u = _mm_add_ps(_mm_mul_ps(q75, _mm_loadu_ps(h0)), _mm_mul_ps(q25, _mm_loadu_ps(h1)));            \
        const __m128 wk = DOF_BCK(w4, k);                                                                            \
        __m128 o = _mm_blendv_ps(sv, _mm_add_ps(sv, _mm_mul_ps(wk, _mm_sub_ps(u, sv))), DOF_BCK(wpos, k));          \
        if (lnear && _mm_movemask_ps(nn) >> (k) & 1) {                                                               \
            const __m128 q = _mm_loadu_ps(lnear + 4 * (ptrdiff_t)xi), q3 = dof_bcast3(q);                            \
            const __m128 pos = _mm_cmpgt_ps(q3, zero);                                                               \
            o = _mm_blendv_ps(o, _mm_add_ps(o, _mm_mul_ps(_mm_min_ps(q3, one), _mm_sub_ps(_mm_div_ps(q, q3), o))), pos); \
        }                                                                                                            \
        _mm_storeu_ps(out + 4 * (ptrdiff_t)xi, _mm_blend_ps(o, sv, 8));                                              \
    } while (0)
    DOF_PX(0);
    DOF_PX(1);
    DOF_PX(2);
    DOF_PX(3);
#undef DOF_PX
}
#undef DOF_BCK

static inline void dof_periph_row_x86(float *restrict out, const float *sharp, const float *coc, const float *half,
                                      const float *lnear, int x0, int n)
{
    int x = x0;
    for (; x + 4 <= x0 + n; x += 4)
        dof_periph4(out, sharp, coc, half, lnear, x);
    if (x < x0 + n)
        fv_dof_periph_row_c(out, sharp, coc, half, lnear, x, x0 + n - x);
}

/* ---- upsample_row, one pixel a vector, run by run: the s = 2^L pixels of a run share their
 * texels j, j + 1 (x in [s j + s/2, s j + s/2 + s)), so one d = p1 - p0 a run and per pixel
 * p0 + a d, the reference's operations on the same values (the SSE4.1 version; the AVX2 one's
 * ends). Weights (2r + 1) / 2s, r the pixel's place in its run: exact. ---- */

#define DOF_UP_MAXL 5 /* the pyramid's deepest; beyond, the reference */

/* any [x0, x0 + n), partial runs included */
static inline void dof_upruns_x86(float *restrict dst, const float *tmp, int L, int sw, int x0, int n)
{
    const int s = 1 << L, s2 = 2 << L;
    const float inv = 1.0f / (float)s2;
    for (int i = 0; i < n;) {
        const int m = 2 * (x0 + i) + 1 + s, j = (m >> (L + 1)) - 1, r = (m & (s2 - 1)) >> 1;
        const int cnt = s - r < n - i ? s - r : n - i;
        const __m128 p0 = _mm_loadu_ps(tmp + 4 * (ptrdiff_t)fv_clampi(j, 0, sw - 1));
        const __m128 d = _mm_sub_ps(_mm_loadu_ps(tmp + 4 * (ptrdiff_t)fv_clampi(j + 1, 0, sw - 1)), p0);
        for (int k = 0; k < cnt; k++)
            _mm_storeu_ps(dst + 4 * (i + k),
                          _mm_add_ps(p0, _mm_mul_ps(_mm_set1_ps((float)(2 * (r + k) + 1) * inv), d)));
        i += cnt;
    }
}

/* by 2: the run of texels j, j + 1 is pixels 2j + 1 (weight 1/4) and 2j + 2 (3/4), the next
 * run's p0 this one's p1; interior runs only (j >= 0, j + 1 < sw) */
static inline void dof_up2_x86(float *restrict dst, const float *tmp, int j, int runs)
{
    const __m128 a1 = _mm_set1_ps(0.25f), a3 = _mm_set1_ps(0.75f);
    const float *t = tmp + 4 * (ptrdiff_t)j;
    __m128 q0 = _mm_loadu_ps(t);
    for (int q = 0; q < runs; q++, t += 4, dst += 8) {
        const __m128 q1 = _mm_loadu_ps(t + 4), d = _mm_sub_ps(q1, q0);
        _mm_storeu_ps(dst, _mm_add_ps(q0, _mm_mul_ps(a1, d)));
        _mm_storeu_ps(dst + 4, _mm_add_ps(q0, _mm_mul_ps(a3, d)));
        q0 = q1;
    }
}

/* by s >= 4: whole runs (L constant: the weights (2r + 1) / 2s fold to constants) */
static inline __attribute__((always_inline)) void dof_upruns_whole_x86(float *restrict dst, const float *tmp, int sw,
                                                                       int j, int runs, const int L)
{
    const int s = 1 << L;
    for (int q = 0; q < runs; q++, j++, dst += 4 * s) {
        const __m128 p0 = _mm_loadu_ps(tmp + 4 * (ptrdiff_t)fv_clampi(j, 0, sw - 1));
        const __m128 d = _mm_sub_ps(_mm_loadu_ps(tmp + 4 * (ptrdiff_t)fv_clampi(j + 1, 0, sw - 1)), p0);
        for (int r = 0; r < s; r++)
            _mm_storeu_ps(dst + 4 * r, _mm_add_ps(p0, _mm_mul_ps(_mm_set1_ps((float)(2 * r + 1) / (float)(2 * s)), d)));
    }
}

/* the first run start >= x0 (x = s j + s/2; j0 = ceil((x0 - s/2) / s), x0 >= 0) and the number of
 * whole runs from it (by 2: interior ones, j >= 0 and j + 1 < sw) */
static inline int dof_up_whole(int L, int sw, int x0, int n, int *j0)
{
    const int s = 1 << L, x1 = x0 + n;
    *j0 = (x0 + s / 2 - 1) / s;
    const int a = s * *j0 + s / 2;
    if (L == 1) {
        const int e = x1 < 2 * sw - 1 ? x1 : 2 * sw - 1;
        return a < e ? (e - a) >> 1 : 0;
    }
    return a < x1 ? (x1 - a) / s : 0;
}

static inline void dof_upsample_row_x86(float *restrict dst, const float *tmp, int L, int sw, int x0, int n)
{
    int j0, runs;
    if (L < 1 || L > DOF_UP_MAXL) {
        fv_dof_upsample_row_c(dst, tmp, L, sw, x0, n);
        return;
    }
    if ((runs = dof_up_whole(L, sw, x0, n, &j0)) <= 0) {
        dof_upruns_x86(dst, tmp, L, sw, x0, n);
        return;
    }
    const int s = 1 << L, a = s * j0 + s / 2, b = a + s * runs;
    dof_upruns_x86(dst, tmp, L, sw, x0, a - x0);
    float *d = dst + 4 * (a - x0);
    switch (L) {
    case 1: dof_up2_x86(d, tmp, j0, runs); break;
    case 2: dof_upruns_whole_x86(d, tmp, sw, j0, runs, 2); break;
    case 3: dof_upruns_whole_x86(d, tmp, sw, j0, runs, 3); break;
    case 4: dof_upruns_whole_x86(d, tmp, sw, j0, runs, 4); break;
    default: dof_upruns_whole_x86(d, tmp, sw, j0, runs, 5); break;
    }
    dof_upruns_x86(dst + 4 * (b - x0), tmp, L, sw, b, x0 + n - b);
}

/* ---- pyrblur_row ----
 * The per-pixel scalars (active, level LUT index, l, L0, L1, f, mix) of 4 pixels at once, then
 * one pixel a vector: the reference's operations on its 4 channels, kept by selects (a pixel the
 * reference skips gets its own bits back; its garbage levels are valid ones, see below).
 *   The LUT index: the reference's min((int)(m steps), max) is, for m steps in [0, 2^31),
 * (int) of min(m steps, max) (max an integer: trunc(v) < max iff v < max). Clamping the float
 * first (and NaN to 0: x86 max returns its second operand on NaN) keeps every lane's index in
 * [0, max], skipped ones too, so the lookup never leaves the table; then min(l, need) and its
 * (int) are in [0, need] (the table holds levels >= 0) and so are L0 and L1: the loads of a
 * skipped pixel stay in the rows up[0..need] at the call's pixels. */
typedef struct {
    __m128 steps, lmax, need, zero, one, msign;
    __m128i needi;
} dof_pb_k;

static inline dof_pb_k dof_pb_setup(const fv_dof_pyrblur_args *a)
{
    dof_pb_k k;
    k.steps = _mm_set1_ps((float)a->lambda_steps);
    k.lmax = _mm_set1_ps((float)a->lambda_max);
    k.need = _mm_set1_ps((float)a->need);
    k.zero = _mm_setzero_ps();
    k.one = _mm_set1_ps(1.0f);
    k.msign = _mm_set1_ps(-0.0f);
    k.needi = _mm_set1_epi32(a->need);
    return k;
}

/* b = mix ? b + t (pv - b) : pv, pv = u0 + f (u1 - u0); kept where act (all lanes broadcast).
 * domix = 0: no pixel of the block both mixes and is blended (r = pv is then right for every
 * blended one); doact = 0: every pixel of the block is blended. Constants at each call. */
static inline __m128 dof_pb1(__m128 b, const float *u0p, const float *u1p, __m128 f, __m128 t, __m128 mix,
                             __m128 act, int domix, int doact)
{
    const __m128 u0 = _mm_loadu_ps(u0p), u1 = _mm_loadu_ps(u1p);
    const __m128 pv = _mm_add_ps(u0, _mm_mul_ps(f, _mm_sub_ps(u1, u0)));
    const __m128 r = domix ? _mm_blendv_ps(pv, _mm_add_ps(b, _mm_mul_ps(t, _mm_sub_ps(pv, b))), mix) : pv;
    return doact ? _mm_blendv_ps(b, r, act) : r;
}

#define DOF_BC(v, k) _mm_shuffle_ps(v, v, _MM_SHUFFLE(k, k, k, k))

/* the 4 pixels of a block from pixel i (b = blur + 4 i) */
static inline void dof_pb4(float *b, const float *const *up, const int32_t *L0, const int32_t *L1, __m128 f,
                           __m128 t, __m128 mix, __m128 act, int i, int domix, int doact)
{
    const ptrdiff_t o = 4 * (ptrdiff_t)i;
    _mm_storeu_ps(b, dof_pb1(_mm_loadu_ps(b), up[L0[0]] + o, up[L1[0]] + o, DOF_BC(f, 0), DOF_BC(t, 0),
                             DOF_BC(mix, 0), DOF_BC(act, 0), domix, doact));
    _mm_storeu_ps(b + 4, dof_pb1(_mm_loadu_ps(b + 4), up[L0[1]] + o + 4, up[L1[1]] + o + 4, DOF_BC(f, 1),
                                 DOF_BC(t, 1), DOF_BC(mix, 1), DOF_BC(act, 1), domix, doact));
    _mm_storeu_ps(b + 8, dof_pb1(_mm_loadu_ps(b + 8), up[L0[2]] + o + 8, up[L1[2]] + o + 8, DOF_BC(f, 2),
                                 DOF_BC(t, 2), DOF_BC(mix, 2), DOF_BC(act, 2), domix, doact));
    _mm_storeu_ps(b + 12, dof_pb1(_mm_loadu_ps(b + 12), up[L0[3]] + o + 12, up[L1[3]] + o + 12, DOF_BC(f, 3),
                                  DOF_BC(t, 3), DOF_BC(mix, 3), DOF_BC(act, 3), domix, doact));
}

static inline void dof_pyrblur_row_x86(float *restrict blur, const fv_dof_pyrblur_args *a, int x0, int n)
{
    const dof_pb_k k = dof_pb_setup(a);
    int i = x0;
    for (; i + 4 <= x0 + n; i += 4) {
        const __m128 c = _mm_loadu_ps(a->coc + i), t = _mm_loadu_ps(a->t + i);
        const __m128 m = _mm_andnot_ps(k.msign, c); /* |c| (-0 -> +0: skipped either way) */
        const __m128 act = _mm_and_ps(_mm_cmpgt_ps(m, k.zero), _mm_cmpgt_ps(t, k.zero));
        if (!_mm_movemask_ps(act))
            continue;
        const __m128 v = _mm_min_ps(_mm_max_ps(_mm_mul_ps(m, k.steps), k.zero), k.lmax);
        _Alignas(16) int32_t li[4], L0[4], L1[4];
        _mm_store_si128((__m128i *)li, _mm_cvttps_epi32(v));
        const __m128 l = _mm_min_ps(_mm_setr_ps(a->lambda[li[0]], a->lambda[li[1]], a->lambda[li[2]], a->lambda[li[3]]),
                                    k.need); /* l < need ? l : need */
        const __m128i l0 = _mm_cvttps_epi32(l);
        const __m128 f = _mm_sub_ps(l, _mm_cvtepi32_ps(l0));
        _mm_store_si128((__m128i *)L0, l0);
        _mm_store_si128((__m128i *)L1, _mm_sub_epi32(l0, _mm_cmplt_epi32(l0, k.needi))); /* + 1 where L0 < need */
        const __m128 mix = _mm_and_ps(_mm_cmpgt_ps(c, k.zero), _mm_cmplt_ps(t, k.one));
        float *b = blur + 4 * i;
        const int domix = _mm_movemask_ps(_mm_and_ps(mix, act)) != 0, doact = _mm_movemask_ps(act) != 15;
        /* the common blocks (all blended, none mixing: the periphery) without the selects */
        if (!domix && !doact)
            dof_pb4(b, a->up, L0, L1, f, t, mix, act, i, 0, 0);
        else
            dof_pb4(b, a->up, L0, L1, f, t, mix, act, i, 1, 1);
    }
    for (; i < x0 + n; i++) { /* the reference's control flow, channels as a vector */
        const float c = a->coc[i], t = a->t[i], m = c < 0.0f ? -c : c;
        if (!(m > 0.0f && t > 0.0f))
            continue;
        const float v = m * (float)a->lambda_steps;
        float l = a->lambda[v < (float)a->lambda_max ? (int)v : a->lambda_max];
        l = l < (float)a->need ? l : (float)a->need;
        const int L0 = (int)l, L1 = L0 < a->need ? L0 + 1 : L0;
        const __m128 all = _mm_castsi128_ps(_mm_set1_epi32(-1));
        const __m128 mix = c > 0.0f && t < 1.0f ? all : k.zero;
        float *b = blur + 4 * i;
        _mm_storeu_ps(b, dof_pb1(_mm_loadu_ps(b), a->up[L0] + 4 * i, a->up[L1] + 4 * i, _mm_set1_ps(l - (float)L0),
                                 _mm_set1_ps(t), mix, all, 1, 0));
    }
}


/* The Gaussian row kernels' set-up (tap offsets, the masked far row of a chunk); DOF_GAUSS is the
 * ISA's block routine: dof_gauss_4 above, or for AVX2 dof_gauss_8 (core/x86/dof_avx2.c, 8 pixels
 * a step, then dof_gauss_4). */
#if FV_X86_W == 8
static inline void dof_gauss_8(float *d, const float *p, const ptrdiff_t *off, int n, const uint8_t *sig,
                               const fv_dof_gauss_tab *tab, int norm);
#define DOF_GAUSS dof_gauss_8
#else
#define DOF_GAUSS dof_gauss_4
#endif

static void FV_X86_FN(hgauss_row)(float *restrict dst, const float *rgbd, const float *coc, int w, int x0, int n,
                                  const uint8_t *sig, const fv_dof_gauss_tab *tab)
{
    _Alignas(4 * FV_X86_W) float m[4 * (DOF_CH + 2 * FV_DOF_RMAX)];
    ptrdiff_t offs[2 * FV_DOF_RMAX + 1], *off = offs + FV_DOF_RMAX;
    dof_offsets_h(off, FV_DOF_RMAX);
    for (int c0 = 0; c0 < n; c0 += DOF_CH) {
        const int cn = n - c0 < DOF_CH ? n - c0 : DOF_CH, Rc = dof_span_rad(sig + c0, cn, tab);
        dof_mask_row(m, rgbd, coc, w, x0 + c0 - Rc, cn + 2 * Rc);
        /* output pixel c0 + i from m + 4 (Rc + i) */
        DOF_GAUSS(dst + 4 * (ptrdiff_t)(x0 + c0), m + 4 * Rc, off, cn, sig + c0, tab, 1);
    }
}

static void FV_X86_FN(vgauss_row)(float *restrict dst, const float *src, ptrdiff_t stride, int y, int ylo, int yhi,
                                  int x0, int n, const uint8_t *sig, const fv_dof_gauss_tab *tab)
{
    ptrdiff_t offs[2 * FV_DOF_RMAX + 1], *off = offs + FV_DOF_RMAX;
    const int R = dof_span_rad(sig, n, tab);
    dof_offsets_v(off, R, stride, y, ylo, yhi);
    DOF_GAUSS(dst + 4 * (ptrdiff_t)x0, src + 4 * (ptrdiff_t)x0, off, n, sig, tab, 0);
}
