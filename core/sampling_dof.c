/* fovea: depth-of-field-driven sampling: thins the acuity sampler's bits (sampling_dof.h). */
#include "sampling_dof.h"

#include <math.h>
#include <string.h>

#include "base/util.h"
#include "tile.h"

_Static_assert(FV_TILE == 16, "fv_dofsamp_tile works on 16x16 tiles");

void fv_dofsamp_params_default(fv_dofsamp_params *p)
{
    p->enabled = 1;
    p->kappa = 2.0f;
    p->coc_cap_px = 32.0f;
}

void fv_dofsamp_frame_setup(fv_dofsamp_frame *f, const fv_dofsamp_params *prm, const fv_taa_frame *taa,
                            const fv_sampler *smp, int gx, int gy, float focus_a_m, float focus_b_m,
                            float tolerance_m, float px_per_dpt, uint32_t frame, int phase)
{
    memset(f, 0, sizeof *f);
    f->taa = taa;
    f->smp = smp;
    f->gx = gx;
    f->gy = gy;
    const float nr = fminf(focus_a_m, focus_b_m) - tolerance_m, fr = fmaxf(focus_a_m, focus_b_m) + tolerance_m;
    /* Weier's band [d_o - t, d_o + t] in dioptres; a band reaching the eye keeps everything nearer sharp */
    f->lo_dpt = 1.0f / fr;
    f->hi_dpt = nr > 0.0f ? 1.0f / nr : INFINITY;
    f->px_per_dpt = px_per_dpt;
    f->kappa = prm->kappa;
    f->coc_cap_px = prm->coc_cap_px;
    f->seed = frame;
    f->phase = phase;
}

/* Dioptres of defocus beyond the sharp band (0 inside it). */
static inline float defocus_dpt(const fv_dofsamp_frame *f, float depth_m)
{
    const float D = 1.0f / (depth_m > 0.05f ? depth_m : 0.05f); /* FV_COC_MIN_DEPTH_M */
    return D < f->lo_dpt ? f->lo_dpt - D : D > f->hi_dpt ? D - f->hi_dpt : 0.0f;
}

float fv_dofsamp_coc_px(const fv_dofsamp_frame *f, float depth_m) { return f->px_per_dpt * defocus_dpt(f, depth_m); }

float fv_dofsamp_density(const fv_dofsamp_frame *f, float c_px)
{
    const float c = (c_px < f->coc_cap_px ? c_px : f->coc_cap_px) / f->kappa;
    const float a = c * c + (1.0f / 3.0f); /* the texel area 4^L of the level read (kappa 2) */
    return a > 1.0f ? 1.0f / a : 1.0f;
}

float fv_dofsamp_keep(const fv_dofsamp_frame *f, float p, float c_px)
{
    const float d = fv_dofsamp_density(f, c_px);
    return d < p ? d / p : 1.0f;
}


static inline int floor_shr(int v, int s) { return v >= 0 ? v >> s : -((-v + (1 << s) - 1) >> s); }

/* The tile's motion to the history (as fv_taa_prefetch guesses it): the previous frame's depth
 * at the tile (one texel of the tile level) projected into the previous view; whole pixels. */
static void tile_flow(const fv_taa_frame *t, int x0, int y0, int tw, int th, int *dx, int *dy)
{
    *dx = *dy = 0;
    if (t->identity)
        return;
    const int l = t->hist->levels - 1 < FV_TILE_PULL_LEVELS ? t->hist->levels - 1 : FV_TILE_PULL_LEVELS;
    const fv_pyr_level *hl = &t->hist->lv[l];
    const float cx = (float)x0 + 0.5f * (float)tw, cy = (float)y0 + 0.5f * (float)th;
    int hx = (int)cx >> l, hy = (int)cy >> l;
    hx = hx < hl->w ? hx : hl->w - 1;
    hy = hy < hl->h ? hy : hl->h - 1;
    float u, v;
    if (fv_taa_project(t, cx, cy, hl->rgbd[4 * ((ptrdiff_t)hy * hl->stride + hx) + 3], &u, &v) <= 0.0f ||
        !(fabsf(u - cx) < 4096.0f && fabsf(v - cy) < 4096.0f))
        return;
    *dx = (int)floorf(u - cx + 0.5f);
    *dy = (int)floorf(v - cy + 0.5f);
}

size_t fv_dofsamp_map_len(const fv_pyramid *hist)
{
    const int l = hist->levels - 1 < FV_DOFSAMP_LEVEL ? hist->levels - 1 : FV_DOFSAMP_LEVEL;
    return (size_t)(hist->lv[l].w + 2) * (size_t)(hist->lv[l].h + 2);
}

void fv_dofsamp_map_attach(fv_dofsamp_frame *f, float *map)
{
    const fv_pyramid *h = f->taa->hist;
    f->map_level = h->levels - 1 < FV_DOFSAMP_LEVEL ? h->levels - 1 : FV_DOFSAMP_LEVEL;
    f->map = map;
    f->map_w = h->lv[f->map_level].w + 2;
    f->map_h = h->lv[f->map_level].h + 2;
}

/* Map row j is history row j - 1 (the border rows included): the texel's depth converted to
 * this frame's view (N rows: previous pixel and depth -> current), then its defocus; no depth
 * or behind the eye: 0 (unknown, kept sharp). Branch-free, so the compiler vectorises it. */
void fv_dofsamp_map_rows(const fv_dofsamp_frame *f, int j0, int j1)
{
    const fv_taa_frame *t = f->taa;
    const fv_pyr_level *hl = &t->hist->lv[f->map_level];
    const float scale = (float)(1 << f->map_level);
    const float lo = f->lo_dpt, hi = f->hi_dpt, T = t->T2[2];
    for (int j = j0; j < j1; j++) {
        const int iy = j - 1;
        const float v = ((float)iy + 0.5f) * scale;
        const float k0 = t->N0[2] + v * t->NY[2], kx = t->NX[2];
        const float *src = hl->rgbd + 4 * ((ptrdiff_t)iy * hl->stride - 1);
        float *dst = f->map + (ptrdiff_t)j * f->map_w;
        for (int i = 0; i < f->map_w; i++) {
            const float z = src[4 * i + 3], u = ((float)(i - 1) + 0.5f) * scale;
            const float zc = T + z * (k0 + u * kx);
            const float D = 1.0f / (zc > 0.05f ? zc : 0.05f); /* FV_COC_MIN_DEPTH_M */
            const float a = lo - D, b = D - hi, m = a > b ? a : b;
            dst[i] = z > 0.0f && zc > 0.0f && m > 0.0f ? m : 0.0f;
        }
    }
}

/* The acuity probability at the point of [x0, x1) x [y0, y1) farthest from (lowest p) or nearest
 * to (highest p) the gaze: the models' p falls with the distance from the gaze. */
static float rect_p(const fv_dofsamp_frame *f, int x0, int y0, int x1, int y1, int nearest)
{
    const float ax = (float)x0 - (float)f->gx, bx = (float)x1 - (float)f->gx;
    const float ay = (float)y0 - (float)f->gy, by = (float)y1 - (float)f->gy;
    float dx, dy;
    if (nearest) {
        dx = ax > 0.0f ? ax : bx < 0.0f ? bx : 0.0f;
        dy = ay > 0.0f ? ay : by < 0.0f ? by : 0.0f;
    } else {
        dx = fabsf(ax) > fabsf(bx) ? ax : bx;
        dy = fabsf(ay) > fabsf(by) ? ay : by;
    }
    return fv_sampler_probability(f->smp, dx, dy);
}

float fv_dofsamp_tile(const fv_dofsamp_frame *f, int x0, int y0, int tw, int th, uint32_t rows[16])
{
    const fv_taa_frame *t = f->taa;
    /* the tile's highest acuity probability: where d(c) < p can hold at all */
    const float p_hi = rect_p(f, x0, y0, x0 + tw, y0 + th, 1);
    const float d_min = fv_dofsamp_density(f, f->coc_cap_px);
    if (!(d_min < p_hi)) /* even the largest CoC needs every sample */
        return 1.0f;

    /* Defocus of the history's texels around the tile (fv_dofsamp_map), moved by the tile's
     * flow, one texel of margin: 6 x 6. Beyond the history's border: unknown, kept sharp. */
    int fx, fy;
    tile_flow(t, x0, y0, tw, th, &fx, &fy);
    const int sh = f->map_level;
    const int nb = 16 >> sh, ng = nb + 2; /* blocks per tile side, texels per grid side */
    const int ix0 = floor_shr(x0 + fx, sh) - 1, iy0 = floor_shr(y0 + fy, sh) - 1;
    float e[18 * 18], emax = 0.0f;
    /* the grid's columns inside the map: [ia, ib) */
    const int ia = ix0 >= -1 ? 0 : -1 - ix0, ib = f->map_w - 1 - ix0 < ng ? f->map_w - 1 - ix0 : ng;
    for (int j = 0; j < ng; j++) {
        const int iy = iy0 + j;
        float *er = e + ng * j;
        for (int i = 0; i < ng; i++)
            er[i] = 0.0f;
        if (iy < -1 || iy > f->map_h - 2)
            continue;
        const float *mr = f->map + (ptrdiff_t)(iy + 1) * f->map_w + ix0 + 1;
        for (int i = ia; i < ib; i++) {
            er[i] = mr[i];
            emax = mr[i] > emax ? mr[i] : emax;
        }
    }
    /* CoCs up to kappa / sqrt(p_hi) keep every sample: most tiles stop here */
    if (!(fv_dofsamp_density(f, f->px_per_dpt * emax) < p_hi))
        return 1.0f;
    /* the tile's lowest p: one p for every block where the tile lies where p is flat (the
     * periphery, the fovea's inside) */
    const float p_lo = rect_p(f, x0, y0, x0 + tw, y0 + th, 0);
    /* per block: the smallest defocus of its 3x3 texel neighbourhood (separable) -> keep
     * threshold */
    float eh[18 * 16];
    for (int j = 0; j < ng; j++)
        for (int i = 0; i < nb; i++) {
            const float *r = e + ng * j + i;
            const float a = r[0] < r[1] ? r[0] : r[1];
            eh[nb * j + i] = a < r[2] ? a : r[2];
        }
    uint32_t thr[16][16];
    double qsum = 0.0;
    int any = 0;
    const int B = 1 << sh;
    for (int j = 0; j < nb; j++)
        for (int i = 0; i < nb; i++) {
            const float *c3 = eh + nb * j + i;
            const float a = c3[0] < c3[nb] ? c3[0] : c3[nb];
            const float c = f->px_per_dpt * (a < c3[2 * nb] ? a : c3[2 * nb]);
            const int bw = tw - (i << sh), bh = th - (j << sh);
            const int cw = bw < 0 ? 0 : bw < B ? bw : B, ch = bh < 0 ? 0 : bh < B ? bh : B;
            float q = 1.0f;
            if (cw > 0 && ch > 0) {
                /* the block's lowest p: its pixels nearer the gaze keep at least d */
                const float p = p_lo == p_hi ? p_lo
                                             : rect_p(f, x0 + (i << sh), y0 + (j << sh), x0 + (i << sh) + cw,
                                                      y0 + (j << sh) + ch, 0);
                q = fv_dofsamp_keep(f, p, c);
            }
            /* q = 1: every bit survives (UINT32_MAX marks it, the test below never drops it) */
            thr[j][i] = q < 1.0f ? (uint32_t)((double)q * 4294967296.0) : UINT32_MAX;
            any |= q < 1.0f;
            qsum += (double)q * cw * ch;
        }
    if (!any)
        return 1.0f;
    /* The variate: outside r1 with Weier's pattern (S_out) the pixel's rank in S_out's lattice
     * dither, so the kept ones are a thinner copy of the same even dither (no clumps, no holes);
     * elsewhere (the fovea, the transition's Halton points, Liu's pattern) the R2 lattice's value
     * at the pixel, an even dither of the pixels the pattern has. Both move by the golden ratio
     * each frame, so the frames together still visit every pixel. */
    const fv_sampler *smp = f->smp;
    const int sout = !smp->prm.full && smp->prm.kind == FV_SAMPLER_WEIER;
    const double r1sq = (double)smp->r1_px * smp->r1_px, inv_p = 1.0 / (double)smp->prm.p_min;
    /* The shift: frame x golden ratio, but S_out's pixels by their visit: an S_out pixel is in
     * the pattern one frame in K (phase = frame mod K), so its variate moves by the golden ratio
     * between two of its visits (by frame it would move 5 g mod 1 = 0.09 at K 5: a pixel kept
     * once would be kept the next few visits and then dropped for dozens of frames). */
    const double gold = 0.6180339887498949;
    const double g = (double)(f->seed % 1000003u) * gold; /* small: exact enough */
    const double g_out = (double)((f->seed / (uint32_t)smp->phases) % 1000003u) * gold;
    const int kph = (f->phase % smp->phases + smp->phases) % smp->phases;
    const double koff = (double)kph / smp->phases;
    for (int y = 0; y < th; y++) {
        uint32_t r = rows[y], out = r;
        const double dy = (double)(y0 + y - f->gy);
        while (r) {
            const int x = __builtin_ctz(r);
            r &= r - 1;
            const uint32_t th_ = thr[y >> sh][x >> sh];
            if (th_ == UINT32_MAX)
                continue;
            const double dx = (double)(x0 + x - f->gx);
            double v;
            if (sout && dx * dx + dy * dy >= r1sq)
                v = fv_sampler_lattice_at(x0 + x, y0 + y, koff) * inv_p + g_out;
            else
                v = fv_sampler_lattice_at(x0 + x, y0 + y, 0.0) + g;
            v -= (double)(long long)v;
            if ((uint32_t)(v * 4294967296.0) >= th_)
                out &= ~(1u << x);
        }
        rows[y] = out;
    }
    return (float)(qsum / (double)(tw * th));
}
