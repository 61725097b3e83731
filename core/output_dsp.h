/* fovea: the output stage's kernel (one table per module; core/cpu.h has the pattern). C
 * reference: core/output_ref.c.
 *
 * rgb8_row: linear RGB floats to sRGB-encoded bytes through a table, for x in [0, n) and c in
 *   {r, g, b}: with v = rgbd[4x + c] (the 4th float, depth, is never read),
 *     i = v > 0 ? (v < 1 ? (int)(v * FV_SRGB_LUT + 0.5f) : FV_SRGB_LUT) : 0   (NaN: 0)
 *     dst[3x + c] = lut[i]
 *   lut holds FV_SRGB_LUT + 1 entries and must be readable FV_SRGB_LUT_PAD bytes past them
 *   (vector gathers read whole words). SSE4.1 and NEON give the reference's bytes for any
 *   table. AVX2 computes sRGB instead of reading the table, so it takes only the sRGB table of
 *   fv_srgb_lut_init: within 1 of the reference's bytes (measured over every float in
 *   [-1.5, 1.5]: 0.83 % of them differ, by 1), exactly 0 for v <= 0 or NaN, 255 for v >= 1. */
#ifndef FOVEA_OUTPUT_DSP_H
#define FOVEA_OUTPUT_DSP_H

#include <stdint.h>

#include "cpu.h"

#define FV_SRGB_LUT 4096   /* steps of the linear [0, 1] -> sRGB table */
#define FV_SRGB_LUT_PAD 3  /* bytes past the last entry a gather may read */

typedef void (*fv_rgb8_row_fn)(uint8_t *restrict dst, const float *rgbd, int n, const uint8_t *lut);

typedef struct fv_output_dsp {
    fv_rgb8_row_fn rgb8_row;
} fv_output_dsp;

void fv_output_dsp_init(fv_output_dsp *d, unsigned isa_mask);

/* The table the output stage uses: lut[i] = round(255 sRGB(i / FV_SRGB_LUT)), i in
 * [0, FV_SRGB_LUT], then FV_SRGB_LUT_PAD zero bytes. */
void fv_srgb_lut_init(uint8_t lut[FV_SRGB_LUT + 1 + FV_SRGB_LUT_PAD]);

/* ---- internal: reference and per-ISA fillers ---- */
void fv_rgb8_row_c(uint8_t *restrict dst, const float *rgbd, int n, const uint8_t *lut);
static inline int fv_srgb_index(float v)
{
    return v > 0.0f ? (v < 1.0f ? (int)(v * FV_SRGB_LUT + 0.5f) : FV_SRGB_LUT) : 0;
}
#if defined(__x86_64__)
void fv_output_dsp_init_sse41(fv_output_dsp *d);
void fv_output_dsp_init_avx2(fv_output_dsp *d);
#elif defined(__aarch64__)
void fv_output_dsp_init_neon(fv_output_dsp *d);
#endif

#endif
