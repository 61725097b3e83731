/* fovea: depth-of-field kernels, AArch64 Advanced SIMD. Bit-identical to the C references in
 * core/dof/dof_ref.c: in the Gaussians one pixel = one float32x4_t (the references add channel
 * by channel in the same order); true division (FDIV), multiply then add (no FMLA: the tree is
 * built with -ffp-contract=off). The CoC takes 4 pixels at a time (LD4 deinterleaves the
 * depths); the Gaussians 4 output pixels at a time so 4 independent add chains overlap; the
 * combine 4 pixels at a time as channel vectors; the up-sampling and the periphery's level blend
 * one pixel a vector (the latter's per-pixel scalars 4 at a time).
 *
 * The Gaussians take blocks of pixels with different sigmas through one loop over the block's
 * largest radius R: a pixel whose own radius is smaller adds w[s][|j|] * v = +-0 for |j| beyond
 * it (the table holds 0 there, core/dof/weier_impl.h), and an accumulator that starts at +0 is
 * never -0 (x + y is -0 only if both are -0), so adding +-0 leaves its bits unchanged. The same
 * argument lets the horizontal pass add +0 (a masked tap) for a near sample instead of skipping
 * it. The values read for those extra taps lie in the rows / columns the call covers and must be
 * finite (they are: level 0 and far_h are finite everywhere the pass reads). */
#include <arm_neon.h>
#include <stdint.h>
#include <string.h>

#include "dof/weier_impl.h"
#include "base/util.h"
#include "dof/dof_dsp.h"

#define CH 128 /* output pixels per chunk of the horizontal pass's masked row (TILE * 8) */


static inline float32x4_t sel(uint32x4_t m, float32x4_t a, float32x4_t b) { return vbslq_f32(m, a, b); }

static void coc_row_neon(float *restrict coc, const float *rgbd, int n, float K, float dn, float df)
{
    const float32x4_t idn = vdupq_n_f32(1.0f / dn), idf = vdupq_n_f32(1.0f / df);
    const float32x4_t vdn = vdupq_n_f32(dn), vdf = vdupq_n_f32(df), lo = vdupq_n_f32(FV_COC_MIN_DEPTH_M);
    const float32x4_t one = vdupq_n_f32(1.0f), zero = vdupq_n_f32(0.0f);
    int x = 0;
    for (; x + 4 <= n; x += 4) {
        const float32x4_t d = vld4q_f32(rgbd + 4 * x).val[3];
        const float32x4_t g = sel(vcgtq_f32(d, lo), d, lo);
        const float32x4_t ig = vdivq_f32(one, g);
        const float32x4_t nr = vmulq_n_f32(vsubq_f32(idn, ig), K);
        const float32x4_t fr = vmulq_n_f32(vsubq_f32(idf, ig), K);
        vst1q_f32(coc + x, sel(vcltq_f32(g, vdn), nr, sel(vcgtq_f32(g, vdf), fr, zero)));
    }
    if (x < n)
        fv_dof_coc_row_c(coc + x, rgbd + 4 * x, n - x, K, dn, df);
}

/* (r, g, b, 1) for a far sample (coc > 0), +0 otherwise, positions base .. base+len-1 clamped
 * into [0, w). */
static inline void mask_row(float *restrict m, const float *rgbd, const float *coc, int w, int base, int len)
{
    for (int k = 0; k < len; k++) {
        const int q = fv_clampi(base + k, 0, w - 1);
        const float32x4_t p = vsetq_lane_f32(1.0f, vld1q_f32(rgbd + 4 * q), 3);
        const uint32x4_t far = vcgtq_f32(vdupq_n_f32(coc[q]), vdupq_n_f32(0.0f));
        vst1q_f32(m + 4 * k, vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(p), far)));
    }
}

static inline float32x4_t g1(const float *m, const float *wt, int R)
{
    float32x4_t a = vdupq_n_f32(0.0f);
    for (int j = -R; j <= R; j++)
        a = vaddq_f32(a, vmulq_n_f32(vld1q_f32(m + 4 * j), wt[j < 0 ? -j : j]));
    return a;
}

static void hgauss_row_neon(float *restrict dst, const float *rgbd, const float *coc, int w, int x0, int n,
                            const uint8_t *sig, const fv_dof_gauss_tab *tab)
{
    float m[4 * (CH + 2 * FV_DOF_RMAX)];
    for (int c0 = 0; c0 < n; c0 += CH) {
        const int cn = n - c0 < CH ? n - c0 : CH;
        const uint8_t *sg = sig + c0;
        int Rc = 0;
        for (int i = 0; i < cn; i++)
            Rc = fv_maxi(Rc, tab->rad[sg[i]]);
        mask_row(m, rgbd, coc, w, x0 + c0 - Rc, cn + 2 * Rc);
        const float *mc = m + 4 * Rc; /* output pixel c0 + i at mc + 4 i */
        float *d = dst + 4 * (ptrdiff_t)(x0 + c0);
        int i = 0;
        for (; i + 4 <= cn; i += 4) {
            const uint8_t *s = sg + i;
            const float *w0 = tab->w[s[0]], *w1 = tab->w[s[1]], *w2 = tab->w[s[2]], *w3 = tab->w[s[3]];
            const int R = fv_maxi(fv_maxi(tab->rad[s[0]], tab->rad[s[1]]), fv_maxi(tab->rad[s[2]], tab->rad[s[3]]));
            float32x4_t a0 = vdupq_n_f32(0.0f), a1 = a0, a2 = a0, a3 = a0;
            for (int j = -R; j <= R; j++) {
                const int k = j < 0 ? -j : j;
                const float *p = mc + 4 * (i + j);
                a0 = vaddq_f32(a0, vmulq_n_f32(vld1q_f32(p), w0[k]));
                a1 = vaddq_f32(a1, vmulq_n_f32(vld1q_f32(p + 4), w1[k]));
                a2 = vaddq_f32(a2, vmulq_n_f32(vld1q_f32(p + 8), w2[k]));
                a3 = vaddq_f32(a3, vmulq_n_f32(vld1q_f32(p + 12), w3[k]));
            }
            vst1q_f32(d + 4 * i, vmulq_n_f32(a0, tab->inv[s[0]]));
            vst1q_f32(d + 4 * i + 4, vmulq_n_f32(a1, tab->inv[s[1]]));
            vst1q_f32(d + 4 * i + 8, vmulq_n_f32(a2, tab->inv[s[2]]));
            vst1q_f32(d + 4 * i + 12, vmulq_n_f32(a3, tab->inv[s[3]]));
        }
        for (; i < cn; i++)
            vst1q_f32(d + 4 * i, vmulq_n_f32(g1(mc + 4 * i, tab->w[sg[i]], tab->rad[sg[i]]), tab->inv[sg[i]]));
    }
}

/* Four output pixels, each its own sigma, to the block's largest radius. of: the taps' row offsets. */
static inline void vg4(float *o, const float *col, const ptrdiff_t *of, const uint8_t *s, const fv_dof_gauss_tab *tab)
{
    const float *w0 = tab->w[s[0]], *w1 = tab->w[s[1]], *w2 = tab->w[s[2]], *w3 = tab->w[s[3]];
    const int R = fv_maxi(fv_maxi(tab->rad[s[0]], tab->rad[s[1]]), fv_maxi(tab->rad[s[2]], tab->rad[s[3]]));
    float32x4_t a0 = vdupq_n_f32(0.0f), a1 = a0, a2 = a0, a3 = a0;
    for (int j = -R; j <= R; j++) {
        const int k = j < 0 ? -j : j;
        const float *p = col + of[j];
        a0 = vaddq_f32(a0, vmulq_n_f32(vld1q_f32(p), w0[k]));
        a1 = vaddq_f32(a1, vmulq_n_f32(vld1q_f32(p + 4), w1[k]));
        a2 = vaddq_f32(a2, vmulq_n_f32(vld1q_f32(p + 8), w2[k]));
        a3 = vaddq_f32(a3, vmulq_n_f32(vld1q_f32(p + 12), w3[k]));
    }
    vst1q_f32(o, a0);
    vst1q_f32(o + 4, a1);
    vst1q_f32(o + 8, a2);
    vst1q_f32(o + 12, a3);
}

/* The taps' row offsets are clamped once a call (the reference clamps per tap and pixel). Eight
 * pixels of one sigma (the usual case: the far region's CoC varies slowly along a row) share each
 * tap's weight and offset; mixed blocks run as two blocks of 4. */
static void vgauss_row_neon(float *restrict dst, const float *src, ptrdiff_t stride, int y, int ylo, int yhi,
                            int x0, int n, const uint8_t *sig, const fv_dof_gauss_tab *tab)
{
    ptrdiff_t off[2 * FV_DOF_RMAX + 1];
    int Rm = 0;
    for (int i = 0; i < n; i++)
        Rm = fv_maxi(Rm, tab->rad[sig[i]]);
    for (int j = -Rm; j <= Rm; j++)
        off[j + Rm] = 4 * (ptrdiff_t)fv_clampi(y + j, ylo, yhi - 1) * stride;
    const ptrdiff_t *of = off + Rm;
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        const uint8_t *s = sig + i;
        const float *col = src + 4 * (ptrdiff_t)(x0 + i);
        float *o = dst + 4 * (ptrdiff_t)(x0 + i);
        uint64_t s8;
        memcpy(&s8, s, 8);
        if (s8 != s[0] * 0x0101010101010101ull) {
            vg4(o, col, of, s, tab);
            vg4(o + 16, col + 16, of, s + 4, tab);
            continue;
        }
        const float *wt = tab->w[s[0]];
        const int R = tab->rad[s[0]];
        float32x4_t a0 = vdupq_n_f32(0.0f), a1 = a0, a2 = a0, a3 = a0, a4 = a0, a5 = a0, a6 = a0, a7 = a0;
        for (int j = -R; j <= R; j++) {
            const float g = wt[j < 0 ? -j : j];
            const float *p = col + of[j];
            a0 = vaddq_f32(a0, vmulq_n_f32(vld1q_f32(p), g));
            a1 = vaddq_f32(a1, vmulq_n_f32(vld1q_f32(p + 4), g));
            a2 = vaddq_f32(a2, vmulq_n_f32(vld1q_f32(p + 8), g));
            a3 = vaddq_f32(a3, vmulq_n_f32(vld1q_f32(p + 12), g));
            a4 = vaddq_f32(a4, vmulq_n_f32(vld1q_f32(p + 16), g));
            a5 = vaddq_f32(a5, vmulq_n_f32(vld1q_f32(p + 20), g));
            a6 = vaddq_f32(a6, vmulq_n_f32(vld1q_f32(p + 24), g));
            a7 = vaddq_f32(a7, vmulq_n_f32(vld1q_f32(p + 28), g));
        }
        vst1q_f32(o, a0);
        vst1q_f32(o + 4, a1);
        vst1q_f32(o + 8, a2);
        vst1q_f32(o + 12, a3);
        vst1q_f32(o + 16, a4);
        vst1q_f32(o + 20, a5);
        vst1q_f32(o + 24, a6);
        vst1q_f32(o + 28, a7);
    }
    for (; i + 4 <= n; i += 4)
        vg4(dst + 4 * (ptrdiff_t)(x0 + i), src + 4 * (ptrdiff_t)(x0 + i), of, sig + i, tab);
    for (; i < n; i++) {
        const float *wt = tab->w[sig[i]], *col = src + 4 * (ptrdiff_t)(x0 + i);
        const int R = tab->rad[sig[i]];
        float32x4_t a = vdupq_n_f32(0.0f);
        for (int j = -R; j <= R; j++)
            a = vaddq_f32(a, vmulq_n_f32(vld1q_f32(col + of[j]), wt[j < 0 ? -j : j]));
        vst1q_f32(dst + 4 * (ptrdiff_t)(x0 + i), a);
    }
}

/* a + s (b - a) */
static inline float32x4_t lerp(float32x4_t a, float32x4_t b, float32x4_t s)
{
    return vaddq_f32(a, vmulq_f32(s, vsubq_f32(b, a)));
}

/* 4 pixels at a time without branches: LD4 splits them into channel vectors, so the per-pixel
 * scalars (coc, t, coverage) are plain lanes; each step is computed for the 4 and kept per pixel
 * by a select on the reference's condition (a pixel whose step the reference skips keeps its
 * bits; the skipped step may read and compute garbage, which the select drops). */
static void combine_row_neon(float *restrict out, const fv_dof_combine_args *a, int x0, int n)
{
    /* the arguments in locals (stores to out may alias *a as far as the compiler knows) and the
     * channels as named vectors, every per-channel step written out: arrays of vectors or a
     * float32x4x4_t indexed in a loop made gcc keep them on the stack (1.59x) */
    const float *const sharp = a->sharp, *const coc = a->coc, *const tr = a->t, *const farp = a->far;
    const float *const nearp = a->near, *const lnear = a->lnear, *const enh = a->enh;
    const float gain = a->gain;
    const float32x4_t zero = vdupq_n_f32(0.0f), one = vdupq_n_f32(1.0f);
    int x = x0;
    for (; x + 4 <= x0 + n; x += 4) {
        const float32x4x4_t s = vld4q_f32(sharp + 4 * x);
        float32x4_t o0 = s.val[0], o1 = s.val[1], o2 = s.val[2];
        const float32x4_t c = vld1q_f32(coc + x), t = vld1q_f32(tr + x);
        const uint32x4_t cneg = vcltq_f32(c, zero), tp = vcgtq_f32(t, zero);
        /* towards the pixel's own blur by ab = c > 0 ? min(c, 1) : c < 0 && t > 0 ? t min(-c, 1) : 0 */
        const float32x4_t nc = vnegq_f32(c);
        const float32x4_t abn = sel(vandq_u32(cneg, tp), vmulq_f32(t, sel(vcltq_f32(nc, one), nc, one)), zero);
        const float32x4_t ab = sel(vcgtq_f32(c, zero), sel(vcltq_f32(c, one), c, one), abn);
        const uint32x4_t far = vcgtq_f32(ab, zero);
        if (vmaxvq_u32(far)) {
            const float32x4x4_t f = vld4q_f32(farp + 4 * x);
            const float32x4_t f0 = f.val[0], f1 = f.val[1], f2 = f.val[2];
            o0 = sel(far, lerp(o0, f0, ab), o0);
            o1 = sel(far, lerp(o1, f1, ab), o1);
            o2 = sel(far, lerp(o2, f2, ab), o2);
        }
        float32x4_t n0 = zero, n1 = zero, n2 = zero, n3 = zero;
        if (nearp) {
            const float32x4x4_t q = vld4q_f32(nearp + 4 * x);
            n0 = q.val[0], n1 = q.val[1], n2 = q.val[2], n3 = q.val[3];
        }
        if (lnear && vmaxvq_u32(tp)) {
            const float32x4_t sc = sel(cneg, zero, one); /* c < 0 ? 0 : 1 */
            const float32x4x4_t q = vld4q_f32(lnear + 4 * x);
            const float32x4_t q0 = q.val[0], q1 = q.val[1], q2 = q.val[2], q3 = q.val[3];
            n0 = sel(tp, vaddq_f32(n0, vmulq_f32(t, vsubq_f32(vmulq_f32(sc, q0), n0))), n0);
            n1 = sel(tp, vaddq_f32(n1, vmulq_f32(t, vsubq_f32(vmulq_f32(sc, q1), n1))), n1);
            n2 = sel(tp, vaddq_f32(n2, vmulq_f32(t, vsubq_f32(vmulq_f32(sc, q2), n2))), n2);
            n3 = sel(tp, vaddq_f32(n3, vmulq_f32(t, vsubq_f32(vmulq_f32(sc, q3), n3))), n3);
        }
        const uint32x4_t pos = vcgtq_f32(n3, zero);
        if (vmaxvq_u32(pos)) {
            const float32x4_t cov = sel(vcltq_f32(n3, one), n3, one);
            o0 = sel(pos, lerp(o0, vdivq_f32(n0, n3), cov), o0);
            o1 = sel(pos, lerp(o1, vdivq_f32(n1, n3), cov), o1);
            o2 = sel(pos, lerp(o2, vdivq_f32(n2, n3), cov), o2);
        }
        if (enh) {
            const float32x4_t g = vmulq_n_f32(t, gain);
            const uint32x4_t gp = vcgtq_f32(g, zero);
            if (vmaxvq_u32(gp)) {
                const float32x4x4_t b = vld4q_f32(enh + 4 * x);
                const float32x4_t b0 = b.val[0], b1 = b.val[1], b2 = b.val[2];
                const float32x4_t v0 = vaddq_f32(o0, vmulq_f32(g, vsubq_f32(o0, b0)));
                const float32x4_t v1 = vaddq_f32(o1, vmulq_f32(g, vsubq_f32(o1, b1)));
                const float32x4_t v2 = vaddq_f32(o2, vmulq_f32(g, vsubq_f32(o2, b2)));
                o0 = sel(gp, sel(vcgtq_f32(v0, zero), v0, zero), o0); /* v > 0 ? v : +0 */
                o1 = sel(gp, sel(vcgtq_f32(v1, zero), v1, zero), o1);
                o2 = sel(gp, sel(vcgtq_f32(v2, zero), v2, zero), o2);
            }
        }
        const float32x4x4_t r = {{o0, o1, o2, s.val[3]}};
        vst4q_f32(out + 4 * x, r);
    }
    if (x < x0 + n)
        fv_dof_combine_row_c(out, a, x, x0 + n - x);
}

/* one pixel a vector: dst = p0 + a (p1 - p0), 4 weights a load */
/* Up-sampling by s = 2^L, one pixel a vector, run by run: the s pixels of a run (x in
 * [s j + s/2, s j + s/2 + s)) share texels j, j + 1, so one d = p1 - p0 a run and per pixel
 * p0 + a d (multiply, then add), the reference's operations on the same values; the weights
 * (2r + 1) / 2s, r the place in the run, are exact. */
#define UP_MAXL 5 /* the pyramid's deepest; beyond, the reference */

/* any [x0, x0 + n), partial runs included */
static void upruns_neon(float *restrict dst, const float *tmp, int L, int sw, int x0, int n)
{
    const int s = 1 << L, s2 = 2 << L;
    const float inv = 1.0f / (float)s2;
    for (int i = 0; i < n;) {
        const int m = 2 * (x0 + i) + 1 + s, j = (m >> (L + 1)) - 1, r = (m & (s2 - 1)) >> 1;
        const int cnt = s - r < n - i ? s - r : n - i;
        const int j0 = j < 0 ? 0 : j > sw - 1 ? sw - 1 : j, j1 = j + 1 < 0 ? 0 : j + 1 > sw - 1 ? sw - 1 : j + 1;
        const float32x4_t p0 = vld1q_f32(tmp + 4 * (ptrdiff_t)j0);
        const float32x4_t d = vsubq_f32(vld1q_f32(tmp + 4 * (ptrdiff_t)j1), p0);
        for (int k = 0; k < cnt; k++)
            vst1q_f32(dst + 4 * (i + k), vaddq_f32(p0, vmulq_n_f32(d, (float)(2 * (r + k) + 1) * inv)));
        i += cnt;
    }
}

/* By 2: the run of texels j, j + 1 is pixels 2j + 1 (weight 1/4) and 2j + 2 (3/4); 4 runs (8
 * pixels) a step from one 4-texel load, the previous step's last texel carried; interior runs
 * only (j >= 0, j + 1 < sw). */
static void up2_neon(float *restrict dst, const float *tmp, int j, int runs)
{
    const float *t = tmp + 4 * (ptrdiff_t)j;
    float32x4_t q0 = vld1q_f32(t);
    int q = 0;
    for (; q + 4 <= runs; q += 4, t += 16, dst += 32) {
        const float32x4x4_t v = vld1q_f32_x4(t + 4);
        const float32x4_t d0 = vsubq_f32(v.val[0], q0), d1 = vsubq_f32(v.val[1], v.val[0]);
        const float32x4_t d2 = vsubq_f32(v.val[2], v.val[1]), d3 = vsubq_f32(v.val[3], v.val[2]);
        const float32x4x4_t o0 = {{vaddq_f32(q0, vmulq_n_f32(d0, 0.25f)), vaddq_f32(q0, vmulq_n_f32(d0, 0.75f)),
                                   vaddq_f32(v.val[0], vmulq_n_f32(d1, 0.25f)),
                                   vaddq_f32(v.val[0], vmulq_n_f32(d1, 0.75f))}};
        const float32x4x4_t o1 = {{vaddq_f32(v.val[1], vmulq_n_f32(d2, 0.25f)),
                                   vaddq_f32(v.val[1], vmulq_n_f32(d2, 0.75f)),
                                   vaddq_f32(v.val[2], vmulq_n_f32(d3, 0.25f)),
                                   vaddq_f32(v.val[2], vmulq_n_f32(d3, 0.75f))}};
        vst1q_f32_x4(dst, o0);
        vst1q_f32_x4(dst + 16, o1);
        q0 = v.val[3];
    }
    for (; q < runs; q++, t += 4, dst += 8) {
        const float32x4_t q1 = vld1q_f32(t + 4), d = vsubq_f32(q1, q0);
        vst1q_f32(dst, vaddq_f32(q0, vmulq_n_f32(d, 0.25f)));
        vst1q_f32(dst + 4, vaddq_f32(q0, vmulq_n_f32(d, 0.75f)));
        q0 = q1;
    }
}

/* By s >= 4: whole runs, 4 pixels a step (the weights as lanes of w4, constants once L is: one
 * 4-register store) */
static inline __attribute__((always_inline)) void upruns4_neon(float *restrict dst, const float *tmp, int sw, int j,
                                                                int runs, const int L)
{
    const int s = 1 << L;
    for (int q = 0; q < runs; q++, j++) {
        const int j0 = j < 0 ? 0 : j > sw - 1 ? sw - 1 : j, j1 = j + 1 > sw - 1 ? sw - 1 : j + 1;
        const float32x4_t p0 = vld1q_f32(tmp + 4 * (ptrdiff_t)j0);
        const float32x4_t d = vsubq_f32(vld1q_f32(tmp + 4 * (ptrdiff_t)j1), p0);
        for (int g = 0; g < s; g += 4, dst += 16) {
            const float32x4_t w4 = {(float)(2 * g + 1) / (float)(2 * s), (float)(2 * g + 3) / (float)(2 * s),
                                    (float)(2 * g + 5) / (float)(2 * s), (float)(2 * g + 7) / (float)(2 * s)};
            const float32x4x4_t o = {{vaddq_f32(p0, vmulq_laneq_f32(d, w4, 0)),
                                      vaddq_f32(p0, vmulq_laneq_f32(d, w4, 1)),
                                      vaddq_f32(p0, vmulq_laneq_f32(d, w4, 2)),
                                      vaddq_f32(p0, vmulq_laneq_f32(d, w4, 3))}};
            vst1q_f32_x4(dst, o);
        }
    }
}

static void upsample_row_neon(float *restrict dst, const float *tmp, int L, int sw, int x0, int n)
{
    if (L < 1 || L > UP_MAXL) {
        fv_dof_upsample_row_c(dst, tmp, L, sw, x0, n);
        return;
    }
    const int s = 1 << L, x1 = x0 + n;
    /* the first run start >= x0 (x = s j + s/2; j0 = ceil((x0 - s/2) / s), x0 >= 0), whole runs
     * (by 2: interior ones, j >= 0 and j + 1 < sw), the rest */
    int j0 = (x0 + s / 2 - 1) / s, runs;
    if (L == 1) {
        j0 = j0 > 0 ? j0 : 0;
        const int a = 2 * j0 + 1, e = x1 < 2 * sw - 1 ? x1 : 2 * sw - 1;
        runs = a < e ? (e - a) >> 1 : 0;
    } else {
        const int a = s * j0 + s / 2;
        runs = a < x1 ? (x1 - a) / s : 0;
    }
    if (runs <= 0) {
        upruns_neon(dst, tmp, L, sw, x0, n);
        return;
    }
    const int a = s * j0 + s / 2, b = a + s * runs;
    upruns_neon(dst, tmp, L, sw, x0, a - x0);
    float *d = dst + 4 * (a - x0);
    switch (L) {
    case 1: up2_neon(d, tmp, j0, runs); break;
    case 2: upruns4_neon(d, tmp, sw, j0, runs, 2); break;
    case 3: upruns4_neon(d, tmp, sw, j0, runs, 3); break;
    case 4: upruns4_neon(d, tmp, sw, j0, runs, 4); break;
    default: upruns4_neon(d, tmp, sw, j0, runs, 5); break;
    }
    upruns_neon(dst + 4 * (b - x0), tmp, L, sw, b, x1 - b);
}

/* 4 pixels at a time: their scalars as lanes, then one pixel a vector, each kept by selects (a
 * pixel the reference skips gets its own bits back). The LUT index: the reference's
 * min((int)(m steps), max) is, for m steps in [0, 2^31), (int) of min(m steps, max) (max an
 * integer); clamping the float first (NaN to 0) keeps every lane's index in [0, max], skipped
 * ones too, so the lookup stays in the table and L0, L1 in [0, need] (the table holds levels
 * >= 0): a skipped pixel's loads stay in the rows up[0..need] at the call's pixels. */
static void pyrblur_row_neon(float *restrict blur, const fv_dof_pyrblur_args *a, int x0, int n)
{
    /* the rows L0 and L1 = L0 < need ? L0 + 1 : L0 by L0 (L1 without vector work) */
    const float *up0[8], *up1[8];
    if (a->need > 7) {
        fv_dof_pyrblur_row_c(blur, a, x0, n);
        return;
    }
    for (int L = 0; L <= a->need; L++)
        up0[L] = a->up[L], up1[L] = a->up[L < a->need ? L + 1 : L];
    const float32x4_t zero = vdupq_n_f32(0.0f), one = vdupq_n_f32(1.0f), lmax = vdupq_n_f32((float)a->lambda_max);
    const float32x4_t need = vdupq_n_f32((float)a->need);
    const float steps = (float)a->lambda_steps;
    const float *const coc = a->coc, *const tr = a->t, *const lambda = a->lambda;
    int i = x0;
    for (; i + 4 <= x0 + n; i += 4) {
        const float32x4_t c = vld1q_f32(coc + i), t = vld1q_f32(tr + i);
        const float32x4_t m = vabsq_f32(c); /* -0 -> +0: skipped either way */
        const uint32x4_t act = vandq_u32(vcgtq_f32(m, zero), vcgtq_f32(t, zero));
        if (!vmaxvq_u32(act))
            continue;
        /* m steps >= +0 or NaN: FMAXNM makes NaN 0 (as the select v > 0 ? v : 0), then FMIN */
        const uint32x4_t li = vcvtq_u32_f32(vminq_f32(vmaxnmq_f32(vmulq_n_f32(m, steps), zero), lmax));
        float32x4_t l = vld1q_dup_f32(lambda + vgetq_lane_u32(li, 0));
        l = vld1q_lane_f32(lambda + vgetq_lane_u32(li, 1), l, 1);
        l = vld1q_lane_f32(lambda + vgetq_lane_u32(li, 2), l, 2);
        l = vld1q_lane_f32(lambda + vgetq_lane_u32(li, 3), l, 3);
        l = sel(vcltq_f32(l, need), l, need); /* l < need ? l : need */
        const int32x4_t l0 = vcvtq_s32_f32(l);
        const float32x4_t f = vsubq_f32(l, vcvtq_f32_s32(l0));
        const uint32x4_t mix = vandq_u32(vcgtq_f32(c, zero), vcltq_f32(t, one));
        /* pixel k: b = mix ? b + t (pv - b) : pv, pv = u0 + f (u1 - u0); kept where act. Written out
         * per lane (lane operands straight from the vectors: a loop over k made gcc store them to
         * the stack and reload them one by one; channel vectors by LD4 to lanes made it spill the
         * structs: 1.81x) */
#define PB1(k)                                                                                                    \
    do {                                                                                                          \
        const ptrdiff_t o = 4 * (ptrdiff_t)(i + k);                                                               \
        const uint32_t L0 = vgetq_lane_u32(vreinterpretq_u32_s32(l0), k); /* >= 0: no sign extension */      \
        const float32x4_t b = vld1q_f32(blur + o), u0 = vld1q_f32(up0[L0] + o), u1 = vld1q_f32(up1[L0] + o);         \
        const float32x4_t pv = vaddq_f32(u0, vmulq_laneq_f32(vsubq_f32(u1, u0), f, k));                          \
        const float32x4_t r = sel(vdupq_laneq_u32(mix, k), vaddq_f32(b, vmulq_laneq_f32(vsubq_f32(pv, b), t, k)), pv); \
        vst1q_f32(blur + o, sel(vdupq_laneq_u32(act, k), r, b));                                                 \
    } while (0)
        PB1(0);
        PB1(1);
        PB1(2);
        PB1(3);
#undef PB1
    }
    if (i < x0 + n)
        fv_dof_pyrblur_row_c(blur, a, i, x0 + n - i);
}

/* Two blocks (8 pixels) a step. vld4q de-interleaves a block into r, g, b, depth vectors (lane k
 * = pixel k), so the near mask applies as it is and the reference's (q0 + q2) + (q1 + q3) is a
 * half add then a pairwise add; min / max pairwise (FMIN orders -0 below +0, x86 does not: the
 * + 0 makes both +0). */
static inline float32x4_t nb_sum(const float *p, uint32x4_t m)
{
    const float32x4x4_t v = vld4q_f32(p);
#define NB_H(x) vadd_f32(vget_low_f32(x), vget_high_f32(x))
#define NB_M(x) vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(x), m))
    const float32x2_t r = NB_H(NB_M(v.val[0])), g = NB_H(NB_M(v.val[1])), b = NB_H(NB_M(v.val[2]));
    const float32x2_t w = NB_H(NB_M(vdupq_n_f32(1.0f)));
#undef NB_M
#undef NB_H
    return vcombine_f32(vpadd_f32(r, g), vpadd_f32(b, w));
}

static void nearblk_row_neon(float *restrict sum, float *restrict ext, const float *coc, const float *rgbd, int n)
{
    const float32x4_t zero = vdupq_n_f32(0.0f);
    const uint32x4_t odd = vreinterpretq_u32_u64(vdupq_n_u64(0xffffffff00000000ull)); /* lanes 1, 3 */
    int b = 0;
    for (; 4 * b + 8 <= n; b += 2) {
        const float32x4_t c0 = vld1q_f32(coc + 4 * b), c1 = vld1q_f32(coc + 4 * b + 4);
        vst1q_f32(sum + 4 * b, vaddq_f32(vld1q_f32(sum + 4 * b), nb_sum(rgbd + 16 * b, vcltq_f32(c0, zero))));
        vst1q_f32(sum + 4 * b + 4, vaddq_f32(vld1q_f32(sum + 4 * b + 4), nb_sum(rgbd + 16 * b + 16, vcltq_f32(c1, zero))));
        float32x4_t lo = vpminq_f32(c0, c1), hi = vpmaxq_f32(c0, c1);
        lo = vpminq_f32(lo, lo), hi = vpmaxq_f32(hi, hi); /* lanes 0, 1: blocks b, b + 1 */
        const float32x4_t v = vzip1q_f32(lo, hi), e = vld1q_f32(ext + 2 * b);
        vst1q_f32(ext + 2 * b, vaddq_f32(vbslq_f32(odd, vmaxq_f32(v, e), vminq_f32(v, e)), zero));
    }
    if (4 * b < n)
        fv_dof_nearblk_row_c(sum + 4 * b, ext + 2 * b, coc + 4 * b, rgbd + 16 * b, n - 4 * b);
}

/* 4 outputs a step whose taps all lie in the row (the SSE4.1 scheme, core/x86/dof_tmpl.h):
 * FMAX of +0 and a radius >= +0 is the radius, as on x86. |j| runs as a float vector (whole
 * numbers: exact), down to 0 over the left taps and up over the right ones. */
typedef struct {
    float32x4_t a0, a1, a2, a3, rm;
} nbox4;

static inline void nbox_tap(nbox4 *k, const float *src, const float *r, const float *wgt, int t, float32x4_t aj)
{
    const float32x4_t r4 = vld1q_f32(r + t);
    const uint32x4_t m = vcgeq_f32(r4, aj);
    const float32x4_t w4 = vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(vld1q_f32(wgt + t)), m));
    k->rm = vmaxq_f32(vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(r4), m)), k->rm);
    const float *p = src + 4 * (ptrdiff_t)t;
    /* by-lane products: w * p as the reference (the product commutes) */
    k->a0 = vaddq_f32(k->a0, vmulq_laneq_f32(vld1q_f32(p), w4, 0));
    k->a1 = vaddq_f32(k->a1, vmulq_laneq_f32(vld1q_f32(p + 4), w4, 1));
    k->a2 = vaddq_f32(k->a2, vmulq_laneq_f32(vld1q_f32(p + 8), w4, 2));
    k->a3 = vaddq_f32(k->a3, vmulq_laneq_f32(vld1q_f32(p + 12), w4, 3));
}

static void nearbox_row_neon(float *restrict out, float *restrict out_r, float *restrict out_w, const float *src,
                             const float *r, const float *wgt, int w, int x0, int n, int reach)
{
    const float32x4_t one = vdupq_n_f32(1.0f);
    int i = x0;
    while (i < x0 + n) {
        if (!(i >= reach && i + 3 + reach < w && i + 4 <= x0 + n)) { /* the row's ends */
            fv_dof_nearbox_row_c(out, out_r, out_w, src, r, wgt, w, i, 1, reach), i++;
            continue;
        }
        const float32x4_t z = vdupq_n_f32(0.0f);
        nbox4 k = {z, z, z, z, z};
        float32x4_t aj = vdupq_n_f32((float)reach);
        for (int j = -reach; j < 0; j++, aj = vsubq_f32(aj, one))
            nbox_tap(&k, src, r, wgt, i + j, aj);
        aj = z;
        for (int j = 0; j <= reach; j++, aj = vaddq_f32(aj, one))
            nbox_tap(&k, src, r, wgt, i + j, aj);
        float *o = out + 4 * (ptrdiff_t)i;
        vst1q_f32(o, k.a0), vst1q_f32(o + 4, k.a1), vst1q_f32(o + 8, k.a2), vst1q_f32(o + 12, k.a3);
        vst1q_f32(out_r + i, k.rm);
        vst1q_f32(out_w + i, vdivq_f32(one, vaddq_f32(vaddq_f32(k.rm, k.rm), one)));
        i += 4;
    }
}

/* 4 pixels a step from an even x, deinterleaved (vld4q: one vector a channel, a lane a pixel), so
 * the per-pixel scalars need no broadcasts: the texels k - 1 .. k + 2 (k = x / 2) as H = (a, b, c,
 * d) give the pixels' main taps (b, b, c, c) and their neighbours (a, c, b, d) */
static void periph_row_neon(float *restrict out, const float *sharp, const float *coc, const float *half,
                            const float *lnear, int x0, int n)
{
    const float32x4_t one = vdupq_n_f32(1.0f), zero = vdupq_n_f32(0.0f), slope = vdupq_n_f32(FV_DOF_L1_SLOPE);
    const float32x4_t q75 = vdupq_n_f32(0.75f), q25 = vdupq_n_f32(0.25f);
    int x = x0;
    if (x & 1) {
        fv_dof_periph_row_c(out, sharp, coc, half, lnear, x, 1);
        x++;
    }
    for (; x + 4 <= x0 + n; x += 4) {
        const float32x4_t c = vld1q_f32(coc + x), m = vabsq_f32(c);
        const float32x4_t w = vmulq_f32(vminq_f32(m, one), vminq_f32(vmulq_f32(vmulq_f32(m, m), slope), one));
        const uint32x4_t wpos = vcgtq_f32(w, zero), nn = vcgeq_f32(c, zero);
        const float32x4x4_t h = vld4q_f32(half + 2 * (ptrdiff_t)x - 4), sv = vld4q_f32(sharp + 4 * (ptrdiff_t)x);
        float32x4x4_t o;
        for (int k = 0; k < 3; k++) {
            const float32x4_t e = vextq_f32(h.val[k], h.val[k], 1), f = vextq_f32(h.val[k], h.val[k], 2);
            const float32x4_t u = vaddq_f32(vmulq_f32(q75, vzip1q_f32(e, e)), vmulq_f32(q25, vzip1q_f32(h.val[k], f)));
            o.val[k] = sel(wpos, vaddq_f32(sv.val[k], vmulq_f32(w, vsubq_f32(u, sv.val[k]))), sv.val[k]);
        }
        if (lnear && vmaxvq_u32(nn)) {
            const float32x4x4_t q = vld4q_f32(lnear + 4 * (ptrdiff_t)x);
            const uint32x4_t pos = vandq_u32(vcgtq_f32(q.val[3], zero), nn);
            const float32x4_t cov = vminq_f32(q.val[3], one);
            for (int k = 0; k < 3; k++)
                o.val[k] = sel(pos, vaddq_f32(o.val[k], vmulq_f32(cov, vsubq_f32(vdivq_f32(q.val[k], q.val[3]), o.val[k]))),
                               o.val[k]);
        }
        o.val[3] = sv.val[3];
        vst4q_f32(out + 4 * (ptrdiff_t)x, o);
    }
    if (x < x0 + n)
        fv_dof_periph_row_c(out, sharp, coc, half, lnear, x, x0 + n - x);
}

/* 4 texels a step: vpaddq gives the reference's pair sums in order (a0+a1 a2+a3 b0+b1 b2+b3) */
static void hcoc_row_neon(float *restrict hc, const float *ca, const float *cb, int n)
{
    int u = 0;
    for (; u + 4 <= n; u += 4) {
        const float32x4_t a = vpaddq_f32(vabsq_f32(vld1q_f32(ca + 2 * u)), vabsq_f32(vld1q_f32(ca + 2 * u + 4)));
        const float32x4_t b = vpaddq_f32(vabsq_f32(vld1q_f32(cb + 2 * u)), vabsq_f32(vld1q_f32(cb + 2 * u + 4)));
        vst1q_f32(hc + u, vmulq_n_f32(vaddq_f32(a, b), 0.25f));
    }
    if (u < n)
        fv_dof_hcoc_row_c(hc + u, ca + 2 * u, cb + 2 * u, n - u);
}

/* 4 blocks a step: LD2 splits ext into min / max, LD4 the sums into channels (the count is lane
 * 3); floor by FRINTM; FMIN / FMAX give the reference's selects on these values (whole numbers
 * and -0: max(-0, +0) is +0, as the reference's select); true division */
static void nearfin_row_neon(float *restrict rad, float *restrict rb, float *restrict wgt, float *restrict sum,
                             const float *ext, int n, float inv)
{
    const float32x4_t rmax = vdupq_n_f32((float)FV_DOF_RMAX), zero = vdupq_n_f32(0.0f), one = vdupq_n_f32(1.0f);
    const float32x4_t m1 = vdupq_n_f32(-1.0f);
    int i = 0;
    for (; i + 4 <= n; i += 4) {
        const float32x4x2_t e = vld2q_f32(ext + 2 * i);
        const float32x4x4_t s = vld4q_f32(sum + 4 * i);
        const float32x4_t r = vminq_f32(vrndmq_f32(vmulq_n_f32(vnegq_f32(e.val[0]), 0.5f)), rmax);
        const float32x4_t b = vbslq_f32(vcgtq_f32(s.val[3], zero), vrndmq_f32(vmulq_n_f32(r, 0.25f)), m1);
        vst1q_f32(rad + i, r);
        vst1q_f32(rb + i, b);
        vst1q_f32(wgt + i, vdivq_f32(one, vaddq_f32(vmulq_n_f32(vmaxq_f32(b, zero), 2.0f), one)));
        /* the four written out: a loop over s.val makes gcc spill s to the stack */
        const float32x4x4_t m = {{vmulq_n_f32(s.val[0], inv), vmulq_n_f32(s.val[1], inv), vmulq_n_f32(s.val[2], inv),
                                  vmulq_n_f32(s.val[3], inv)}};
        vst4q_f32(sum + 4 * i, m);
    }
    if (i < n)
        fv_dof_nearfin_row_c(rad + i, rb + i, wgt + i, sum + 4 * i, ext + 2 * i, n - i, inv);
}

void fv_dof_dsp_init_neon(fv_dof_dsp *d)
{
    d->dof_nearfin_row = nearfin_row_neon;
    d->dof_hcoc_row = hcoc_row_neon;
    d->dof_periph_row = periph_row_neon;
    d->dof_nearbox_row = nearbox_row_neon;
    d->dof_nearblk_row = nearblk_row_neon;
    d->dof_upsample_row = upsample_row_neon;
    d->dof_pyrblur_row = pyrblur_row_neon;
    d->dof_coc_row = coc_row_neon;
    d->dof_hgauss_row = hgauss_row_neon;
    d->dof_vgauss_row = vgauss_row_neon;
    d->dof_combine_row = combine_row_neon;
}
