/* fovea: temporal reprojection with a lens (reproject.h, "with a lens"): the lens folded into the
 * per-frame rows around each tile, so the kernels (reproject_dsp.h) run as they are. */
#include <math.h>
#include <string.h>

#include "reproject.h"

void fv_taa_frame_set_lens(fv_taa_frame *f, const fv_lens_map *m)
{
    f->lens = f->identity ? NULL : m; /* pixel to the same pixel: no lens to undo */
}

float fv_taa_lens_tile_depth(const fv_pyr_level *l0, int x0, int y0, int tw, int th)
{
    float si = 0.0f, n = 0.0f;
    for (int y = 1; y < th; y += 4) /* 16 of a 16 x 16 tile's pixels: the depth matters to parallax only */
        for (int x = 1; x < tw; x += 4) {
            const ptrdiff_t k = (ptrdiff_t)(y0 + y) * l0->stride + x0 + x;
            if (l0->wgt[k] == 1.0f && l0->rgbd[4 * k + 3] > 0.0f)
                si += 1.0f / l0->rgbd[4 * k + 3], n += 1.0f;
        }
    return si > 0.0f ? n / si : 1000.0f /* FV_DEPTH_MISS_M */;
}

void fv_taa_lens_tile_blend(const fv_taa_frame *f, fv_taa_frame *t, float cx, float cy, float d_m)
{
    *t = *f;
    t->lens = NULL;
    fv_lens_map_fold(f->lens, f->T, f->M0, f->MX, f->MY, cx, cy, 1.0f / d_m, t->T, t->M0, t->MX, t->MY);
}

void fv_taa_lens_tile_fill(const fv_taa_frame *f, fv_taa_frame *t, float hx, float hy, float d_m)
{
    fv_lens_map_fold(f->lens, f->T2, f->N0, f->NX, f->NY, hx, hy, 1.0f / d_m, t->T2, t->N0, t->NX, t->NY);
}

float fv_taa_project_lens(const fv_taa_frame *f, float px, float py, float d, float *u, float *v)
{
    float qx, qy;
    fv_lens_map_fwd(f->lens, px, py, &qx, &qy);
    const float U = f->T[0] + d * ((f->M0[0] + qy * f->MY[0]) + qx * f->MX[0]);
    const float V = f->T[1] + d * ((f->M0[1] + qy * f->MY[1]) + qx * f->MX[1]);
    const float Z = f->T[2] + d * ((f->M0[2] + qy * f->MY[2]) + qx * f->MX[2]);
    if (Z > 0.0f)
        fv_lens_map_inv(f->lens, U / Z, V / Z, u, v);
    return Z;
}
