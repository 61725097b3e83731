/* fovea: the last stage of a frame: the eye's linear RGB float image to the display format
 * (sRGB-encoded 8-bit RGB), with the lens's lateral chromatic aberration resampled on the way
 * where the HMD lens profile has per-channel scales (core/lens.h). */
#include "output_convert.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void fv_output_conv_init(fv_output_conv *p, unsigned isa_mask)
{
    fv_output_dsp_init(&p->dsp, isa_mask);
    fv_srgb_lut_init(p->srgb);
}

fv_lens_lca *fv_output_lca_create(const fv_camera *cam)
{
    if (!cam->lens_on || (cam->lens_scale_rgb[0] == cam->lens_scale && cam->lens_scale_rgb[2] == cam->lens_scale))
        return NULL;
    fv_lens_lca *lca = malloc(sizeof *lca);
    if (!lca)
        return NULL;
    /* radii out to the farthest image corner */
    float rmax = 0.0f;
    const float xs[2] = {cam->tan_left, cam->tan_right}, ys[2] = {cam->tan_bottom, cam->tan_top};
    for (int i = 0; i < 4; i++) {
        const float dx = xs[i & 1] - cam->lens_cx, dy = ys[i >> 1] - cam->lens_cy;
        rmax = fmaxf(rmax, sqrtf(dx * dx + dy * dy));
    }
    fv_lens_lca_init(lca, cam->lens_k1, cam->lens_k2, cam->lens_scale_rgb, 1.05f * rmax);
    return lca;
}

/* Rows [y0, y0+n) of the image; the lens resampling reads any row of img. */
static void convert_rows(const fv_output_conv *p, const float *img, ptrdiff_t stride, int w, int h, const fv_camera *c,
                         const fv_lens_lca *lca, uint8_t *dst, ptrdiff_t dst_stride, int y0, int n)
{
    if (lca && lca->on) {
        /* red and blue read where green's rays carry their directions (core/lens.h) */
        const fv_lca_geom g = {c->tan_left, c->tan_top, c->px_tan, 1.0f / c->px_tan, c->lens_cx, c->lens_cy, img, stride, w, h};
        for (int y = y0; y < y0 + n; y++)
            p->dsp.lca_row(dst + y * dst_stride, y, &g, lca, p->srgb);
        return;
    }
    for (int y = y0; y < y0 + n; y++)
        p->dsp.rgb8_row(dst + y * dst_stride, img + 4 * y * stride, w, p->srgb);
}

void fv_output_convert(const fv_output_conv *p, const float *img, ptrdiff_t stride, int w, int h,
                       const fv_camera *c, const fv_lens_lca *lca, uint8_t *dst, ptrdiff_t dst_stride)
{
    convert_rows(p, img, stride, w, h, c, lca, dst, dst_stride, 0, h);
}

typedef struct {
    const fv_output_conv *c;
    const float *img;
    ptrdiff_t stride, dst_stride;
    int w, h;
    const fv_camera *cam;
    const fv_lens_lca *lca;
    uint8_t *dst;
} band_job;

#define BAND_ROWS 32

static void band(void *ctx, int b, int tid)
{
    (void)tid;
    const band_job *j = ctx;
    const int y0 = b * BAND_ROWS, n = j->h - y0 < BAND_ROWS ? j->h - y0 : BAND_ROWS;
    convert_rows(j->c, j->img, j->stride, j->w, j->h, j->cam, j->lca, j->dst, j->dst_stride, y0, n);
}

void fv_output_convert_pool(const fv_output_conv *c, const float *img, ptrdiff_t stride, int w, int h,
                            const fv_camera *cam, const fv_lens_lca *lca, uint8_t *dst, ptrdiff_t dst_stride,
                            fv_pool *pool)
{
    band_job j = {c, img, stride, dst_stride, w, h, cam, lca, dst};
    fv_pool_run(pool, (h + BAND_ROWS - 1) / BAND_ROWS, band, &j);
}
