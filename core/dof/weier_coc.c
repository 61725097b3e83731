/* fovea: the layered filter's CoC stage: the signed CoC per pixel (Weier eq. (3)), per tile the
 * largest near radius and far sigma, dilated to what can reach each tile. */
#include "dof/weier_passes.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "base/util.h"

void fvw_coc_band(void *ctx, int band, int tid)
{
    fvw_ctx *x = ctx;
    const fv_pyr_level *l0 = &x->v->pyr->lv[0];
    const ptrdiff_t st = x->wk->stride;
    const int y0 = band * TILE, y1 = fv_mini(y0 + TILE, x->h);
    /* per row the CoC and, while the row is in L1, the tile statistics and the quarter-resolution
     * near source in one kernel sweep: per 4x4 block the near pixels' colour sum and count
     * (dof_nearblk_row), the smallest and largest c (ext: the largest near radius, the largest
     * far c) */
    const float inv_blk = 1.0f / (LOW * LOW);
    float *ext = fvw_slot(x, tid, 0); /* 2 lw floats, then lw of near radii (the slot holds 4 w) */
    /* the CoC plane is kept only for the centre rectangle's rows (the horizontal pass and the
     * fused pass read it there); elsewhere the fused pass recomputes its row from level 0, which
     * it reads anyway, so this pass keeps those rows in the thread's slots 1-2 for the block
     * statistics and the half-resolution CoC only (7.4 MB less written and read back) */
    const int pitch = fv_mini((x->w + 15) & ~15, 2 * x->w);
    for (int by = y0 / LOW; by < (y1 + LOW - 1) / LOW; by++) {
        float *src = x->l_src + 4 * (ptrdiff_t)by * x->lw;
        const float *crow[LOW];
        memset(src, 0, (size_t)x->lw * 4 * sizeof(float));
        memset(ext, 0, (size_t)x->lw * 2 * sizeof(float));
        for (int y = by * LOW; y < fv_mini(by * LOW + LOW, x->h); y++) {
            const float *rgbd = l0->rgbd + 4 * (ptrdiff_t)y * l0->stride;
            float *c = fvw_coc_kept(x, y) ? x->wk->p1[0] + y * st : fvw_slot(x, tid, 1) + (y - by * LOW) * pitch;
            x->dsp->dof_coc_row(c, rgbd, x->w, x->K, x->dn, x->df);
            x->dsp->dof_nearblk_row(src, ext, c, rgbd, x->w);
            crow[y - by * LOW] = c;
        }
        const float full_h = (float)(fv_mini(by * LOW + LOW, x->h) - by * LOW);
        int nlo = x->lw, nhi = 0; /* the blocks with a pixel that is not near */
        for (int i = 0; i < x->lw; i++) {
            const int xa = i * LOW;
            if (src[4 * i + 3] < full_h * (float)(fv_mini(xa + LOW, x->w) - xa))
                nlo = nlo < i ? nlo : i, nhi = i + 1;
        }
        /* per block the largest near radius (capped), the radius in whole blocks (the up-sampling
         * adds about one; -1: no near pixel), its box weight and the mean colour */
        float *rad = ext + 2 * x->lw;
        x->dsp->dof_nearfin_row(rad, x->l_r + (ptrdiff_t)by * x->lw, x->l_w + (ptrdiff_t)by * x->lw, src, ext, x->lw,
                                inv_blk);
        for (int i = 0; i < x->lw; i++) {
            const int xa = i * LOW;
            /* the tile's largest near radius and far c (first block of the tile in the band: reset) */
            float *tn = &x->t_near_own[band * x->tw + xa / TILE], *tf = &x->t_fsig_own[band * x->tw + xa / TILE];
            if (by == y0 / LOW && xa % TILE == 0)
                *tn = 0.0f, *tf = 0.0f;
            *tn = rad[i] > *tn ? rad[i] : *tn;
            *tf = ext[2 * i + 1] > *tf ? ext[2 * i + 1] : *tf;
        }
        x->l_nn[2 * by] = nlo, x->l_nn[2 * by + 1] = nhi;
        /* the half-resolution periphery's CoC while the block row is in cache: per level-1 texel
         * the mean |c| of its 2x2 pixels (the last column / row of an odd size clamps) */
        for (int vy = 2 * by; x->half_on && vy < fv_mini(2 * by + 2, x->hh); vy++) {
            const float *ca = crow[2 * vy - by * LOW], *cb = crow[fv_mini(2 * vy + 1, x->h - 1) - by * LOW];
            float *ch = x->hcoc + (ptrdiff_t)vy * x->hw;
            const int uw = x->w / 2; /* texels with two columns */
            x->dsp->dof_hcoc_row(ch, ca, cb, uw);
            for (int u = uw; u < x->hw; u++)
                ch[u] = 0.25f * ((fabsf(ca[2 * u]) + fabsf(ca[2 * u])) + (fabsf(cb[2 * u]) + fabsf(cb[2 * u])));
        }
    }
    for (int tx = 0; tx < x->tw; tx++) /* far c -> sigma */
        x->t_fsig_own[band * x->tw + tx] *= 0.25f;
}

/* max over the (2 r + 1)^2 tiles around each tile of src into dst (borders: the tiles that
 * exist), separably: rows into tmp, then columns */
static void tile_max(float *restrict dst, const float *src, float *restrict tmp, int tw, int th, int r)
{
    for (int ty = 0; ty < th; ty++)
        for (int tx = 0; tx < tw; tx++) {
            float m = 0.0f;
            for (int i = fv_maxi(tx - r, 0); i <= fv_mini(tx + r, tw - 1); i++)
                m = src[ty * tw + i] > m ? src[ty * tw + i] : m;
            tmp[ty * tw + tx] = m;
        }
    for (int ty = 0; ty < th; ty++)
        for (int tx = 0; tx < tw; tx++) {
            float m = 0.0f;
            for (int j = fv_maxi(ty - r, 0); j <= fv_mini(ty + r, th - 1); j++)
                m = tmp[j * tw + tx] > m ? tmp[j * tw + tx] : m;
            dst[ty * tw + tx] = m;
        }
}

/* Tile row ty of the dilation below for a near reach of dn tiles, as a square window (the same
 * values: max is exact in any order); reads the own values of tile rows ty - 2 .. ty + 2. */
void fvw_dilate_row(fvw_ctx *x, int ty, int dn)
{
    const int df = (FV_DOF_RMAX + TILE - 1) / TILE;
    for (int tx = 0; tx < x->tw; tx++) {
        float mn = 0.0f, mf = 0.0f;
        for (int j = fv_maxi(ty - dn, 0); j <= fv_mini(ty + dn, x->th - 1); j++)
            for (int i = fv_maxi(tx - dn, 0); i <= fv_mini(tx + dn, x->tw - 1); i++)
                mn = x->t_near_own[j * x->tw + i] > mn ? x->t_near_own[j * x->tw + i] : mn;
        for (int j = fv_maxi(ty - df, 0); j <= fv_mini(ty + df, x->th - 1); j++)
            for (int i = fv_maxi(tx - df, 0); i <= fv_mini(tx + df, x->tw - 1); i++)
                mf = x->t_fsig_own[j * x->tw + i] > mf ? x->t_fsig_own[j * x->tw + i] : mf;
        x->t_near[ty * x->tw + tx] = mn, x->t_fsig[ty * x->tw + tx] = mf;
    }
}

/* Each tile learns the largest near radius / far sigma of the tiles within reach (a max is
 * separable: the same values as the square window). */
void fvw_dilate_tiles(fvw_ctx *x)
{
    float rmax = 0.0f;
    for (int i = 0; i < x->tw * x->th; i++)
        rmax = x->t_near_own[i] > rmax ? x->t_near_own[i] : rmax;
    const int dn = (int)ceilf(rmax / TILE), df = (FV_DOF_RMAX + TILE - 1) / TILE;
    float *tmp = fvw_slot(x, 0, 2); /* thread 0's row buffers 2.. (free between the passes) */
    x->near_tiles = dn;
    tile_max(x->t_near, x->t_near_own, tmp, x->tw, x->th, dn);
    tile_max(x->t_fsig, x->t_fsig_own, tmp, x->tw, x->th, df);
    int lr = -1; /* -1: no near block at all */
    for (ptrdiff_t i = 0; i < (ptrdiff_t)x->lw * x->lh; i++)
        lr = x->l_r[i] > (float)lr ? (int)x->l_r[i] : lr;
    x->l_reach = lr;
}

