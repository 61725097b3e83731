/* fovea: the pull-push kernels (one table per module, dav1d style; core/cpu.h has the pattern
 * and the contract every ISA version keeps). C references: core/pullpush_ref.c. */
#ifndef FOVEA_PULLPUSH_DSP_H
#define FOVEA_PULLPUSH_DSP_H

#include "cpu.h"

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

typedef struct fv_pullpush_dsp {
    fv_pull_row_fn pull_row;
    fv_push_row_fn push_row;
} fv_pullpush_dsp;

/* Fills d with the best kernels allowed by isa_mask & fv_cpu_isas() (FV_ISA_C: the references);
 * every allowed ISA overwrites the entries it implements, lowest first. */
void fv_pullpush_dsp_init(fv_pullpush_dsp *d, unsigned isa_mask);

/* ---- internal: references and per-ISA fillers (each sets every entry it has) ---- */
void fv_pull_row_c(float *restrict dst_rgbd, float *restrict dst_wgt, const float *src0_rgbd,
                   const float *src0_wgt, const float *src1_rgbd, const float *src1_wgt, int n);
void fv_push_row_c(float *restrict fine_rgbd, const float *fine_wgt, const float *coarse_near,
                   const float *coarse_far, int n);
#if defined(__x86_64__)
void fv_pullpush_dsp_init_sse41(fv_pullpush_dsp *d);
void fv_pullpush_dsp_init_avx2(fv_pullpush_dsp *d);
#elif defined(__aarch64__)
void fv_pullpush_dsp_init_neon(fv_pullpush_dsp *d);
#endif

#endif
