/* fovea: conversion of an eye's image to the display format (the frame's last stage). */
#ifndef FOVEA_OUTPUT_CONVERT_H
#define FOVEA_OUTPUT_CONVERT_H

#include <stddef.h>
#include <stdint.h>

#include "camera.h"
#include "lens.h"
#include "output_dsp.h"
#include "pool.h"

typedef struct fv_output_conv {
    fv_output_dsp dsp;
    uint8_t srgb[FV_SRGB_LUT + 1 + FV_SRGB_LUT_PAD]; /* linear [0, 1] -> sRGB 8-bit (rounded), padded */
} fv_output_conv;

/* The table and the kernels allowed by isa_mask (FV_ISA_* bits). */
void fv_output_conv_init(fv_output_conv *c, unsigned isa_mask);

/* The lateral chromatic aberration tables of cam's lens (free() it), or NULL when the lens has
 * none (no lens, or equal scales for all channels) or there is no memory (converted without). */
fv_lens_lca *fv_output_lca_create(const fv_camera *cam);

/* img: w x h pixels of 4 floats (linear r, g, b, depth_m), rows stride pixels apart -> dst: sRGB
 * 8-bit RGB, rows dst_stride bytes apart. Values are clamped to [0, 1] and looked up in the
 * table at the nearest of its steps (the output kernel, core/output_dsp.h). With lca (may be NULL), red and blue are resampled
 * bilinearly where the lens moves them relative to green (cam's frustum maps pixels to
 * directions). */
void fv_output_convert(const fv_output_conv *c, const float *img, ptrdiff_t stride, int w, int h,
                       const fv_camera *cam, const fv_lens_lca *lca, uint8_t *dst, ptrdiff_t dst_stride);
/* The same, its rows split into bands over the pool's workers (the same bytes). */
void fv_output_convert_pool(const fv_output_conv *c, const float *img, ptrdiff_t stride, int w, int h,
                            const fv_camera *cam, const fv_lens_lca *lca, uint8_t *dst, ptrdiff_t dst_stride,
                            fv_pool *pool);

#endif
