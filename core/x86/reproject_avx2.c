/* fovea: temporal reprojection kernels, AVX2. The blend takes eight samples a step: the tile's
 * samples are gathered in row-major groups of eight, projected lane by lane, and where the
 * footprint is one texel of level 0 (the default configuration, a dense rotating history) the
 * single bilinear tap runs in SoA form (each sample's two texel rows one 256-bit load each, 8x8
 * transposes); wider footprints go through the shared scalar taps. The fill takes eight pixels
 * at a time. Same operations in the same order per lane as the reference (built with -mfma but
 * -ffp-contract=off, no FMA intrinsics): bit-identical.
 * (A first version was no faster than the per-sample loop: its taps waited on history misses
 * one group at a time and its per-lane loops over arrays of vectors went through the stack;
 * here groups are prefetched two ahead and the per-lane code is straight-line; docs/reproject.md.) */
#include <immintrin.h>

#include <stdint.h>
#include <string.h>

#include "reproject_dsp.h"
#include "reproject.h"
#include "reproject_still_lane.h"
#define FV_X86_W 8
#define FV_X86_FN(name) name##_avx2
#include "x86/reproject_tmpl.h"

static inline void tap(const fv_pyr_level *L, float s, float t, float zexp, float inv_tol, acc4 *acc, float *accw)
{
    const tap_pos p = tap_at(L, s, t);
    const __m256 top = _mm256_loadu_ps(L->rgbd + 4 * p.o00); /* c00 | c10 */
    const __m256 bot = _mm256_loadu_ps(L->rgbd + 4 * p.o01); /* c01 | c11 */
    /* depths in texel order 00, 01, 10, 11 */
    const __m256 zw = _mm256_unpackhi_ps(top, bot); /* (c00.b, c01.b, c00.d, c01.d | c10.b, c11.b, c10.d, c11.d) */
    const __m128 d = _mm_movehl_ps(_mm256_extractf128_ps(zw, 1), _mm256_castps256_ps128(zw));
    const __m128 wt = tap_weights(L, &p, d, zexp, inv_tol);
    /* (w00 | w10) for the top row, (w01 | w11) for the bottom row, each broadcast over 4 lanes */
    const __m256 wt8 = _mm256_castps128_ps256(wt);
    const __m256 wtop = _mm256_permutevar8x32_ps(wt8, _mm256_setr_epi32(0, 0, 0, 0, 2, 2, 2, 2));
    const __m256 wbot = _mm256_permutevar8x32_ps(wt8, _mm256_setr_epi32(1, 1, 1, 1, 3, 3, 3, 3));
    const __m256 s8 = _mm256_add_ps(_mm256_mul_ps(wtop, top), _mm256_mul_ps(wbot, bot)); /* 00+01 | 10+11 */
    *acc = _mm_add_ps(*acc, _mm_add_ps(_mm256_castps256_ps128(s8), _mm256_extractf128_ps(s8, 1)));
    *accw = *accw + tap_weight_sum(wt);
}

static inline uint64_t sample_mask(const float *wgt, int n)
{
    uint64_t m = 0;
    int i = 0;
    for (; i + 8 <= n; i += 8)
        m |= (uint64_t)_mm256_movemask_ps(_mm256_cmp_ps(_mm256_loadu_ps(wgt + i), _mm256_set1_ps(1.0f), _CMP_EQ_OQ)) << i;
    for (; i < n; i++)
        m |= (uint64_t)(wgt[i] == 1.0f) << i;
    return m;
}

#define TAA_FN FV_X86_FN
#define TAA_OWN_BLEND /* eight samples a step, below */
#include "../reproject_tmpl.h" /* the row loops every ISA shares */

/* Lanes k and k + 4 of eight 256-bit rows -> in-lane 4x4 transposes: with x[k] holding sample k's
 * (c0, c1, c2, c3 | c0', c1', c2', c3'), returns c0..c3 (out[0..3]) and c0'..c3' (out[4..7]) as
 * vectors of the eight samples (lanes 0-3: samples 0-3, lanes 4-7: samples 4-7). */
#define SOA4(a0, a1, a2, a3, o0, o1, o2, o3)                                                        \
    do {                                                                                            \
        const __m256 t0_ = _mm256_unpacklo_ps(a0, a1), t1_ = _mm256_unpackhi_ps(a0, a1);            \
        const __m256 t2_ = _mm256_unpacklo_ps(a2, a3), t3_ = _mm256_unpackhi_ps(a2, a3);            \
        o0 = _mm256_shuffle_ps(t0_, t2_, _MM_SHUFFLE(1, 0, 1, 0));                                  \
        o1 = _mm256_shuffle_ps(t0_, t2_, _MM_SHUFFLE(3, 2, 3, 2));                                  \
        o2 = _mm256_shuffle_ps(t1_, t3_, _MM_SHUFFLE(1, 0, 1, 0));                                  \
        o3 = _mm256_shuffle_ps(t1_, t3_, _MM_SHUFFLE(3, 2, 3, 2));                                  \
    } while (0)
#define SOA8(x, out)                                                                                 \
    do {                                                                                            \
        SOA4(_mm256_permute2f128_ps(x[0], x[4], 0x20), _mm256_permute2f128_ps(x[1], x[5], 0x20),     \
             _mm256_permute2f128_ps(x[2], x[6], 0x20), _mm256_permute2f128_ps(x[3], x[7], 0x20),     \
             out[0], out[1], out[2], out[3]);                                                       \
        SOA4(_mm256_permute2f128_ps(x[0], x[4], 0x31), _mm256_permute2f128_ps(x[1], x[5], 0x31),     \
             _mm256_permute2f128_ps(x[2], x[6], 0x31), _mm256_permute2f128_ps(x[3], x[7], 0x31),     \
             out[4], out[5], out[6], out[7]);                                                       \
    } while (0)

/* Two floats (a weight and its right neighbour's) at p + o[k] for eight samples k -> the first and
 * the second as vectors of the eight samples (lane order as SOA8). */
static inline __attribute__((always_inline)) void soa8_pairs(const float *p, const int32_t o[8], __m256 *first,
                                                             __m256 *second)
{
#define PAIR(k) _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(p + o[k])))), \
                                     _mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(p + o[k + 4]))), 1)
    const __m256 q0 = PAIR(0), q1 = PAIR(1), q2 = PAIR(2), q3 = PAIR(3);
#undef PAIR
    const __m256 a = _mm256_unpacklo_ps(q0, q1), b = _mm256_unpacklo_ps(q2, q3);
    *first = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(1, 0, 1, 0));
    *second = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 2, 3, 2));
}

typedef struct {
    __m256 R, G, B, D, u, v, z, inv_tol; /* the samples and their projection */
    int32_t off[8];                      /* each sample's pixel offset from the block */
    int32_t oi[8];                       /* level-0 offset of each single tap's texel 00 */
    unsigned sm;                         /* lanes whose single tap is pending */
} taa_group;

/* A group of eight samples in row-major order (off[]: pixel offsets from rgbd_blk; xs[], ys[]:
 * pixel coordinates; lanes n..7 repeat an earlier sample and are never written), projected as
 * the reference does, lane by lane (core/reproject_tmpl.h): the flow sums are added in sample
 * order; where the footprint is one texel of level 0 (the default configuration: a dense
 * rotating history) the single tap is left pending in g with its history prefetched; samples
 * with wider footprints take the scalar taps at once. Returns the pending lanes. */
static inline __attribute__((always_inline)) unsigned group_project(const struct fv_taa_frame *f,
                                                                    const struct fv_taa_tile *t, float *rgbd_blk,
                                                                    const int32_t off[8], const int32_t xs[8],
                                                                    const int32_t ys[8], int n, int keep_sample,
                                                                    float *fdx, float *fdy, float *fn, taa_group *g)
{
#define PX(k) (rgbd_blk + 4 * (ptrdiff_t)off[k])
#define LD2(k) _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(PX(k))), _mm_loadu_ps(PX(k + 4)), 1)
    __m256 R, G, B, D;
    SOA4(LD2(0), LD2(1), LD2(2), LD2(3), R, G, B, D); /* samples 0-3 | 4-7 as r, g, b, depth */
#undef LD2
    const __m256i xi = _mm256_loadu_si256((const __m256i *)xs), yi = _mm256_loadu_si256((const __m256i *)ys);
    const __m256 half = _mm256_set1_ps(0.5f), one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps();
    const __m256 pxc = _mm256_add_ps(_mm256_cvtepi32_ps(xi), half), py = _mm256_add_ps(_mm256_cvtepi32_ps(yi), half);
    __m256 u, v, z, rz, valid;
    if (f->identity) {
        u = pxc, v = py, z = D;
        rz = _mm256_div_ps(one, z);
        valid = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    } else {
        /* written out (GCC kept a loop over k with its broadcasts, 42 instructions a group) */
#define ROWK(k) _mm256_add_ps(_mm256_set1_ps(f->T[k]),                                                              \
                              _mm256_mul_ps(D, _mm256_add_ps(_mm256_add_ps(_mm256_set1_ps(f->M0[k]),                \
                                                                           _mm256_mul_ps(py, _mm256_set1_ps(f->MY[k]))), \
                                                             _mm256_mul_ps(pxc, _mm256_set1_ps(f->MX[k])))))
        const __m256 cU = ROWK(0), cV = ROWK(1);
        z = ROWK(2);
#undef ROWK
        valid = _mm256_cmp_ps(z, _mm256_set1_ps(1e-4f), _CMP_GT_OQ);
        rz = _mm256_div_ps(one, z);
        u = _mm256_mul_ps(cU, rz);
        v = _mm256_mul_ps(cV, rz);
    }
    valid = _mm256_and_ps(valid, _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(u, zero, _CMP_GE_OQ),
                                                             _mm256_cmp_ps(u, _mm256_set1_ps(f->prev_w), _CMP_LT_OQ)),
                                               _mm256_and_ps(_mm256_cmp_ps(v, zero, _CMP_GE_OQ),
                                                             _mm256_cmp_ps(v, _mm256_set1_ps(f->prev_h), _CMP_LT_OQ))));
    const unsigned vm = (unsigned)_mm256_movemask_ps(valid) & ((1u << n) - 1u);
    if (!vm)
        return 0;
    { /* the flow sums, in sample order as the reference adds them: (dx, dy) pairs, one 2-lane add
       * per sample (lanes 2 and 3 of the accumulator carry garbage, never read) */
        const __m256 du = _mm256_sub_ps(u, pxc), dv = _mm256_sub_ps(v, py);
        const __m256 lo = _mm256_unpacklo_ps(du, dv), hi = _mm256_unpackhi_ps(du, dv);
        /* pairs of samples 0, 1 | 4, 5 and 2, 3 | 6, 7 */
        const __m128 p01 = _mm256_castps256_ps128(lo), p23 = _mm256_castps256_ps128(hi);
        const __m128 p45 = _mm256_extractf128_ps(lo, 1), p67 = _mm256_extractf128_ps(hi, 1);
        __m128 acc = _mm_setr_ps(*fdx, *fdy, 0.0f, 0.0f);
        if (vm == 0xffu) {
            acc = _mm_add_ps(acc, p01), acc = _mm_add_ps(acc, _mm_movehl_ps(p01, p01));
            acc = _mm_add_ps(acc, p23), acc = _mm_add_ps(acc, _mm_movehl_ps(p23, p23));
            acc = _mm_add_ps(acc, p45), acc = _mm_add_ps(acc, _mm_movehl_ps(p45, p45));
            acc = _mm_add_ps(acc, p67), acc = _mm_add_ps(acc, _mm_movehl_ps(p67, p67));
        } else {
            const __m128 pr[8] = {p01, _mm_movehl_ps(p01, p01), p23, _mm_movehl_ps(p23, p23),
                                  p45, _mm_movehl_ps(p45, p45), p67, _mm_movehl_ps(p67, p67)};
            for (unsigned m = vm; m; m &= m - 1)
                acc = _mm_add_ps(acc, pr[__builtin_ctz(m)]);
        }
        *fdx = _mm_cvtss_f32(acc), *fdy = _mm_cvtss_f32(_mm_shuffle_ps(acc, acc, 1));
        /* sn + 1 per sample is exact on integers below 2^24: the count at once */
        *fn = *fn + (float)__builtin_popcount(vm);
    }
    if (keep_sample)
        return 0; /* history has no weight here: the samples stay exactly as traced */
    /* footprint: one texel of level 0 where !(fp >= 2) and the half extent o < 1/8 */
    const __m256 fp = _mm256_mul_ps(_mm256_mul_ps(D, rz), _mm256_set1_ps(t->widen));
    __m256 o = _mm256_mul_ps(_mm256_sub_ps(fp, one), half);
    o = _mm256_blendv_ps(half, o, _mm256_cmp_ps(o, half, _CMP_LT_OQ)); /* o < 0.5 ? o : 0.5 */
    const __m256 single = _mm256_andnot_ps(_mm256_or_ps(_mm256_cmp_ps(fp, _mm256_set1_ps(2.0f), _CMP_GE_OQ),
                                                        _mm256_cmp_ps(o, _mm256_set1_ps(0.125f), _CMP_GE_OQ)),
                                           valid);
    const unsigned sm = (unsigned)_mm256_movemask_ps(single) & vm;
    const __m256 inv_tol = _mm256_mul_ps(rz, _mm256_set1_ps(f->inv_depth_tol));
    if (sm != vm) { /* wider footprints: the scalar taps (rare in the default configuration) */
        float uu[8], vv[8], zz[8], it[8], ff[8];
        _mm256_storeu_ps(uu, u), _mm256_storeu_ps(vv, v), _mm256_storeu_ps(zz, z);
        _mm256_storeu_ps(it, inv_tol), _mm256_storeu_ps(ff, fp);
        for (unsigned m = vm & ~sm; m; m &= m - 1) {
            const int k = __builtin_ctz(m);
            taa_pending q;
            q.px = PX(k);
            q.u = uu[k], q.v = vv[k], q.z = zz[k], q.inv_tol = it[k];
            q.l = taa_footprint(f, ff[k], &q.o);
            taa_taps(f, t, &q);
        }
    }
#undef PX
    if (!sm)
        return 0;
    /* the single tap reads texels floor(u - 0.5), floor(v - 0.5) and their neighbours at level 0:
     * prefetch their lines now, the taps run TAA_GROUP_DIST groups later */
    const fv_pyr_level *L = &f->hist->lv[0];
    __m256i o00 = _mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(_mm256_floor_ps(_mm256_sub_ps(v, half))),
                                                      _mm256_set1_epi32((int)L->stride)),
                                   _mm256_cvttps_epi32(_mm256_floor_ps(_mm256_sub_ps(u, half))));
    o00 = _mm256_and_si256(o00, _mm256_castps_si256(single)); /* other lanes read texel (0, 0) */
    _mm256_storeu_si256((__m256i *)g->oi, o00);
    { /* idle lanes prefetch texel (0, 0), harmless; written out (GCC kept a 12-instruction loop) */
        const char *c0 = (const char *)L->rgbd, *c1 = (const char *)(L->rgbd + 4 * L->stride);
        const char *w0 = (const char *)L->wgt, *w1 = (const char *)(L->wgt + L->stride);
#define PF(k)                                                                                        \
        do {                                                                                         \
            const ptrdiff_t o_ = (ptrdiff_t)g->oi[k];                                                \
            _mm_prefetch(c0 + 16 * o_, _MM_HINT_T0), _mm_prefetch(c1 + 16 * o_, _MM_HINT_T0);        \
            _mm_prefetch(w0 + 4 * o_, _MM_HINT_T0), _mm_prefetch(w1 + 4 * o_, _MM_HINT_T0);          \
        } while (0)
        PF(0); PF(1); PF(2); PF(3); PF(4); PF(5); PF(6); PF(7);
#undef PF
    }
    memcpy(g->off, off, sizeof g->off);
    g->R = R, g->G = G, g->B = B, g->D = D, g->u = u, g->v = v, g->z = z, g->inv_tol = inv_tol;
    g->sm = sm;
    return sm;
}

/* The single taps of a projected group and the blend of its samples (the reference's tap at
 * level 0 and out_blend, lane by lane). */
static inline __attribute__((always_inline)) void group_taps(const struct fv_taa_frame *f,
                                                             const struct fv_taa_tile *t, float *rgbd_blk,
                                                             const taa_group *g)
{
    const fv_pyr_level *L = &f->hist->lv[0];
    const __m256 half = _mm256_set1_ps(0.5f), one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps();
    const __m256 z = g->z, inv_tol = g->inv_tol;
    const int32_t *oi = g->oi;
    /* s = u * 1 - 0.5, t = v * 1 - 0.5 */
    const __m256 s = _mm256_sub_ps(g->u, half), tt = _mm256_sub_ps(g->v, half);
    const __m256 fx = _mm256_sub_ps(s, _mm256_floor_ps(s)), fy = _mm256_sub_ps(tt, _mm256_floor_ps(tt));
    const __m256 omx = _mm256_sub_ps(one, fx), omy = _mm256_sub_ps(one, fy);
    const float *h0 = L->rgbd, *h1 = L->rgbd + 4 * L->stride;
    __m256 x[8], ct[8], cb[8]; /* r, g, b, depth of texels 00, 10 (ct) and 01, 11 (cb) */
#define LT(k) x[k] = _mm256_loadu_ps(h0 + 4 * (ptrdiff_t)oi[k]) /* c00 | c10 */
    LT(0), LT(1), LT(2), LT(3), LT(4), LT(5), LT(6), LT(7);
#undef LT
    SOA8(x, ct);
#define LB(k) x[k] = _mm256_loadu_ps(h1 + 4 * (ptrdiff_t)oi[k]) /* c01 | c11 */
    LB(0), LB(1), LB(2), LB(3), LB(4), LB(5), LB(6), LB(7);
#undef LB
    SOA8(x, cb);
    __m256 W00, W10, W01, W11;
    soa8_pairs(L->wgt, oi, &W00, &W10);
    soa8_pairs(L->wgt + L->stride, oi, &W01, &W11);
    const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
#define AGREE(d) _mm256_max_ps(_mm256_sub_ps(one, _mm256_mul_ps(_mm256_and_ps(_mm256_sub_ps(d, z), absmask), inv_tol)), zero)
    const __m256 w00 = _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(omx, omy), W00), AGREE(ct[3]));
    const __m256 w01 = _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(omx, fy), W01), AGREE(cb[3]));
    const __m256 w10 = _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(fx, omy), W10), AGREE(ct[7]));
    const __m256 w11 = _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(fx, fy), W11), AGREE(cb[7]));
#undef AGREE
    const __m256 accw = _mm256_add_ps(zero, _mm256_add_ps(_mm256_add_ps(w00, w01), _mm256_add_ps(w10, w11)));
    const __m256 ok = _mm256_cmp_ps(accw, zero, _CMP_GT_OQ);
    const unsigned bm = (unsigned)_mm256_movemask_ps(ok) & g->sm;
    if (!bm)
        return; /* no valid history: the samples stand alone */
    const __m256 alpha = _mm256_max_ps(_mm256_sub_ps(one, accw), _mm256_set1_ps(t->alpha)); /* a1 > alpha ? a1 : alpha */
    __m256 res[3];
    /* written out (GCC kept a loop over the channels with px[] on the stack) */
#define CHAN(c, pxc)                                                                                          \
    do {                                                                                                      \
        const __m256 acc = _mm256_add_ps(zero, _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(w00, ct[c]), _mm256_mul_ps(w01, cb[c])), \
                                                             _mm256_add_ps(_mm256_mul_ps(w10, ct[4 + c]), _mm256_mul_ps(w11, cb[4 + c])))); \
        const __m256 hh = _mm256_div_ps(acc, accw);                                                           \
        /* lanes without history keep their colour (stored back unchanged below) */                          \
        res[c] = _mm256_blendv_ps(pxc, _mm256_add_ps(hh, _mm256_mul_ps(alpha, _mm256_sub_ps(pxc, hh))), ok);   \
    } while (0)
    CHAN(0, g->R);
    CHAN(1, g->G);
    CHAN(2, g->B);
#undef CHAN
    /* back to pixels (r, g, b, depth: the depth stays the sample's), lanes k | k + 4 */
    __m256 pk[4];
    SOA4(res[0], res[1], res[2], g->D, pk[0], pk[1], pk[2], pk[3]);
#define ST(k) _mm_storeu_ps(rgbd_blk + 4 * (ptrdiff_t)g->off[k], k < 4 ? _mm256_castps256_ps128(pk[k & 3]) \
                                                                        : _mm256_extractf128_ps(pk[k & 3], 1))
    if (g->sm == 0xffu) { /* every lane a pending sample: store all, those without history unchanged */
        ST(0), ST(1), ST(2), ST(3), ST(4), ST(5), ST(6), ST(7);
    } else {
        for (unsigned m = bm; m; m &= m - 1) {
            switch (__builtin_ctz(m)) {
            case 0: ST(0); break;
            case 1: ST(1); break;
            case 2: ST(2); break;
            case 3: ST(3); break;
            case 4: ST(4); break;
            case 5: ST(5); break;
            case 6: ST(6); break;
            default: ST(7); break;
            }
        }
    }
#undef ST
}

/* The listing of a row's samples (reproject_blend_tmpl.h), eight pixels a step: the byte indices of
 * the set bits of each mask byte from a table (2 KiB), widened and stored whole; n advances by the
 * byte's popcount. ~10 instructions per 8 pixels instead of ~14 per sample with tzcnt. The row's
 * pixels are prefetched once (hot after shading in the pipeline; cold in checkasm --bench). */
static const uint64_t taa_list_lut[256] = {
    0x0000000000000000ull, 0x0000000000000000ull, 0x0000000000000001ull, 0x0000000000000100ull,
    0x0000000000000002ull, 0x0000000000000200ull, 0x0000000000000201ull, 0x0000000000020100ull,
    0x0000000000000003ull, 0x0000000000000300ull, 0x0000000000000301ull, 0x0000000000030100ull,
    0x0000000000000302ull, 0x0000000000030200ull, 0x0000000000030201ull, 0x0000000003020100ull,
    0x0000000000000004ull, 0x0000000000000400ull, 0x0000000000000401ull, 0x0000000000040100ull,
    0x0000000000000402ull, 0x0000000000040200ull, 0x0000000000040201ull, 0x0000000004020100ull,
    0x0000000000000403ull, 0x0000000000040300ull, 0x0000000000040301ull, 0x0000000004030100ull,
    0x0000000000040302ull, 0x0000000004030200ull, 0x0000000004030201ull, 0x0000000403020100ull,
    0x0000000000000005ull, 0x0000000000000500ull, 0x0000000000000501ull, 0x0000000000050100ull,
    0x0000000000000502ull, 0x0000000000050200ull, 0x0000000000050201ull, 0x0000000005020100ull,
    0x0000000000000503ull, 0x0000000000050300ull, 0x0000000000050301ull, 0x0000000005030100ull,
    0x0000000000050302ull, 0x0000000005030200ull, 0x0000000005030201ull, 0x0000000503020100ull,
    0x0000000000000504ull, 0x0000000000050400ull, 0x0000000000050401ull, 0x0000000005040100ull,
    0x0000000000050402ull, 0x0000000005040200ull, 0x0000000005040201ull, 0x0000000504020100ull,
    0x0000000000050403ull, 0x0000000005040300ull, 0x0000000005040301ull, 0x0000000504030100ull,
    0x0000000005040302ull, 0x0000000504030200ull, 0x0000000504030201ull, 0x0000050403020100ull,
    0x0000000000000006ull, 0x0000000000000600ull, 0x0000000000000601ull, 0x0000000000060100ull,
    0x0000000000000602ull, 0x0000000000060200ull, 0x0000000000060201ull, 0x0000000006020100ull,
    0x0000000000000603ull, 0x0000000000060300ull, 0x0000000000060301ull, 0x0000000006030100ull,
    0x0000000000060302ull, 0x0000000006030200ull, 0x0000000006030201ull, 0x0000000603020100ull,
    0x0000000000000604ull, 0x0000000000060400ull, 0x0000000000060401ull, 0x0000000006040100ull,
    0x0000000000060402ull, 0x0000000006040200ull, 0x0000000006040201ull, 0x0000000604020100ull,
    0x0000000000060403ull, 0x0000000006040300ull, 0x0000000006040301ull, 0x0000000604030100ull,
    0x0000000006040302ull, 0x0000000604030200ull, 0x0000000604030201ull, 0x0000060403020100ull,
    0x0000000000000605ull, 0x0000000000060500ull, 0x0000000000060501ull, 0x0000000006050100ull,
    0x0000000000060502ull, 0x0000000006050200ull, 0x0000000006050201ull, 0x0000000605020100ull,
    0x0000000000060503ull, 0x0000000006050300ull, 0x0000000006050301ull, 0x0000000605030100ull,
    0x0000000006050302ull, 0x0000000605030200ull, 0x0000000605030201ull, 0x0000060503020100ull,
    0x0000000000060504ull, 0x0000000006050400ull, 0x0000000006050401ull, 0x0000000605040100ull,
    0x0000000006050402ull, 0x0000000605040200ull, 0x0000000605040201ull, 0x0000060504020100ull,
    0x0000000006050403ull, 0x0000000605040300ull, 0x0000000605040301ull, 0x0000060504030100ull,
    0x0000000605040302ull, 0x0000060504030200ull, 0x0000060504030201ull, 0x0006050403020100ull,
    0x0000000000000007ull, 0x0000000000000700ull, 0x0000000000000701ull, 0x0000000000070100ull,
    0x0000000000000702ull, 0x0000000000070200ull, 0x0000000000070201ull, 0x0000000007020100ull,
    0x0000000000000703ull, 0x0000000000070300ull, 0x0000000000070301ull, 0x0000000007030100ull,
    0x0000000000070302ull, 0x0000000007030200ull, 0x0000000007030201ull, 0x0000000703020100ull,
    0x0000000000000704ull, 0x0000000000070400ull, 0x0000000000070401ull, 0x0000000007040100ull,
    0x0000000000070402ull, 0x0000000007040200ull, 0x0000000007040201ull, 0x0000000704020100ull,
    0x0000000000070403ull, 0x0000000007040300ull, 0x0000000007040301ull, 0x0000000704030100ull,
    0x0000000007040302ull, 0x0000000704030200ull, 0x0000000704030201ull, 0x0000070403020100ull,
    0x0000000000000705ull, 0x0000000000070500ull, 0x0000000000070501ull, 0x0000000007050100ull,
    0x0000000000070502ull, 0x0000000007050200ull, 0x0000000007050201ull, 0x0000000705020100ull,
    0x0000000000070503ull, 0x0000000007050300ull, 0x0000000007050301ull, 0x0000000705030100ull,
    0x0000000007050302ull, 0x0000000705030200ull, 0x0000000705030201ull, 0x0000070503020100ull,
    0x0000000000070504ull, 0x0000000007050400ull, 0x0000000007050401ull, 0x0000000705040100ull,
    0x0000000007050402ull, 0x0000000705040200ull, 0x0000000705040201ull, 0x0000070504020100ull,
    0x0000000007050403ull, 0x0000000705040300ull, 0x0000000705040301ull, 0x0000070504030100ull,
    0x0000000705040302ull, 0x0000070504030200ull, 0x0000070504030201ull, 0x0007050403020100ull,
    0x0000000000000706ull, 0x0000000000070600ull, 0x0000000000070601ull, 0x0000000007060100ull,
    0x0000000000070602ull, 0x0000000007060200ull, 0x0000000007060201ull, 0x0000000706020100ull,
    0x0000000000070603ull, 0x0000000007060300ull, 0x0000000007060301ull, 0x0000000706030100ull,
    0x0000000007060302ull, 0x0000000706030200ull, 0x0000000706030201ull, 0x0000070603020100ull,
    0x0000000000070604ull, 0x0000000007060400ull, 0x0000000007060401ull, 0x0000000706040100ull,
    0x0000000007060402ull, 0x0000000706040200ull, 0x0000000706040201ull, 0x0000070604020100ull,
    0x0000000007060403ull, 0x0000000706040300ull, 0x0000000706040301ull, 0x0000070604030100ull,
    0x0000000706040302ull, 0x0000070604030200ull, 0x0000070604030201ull, 0x0007060403020100ull,
    0x0000000000070605ull, 0x0000000007060500ull, 0x0000000007060501ull, 0x0000000706050100ull,
    0x0000000007060502ull, 0x0000000706050200ull, 0x0000000706050201ull, 0x0000070605020100ull,
    0x0000000007060503ull, 0x0000000706050300ull, 0x0000000706050301ull, 0x0000070605030100ull,
    0x0000000706050302ull, 0x0000070605030200ull, 0x0000070605030201ull, 0x0007060503020100ull,
    0x0000000007060504ull, 0x0000000706050400ull, 0x0000000706050401ull, 0x0000070605040100ull,
    0x0000000706050402ull, 0x0000070605040200ull, 0x0000070605040201ull, 0x0007060504020100ull,
    0x0000000706050403ull, 0x0000070605040300ull, 0x0000070605040301ull, 0x0007060504030100ull,
    0x0000070605040302ull, 0x0007060504030200ull, 0x0007060504030201ull, 0x0706050403020100ull,
};
static inline __attribute__((always_inline)) int list_row_avx2(const float *wgt, int32_t ro, int32_t x0, int32_t y, int w,
                                                               const float *rgbd_row, int32_t *off, int32_t *xs,
                                                               int32_t *ys, int n)
{
    for (int i = 0; i < w; i += 16)
        _mm_prefetch((const char *)(rgbd_row + 4 * i), _MM_HINT_T0), _mm_prefetch((const char *)(rgbd_row + 4 * i + 32), _MM_HINT_T0);
    const __m256i vy = _mm256_set1_epi32(y), vro = _mm256_set1_epi32(ro), vx0 = _mm256_set1_epi32(x0);
    const __m256 one = _mm256_set1_ps(1.0f);
    for (int i = 0; i < w; i += 8) {
        unsigned mb;
        if (i + 8 <= w)
            mb = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(_mm256_loadu_ps(wgt + i), one, _CMP_EQ_OQ));
        else
            for (int k = mb = 0; i + k < w; k++)
                mb |= (unsigned)(wgt[i + k] == 1.0f) << k;
        const __m256i idx = _mm256_add_epi32(_mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)&taa_list_lut[mb])),
                                             _mm256_set1_epi32(i));
        _mm256_storeu_si256((__m256i *)(off + n), _mm256_add_epi32(idx, vro));
        _mm256_storeu_si256((__m256i *)(xs + n), _mm256_add_epi32(idx, vx0));
        _mm256_storeu_si256((__m256i *)(ys + n), vy);
        n += __builtin_popcount(mb);
    }
    return n;
}
#define TAA_LIST_ROW list_row_avx2
#define TAA_GROUP_LANES 8
#define TAA_GROUP_DIST 2 /* groups (16 samples) between a group's projection and its taps */
#define TAA_GROUP_RING 4
#include "../reproject_blend_tmpl.h"

/* The fill, eight pixels at a time: each lane does the reference's operations (taa_fill_px). The
 * history pixels stay as loaded, two per 256-bit register; their depths are taken out in the
 * lane order 0, 2, 4, 6, 1, 3, 5, 7 (two shuffles), checked in that order, and only the depth
 * lanes of the stored pixels are replaced.
 * Per block, not per row (branch taa9): the span of whole steps, the columns' uc * NX and pixel
 * centres and the frame's constants are the same for every row of the block (the flow is the
 * block's), so they are made once; a row costs its B = N0 + vc NY and its steps. The products
 * uc * NX are the reference's (B + uc NX adds the same float), so the bits do not change. */
#define FILL_MAX_STEPS 8 /* w <= 64 */
static void taa_fill_avx2(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd_blk, float *wgt_blk,
                          ptrdiff_t stride, int x0, int y0, int w, int h)
{
    int ilo, ihi;
    taa_fill_span(f, t, x0, w, &ilo, &ihi);
    const int sx0 = x0 + t->flow_x, nstep = ihi - ilo >= 8 ? (ihi - ilo) / 8 : 0, iend = ilo + 8 * nstep;
    const int identity = f->identity;
    const fv_pyr_level *L = &f->hist->lv[0];
    const float *hrgbd = L->rgbd, *hwgt = L->wgt;
    const ptrdiff_t hstride = L->stride;
    const float prev_h = f->prev_h;
    const float N0[3] = {f->N0[0], f->N0[1], f->N0[2]}, NY[3] = {f->NY[0], f->NY[1], f->NY[2]};
    const __m256 zero = _mm256_setzero_ps(), half = _mm256_set1_ps(0.5f), mhalf = _mm256_set1_ps(-0.5f);
    const __m256i order = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);     /* lane -> pixel of the depth order */
    const __m256i to_linear = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7); /* depth order -> pixel order */
    const __m256 T20 = _mm256_set1_ps(f->T2[0]), T21 = _mm256_set1_ps(f->T2[1]), T22 = _mm256_set1_ps(f->T2[2]);
    const __m256 zmin = _mm256_set1_ps(1e-4f), one = _mm256_set1_ps(1.0f);
    /* per step: uc NX[0..2] and the pixel centres, in the depth order */
    __m256 cu0[FILL_MAX_STEPS], cu1[FILL_MAX_STEPS], cu2[FILL_MAX_STEPS], cpx[FILL_MAX_STEPS];
    if (!identity)
        for (int s = 0; s < nstep; s++) {
            const int i = ilo + 8 * s;
            const __m256 uc = _mm256_add_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(sx0 + i), order)), half);
            cu0[s] = _mm256_mul_ps(uc, _mm256_set1_ps(f->NX[0]));
            cu1[s] = _mm256_mul_ps(uc, _mm256_set1_ps(f->NX[1]));
            cu2[s] = _mm256_mul_ps(uc, _mm256_set1_ps(f->NX[2]));
            cpx[s] = _mm256_add_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(x0 + i), order)), half);
        }
    for (int r = 0; r < h; r++) {
        float *rgbd = rgbd_blk + 4 * r * stride, *wgt = wgt_blk + r * stride;
        const int sy = y0 + r + t->flow_y;
        if (!(sy >= 0 && (float)sy < prev_h))
            continue;
        const float vc = (float)sy + 0.5f;
        const float B[3] = {N0[0] + vc * NY[0], N0[1] + vc * NY[1], N0[2] + vc * NY[2]};
        const ptrdiff_t ho = (ptrdiff_t)sy * hstride;
        const float *hw = hwgt + ho, *hrow = hrgbd + 4 * ho;
        const float py = (float)(y0 + r) + 0.5f;
        const __m256 B0 = _mm256_set1_ps(B[0]), B1 = _mm256_set1_ps(B[1]), B2 = _mm256_set1_ps(B[2]);
        const __m256 pyv = _mm256_set1_ps(py);
        for (int s = 0; s < nstep; s++) {
            const int i = ilo + 8 * s, sx = sx0 + i;
            const __m256 wv = _mm256_loadu_ps(wgt + i);
            const __m256 ws = _mm256_loadu_ps(hw + sx);
            __m256 m = _mm256_and_ps(_mm256_cmp_ps(wv, zero, _CMP_EQ_OQ), _mm256_cmp_ps(ws, zero, _CMP_GT_OQ));
            if (!_mm256_movemask_ps(m))
                continue;
            const float *src = hrow + 4 * sx;
            /* pixels 0|1, 2|3, 4|5, 6|7 (named, not an array: GCC copied an array through the stack in
             * 16-byte halves, and the 32-byte reloads then missed store forwarding) */
            __m256 p0 = _mm256_loadu_ps(src), p1 = _mm256_loadu_ps(src + 8), p2 = _mm256_loadu_ps(src + 16),
                   p3 = _mm256_loadu_ps(src + 24);
            if (!identity) {
                const __m256 a = _mm256_unpackhi_ps(p0, p1), b = _mm256_unpackhi_ps(p2, p3);
                const __m256 D = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 2, 3, 2)); /* depths 0, 2, 4, 6 | 1, 3, 5, 7 */
                const __m256 cU = _mm256_add_ps(T20, _mm256_mul_ps(D, _mm256_add_ps(B0, cu0[s])));
                const __m256 cV = _mm256_add_ps(T21, _mm256_mul_ps(D, _mm256_add_ps(B1, cu1[s])));
                const __m256 z = _mm256_add_ps(T22, _mm256_mul_ps(D, _mm256_add_ps(B2, cu2[s])));
                const __m256 rz = _mm256_div_ps(one, z);
                const __m256 ex = _mm256_sub_ps(_mm256_mul_ps(cU, rz), cpx[s]);
                const __m256 ey = _mm256_sub_ps(_mm256_mul_ps(cV, rz), pyv);
                const __m256 ok = _mm256_and_ps(_mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(ex, half, _CMP_LE_OQ), _mm256_cmp_ps(ex, mhalf, _CMP_GE_OQ)),
                                                              _mm256_and_ps(_mm256_cmp_ps(ey, half, _CMP_LE_OQ), _mm256_cmp_ps(ey, mhalf, _CMP_GE_OQ))),
                                                _mm256_cmp_ps(z, zmin, _CMP_GT_OQ));
                m = _mm256_and_ps(m, _mm256_permutevar8x32_ps(ok, to_linear));
                if (!_mm256_movemask_ps(m))
                    continue;
                /* this view's depth into lanes 3 and 7 of each pixel pair (z's element k of each half) */
                p0 = _mm256_blend_ps(p0, _mm256_permute_ps(z, 0x00), 0x88);
                p1 = _mm256_blend_ps(p1, _mm256_permute_ps(z, 0x55), 0x88);
                p2 = _mm256_blend_ps(p2, _mm256_permute_ps(z, 0xaa), 0x88);
                p3 = _mm256_blend_ps(p3, _mm256_permute_ps(z, 0xff), 0x88);
            }
            float *o = rgbd + 4 * i;
            if (_mm256_movemask_ps(m) == 0xff) {
                _mm256_storeu_ps(o, p0), _mm256_storeu_ps(o + 8, p1);
                _mm256_storeu_ps(o + 16, p2), _mm256_storeu_ps(o + 24, p3);
                _mm256_storeu_ps(wgt + i, ws);
            } else {
                /* each pixel pair's two mask lanes over its four floats */
                const __m256i mi = _mm256_castps_si256(m);
                const __m256i lo = _mm256_unpacklo_epi32(mi, mi), hi = _mm256_unpackhi_epi32(mi, mi);
                /* lo: pixels 0, 0, 1, 1 | 4, 4, 5, 5; hi: 2, 2, 3, 3 | 6, 6, 7, 7 */
                const __m256i m0 = _mm256_unpacklo_epi64(lo, lo), m1 = _mm256_unpackhi_epi64(lo, lo);
                const __m256i m2 = _mm256_unpacklo_epi64(hi, hi), m3 = _mm256_unpackhi_epi64(hi, hi);
                /* m0: 0 x4 | 4 x4, m1: 1 x4 | 5 x4, m2: 2 x4 | 6 x4, m3: 3 x4 | 7 x4 */
#define ST(k, pk, mk) _mm256_storeu_ps(o + 8 * k, _mm256_blendv_ps(_mm256_loadu_ps(o + 8 * k), pk, _mm256_castsi256_ps(mk)))
                ST(0, p0, _mm256_permute2x128_si256(m0, m1, 0x20)); /* pixels 0 | 1 */
                ST(1, p1, _mm256_permute2x128_si256(m2, m3, 0x20)); /* 2 | 3 */
                ST(2, p2, _mm256_permute2x128_si256(m0, m1, 0x31)); /* 4 | 5 */
                ST(3, p3, _mm256_permute2x128_si256(m2, m3, 0x31)); /* 6 | 7 */
#undef ST
                _mm256_storeu_ps(wgt + i, _mm256_blendv_ps(wv, ws, m));
            }
        }
    }
    if (ilo == 0 && iend == w)
        return;
    /* the rows' edges outside the whole steps, pixel by pixel (each pixel's fill is independent of
     * the others', so doing them after the steps gives the same bits) */
    for (int r = 0; r < h; r++) {
        const float *hw, *hrow;
        float B[3];
        if (!(hrow = taa_fill_setup(f, t, y0 + r, &hw, B)))
            continue;
        float *rgbd = rgbd_blk + 4 * r * stride, *wgt = wgt_blk + r * stride;
        const float py = (float)(y0 + r) + 0.5f;
        taa_fill_px(f, t, rgbd, wgt, hrow, hw, B, x0, py, 0, ilo);
        taa_fill_px(f, t, rgbd, wgt, hrow, hw, B, x0, py, iend, w);
    }
}

/* ------------------------------------------------------------------ the still head's blend */

/* taa_still (reproject_dsp.h): eight samples a step, the reference lane's operations per lane
 * (ordered compares: a NaN lane takes the C branch's side). */
static void taa_still_avx2(float *s, const float *h, ptrdiff_t plane, int n, float widen, float alpha,
                           float inv_depth_tol, uint8_t *wide)
{
    const __m256 one = _mm256_set1_ps(1.0f), two = _mm256_set1_ps(2.0f), zero = _mm256_setzero_ps();
    const __m256 vw = _mm256_set1_ps(widen), va = _mm256_set1_ps(alpha), vt = _mm256_set1_ps(inv_depth_tol);
    const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    int k = 0;
    for (; k + 8 <= n; k += 8) {
        const __m256 d = _mm256_loadu_ps(s + 3 * plane + k);
        const __m256 rz = _mm256_div_ps(one, d);
        const __m256 wm = _mm256_cmp_ps(_mm256_mul_ps(_mm256_mul_ps(d, rz), vw), two, _CMP_GE_OQ);
        /* the eight mask bytes: each lane's top bit to bit 0 of its byte */
        const __m128i m16 = _mm_packs_epi32(_mm256_castsi256_si128(_mm256_castps_si256(wm)),
                                            _mm256_extracti128_si256(_mm256_castps_si256(wm), 1));
        _mm_storel_epi64((__m128i *)(wide + k), _mm_and_si128(_mm_packs_epi16(m16, m16), _mm_set1_epi8(1)));
        const __m256 dd = _mm256_and_ps(_mm256_sub_ps(_mm256_loadu_ps(h + 3 * plane + k), d), absmask);
        __m256 a = _mm256_sub_ps(one, _mm256_mul_ps(dd, _mm256_mul_ps(rz, vt)));
        a = _mm256_and_ps(a, _mm256_cmp_ps(a, zero, _CMP_GT_OQ));
        const __m256 w = _mm256_mul_ps(_mm256_loadu_ps(h + 4 * plane + k), a);
        const __m256 ok = _mm256_andnot_ps(wm, _mm256_cmp_ps(w, zero, _CMP_GT_OQ));
        if (_mm256_testz_ps(ok, ok))
            continue;
        const __m256 a1 = _mm256_sub_ps(one, w);
        const __m256 al = _mm256_blendv_ps(va, a1, _mm256_cmp_ps(a1, va, _CMP_GT_OQ));
        for (int c = 0; c < 3; c++) {
            const __m256 sc = _mm256_loadu_ps(s + c * plane + k);
            const __m256 hc = _mm256_div_ps(_mm256_add_ps(zero, _mm256_mul_ps(w, _mm256_loadu_ps(h + c * plane + k))), w);
            const __m256 o = _mm256_add_ps(hc, _mm256_mul_ps(al, _mm256_sub_ps(sc, hc)));
            _mm256_storeu_ps(s + c * plane + k, _mm256_blendv_ps(sc, o, ok));
        }
    }
    for (; k < n; k++)
        taa_still_lane(s, h, plane, k, widen, alpha, inv_depth_tol, wide);
}

void fv_reproject_dsp_init_avx2(fv_reproject_dsp *d)
{
    d->taa_blend = taa_blend_avx2;
    d->taa_fill = taa_fill_avx2;
    d->taa_still = taa_still_avx2;
    d->taa_aa = fv_taa_aa_tile_avx2; /* core/x86/reproject_aa_avx2.c */
}
