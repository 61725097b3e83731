/* fovea: timewarp set-up (the kernel: timewarp_dsp.h, timewarp_ref.c). */
#include "timewarp.h"

#include <math.h>
#include <string.h>

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
