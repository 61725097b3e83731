/* fovea: one small dispatch table of hand-vectorised kernels (dav1d / libjpeg-turbo style).
 *
 * Pattern (one per module X, e.g. pullpush; later reproject, dof):
 *   core/X.c            plain-C reference kernels fv_<k>_c + void fv_X_init_c(fv_dsp *)
 *   core/x86/X_sse41.c  void fv_X_init_sse41(fv_dsp *)   (built with -msse4.1, x86_64 only)
 *   core/x86/X_avx2.c   void fv_X_init_avx2(fv_dsp *)    (built with -mavx2 -mfma, x86_64 only)
 *   core/arm/X_neon.c   void fv_X_init_neon(fv_dsp *)    (aarch64 only)
 * fv_dsp_init (core/dsp.c) fills the table with the C references, then lets every allowed ISA,
 * lowest first, overwrite the entries it implements.
 *
 * Contract for every ISA version of a kernel: bit-identical to its C reference for all finite
 * inputs (same IEEE operations in the same order, true division, no FMA contraction: the whole
 * tree is built with -ffp-contract=off), under the same FTZ/DAZ mode. Kernels read and write
 * exactly the pixels their contract names (no over-reads, no writes past n), take any row
 * alignment (4-byte aligned floats), and keep no state. */
#ifndef FOVEA_DSP_H
#define FOVEA_DSP_H

#include <stddef.h>
#include <stdint.h>

enum {
    FV_ISA_C = 0,
    FV_ISA_SSE41 = 1 << 0,
    FV_ISA_AVX2 = 1 << 1,
    FV_ISA_NEON = 1 << 2,
};

/* Pixels are 4 floats (r, g, b, depth_m); weights are a separate plane of floats in [0,1].
 * The colour of a zero-weight pixel is never used (it may hold anything, even NaN); colours of
 * pixels with weight > 0 must be finite.
 *
 * pull_row: one coarse row from the two fine rows below it. For X in [0, n):
 *   reads fine pixels 2X and 2X+1 of both rows (so 2n pixels per row; pad odd widths with a
 *   zero-weight pixel), with a = row 0, b = row 1, 0/1 = left/right child, and
 *   p(w, c) = w > 0 ? w * c : +0:
 *     sw  = (wa0 + wb0) + (wa1 + wb1)
 *     t   = (p(wa0, ca0) + p(wb0, cb0)) + (p(wa1, ca1) + p(wb1, cb1))   per channel
 *     dst = sw > 0 ? t / sw : +0                                         per channel
 *     dst_w = sw < 1 ? sw : 1
 *
 * push_row: fills one fine row (in place) from the coarser, already filled level. Fine pixel
 *   x (in [0, n)) lies under coarse pixel X = x >> 1; its horizontal neighbour is Xf = X - 1
 *   (x even) or X + 1 (x odd). coarse_near is the coarse row under the fine row, coarse_far
 *   the vertical neighbour row (Y - 1 for even fine rows, Y + 1 for odd ones). Both coarse
 *   rows are read at pixels [-1, (n + 1) / 2] inclusive (a replicated 1-pixel border).
 *     if !(w < 1): pixel untouched (not even rewritten)
 *     v(X)   = near[X] + 0.25 * (far[X] - near[X])                (vertical 3/4, 1/4)
 *     interp = v(X) + 0.25 * (v(Xf) - v(X))                        (so 9/16 3/16 3/16 1/16)
 *     c      = w > 0 ? fine : +0                                   per channel
 *     fine   = c + (1 - w) * (interp - c)                          (w = 0: exactly interp,
 *                                                                   up to the sign of a zero)
 */
typedef void (*fv_pull_row_fn)(float *restrict dst_rgbd, float *restrict dst_wgt, const float *src0_rgbd,
                               const float *src0_wgt, const float *src1_rgbd, const float *src1_wgt, int n);
typedef void (*fv_push_row_fn)(float *restrict fine_rgbd, const float *fine_wgt, const float *coarse_near,
                               const float *coarse_far, int n);

/* Temporal reprojection (core/reproject.h has the model), on a block of level 0: pixels
 * x0 .. x0+w-1 (w <= 64) of rows y0 .. y0+h-1; rgbd / wgt point at pixel (x0, y0), rows are
 * stride pixels apart. One call per tile, so the per-call set-up is paid once.
 * taa_blend: every pixel with weight 1 (a sample) is blended with its reprojected history; the
 *   sums of its flow to the previous frame are added to *flow in row-major pixel order. Other
 *   pixels untouched.
 * taa_fill: every pixel with weight 0 (a hole) takes valid history, if any: colour, depth in
 *   this frame's view, weight = the history's confidence in (0, 1]. Others untouched.
 * Both read the history pyramid only at texels [-1, w] x [-1, h] of a level (its border).
 * All arithmetic outside the 4-channel texel accumulation is scalar and shared
 * (core/reproject_tmpl.h), so every ISA version gives the reference's bits. */
struct fv_taa_frame;
struct fv_taa_tile;
struct fv_taa_flow;
typedef void (*fv_taa_blend_fn)(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd,
                                const float *wgt, ptrdiff_t stride, int x0, int y0, int w, int h,
                                struct fv_taa_flow *flow);
typedef void (*fv_taa_fill_fn)(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, float *wgt,
                               ptrdiff_t stride, int x0, int y0, int w, int h);
/* ---- eye tracker kernels (core/eyetrack/kernels.c; integer or one rounding per float
 * operation in a fixed order, so every ISA is exact) ----
 * et_down2_row: dst[x] = (a[2x] + a[2x+1] + b[2x] + b[2x+1] + 2) >> 2 for x in [0, n)
 *   (reads 2n pixels of each source row).
 * et_integral_row: dst[x] = above[x] + (src[0] + ... + src[x]) (uint32, wraps mod 2^32; the
 *   tracker's images are far too small to wrap), for x in [0, n).
 * et_thresh_row: dst[x] = src[x] >= t ? 255 : 0 (t in [0, 256]); returns the count of 255s.
 * et_box_score_row: box search scores of n centres in a row of an integral image, every box
 *   and ring inside it: for x in [0, n), si = ib[x+din] - it[x+din] - ib[x] + it[x] (the box
 *   between rows it and ib), so = (the same over ot, ob, dout) - si (the ring),
 *   mi = (float)si * inv_a, mo = (float)so * inv_r, dst[x] = (mo - mi) - (mi - dark), each
 *   operation rounded to float in that order; returns the largest dst[x] (-inf for n = 0; the
 *   sign of a zero maximum is unspecified). The box sums must be below 2^31.
 * et_box3_row: one row of a 3x3 box filter with replicated edges: dst[x] = (S * 3641 + 16384)
 *   >> 15 (S / 9 rounded, as a rounding 16-bit high multiply gives it), S the sum of r0, r1, r2
 *   over columns clamp(x - 1 .. x + 1, 0, n - 1), for x in [0, n) (reads n pixels of each row). */
typedef void (*fv_et_down2_row_fn)(uint8_t *restrict dst, const uint8_t *a, const uint8_t *b, int n);
typedef void (*fv_et_integral_row_fn)(uint32_t *restrict dst, const uint32_t *above, const uint8_t *src, int n);
typedef int (*fv_et_thresh_row_fn)(uint8_t *restrict dst, const uint8_t *src, int n, int t);
typedef float (*fv_et_box_score_row_fn)(float *restrict dst, const uint32_t *it, const uint32_t *ib, int din,
                                        const uint32_t *ot, const uint32_t *ob, int dout, int n, float inv_a,
                                        float inv_r, float dark);
typedef void (*fv_et_box3_row_fn)(uint8_t *restrict dst, const uint8_t *r0, const uint8_t *r1, const uint8_t *r2,
                                  int n);

/* ---- layered depth of field (core/dof/weier.c; core/dof/weier_impl.h has the structs) ----
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
/* dof_upsample_row: dst[x] = tmp[i0[x]] + ax[x] (tmp[i1[x]] - tmp[i0[x]]) for x in [0, n)
 *   (4 channels; the horizontal half of a separable bilinear up-sampling).
 * dof_pyrblur_row: for x in [x0, x0+n) with coc != 0 and t > 0: the continuous level
 *   l = min(lambda[min(int(|coc| steps), max)], need), pv = up[L0] + f (up[L1] - up[L0])
 *   (L0 = int l, L1 = min(L0 + 1, need), f = l - L0), blur[x] = coc > 0 && t < 1 ?
 *   blur + t (pv - blur) : pv (4 channels); other pixels keep their bits. |coc| lambda_steps must
 *   stay below 2^31 (the reference's int conversion); lambda holds levels >= 0. The ISA versions
 *   compute several pixels at once and keep each by a select on the reference's condition: they
 *   may read (never use) up[0..need] and blur at pixels of [x0, x0+n) the reference skips, and
 *   store a skipped pixel's blur back unchanged. */
typedef void (*fv_dof_upsample_row_fn)(float *restrict dst, const float *tmp, const int32_t *i0, const int32_t *i1,
                                       const float *ax, int n);
typedef void (*fv_dof_pyrblur_row_fn)(float *restrict blur, const struct fv_dof_pyrblur_args *a, int x0, int n);
typedef void (*fv_dof_coc_row_fn)(float *restrict coc, const float *rgbd, int n, float K, float dn, float df);
typedef void (*fv_dof_hgauss_row_fn)(float *restrict dst, const float *rgbd, const float *coc, int w, int x0, int n,
                                     const uint8_t *sig, const struct fv_dof_gauss_tab *tab);
typedef void (*fv_dof_vgauss_row_fn)(float *restrict dst, const float *src, ptrdiff_t stride, int y, int ylo, int yhi,
                                     int x0, int n, const uint8_t *sig, const struct fv_dof_gauss_tab *tab);
typedef void (*fv_dof_combine_row_fn)(float *restrict out, const struct fv_dof_combine_args *a, int x0, int n);

typedef struct fv_dsp {
    unsigned isa; /* the ISA actually selected (one FV_ISA_* value) */
    fv_pull_row_fn pull_row;
    fv_push_row_fn push_row;
    fv_taa_blend_fn taa_blend;
    fv_taa_fill_fn taa_fill;
    /* depth of field */
    fv_dof_coc_row_fn dof_coc_row;
    fv_dof_hgauss_row_fn dof_hgauss_row;
    fv_dof_vgauss_row_fn dof_vgauss_row;
    fv_dof_combine_row_fn dof_combine_row;
    fv_dof_upsample_row_fn dof_upsample_row;
    fv_dof_pyrblur_row_fn dof_pyrblur_row;
    /* eye tracker */
    fv_et_down2_row_fn et_down2_row;
    fv_et_integral_row_fn et_integral_row;
    fv_et_thresh_row_fn et_thresh_row;
    fv_et_box_score_row_fn et_box_score_row;
    fv_et_box3_row_fn et_box3_row;
} fv_dsp;

unsigned fv_cpu_isas(void);            /* FV_ISA_* bits this CPU runs */
/* Fills d with the best kernels allowed by isa_mask & fv_cpu_isas(); FV_ISA_C gives references.
 * Every allowed ISA overwrites the entries it implements, lowest first, so
 * fv_dsp_init(d, FV_ISA_SSE41) gives exactly the SSE4.1 kernels (C where there is none). */
void fv_dsp_init(fv_dsp *d, unsigned isa_mask);
const char *fv_isa_name(unsigned isa); /* "c", "sse4.1", "avx2", "neon"; "?" otherwise */

/* ---- internal: reference kernels and per-module, per-ISA table fillers ---- */
void fv_pull_row_c(float *restrict dst_rgbd, float *restrict dst_wgt, const float *src0_rgbd,
                   const float *src0_wgt, const float *src1_rgbd, const float *src1_wgt, int n);
void fv_push_row_c(float *restrict fine_rgbd, const float *fine_wgt, const float *coarse_near,
                   const float *coarse_far, int n);
void fv_taa_blend_c(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, const float *wgt,
                    ptrdiff_t stride, int x0, int y0, int w, int h, struct fv_taa_flow *flow);
void fv_taa_fill_c(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd, float *wgt,
                   ptrdiff_t stride, int x0, int y0, int w, int h);

void fv_pullpush_init_c(fv_dsp *d);
void fv_reproject_init_c(fv_dsp *d);
#if defined(__x86_64__)
void fv_pullpush_init_sse41(fv_dsp *d);
void fv_pullpush_init_avx2(fv_dsp *d);
void fv_reproject_init_sse41(fv_dsp *d);
void fv_reproject_init_avx2(fv_dsp *d);
#elif defined(__aarch64__)
void fv_pullpush_init_neon(fv_dsp *d);
void fv_reproject_init_neon(fv_dsp *d);
#endif

/* depth of field */
void fv_dof_coc_row_c(float *restrict coc, const float *rgbd, int n, float K, float dn, float df);
void fv_dof_hgauss_row_c(float *restrict dst, const float *rgbd, const float *coc, int w, int x0, int n,
                         const uint8_t *sig, const struct fv_dof_gauss_tab *tab);
void fv_dof_vgauss_row_c(float *restrict dst, const float *src, ptrdiff_t stride, int y, int ylo, int yhi, int x0,
                         int n, const uint8_t *sig, const struct fv_dof_gauss_tab *tab);
void fv_dof_combine_row_c(float *restrict out, const struct fv_dof_combine_args *a, int x0, int n);
void fv_dof_upsample_row_c(float *restrict dst, const float *tmp, const int32_t *i0, const int32_t *i1,
                           const float *ax, int n);
void fv_dof_pyrblur_row_c(float *restrict blur, const struct fv_dof_pyrblur_args *a, int x0, int n);
void fv_dof_init_c(fv_dsp *d);
#if defined(__x86_64__)
void fv_dof_init_sse41(fv_dsp *d);
void fv_dof_init_avx2(fv_dsp *d);
#elif defined(__aarch64__)
void fv_dof_init_neon(fv_dsp *d);
#endif

/* eye tracker */
void fv_et_down2_row_c(uint8_t *restrict dst, const uint8_t *a, const uint8_t *b, int n);
void fv_et_integral_row_c(uint32_t *restrict dst, const uint32_t *above, const uint8_t *src, int n);
int fv_et_thresh_row_c(uint8_t *restrict dst, const uint8_t *src, int n, int t);
float fv_et_box_score_row_c(float *restrict dst, const uint32_t *it, const uint32_t *ib, int din, const uint32_t *ot,
                            const uint32_t *ob, int dout, int n, float inv_a, float inv_r, float dark);
void fv_et_box3_row_c(uint8_t *restrict dst, const uint8_t *r0, const uint8_t *r1, const uint8_t *r2, int n);
/* one pixel of et_box3_row (the C reference, and the SIMD versions' edges and tails) */
static inline uint8_t fv_et_box3_px(const uint8_t *r0, const uint8_t *r1, const uint8_t *r2, int n, int x)
{
    const int a = x > 0 ? x - 1 : 0, c = x + 1 < n ? x + 1 : n - 1;
    const int s = r0[a] + r0[x] + r0[c] + r1[a] + r1[x] + r1[c] + r2[a] + r2[x] + r2[c];
    return (uint8_t)((s * 3641 + 16384) >> 15);
}
void fv_eyetrack_init_c(fv_dsp *d);
#if defined(__x86_64__)
void fv_eyetrack_init_sse41(fv_dsp *d);
void fv_eyetrack_init_avx2(fv_dsp *d);
#elif defined(__aarch64__)
void fv_eyetrack_init_neon(fv_dsp *d);
#endif

#endif
