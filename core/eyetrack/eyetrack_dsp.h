/* fovea: the eye tracker's kernels (one table per module, dav1d style; core/cpu.h has the
 * pattern and the contract every ISA version keeps). C references: core/eyetrack/eyetrack_ref.c. */
#ifndef FOVEA_EYETRACK_DSP_H
#define FOVEA_EYETRACK_DSP_H

#include <stdint.h>

#include "../cpu.h"

/* Integer, or one rounding per float operation in a fixed order, so every ISA is exact.
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

typedef struct fv_eyetrack_dsp {
    fv_et_down2_row_fn et_down2_row;
    fv_et_integral_row_fn et_integral_row;
    fv_et_thresh_row_fn et_thresh_row;
    fv_et_box_score_row_fn et_box_score_row;
    fv_et_box3_row_fn et_box3_row;
} fv_eyetrack_dsp;

/* Fills d with the best kernels allowed by isa_mask & fv_cpu_isas() (FV_ISA_C: the references);
 * every allowed ISA overwrites the entries it implements, lowest first. */
void fv_eyetrack_dsp_init(fv_eyetrack_dsp *d, unsigned isa_mask);

/* ---- internal: references and per-ISA fillers (each sets every entry it has) ---- */
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
#if defined(__x86_64__)
void fv_eyetrack_dsp_init_sse41(fv_eyetrack_dsp *d);
void fv_eyetrack_dsp_init_avx2(fv_eyetrack_dsp *d);
#elif defined(__aarch64__)
void fv_eyetrack_dsp_init_neon(fv_eyetrack_dsp *d);
#endif

#endif
