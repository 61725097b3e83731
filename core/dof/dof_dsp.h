/* fovea: the layered depth-of-field kernels (one table per module, dav1d style; core/cpu.h has
 * the pattern and the contract every ISA version keeps). C references: core/dof/dof_ref.c;
 * core/dof/weier_impl.h has the argument structs. */
#ifndef FOVEA_DOF_DSP_H
#define FOVEA_DOF_DSP_H

#include <stddef.h>
#include <stdint.h>

#include "../cpu.h"

/* Called by core/dof/weier.c.
 * dof_coc_row: coc[x] = g < dn ? K (1/dn - 1/g) : g > df ? K (1/df - 1/g) : 0 for x in [0, n),
 *   g = max(depth_m of rgbd[x], 0.05) (the signed CoC of Weier eq. (3), simplified).
 * dof_hgauss_row: for x in [x0, x0+n): the Gaussian sig[x-x0] over the row's FAR samples
 *   (coc > 0), taps clamped to [0, w): dst[x] = (sum g rgb, sum g) * inv[sig] (premultiplied).
 * dof_vgauss_row: for x in [x0, x0+n): dst[x] = sum_j g_j src[clamp(y + j, ylo, yhi - 1)][x]
 *   (4 channels; src rows stride pixels apart).
 *   The ISA versions of both Gaussians run blocks of neighbouring pixels to the block's largest
 *   radius, adding w = 0 taps (the table's zeros) beyond a pixel's own: same bits (an
 *   accumulator starting at +0 is never -0, so + (+-0) changes nothing), but they read (not
 *   use) those extra taps, in the row's [0, w) / the rows [ylo, yhi) at columns [x0, x0+n),
 *   which must hold finite values there (far samples' colours; far_h).
 * dof_combine_row: out[x] for x in [x0, x0+n): o = sharp; towards far by min(1, coc) where
 *   coc > 0, by t min(1, -coc) where coc < 0; near n = near (or 0), blended by t towards
 *   s * lnear where t > 0 (s = 0 for near pixels, else 1); towards n.rgb / n.w by min(1, n.w)
 *   where n.w > 0; with enh,
 *   o = max(0, o + gain t (o - enh)) where gain t > 0; depth copied (fv_dof_combine_row_c has
 *   the order of operations). The ISA versions may read (never use) far, lnear and enh pixels of
 *   [x0, x0+n) the reference skips: they compute a step for several pixels and keep it by a
 *   select on the reference's condition. */
struct fv_dof_gauss_tab;
struct fv_dof_combine_args;
struct fv_dof_pyrblur_args;
/* dof_upsample_row: the horizontal half of a separable bilinear up-sampling by s = 2^L, texel
 *   centres at (k + 0.5) s: for i in [0, n), pixel x = x0 + i, u = (x + 0.5) / s - 0.5,
 *   j = floor(u), a = u - j, p0 = tmp[clamp(j, 0, sw - 1)], p1 = tmp[clamp(j + 1, 0, sw - 1)]
 *   (4 channels): dst[i] = p0 + a (p1 - p0). L in [0, 20], sw >= 1, x0 >= 0, x0 + n < 2^20; reads
 *   only the texels it uses. The ISA versions run the s pixels that share j (x in
 *   [s j + s/2, s j + s/2 + s)) with one p1 - p0: same bits.
 * dof_pyrblur_row: for x in [x0, x0+n) with coc != 0 and t > 0: the continuous level
 *   l = min(lambda[min(int(|coc| steps), max)], need), pv = up[L0] + f (up[L1] - up[L0])
 *   (L0 = int l, L1 = min(L0 + 1, need), f = l - L0), blur[x] = coc > 0 && t < 1 ?
 *   blur + t (pv - blur) : pv (4 channels); other pixels keep their bits. |coc| lambda_steps must
 *   stay below 2^31 (the reference's int conversion); lambda holds levels >= 0. The ISA versions
 *   compute several pixels at once and keep each by a select on the reference's condition: they
 *   may read (never use) up[0..need] and blur at pixels of [x0, x0+n) the reference skips, and
 *   store a skipped pixel's blur back unchanged. */
/* dof_nearblk_row: the CoC pass's per-block statistics of one row, blocks of 4 pixels b in
 *   [0, ceil(n / 4)): sum[4b..4b+3] += (q0 + q2) + (q1 + q3), q_k = (r, g, b, 1) of pixel 4b + k if
 *   its coc < 0, else +0 (also for pixels past n); ext[2b] = min(ext[2b], the block's coc) + 0,
 *   ext[2b + 1] = max(ext[2b + 1], the block's coc) + 0 (+ 0: a zero result is +0 whatever the
 *   ISA's min of signed zeros gives). coc and ext finite. */
/* dof_periph_row: the periphery beyond the transition disc (t = 1, no contrast enhancement) in one
 *   pass: for x in [x0, x0+n), s = sharp[x], c = coc[x], m = |c|, k = x >> 1, h = the half-resolution
 *   blur row up-sampled by 2 with fixed taps: U = 0.75 half[k] + 0.25 half[x odd ? k + 1 : k - 1]
 *   (mul, mul, add; half[-1] and half[hw] are the caller's clamped copies), the own-blur weight
 *   w = min(m, 1) min(m m FV_DOF_L1_SLOPE, 1) (the combine's min(1, |c|) times the level-0..1
 *   interpolation of the periphery's blur, in closed form), o = w > 0 ? s + w (U - s) : s; then
 *   where lnear != NULL and !(c < 0): q = lnear[x], where q.w > 0 o = o + min(q.w, 1) (q.rgb / q.w - o);
 *   out[x] = (o, s.w). coc finite; half finite over the texels read. The ISA versions compute
 *   several pixels at once and keep each by selects on these conditions (they may read, never use,
 *   lnear at near pixels): same bits. */
#define FV_DOF_L1_SLOPE (3.0f / 44.0f)
/* dof_hcoc_row: the half-resolution periphery's CoC, for u in [0, n):
 *   hc[u] = 0.25 ((|ca[2u]| + |ca[2u+1]|) + (|cb[2u]| + |cb[2u+1]|)) (ca, cb: two CoC rows; the
 *   mean |c| of a level-1 texel's 2x2 pixels, in that order of additions). ca, cb hold 2n
 *   floats. */
typedef void (*fv_dof_hcoc_row_fn)(float *restrict hc, const float *ca, const float *cb, int n);
/* dof_nearfin_row: the CoC pass's per-block finish of a block row (after dof_nearblk_row's 4 rows),
 *   for i in [0, n): r = floor(-ext[2i] 0.5), r = r < FV_DOF_RMAX ? r : FV_DOF_RMAX (the block's
 *   largest near radius, capped); rad[i] = r; rb[i] = sum[4i+3] > 0 ? floor(r / 4) : -1 (the
 *   radius in whole blocks, -1: no near pixel); wgt[i] = 1 / (2 (rb[i] > 0 ? rb[i] : 0) + 1);
 *   sum[4i..4i+3] *= inv (the block's mean). ext finite. */
typedef void (*fv_dof_nearfin_row_fn)(float *restrict rad, float *restrict rb, float *restrict wgt,
                                      float *restrict sum, const float *ext, int n, float inv);
typedef void (*fv_dof_periph_row_fn)(float *restrict out, const float *sharp, const float *coc, const float *half,
                                     const float *lnear, int x0, int n);
typedef void (*fv_dof_nearblk_row_fn)(float *restrict sum, float *restrict ext, const float *coc, const float *rgbd,
                                      int n);
/* dof_nearbox_row: the near layer's horizontal scatter-as-gather box, for i in [x0, x0+n):
 *   out[i] = sum over j in [max(-reach, -i), min(reach, w - 1 - i)], ascending, with r[i+j] >= |j|
 *   of wgt[i+j] * src[i+j] (4 channels, each a running sum from +0 in that order);
 *   out_r[i] = the largest such r[i+j] (+0 if none), out_w[i] = 1 / (2 out_r[i] + 1). r holds -1
 *   (not near) or whole numbers +0 .. FV_DOF_RMAX; wgt >= +0 and src finite over [0, w) (the ISA
 *   versions add +0 products for the taps the reference skips). */
typedef void (*fv_dof_nearbox_row_fn)(float *restrict out, float *restrict out_r, float *restrict out_w,
                                      const float *src, const float *r, const float *wgt, int w, int x0, int n,
                                      int reach);
typedef void (*fv_dof_upsample_row_fn)(float *restrict dst, const float *tmp, int L, int sw, int x0, int n);
typedef void (*fv_dof_pyrblur_row_fn)(float *restrict blur, const struct fv_dof_pyrblur_args *a, int x0, int n);
typedef void (*fv_dof_coc_row_fn)(float *restrict coc, const float *rgbd, int n, float K, float dn, float df);
typedef void (*fv_dof_hgauss_row_fn)(float *restrict dst, const float *rgbd, const float *coc, int w, int x0, int n,
                                     const uint8_t *sig, const struct fv_dof_gauss_tab *tab);
typedef void (*fv_dof_vgauss_row_fn)(float *restrict dst, const float *src, ptrdiff_t stride, int y, int ylo, int yhi,
                                     int x0, int n, const uint8_t *sig, const struct fv_dof_gauss_tab *tab);
typedef void (*fv_dof_combine_row_fn)(float *restrict out, const struct fv_dof_combine_args *a, int x0, int n);

typedef struct fv_dof_dsp {
    fv_dof_coc_row_fn dof_coc_row;
    fv_dof_hgauss_row_fn dof_hgauss_row;
    fv_dof_vgauss_row_fn dof_vgauss_row;
    fv_dof_combine_row_fn dof_combine_row;
    fv_dof_upsample_row_fn dof_upsample_row;
    fv_dof_pyrblur_row_fn dof_pyrblur_row;
    fv_dof_nearblk_row_fn dof_nearblk_row;
    fv_dof_nearbox_row_fn dof_nearbox_row;
    fv_dof_periph_row_fn dof_periph_row;
    fv_dof_hcoc_row_fn dof_hcoc_row;
    fv_dof_nearfin_row_fn dof_nearfin_row;
} fv_dof_dsp;

/* Fills d with the best kernels allowed by isa_mask & fv_cpu_isas() (FV_ISA_C: the references);
 * every allowed ISA overwrites the entries it implements, lowest first. */
void fv_dof_dsp_init(fv_dof_dsp *d, unsigned isa_mask);

/* ---- internal: references and per-ISA fillers (each sets every entry it has) ---- */
void fv_dof_coc_row_c(float *restrict coc, const float *rgbd, int n, float K, float dn, float df);
void fv_dof_hgauss_row_c(float *restrict dst, const float *rgbd, const float *coc, int w, int x0, int n,
                         const uint8_t *sig, const struct fv_dof_gauss_tab *tab);
void fv_dof_vgauss_row_c(float *restrict dst, const float *src, ptrdiff_t stride, int y, int ylo, int yhi, int x0,
                         int n, const uint8_t *sig, const struct fv_dof_gauss_tab *tab);
void fv_dof_combine_row_c(float *restrict out, const struct fv_dof_combine_args *a, int x0, int n);
void fv_dof_upsample_row_c(float *restrict dst, const float *tmp, int L, int sw, int x0, int n);
void fv_dof_pyrblur_row_c(float *restrict blur, const struct fv_dof_pyrblur_args *a, int x0, int n);
void fv_dof_nearblk_row_c(float *restrict sum, float *restrict ext, const float *coc, const float *rgbd, int n);
void fv_dof_nearbox_row_c(float *restrict out, float *restrict out_r, float *restrict out_w, const float *src,
                          const float *r, const float *wgt, int w, int x0, int n, int reach);
void fv_dof_periph_row_c(float *restrict out, const float *sharp, const float *coc, const float *half,
                         const float *lnear, int x0, int n);
void fv_dof_hcoc_row_c(float *restrict hc, const float *ca, const float *cb, int n);
void fv_dof_nearfin_row_c(float *restrict rad, float *restrict rb, float *restrict wgt, float *restrict sum,
                          const float *ext, int n, float inv);
#if defined(__x86_64__)
void fv_dof_dsp_init_sse41(fv_dof_dsp *d);
void fv_dof_dsp_init_avx2(fv_dof_dsp *d);
#elif defined(__aarch64__)
void fv_dof_dsp_init_neon(fv_dof_dsp *d);
#endif

#endif
