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
