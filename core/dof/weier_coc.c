/* fovea: the layered filter's CoC stage: the signed CoC per pixel (Weier eq. (3)), per tile the
 * largest near radius and far sigma, dilated to what can reach each tile. */
#include "dof/weier_passes.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "base/util.h"

void fvw_coc_band(void *ctx, int band, int tid)
{
    (void)tid;
    fvw_ctx *x = ctx;
    const fv_pyr_level *l0 = &x->v->pyr->lv[0];
    const ptrdiff_t st = x->wk->stride;
    const int y0 = band * TILE, y1 = fv_mini(y0 + TILE, x->h);
    for (int y = y0; y < y1; y++)
        x->dsp->dof_coc_row(x->wk->p1[0] + y * st, l0->rgbd + 4 * (ptrdiff_t)y * l0->stride, x->w, x->K, x->dn, x->df);
    /* one sweep for the tile statistics and the quarter-resolution near source: per 4x4 block
     * the near pixels' colour sum, count and largest |c|; per tile the largest near and far c */
    const float inv_blk = 1.0f / (LOW * LOW);
    for (int by = y0 / LOW; by < (y1 + LOW - 1) / LOW; by++) {
        float *src = x->l_src + 4 * (ptrdiff_t)by * x->lw, *rr = x->l_r + (ptrdiff_t)by * x->lw;
        memset(src, 0, (size_t)x->lw * 4 * sizeof(float));
        for (int i = 0; i < x->lw; i++)
            rr[i] = 0.0f; /* the largest |c| of the block's near pixels, for now */
        for (int y = by * LOW; y < fv_mini(by * LOW + LOW, x->h); y++) {
            const float *c = x->wk->p1[0] + y * st, *p = l0->rgbd + 4 * (ptrdiff_t)y * l0->stride;
            for (int i = 0; i < x->w; i++) {
                if (!(c[i] < 0.0f))
                    continue;
                float *b = src + 4 * (i / LOW);
                b[0] += p[4 * i], b[1] += p[4 * i + 1], b[2] += p[4 * i + 2], b[3] += 1.0f;
                rr[i / LOW] = -c[i] > rr[i / LOW] ? -c[i] : rr[i / LOW];
            }
        }
        for (int i = 0; i < x->lw; i++) {
            const float cmax = rr[i], *b = src + 4 * i;
            float r = floorf(cmax * 0.5f); /* the largest near radius in pixels, capped */
            r = r < (float)FV_DOF_RMAX ? r : (float)FV_DOF_RMAX;
            /* the tile's largest near radius (first block of the tile in the band: reset) */
            float *tn = &x->t_near_own[band * x->tw + i * LOW / TILE];
            if (by == y0 / LOW && i * LOW % TILE == 0)
                *tn = 0.0f;
            *tn = r > *tn ? r : *tn;
            /* radius in whole blocks (the up-sampling adds about one); -1: no near pixel (rr[i]
             * becomes it) */
            const float rb = b[3] > 0.0f ? floorf(r / LOW) : -1.0f;
            rr[i] = rb;
            x->l_w[(ptrdiff_t)by * x->lw + i] = 1.0f / (2.0f * (rb > 0.0f ? rb : 0.0f) + 1.0f);
            for (int k = 0; k < 4; k++)
                src[4 * i + k] *= inv_blk;
        }
    }
    for (int tx = 0; tx < x->tw; tx++) {
        float fc = 0.0f;
        for (int y = y0; y < y1; y++) {
            const float *c = x->wk->p1[0] + y * st;
            for (int i = tx * TILE; i < fv_mini((tx + 1) * TILE, x->w); i++)
                fc = c[i] > fc ? c[i] : fc;
        }
        x->t_fsig_own[band * x->tw + tx] = fc * 0.25f;
    }
}

/* Each tile learns the largest near radius / far sigma of the tiles within reach. */
void fvw_dilate_tiles(fvw_ctx *x)
{
    float rmax = 0.0f;
    for (int i = 0; i < x->tw * x->th; i++)
        rmax = x->t_near_own[i] > rmax ? x->t_near_own[i] : rmax;
    const int dn = (int)ceilf(rmax / TILE), df = (FV_DOF_RMAX + TILE - 1) / TILE;
    for (int ty = 0; ty < x->th; ty++)
        for (int tx = 0; tx < x->tw; tx++) {
            float n = 0.0f, f = 0.0f;
            for (int j = ty - dn; j <= ty + dn; j++)
                for (int i = tx - dn; i <= tx + dn; i++)
                    if (j >= 0 && j < x->th && i >= 0 && i < x->tw && x->t_near_own[j * x->tw + i] > n)
                        n = x->t_near_own[j * x->tw + i];
            for (int j = ty - df; j <= ty + df; j++)
                for (int i = tx - df; i <= tx + df; i++)
                    if (j >= 0 && j < x->th && i >= 0 && i < x->tw && x->t_fsig_own[j * x->tw + i] > f)
                        f = x->t_fsig_own[j * x->tw + i];
            x->t_near[ty * x->tw + tx] = n;
            x->t_fsig[ty * x->tw + tx] = f;
        }
    int lr = -1; /* -1: no near block at all */
    for (ptrdiff_t i = 0; i < (ptrdiff_t)x->lw * x->lh; i++)
        lr = x->l_r[i] > (float)lr ? (int)x->l_r[i] : lr;
    x->l_reach = lr;
}

