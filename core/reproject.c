/* fovea: temporal reprojection, per-frame / per-tile setup (the kernels: reproject_dsp.h,
 * their references in reproject_ref.c). */
#include "reproject.h"

#include <math.h>
#include <string.h>

#include <stdint.h>

#include "sampling.h"

void fv_taa_params_default(fv_taa_params *p)
{
    p->enabled = 1;
    p->alpha_min = 0.3f;
    p->depth_tol = 0.03f;
    p->fill = 1;
    p->fovea_aa = 1;
    p->in_place = 1;
    p->half_fill = 1;
}

/* ---------------------------------------------------------------- setup */

/* Rows of the projection into camera c, in double: (U, V, Z) = R (P - eye) with U = px Z,
 * V = py Z, Z the view depth. */
static void proj_rows(const fv_camera *c, double R[3][3])
{
    const double pt = c->px_tan;
    for (int k = 0; k < 3; k++) {
        R[0][k] = ((double)c->right[k] + (double)c->tan_left * c->back[k]) / pt;
        R[1][k] = -((double)c->up[k] + (double)c->tan_top * c->back[k]) / pt;
        R[2][k] = -(double)c->back[k];
    }
}

/* dir(px, py) = D0 + px Dx + py Dy (fv_camera_ray with pixel-centre offsets folded into px, py) */
static void ray_basis(const fv_camera *c, double D0[3], double Dx[3], double Dy[3])
{
    for (int k = 0; k < 3; k++) {
        D0[k] = (double)c->tan_left * c->right[k] + (double)c->tan_top * c->up[k] - c->back[k];
        Dx[k] = (double)c->px_tan * c->right[k];
        Dy[k] = -(double)c->px_tan * c->up[k];
    }
}

static void mapping(const fv_camera *from, const fv_camera *to, float T[3], float M0[3], float MX[3], float MY[3])
{
    double R[3][3], D0[3], Dx[3], Dy[3];
    proj_rows(to, R);
    ray_basis(from, D0, Dx, Dy);
    for (int r = 0; r < 3; r++) {
        double t = 0, m0 = 0, mx = 0, my = 0;
        for (int k = 0; k < 3; k++) {
            t += R[r][k] * ((double)from->eye_pos[k] - to->eye_pos[k]);
            m0 += R[r][k] * D0[k];
            mx += R[r][k] * Dx[k];
            my += R[r][k] * Dy[k];
        }
        T[r] = (float)t;
        M0[r] = (float)m0;
        MX[r] = (float)mx;
        MY[r] = (float)my;
    }
}

void fv_taa_frame_setup(fv_taa_frame *f, const fv_camera *cur, const fv_camera *prev, const fv_pyramid *hist,
                        float depth_tol)
{
    memset(f, 0, sizeof *f);
    f->hist = hist;
    mapping(cur, prev, f->T, f->M0, f->MX, f->MY);
    mapping(prev, cur, f->T2, f->N0, f->NX, f->NY);
    f->prev_w = (float)prev->width;
    f->prev_h = (float)prev->height;
    f->inv_depth_tol = 1.0f / depth_tol;
    /* a footprint never reads coarser than 32 px texels: beyond that the history says little */
    f->max_level = hist->levels - 1 < 5 ? hist->levels - 1 : 5;
    f->identity = !memcmp(cur, prev, sizeof *cur);
}

void fv_taa_tile_setup(fv_taa_tile *t, const fv_taa_params *prm, float p, float p_min, int phases)
{
    p = p > 1.0f ? 1.0f : p > 1e-6f ? p : 1e-6f;
    /* a rotating pattern samples this pixel every 1/p frames; a static one every frame */
    const float rate = phases > 1 ? p : 1.0f;
    const float dens = phases > 1 ? (p * (float)phases < 1.0f ? p * (float)phases : 1.0f) : p;
    /* History weight: the user's per-frame share compounded over the frames between two samples
     * of the pixel, scaled by how undersampled the pixel is: full at the periphery's p_min,
     * none where every pixel is sampled every frame (the fovea has nothing to accumulate, only
     * lag to gain). */
    float under = p_min < 1.0f ? (1.0f - p) / (1.0f - p_min) : 0.0f;
    under = under > 1.0f ? 1.0f : under;
    t->alpha = 1.0f - powf(1.0f - prm->alpha_min, 1.0f / rate) * under;
    t->widen = 1.0f / sqrtf(dens);
    t->flow_x = t->flow_y = 0;
}

float fv_taa_project(const fv_taa_frame *f, float px, float py, float d, float *u, float *v)
{
    if (f->lens)
        return fv_taa_project_lens(f, px, py, d, u, v);
    const float U = f->T[0] + d * ((f->M0[0] + py * f->MY[0]) + px * f->MX[0]);
    const float V = f->T[1] + d * ((f->M0[1] + py * f->MY[1]) + px * f->MX[1]);
    const float Z = f->T[2] + d * ((f->M0[2] + py * f->MY[2]) + px * f->MX[2]);
    if (Z > 0.0f) {
        *u = U / Z;
        *v = V / Z;
    }
    return Z;
}

void fv_taa_tile_run(const fv_taa_frame *f, const fv_taa_params *prm, const struct fv_sampler *smp, int gx, int gy,
                     const fv_pyr_level *l0, const fv_reproject_dsp *dsp, int x0, int y0, int tw, int th)
{
    fv_taa_tile_run_keep(f, prm, smp, gx, gy, l0, dsp, x0, y0, tw, th, 1.0f);
}

void fv_taa_still_save(const fv_pyr_level *l0, int x0, int y0, int tw, int th, const uint32_t *rows,
                       fv_taa_still_hist *h)
{
    (void)tw;
    int k = 0;
    for (int y = 0; y < th; y++) {
        const ptrdiff_t o = (ptrdiff_t)(y0 + y) * l0->stride + x0;
        for (uint32_t r = rows[y]; r; r &= r - 1, k++) {
            const int i = __builtin_ctz(r);
            const float *c = l0->rgbd + 4 * (o + i);
            h->h[0][k] = c[0], h->h[1][k] = c[1], h->h[2][k] = c[2], h->h[3][k] = c[3];
            h->h[4][k] = l0->wgt[o + i];
        }
    }
}

void fv_taa_tile_run_keep(const fv_taa_frame *f, const fv_taa_params *prm, const struct fv_sampler *smp, int gx,
                          int gy, const fv_pyr_level *l0, const fv_reproject_dsp *dsp, int x0, int y0, int tw, int th,
                          float keep)
{
    fv_taa_tile tt;
    const float cx = (float)x0 + 0.5f * (float)tw, cy = (float)y0 + 0.5f * (float)th;
    fv_taa_tile_setup(&tt, prm, fv_sampler_probability(smp, cx - (float)gx, cy - (float)gy) * keep, smp->prm.p_min,
                      smp->phases);
    fv_taa_flow fl = {0.0f, 0.0f, 0.0f};
    const ptrdiff_t o = (ptrdiff_t)y0 * l0->stride + x0;
    const fv_taa_frame *fk = f; /* the kernels' frame: f, or with a lens the tile's (reproject.h) */
    fv_taa_frame tl;
    float d0 = 1000.0f; /* with a lens: the depth the tile's map is linearised at */
    if (f->lens) {
        d0 = fv_taa_lens_tile_depth(l0, x0, y0, tw, th);
        fv_taa_lens_tile_blend(f, &tl, cx, cy, d0);
        fk = &tl;
    }
    if (prm->half_fill && !f->identity && fv_taa_tile_is_periphery(smp, gx, gy, x0, y0, tw, th))
        tt.alpha = 1.0f; /* experiment: the periphery's samples as traced */
    dsp->taa_blend(fk, &tt, l0->rgbd + 4 * o, l0->wgt + o, l0->stride, x0, y0, tw, th, &fl);
    if (!prm->fill)
        return;
    float fx = 0.0f, fy = 0.0f;
    if (fl.n > 0.0f) {
        fx = fl.dx / fl.n;
        fy = fl.dy / fl.n;
    } else if (!f->identity) { /* no sample reached the previous image: assume far away */
        float u, v;
        if (fv_taa_project(f, cx, cy, 1000.0f /* FV_DEPTH_MISS_M */, &u, &v) > 0.0f) {
            fx = u - cx;
            fy = v - cy;
        }
    }
    if (!(fabsf(fx) < 65536.0f && fabsf(fy) < 65536.0f))
        return;
    tt.flow_x = (int)floorf(fx + 0.5f);
    tt.flow_y = (int)floorf(fy + 0.5f);
    if (f->lens) {
        float u, v;
        const float z0 = fv_taa_project(f, cx, cy, d0, &u, &v);
        fv_taa_lens_tile_fill(f, &tl, cx + (float)tt.flow_x, cy + (float)tt.flow_y, z0 > 1e-3f ? z0 : d0);
    }
    dsp->taa_fill(fk, &tt, l0->rgbd + 4 * o, l0->wgt + o, l0->stride, x0, y0, tw, th);
}

int fv_taa_tile_is_periphery(const struct fv_sampler *smp, int gx, int gy, int x0, int y0, int tw, int th)
{
    /* the tile's nearest pixel centre to the gaze */
    const float dx = (float)gx < (float)x0 + 0.5f ? (float)x0 + 0.5f - (float)gx
                     : (float)gx > (float)(x0 + tw) - 0.5f ? (float)gx - ((float)(x0 + tw) - 0.5f) : 0.0f;
    const float dy = (float)gy < (float)y0 + 0.5f ? (float)y0 + 0.5f - (float)gy
                     : (float)gy > (float)(y0 + th) - 0.5f ? (float)gy - ((float)(y0 + th) - 0.5f) : 0.0f;
    const float r = smp->r1_px + FV_TAA_HALF_MARGIN_PX;
    return dx * dx + dy * dy > r * r;
}

void fv_taa_frame_half(const fv_taa_frame *f, fv_taa_frame *h, fv_pyramid *pyr1)
{
    *h = *f;
    memset(pyr1, 0, sizeof *pyr1);
    pyr1->levels = 1;
    pyr1->lv[0] = f->hist->lv[1];
    h->hist = pyr1;
    /* previous level-1 texel (s, t) is level-0 (2 s, 2 t); (U, V) in level-1 units are half the
     * level-0 ones: rows 0, 1 halved, the per-texel columns doubled (powers of two: exact) */
    for (int k = 0; k < 2; k++) {
        h->T2[k] = 0.5f * f->T2[k];
        h->N0[k] = 0.5f * f->N0[k];
    }
    h->NX[2] = 2.0f * f->NX[2];
    h->NY[2] = 2.0f * f->NY[2];
    h->prev_w = (float)f->hist->lv[1].w;
    h->prev_h = (float)f->hist->lv[1].h;
    h->lens = NULL;
}

void fv_taa_fill_half(const fv_taa_frame *h, const fv_reproject_dsp *dsp, const fv_pyr_level *l0, int x0, int y0,
                      int tw, int th, float flow_x, float flow_y)
{
    /* the tile's level-1 block with a ring of one texel: block texel (i, j), i, j in -1 .. 8, at
     * [j + 1][i + 1], the history texel (hx0 + i + Rx, hy0 + j + Ry) (R: the level-1 flow rounded)
     * checked against where the tile's mean flow F puts it: level-1 centre (hx0 + i + 1/2 - ex,
     * ...), ex = F - R; the holes then interpolate these points bilinearly, so the rounding does
     * not move the periphery by up to a pixel from frame to frame */
    enum { S = 10 };
    _Alignas(64) float rgbd[S * S * 4];
    _Alignas(64) float wgt[S * S];
    memset(wgt, 0, sizeof wgt); /* every texel of the block is a hole; colours are read only where filled */
    const int hx0 = x0 >> 1, hy0 = y0 >> 1, hw = (tw + 1) >> 1, hh = (th + 1) >> 1;
    const float Fx = 0.5f * flow_x, Fy = 0.5f * flow_y;
    fv_taa_tile t = {.widen = 1.0f, .alpha = 1.0f};
    t.flow_x = (int)floorf(Fx + 0.5f);
    t.flow_y = (int)floorf(Fy + 0.5f);
    const float ex = Fx - (float)t.flow_x, ey = Fy - (float)t.flow_y;
    fv_taa_frame hs = *h; /* the check against the shifted points: U + ex Z, V + ey Z */
    hs.T2[0] += ex * h->T2[2], hs.N0[0] += ex * h->N0[2], hs.NX[0] += ex * h->NX[2], hs.NY[0] += ex * h->NY[2];
    hs.T2[1] += ey * h->T2[2], hs.N0[1] += ey * h->N0[2], hs.NX[1] += ey * h->NX[2], hs.NY[1] += ey * h->NY[2];
    dsp->taa_fill(&hs, &t, rgbd, wgt, S, hx0 - 1, hy0 - 1, hw + 2, hh + 2);
    /* pixel x's centre is block position px = (x + 1/2) / 2 - 1/2 + ex: texel floor(px), weight 1 - frac */
    int ix[16];
    float fxw[16];
    for (int x = 0; x < tw; x++) {
        const float p = 0.5f * (float)x - 0.25f + ex;
        const float fl = floorf(p);
        ix[x] = (int)fl + 1;
        fxw[x] = p - fl;
    }
    for (int y = 0; y < th; y++) {
        const ptrdiff_t o = (ptrdiff_t)(y0 + y) * l0->stride + x0;
        float *wr = l0->wgt + o, *cr = l0->rgbd + 4 * o;
        const float p = 0.5f * (float)y - 0.25f + ey, fl = floorf(p), fy = p - fl;
        const int j = (int)fl + 1;
        for (int x = 0; x < tw; x++) {
            if (wr[x] != 0.0f)
                continue;
            const int i = ix[x];
            const float fx = fxw[x];
            const int k[4] = {j * S + i, j * S + i + 1, (j + 1) * S + i, (j + 1) * S + i + 1};
            const float b[4] = {(1.0f - fx) * (1.0f - fy), fx * (1.0f - fy), (1.0f - fx) * fy, fx * fy};
            float acc[4] = {0, 0, 0, 0}, sw = 0.0f, sc = 0.0f;
            for (int q = 0; q < 4; q++) {
                const float ws = wgt[k[q]];
                if (!(ws > 0.0f && b[q] > 0.0f))
                    continue;
                for (int c = 0; c < 4; c++)
                    acc[c] += b[q] * rgbd[4 * k[q] + c];
                sw += b[q];
                sc += b[q] * ws;
            }
            if (!(sw > 0.0f))
                continue;
            const float inv = 1.0f / sw;
            for (int c = 0; c < 4; c++)
                cr[4 * x + c] = acc[c] * inv;
            wr[x] = sc * inv;
        }
    }
}

/* experiment: the check per level-1 history texel (its mean depth, within one pixel), the
 * level-0 texels copied as the full-resolution fill does */
void fv_taa_fill_blockcheck(const fv_taa_frame *f, const fv_taa_tile *t, const fv_pyr_level *l0, int x0, int y0,
                            int tw, int th)
{
    const fv_pyr_level *H0 = &f->hist->lv[0], *H1 = &f->hist->lv[1];
    const int W = H0->w, Hh = H0->h;
    const int bx = (x0 + t->flow_x) >> 1, by = (y0 + t->flow_y) >> 1;
    uint8_t ok[10][10];
    for (int j = 0; j < 10; j++)
        for (int i = 0; i < 10; i++) {
            ok[j][i] = 0;
            const int s1 = bx + i, t1 = by + j;
            if (s1 < 0 || t1 < 0 || s1 >= H1->w || t1 >= H1->h)
                continue;
            const ptrdiff_t q = (ptrdiff_t)t1 * H1->stride + s1;
            if (!(H1->wgt[q] > 0.0f))
                continue;
            const float D = H1->rgbd[4 * q + 3];
            const float uc = (float)(2 * s1 + 1), vc = (float)(2 * t1 + 1);
            const float U = f->T2[0] + D * ((f->N0[0] + vc * f->NY[0]) + uc * f->NX[0]);
            const float V = f->T2[1] + D * ((f->N0[1] + vc * f->NY[1]) + uc * f->NX[1]);
            const float z = f->T2[2] + D * ((f->N0[2] + vc * f->NY[2]) + uc * f->NX[2]);
            if (!(z > 1e-4f))
                continue;
            const float ex = U / z - (uc - (float)t->flow_x), ey = V / z - (vc - (float)t->flow_y);
            ok[j][i] = ex <= 0.5f && ex >= -0.5f && ey <= 0.5f && ey >= -0.5f;
        }
    for (int y = 0; y < th; y++) {
        const int sy = y0 + y + t->flow_y;
        if (sy < 0 || sy >= Hh)
            continue;
        const float vc = (float)sy + 0.5f;
        const float B2 = f->N0[2] + vc * f->NY[2];
        const ptrdiff_t o = (ptrdiff_t)(y0 + y) * l0->stride + x0, ho = (ptrdiff_t)sy * H0->stride;
        float *wr = l0->wgt + o, *cr = l0->rgbd + 4 * o;
        const uint8_t *okr = ok[(sy >> 1) - by];
        for (int x = 0; x < tw; x++) {
            const int sx = x0 + x + t->flow_x;
            if (wr[x] != 0.0f || sx < 0 || sx >= W || !okr[(sx >> 1) - bx])
                continue;
            const float ws = H0->wgt[ho + sx];
            if (!(ws > 0.0f))
                continue;
            const float *src = H0->rgbd + 4 * (ho + sx);
            const float z = f->T2[2] + src[3] * (B2 + ((float)sx + 0.5f) * f->NX[2]);
            if (!(z > 1e-4f))
                continue;
            cr[4 * x] = src[0], cr[4 * x + 1] = src[1], cr[4 * x + 2] = src[2], cr[4 * x + 3] = z;
            wr[x] = ws;
        }
    }
}

/* The history a tile will read lies around the tile moved by the head motion: guess the move
 * from the previous frame's depth at the tile (one texel of coarse_level) and prefetch those level-0
 * rows, so they arrive while the tile's rays are traced (the reads are otherwise latency-bound
 * misses: each history row is a separate 4-line stretch of a ~37 MB image). */
void fv_taa_prefetch(const fv_taa_frame *f, int coarse_level, int x0, int y0, int tw, int th)
{
    const fv_pyr_level *h0 = &f->hist->lv[0];
    int dx = 0, dy = 0;
    if (!f->identity) {
        const int l = f->hist->levels - 1 < coarse_level ? f->hist->levels - 1 : coarse_level;
        const fv_pyr_level *hl = &f->hist->lv[l];
        const float cx = (float)x0 + 0.5f * (float)tw, cy = (float)y0 + 0.5f * (float)th;
        int hx = (int)cx >> l, hy = (int)cy >> l;
        hx = hx < hl->w ? hx : hl->w - 1;
        hy = hy < hl->h ? hy : hl->h - 1;
        float u, v;
        if (fv_taa_project(f, cx, cy, hl->rgbd[4 * ((ptrdiff_t)hy * hl->stride + hx) + 3], &u, &v) <= 0.0f ||
            !(fabsf(u - cx) < 4096.0f && fabsf(v - cy) < 4096.0f))
            return;
        dx = (int)floorf(u - cx);
        dy = (int)floorf(v - cy);
    }
    int xa = x0 + dx - 1, xb = x0 + dx + tw + 1, ya = y0 + dy - 1, yb = y0 + dy + th + 1;
    xa = xa < -1 ? -1 : xa;
    xb = xb > h0->w ? h0->w : xb;
    ya = ya < -1 ? -1 : ya;
    yb = yb > h0->h ? h0->h : yb;
    if (xa > xb)
        return;
    for (int y = ya; y <= yb; y++) {
        const float *r = h0->rgbd + 4 * ((ptrdiff_t)y * h0->stride + xa);
        for (int x = 0; x <= 4 * (xb - xa); x += 16) /* one 64-byte line = 4 pixels */
            __builtin_prefetch(r + x);
        __builtin_prefetch(r + 4 * (xb - xa));
        /* every line of the weights: 19 floats from x0 - 1 span three lines, and the middle
         * one (the tile's own) was missed when only the ends were fetched */
        const float *wr = h0->wgt + (ptrdiff_t)y * h0->stride + xa;
        for (int x = 0; x <= xb - xa; x += 16)
            __builtin_prefetch(wr + x);
        __builtin_prefetch(wr + (xb - xa));
    }
}
