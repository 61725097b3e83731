/* fovea: timewarp set-up (the kernel: timewarp_dsp.h, timewarp_ref.c). */
#include "timewarp.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "metrics.h"
#include "pipeline.h"
#include "reproject.h"

void fv_tw_setup(fv_tw_map *m, const fv_camera *display, const fv_camera *source, float tol)
{
    /* the reprojection's mapping (fv_taa_frame_setup, core/reproject.c) from the current camera
     * to the previous one is exactly this: source (U, V, Z) = z_d (M0 + px MX + py MY) + T for
     * display pixel coordinates (px, py) at display depth z_d; its history pyramid is not read
     * beyond its level count */
    fv_pyramid none;
    memset(&none, 0, sizeof none);
    none.levels = 1;
    fv_taa_frame f;
    fv_taa_frame_setup(&f, display, source, &none, 0.03f);
    memset(m, 0, sizeof *m);
    for (int k = 0; k < 3; k++) {
        m->a0[k] = f.M0[k];
        m->ax[k] = f.MX[k];
        m->ay[k] = f.MY[k];
        m->t[k] = f.T[k];
    }
    m->tol = tol;
    m->w_scale = 1.0f / FV_TW_INVD_PER_M;
}

void fv_tw_pack_invd(uint16_t *dst, ptrdiff_t dst_stride, const float *rgbd, ptrdiff_t rgbd_stride, int w, int h)
{
    for (int y = 0; y < h; y++) {
        const float *s = rgbd + (ptrdiff_t)y * rgbd_stride;
        uint16_t *o = dst + (ptrdiff_t)y * dst_stride;
        for (int x = 0; x < w; x++) {
            const float z = s[4 * x + 3];
            const float q = z > 0.0f ? FV_TW_INVD_PER_M / z + 0.5f : 65535.0f; /* NaN, <= 0: nearest */
            o[x] = (uint16_t)(q < 65535.0f ? q : 65535.0f);
        }
    }
}

long fv_tw_warp_rows(const fv_timewarp_dsp *d, uint8_t *dst, ptrdiff_t dst_stride, int y0, int y1, const fv_tw_map *m,
                     const fv_tw_src *src)
{
    long holes = 0;
    for (int y = y0; y < y1; y++)
        holes += d->tw_row(dst + (ptrdiff_t)y * dst_stride, 0, y, src->w, m, src);
    return holes;
}

int fv_tw_frame_alloc(fv_tw_frame *f, int w, int h)
{
    memset(f, 0, sizeof *f);
    f->w = w, f->h = h;
    for (int e = 0; e < 2; e++) {
        f->rgb[e] = calloc((size_t)w * h * 3 + FV_TW_RGB_PAD, 1);
        f->invd[e] = calloc((size_t)w * h * 2 + FV_TW_INVD_PAD, 1);
        if (!f->rgb[e] || !f->invd[e]) {
            fv_tw_frame_free(f);
            return -1;
        }
    }
    return 0;
}

void fv_tw_frame_free(fv_tw_frame *f)
{
    for (int e = 0; e < 2; e++) {
        free(f->rgb[e]);
        free(f->invd[e]);
        f->rgb[e] = NULL;
        f->invd[e] = NULL;
    }
}

void fv_tw_frame_capture(fv_tw_frame *f, const fv_pipeline *pl, int e)
{
    const fv_eye eye = e ? FV_EYE_RIGHT : FV_EYE_LEFT;
    fv_pipeline_to_rgb8(pl, eye, f->rgb[e], (ptrdiff_t)f->w * 3);
    ptrdiff_t stride;
    const float *img = fv_pipeline_depth(pl, eye, &stride); /* the final image's depth */
    fv_tw_pack_invd(f->invd[e], f->w, img, stride * 4, f->w, f->h);
    f->cam[e] = *fv_pipeline_camera(pl, eye);
}

long fv_tw_frame_warp(const fv_timewarp_dsp *d, const fv_tw_frame *f, int e, const fv_camera *display, uint8_t *dst,
                      ptrdiff_t dst_stride, float tol)
{
    fv_tw_map m;
    fv_tw_setup(&m, display, &f->cam[e], tol);
    const fv_tw_src s = {f->rgb[e], (ptrdiff_t)f->w * 3, f->invd[e], f->w, f->w, f->h};
    return fv_tw_warp_rows(d, dst, dst_stride, 0, f->h, &m, &s);
}

double fv_tw_psnr_outside_holes(const uint8_t *warped, const uint8_t *ref, const fv_tw_map *m, const fv_tw_src *src,
                                double *disocc_frac)
{
    const int w = src->w, h = src->h;
    float *err = malloc((size_t)w * h * sizeof *err);
    *disocc_frac = NAN;
    if (!err)
        return NAN;
    fv_luma_error(ref, warped, w, h, (ptrdiff_t)w * 3, err);
    double se = 0;
    long n = 0, holes = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            uint8_t px[3];
            if (fv_tw_row_c(px, x, y, 1, m, src)) { /* the reference's verdict for this pixel */
                holes++;
                continue;
            }
            const double e = err[(size_t)y * w + x];
            se += e * e;
            n++;
        }
    free(err);
    *disocc_frac = (double)holes / ((double)w * h);
    if (!n)
        return NAN;
    return se > 0 ? 10.0 * log10(255.0 * 255.0 * (double)n / se) : INFINITY;
}
