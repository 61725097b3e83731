/* Refinement at (up to) full resolution in a window around the search's box: threshold half way
 * between the blob and its surround, iterated weighted centroid of the darker pixels, then rays
 * from there give sub-pixel edge points; in headset mode the lid's edge points are cut and
 * RANSAC picks the consensus, then a direct least-squares ellipse fit with outlier rejection
 * (ellipse.c). The mode's settings (fv_eye_mode_settings) say which sub-steps run. */
#include <math.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <string.h>

#include "base/util.h"
#include "eyetrack/track_impl.h"

#define NRAYS FV_ET_NRAYS


/* Bilinear sample, pixel centres at +0.5 (clamped to the image). */
static inline float sample(const uint8_t *img, int w, int h, float x, float y)
{
    x -= 0.5f, y -= 0.5f;
    x = fv_clampf(x, 0.0f, (float)w - 1.001f);
    y = fv_clampf(y, 0.0f, (float)h - 1.001f);
    const int ix = (int)x, iy = (int)y;
    const float fx = x - ix, fy = y - iy;
    const uint8_t *r = img + iy * w + ix;
    const int x1 = ix + 1 < w ? 1 : 0, y1 = iy + 1 < h ? w : 0;
    const float a = r[0] + fx * (r[x1] - r[0]), b = r[y1] + fx * (r[y1 + x1] - r[y1]);
    return a + fy * (b - a);
}

/* Distance along the ray (cx, cy) + d (dx, dy) of the steepest rise within +-span of d0:
 * central differences 1 px wide every 0.5 px, the peak refined by a parabola through the
 * differences 1 px either side of it. */
static float steepest_rise(const uint8_t *img, int w, int h, float cx, float cy, float dx, float dy, float d0,
                           float span)
{
#define AT(q) sample(img, w, h, cx + (q) * dx, cy + (q) * dy)
    float best = -1e30f, bq = d0;
    for (float q = fmaxf(0.5f, d0 - span); q <= d0 + span; q += 0.5f) {
        const float g = AT(q + 0.5f) - AT(q - 0.5f);
        if (g > best)
            best = g, bq = q;
    }
    const float gm = AT(bq) - AT(bq - 1.0f), gp = AT(bq + 1.0f) - AT(bq);
    const float den = gm - 2.0f * best + gp;
    /* vertex of the parabola through (-1, gm), (0, best), (1, gp), in units of 1 px; the
     * samples of the search were 0.5 px apart, so at most a quarter pixel either way */
    return bq + (den < 0 ? fv_clampf(0.5f * (gm - gp) / den, -0.25f, 0.25f) : 0.0f);
#undef AT
}

/* The ray stays at or above th for len pixels past dist (a pupil edge, not a glint's halo or
 * a stray bright pixel inside the pupil). */
static int sustained(const uint8_t *win, int ww, int wh, float cx, float cy, float dx, float dy, float dist, float len,
                     float th)
{
    for (float d = dist + 0.5f; d <= dist + len; d += 0.5f) {
        const float px = cx + d * dx, py = cy + d * dy;
        if (px < 0.5f || py < 0.5f || px > ww - 0.5f || py > wh - 0.5f)
            return 1;
        if (sample(win, ww, wh, px, py) < th)
            return 0;
    }
    return 1;
}

/* Points within tol of the ellipse; with gradients (gx, gy not NULL), only those whose image
 * gradient points along the ellipse's outward normal (cos >= mincos): a lash or lid edge that
 * happens to lie on a candidate ellipse runs across it, not along it. */
static int count_near(const fv_ellipse *e, const float *x, const float *y, const float *gx, const float *gy, int n,
                      double tol, double mincos)
{
    const double c = cos(e->angle), s = sin(e->angle), ia = 1.0 / e->a, ib = 1.0 / e->b;
    int k = 0;
    for (int i = 0; i < n; i++) {
        const double u = (x[i] - e->cx) * c + (y[i] - e->cy) * s, v = -(x[i] - e->cx) * s + (y[i] - e->cy) * c;
        const double rho = sqrt((u * ia) * (u * ia) + (v * ib) * (v * ib));
        const double d = rho < 1e-12 ? e->b : fabs(rho - 1.0) * sqrt(u * u + v * v) / rho;
        if (d > tol)
            continue;
        if (gx) {
            const double nu = u * ia * ia, nv = v * ib * ib;
            const double nx = nu * c - nv * s, ny = nu * s + nv * c;
            const double dot = nx * gx[i] + ny * gy[i], nn = sqrt((nx * nx + ny * ny) * (gx[i] * gx[i] + gy[i] * gy[i]));
            if (!(dot >= mincos * nn))
                continue;
        }
        k++;
    }
    return k;
}


/* A lid across the pupil puts a run of edge points on a nearly straight line (its radius of
 * curvature is several times the pupil's). Find the best line through pairs of points 2-8 rays
 * apart (the points come in ray order, and a lid's are neighbours); if at least 5 points lie
 * within tol of it, spread over >= 1.2 r along it (an arc of the pupil's own outline that long
 * bends away from any line by more than tol even at b/a = 0.6), it runs within 40 deg of
 * horizontal and it cuts the pupil, drop those points and everything beyond it (lashes).
 * Returns the number of points kept (ex, ey, egx, egy compacted). */
static int drop_lid_line(float *ex, float *ey, float *egx, float *egy, int ne, float cx, float cy, float r)
{
    const float tol = fmaxf(0.5f, 0.025f * r);
    int best = 0;
    float bnx = 0, bny = 0, bd = 0;
    for (int i = 0; i < ne; i++)
        for (int dj = 2; dj <= fv_mini(8, ne - 1); dj++) {
            const int j = (i + dj) % ne;
            const float dx = ex[j] - ex[i], dy = ey[j] - ey[i], len = hypotf(dx, dy);
            if (len < 0.3f * r || fabsf(dy) > 0.643f * len) /* sin 40 deg */
                continue;
            const float nx = -dy / len, ny = dx / len, d = nx * ex[i] + ny * ey[i];
            if (fabsf(nx * cx + ny * cy - d) > 0.95f * r)
                continue;
            int cnt = 0;
            float tmin = 1e30f, tmax = -1e30f;
            for (int k = 0; k < ne; k++)
                if (fabsf(nx * ex[k] + ny * ey[k] - d) <= tol) {
                    const float tt = ny * ex[k] - nx * ey[k];
                    cnt++, tmin = fminf(tmin, tt), tmax = fmaxf(tmax, tt);
                }
            if (cnt >= 5 && tmax - tmin >= 1.2f * r && cnt > best)
                best = cnt, bnx = nx, bny = ny, bd = d;
        }
    if (!best)
        return ne;
    /* side of the line the centre is on: keep points on it, beyond tol */
    const float sc = bnx * cx + bny * cy - bd > 0 ? 1.0f : -1.0f;
    int m = 0;
    for (int k = 0; k < ne; k++)
        if (sc * (bnx * ex[k] + bny * ey[k] - bd) > tol)
            ex[m] = ex[k], ey[m] = ey[k], egx[m] = egx[k], egy[m] = egy[k], m++;
    return m;
}

/* The window refined in, and the blob found there (window pixels). */
typedef struct {
    uint8_t *win;
    int ww, wh, x0, y0, half;
    int med;    /* the window's median grey (when inpainted here) */
    int masked; /* reflections were inpainted here: the mask marks them */
    float cx, cy, r, inner, ring;
} window;

/* Edge points in the refine image's pixels, in ray order. */
typedef struct {
    float x[NRAYS], y[NRAYS];
    float beyond[NRAYS];       /* the brightest of the profile up to 0.5r beyond the point */
    float gx[NRAYS], gy[NRAYS]; /* Sobel gradient at the point */
    int n, nrays;
} edges;

/* A copy of the image around the candidate, reflections inpainted (the search image has them
 * inpainted already). -1 when the window is too small. */
static int cut_window(const fv_et_refine_args *a, window *wn)
{
    const fv_eye_mode_settings *set = a->set;
    const fv_et_candidate *c = &a->c;
    /* headset frames: the search's box can be much smaller than the pupil (the darkest part of
     * it), and rays must reach the pupil's far edge inside the window */
    const int side = set->window_side_div ? fv_mini(a->w, a->h) / set->window_side_div : 0;
    const int half = fv_maxi((int)ceilf(3.0f * c->r), side) + 2;
    const int x0 = fv_maxi(0, (int)c->x - half), y0 = fv_maxi(0, (int)c->y - half);
    const int x1 = fv_mini(a->w, (int)c->x + half), y1 = fv_mini(a->h, (int)c->y + half);
    const int ww = x1 - x0, wh = y1 - y0;
    if (ww < 4 || wh < 4)
        return -1;
    for (int y = 0; y < wh; y++)
        memcpy(a->win + (size_t)y * ww, a->img + (y + y0) * a->stride + x0, (size_t)ww);
    *wn = (window){ a->win, ww, wh, x0, y0, half, 0, 0, c->x - x0, c->y - y0, c->r, c->inner, c->ring };
    if (!set->refine_on_search_image) {
        /* glint halos are wider on an image finer than the search image */
        fv_et_levels lv;
        wn->masked = fv_et_inpaint_reflections(a->dsp, a->win, ww, wh, c->scale > 1 ? set->reflect_grow_px : 1,
                                               a->mask, a->idx, a->fr, &lv);
        wn->med = lv.median;
    }
    return 0;
}

/* Levels of the blob (disc 0.7r) and its surround (ring 1.2r..1.7r), then the weighted centroid
 * of the pixels darker than half way, iterated until it settles. -1 when nothing darker stands
 * out. */
static int centroid(const fv_et_refine_args *a, window *wn)
{
    const uint8_t *win = wn->win;
    const int ww = wn->ww, wh = wn->wh;
    float *dxx = a->dxx;
    float cx = wn->cx, cy = wn->cy, r = wn->r, inner = wn->inner, ring = wn->ring;
    int grown = 0;
    for (int it = 0; it < a->set->centroid_iters; it++) {
        /* blob and surround levels around the current estimate */
        const float ri = 0.7f * r, ro0 = 1.2f * r, ro1 = 1.7f * r, rr = 1.5f * r;
        const float ri2 = ri * ri, ro02 = ro0 * ro0, ro12 = ro1 * ro1, rr2 = rr * rr;
        const int bx0 = fv_maxi(0, (int)(cx - ro1)), bx1 = fv_mini(ww, (int)(cx + ro1) + 1);
        const int by0 = fv_maxi(0, (int)(cy - ro1)), by1 = fv_mini(wh, (int)(cy + ro1) + 1);
        const int ax0 = fv_maxi(0, (int)(cx - rr)), ax1 = fv_mini(ww, (int)(cx + rr) + 1);
        const int ay0 = fv_maxi(0, (int)(cy - rr)), ay1 = fv_mini(wh, (int)(cy + rr) + 1);
        /* dx * dx of every column either loop visits (the same float operations as per pixel) */
        const int qx0 = fv_mini(ax0, bx0), qx1 = fv_maxi(ax1, bx1);
        for (int x = qx0; x < qx1; x++) {
            const float dx = x + 0.5f - cx;
            dxx[x - qx0] = dx * dx;
        }
        /* integer sums: exact, as the double sums were */
        int64_t si = 0, so = 0;
        int ni = 0, no = 0;
        for (int y = by0; y < by1; y++) {
            const float dy = y + 0.5f - cy, dyy = dy * dy;
            const uint8_t *row = win + y * ww;
            for (int x = bx0; x < bx1; x++) {
                const float d2 = dxx[x - qx0] + dyy;
                const int v = row[x];
                if (d2 <= ri2)
                    si += v, ni++;
                else if (d2 >= ro02 && d2 <= ro12)
                    so += v, no++;
            }
        }
        if (ni)
            inner = (float)((double)si / ni);
        if (no)
            ring = (float)((double)so / no);
        /* Headset frames: the search's box can sit between reflections inside a much bigger
         * pupil, with pupil all around it too; grow it until its surround is not pupil */
        if (grown < a->set->box_grow_max && ring < inner + 0.25f * (wn->med - inner) && 1.7f * 1.4f * r < wn->half) {
            r *= 1.4f, grown++, it--;
            continue;
        }
        if (!(ring > inner))
            return -1;
        const float th = 0.5f * (inner + ring);
        /* weighted centroid of the dark pixels near the estimate */
        double sw = 0, sx = 0, sy = 0;
        int area = 0;
        for (int y = ay0; y < ay1; y++) {
            const float dy = y + 0.5f - cy, dyy = dy * dy;
            const uint8_t *row = win + y * ww;
            for (int x = ax0; x < ax1; x++) {
                if (dxx[x - qx0] + dyy > rr2)
                    continue;
                const float v = row[x];
                if (v < th) {
                    const double wt = th - v;
                    sw += wt, sx += wt * (x + 0.5f), sy += wt * (y + 0.5f);
                    area++;
                }
            }
        }
        if (sw <= 0)
            return -1;
        const float nx = (float)(sx / sw), ny = (float)(sy / sw);
        const float nr = fv_clampf(sqrtf(area / (float)M_PI), 0.6f * r, 1.4f * r);
        const int settled = fabsf(nx - cx) < 0.02f * r && fabsf(ny - cy) < 0.02f * r && fabsf(nr - r) < 0.02f * r;
        cx = nx, cy = ny, r = nr;
        if (settled)
            break;
    }
    wn->cx = cx, wn->cy = cy, wn->r = r, wn->inner = inner, wn->ring = ring;
    return 0;
}

/* Along rays from the centroid: the first outward crossing of the mid level that stays above it
 * (a pupil edge, not a glint's halo) and has no much brighter lid beyond. */
static void edge_points(const fv_et_refine_args *a, const window *wn, edges *ed)
{
    const fv_eye_mode_settings *set = a->set;
    const int ww = wn->ww, wh = wn->wh, x0 = wn->x0, y0 = wn->y0;
    const float cx = wn->cx, cy = wn->cy, r = wn->r, inner = wn->inner, ring = wn->ring;
    const float th = 0.5f * (inner + ring);
    const uint8_t *ew = wn->win;
    if (set->smooth_rays) {
        /* 3x3 box: sensor noise would otherwise break the sustained-crossing rule near the
         * true edge and push crossings out into a dark iris (idx is free once inpainted) */
        uint8_t *bl = (uint8_t *)a->idx;
        const uint8_t *win = wn->win;
        for (int y = 0; y < wh; y++)
            a->dsp->et_box3_row(bl + y * ww, win + fv_maxi(0, y - 1) * ww, win + y * ww, win + fv_mini(wh - 1, y + 1) * ww, ww);
        ew = bl;
    }
    int ne = 0;
    const float step = fmaxf(0.25f, r / 24.0f);
    const int nrays = r < 12.0f ? NRAYS / 2 : NRAYS; /* small pupils: fewer edge pixels anyway */
    for (int k = 0; k < nrays; k++) {
        const float ang = (float)(2.0 * M_PI * k / nrays), dx = cosf(ang), dy = sinf(ang);
        float prev = sample(ew, ww, wh, cx, cy), pd = 0;
        for (float dist = step; dist < 2.2f * r; dist += step) {
            const float px = cx + dist * dx, py = cy + dist * dy;
            if (px < 0.5f || py < 0.5f || px > ww - 0.5f || py > wh - 0.5f)
                break;
            const float v = sample(ew, ww, wh, px, py);
            if (v >= th && prev < th && sustained(ew, ww, wh, cx, cy, dx, dy, dist, fmaxf(1.5f, 0.2f * r), th)) {
                const float f = (th - prev) / (v - prev);
                float de = pd + f * (dist - pd);
                if (set->edge_search_px > 0) /* the level's crossing moves with the levels; the edge does not */
                    de = steepest_rise(ew, ww, wh, cx, cy, dx, dy, de, set->edge_search_px);
                /* beyond a pupil edge lies iris; beyond a lid edge, much brighter skin: a ray
                 * that meets the lid gives no point (it would drag the fit) */
                const float po = de + fmaxf(2.0f, 0.15f * r);
                const float vo = sample(ew, ww, wh, cx + po * dx, cy + po * dy);
                float vmax = vo;
                if (set->beyond_frac > 0) {
                    /* the brightest of the profile beyond: iris for a pupil edge, skin between
                     * the lashes for a lid edge */
                    const float pe = de + fmaxf(4.0f, 0.5f * r);
                    for (float q = po + 1.0f; q <= pe; q += 1.0f) {
                        const float qx = cx + q * dx, qy = cy + q * dy;
                        if (qx < 0.5f || qy < 0.5f || qx > ww - 0.5f || qy > wh - 0.5f)
                            break;
                        vmax = fmaxf(vmax, sample(ew, ww, wh, qx, qy));
                    }
                }
                /* an edge next to an inpainted reflection is made up, not seen */
                const int ix = (int)(cx + de * dx), iy = (int)(cy + de * dy);
                int near_mask = 0;
                if (wn->masked)
                    for (int qy = fv_maxi(0, iy - 1); qy <= fv_mini(wh - 1, iy + 1); qy++)
                        for (int qx = fv_maxi(0, ix - 1); qx <= fv_mini(ww - 1, ix + 1); qx++)
                            near_mask |= a->mask[qy * ww + qx] != 0;
                if (!near_mask && vo <= ring + 0.6f * (ring - inner)) {
                    ed->x[ne] = cx + de * dx + x0;
                    ed->y[ne] = cy + de * dy + y0;
                    ed->beyond[ne] = vmax;
                    /* Sobel gradient at the edge point (bilinear samples 1 px apart), for the
                     * RANSAC support test */
                    const float qx = cx + de * dx, qy = cy + de * dy;
                    float g[3][3];
                    for (int j = 0; j < 3; j++)
                        for (int i = 0; i < 3; i++)
                            g[j][i] = sample(ew, ww, wh, qx + (float)(i - 1), qy + (float)(j - 1));
                    ed->gx[ne] = (g[0][2] + 2.0f * g[1][2] + g[2][2]) - (g[0][0] + 2.0f * g[1][0] + g[2][0]);
                    ed->gy[ne] = (g[2][0] + 2.0f * g[2][1] + g[2][2]) - (g[0][0] + 2.0f * g[0][1] + g[0][2]);
                    ne++;
                }
                break;
            }
            prev = v, pd = dist;
        }
    }
    ed->n = ne, ed->nrays = nrays;
}

/* What lies beyond most edge points is iris; points with something clearly brighter beyond
 * them (the lid margin, skin between the lashes: more than frac of the way from the pupil past
 * the iris) are dropped. The median is the iris level as long as the lid hides less than half
 * of the outline. */
static void drop_bright_beyond(edges *ed, float inner, float frac)
{
    const int ne = ed->n;
    float srt[NRAYS];
    memcpy(srt, ed->beyond, sizeof(float) * (size_t)ne);
    for (int i = 1; i < ne; i++)
        for (int j = i; j > 0 && srt[j - 1] > srt[j]; j--) {
            const float tmp = srt[j];
            srt[j] = srt[j - 1], srt[j - 1] = tmp;
        }
    const float iris = srt[ne / 2], lim = iris + frac * (iris - inner);
    int m = 0;
    for (int i = 0; i < ne; i++)
        if (ed->beyond[i] <= lim)
            ed->x[m] = ed->x[i], ed->y[m] = ed->y[i], ed->beyond[m] = ed->beyond[i], ed->gx[m] = ed->gx[i],
            ed->gy[m] = ed->gy[i], m++;
    ed->n = m;
}

/* RANSAC over 6-point fits of plausible size, aspect and centre (a lid can hide a third of the
 * outline and put its own edge in the middle of the points, which moves a least-squares fit);
 * deterministic sampling. Compacts the consensus to the front of ed->x, ed->y and returns its
 * size, or 0 when fewer than 8 points support the best fit. (pcx, pcy), r: the centroid. */
static int ransac(const fv_eye_mode_settings *set, edges *ed, float pcx, float pcy, float r)
{
    float *ex = ed->x, *ey = ed->y;
    const int ne = ed->n;
    uint64_t st = 0x5eedu;
    int best = 0;
    fv_ellipse be = { 0 };
    for (int it = 0; it < set->ransac_iters; it++) {
        float sx[6], sy[6];
        int pick[6], k = 0;
        while (k < 6) {
            st += 0x9e3779b97f4a7c15ull;
            uint64_t z = st;
            z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
            z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
            const int j = (int)((z ^ (z >> 31)) % (uint64_t)ne);
            int dup = 0;
            for (int q = 0; q < k; q++)
                dup |= pick[q] == j;
            if (!dup)
                pick[k] = j, sx[k] = ex[j], sy[k] = ey[j], k++;
        }
        fv_ellipse e;
        if (fv_ellipse_fit(sx, sy, 6, &e) || e.a < 0.5 * r || e.a > 2.5 * r || e.b < set->min_aspect * e.a ||
            hypot(e.cx - pcx, e.cy - pcy) > r)
            continue;
        const int cnt = count_near(&e, ex, ey, ed->gx, ed->gy, ne, fmax(1.0, 0.06 * e.a), set->ransac_grad_mincos);
        if (cnt > best)
            best = cnt, be = e;
    }
    int n = 0;
    if (best >= 8) {
        const double tol = fmax(1.0, 0.06 * be.a);
        for (int i = 0; i < ne; i++)
            if (count_near(&be, ex + i, ey + i, ed->gx + i, ed->gy + i, 1, tol, set->ransac_grad_mincos))
                ex[n] = ex[i], ey[n] = ey[i], n++;
    }
    return n;
}

/* Drops points much nearer or farther than the median radius from (pcx, pcy) (glints, lids,
 * lashes); compacts ed->x, ed->y and returns the count kept. */
static int near_median_radius(edges *ed, float pcx, float pcy)
{
    float *ex = ed->x, *ey = ed->y;
    const int ne = ed->n;
    float rad[NRAYS];
    for (int i = 0; i < ne; i++)
        rad[i] = hypotf(ex[i] - pcx, ey[i] - pcy);
    float sorted[NRAYS];
    memcpy(sorted, rad, sizeof(float) * (size_t)ne);
    for (int i = 1; i < ne; i++) /* insertion sort: 48 values */
        for (int j = i; j > 0 && sorted[j - 1] > sorted[j]; j--) {
            const float tmp = sorted[j];
            sorted[j] = sorted[j - 1], sorted[j - 1] = tmp;
        }
    const float rmed = sorted[ne / 2];
    int n = 0;
    for (int i = 0; i < ne; i++)
        if (fabsf(rad[i] - rmed) <= fmaxf(1.5f, 0.25f * rmed))
            ex[n] = ex[i], ey[n] = ey[i], n++;
    return n;
}

/* Least squares on the first n points of ed, dropping points more than max(0.75 px, 0.08a) off
 * and refitting (up to 3 rounds); the fit goes to out if its size, aspect and centre fit the
 * centroid (out->x, out->y, out->r), the centre looser when a lid line was cut (the visible
 * part's centroid sits low). */
static void fit_outline(const fv_eye_mode_settings *set, edges *ed, int n, int lid, fv_et_pupil *out)
{
    float *ex = ed->x, *ey = ed->y;
    const float r = out->r;
    fv_ellipse e;
    for (int round = 0; round < 3; round++) {
        if (fv_ellipse_fit(ex, ey, n, &e))
            return;
        /* drop points far from the fit (lashes, lids, leftover reflections), refit */
        const double tol = fmax(0.75, 0.08 * e.a);
        int m = 0;
        for (int i = 0; i < n; i++)
            if (fv_ellipse_distance(&e, ex[i], ey[i]) <= tol)
                ex[m] = ex[i], ey[m] = ey[i], m++;
        if (m == n)
            break;
        if (m < 6)
            return;
        n = m;
    }
    if (fv_ellipse_fit(ex, ey, n, &e))
        return;
    const double dc = hypot(e.cx - out->x, e.cy - out->y);
    if (e.a < 0.5 * r || e.a > 2.5 * r || e.b < set->min_aspect * e.a || dc > (lid ? 1.0 : 0.6) * r)
        return;
    out->fit = 1;
    out->e = e;
    out->inliers = (float)n / ed->nrays;
}

int fv_et_refine(const fv_et_refine_args *a, fv_et_pupil *out)
{
    const fv_eye_mode_settings *set = a->set;
    window wn;
    if (cut_window(a, &wn) || centroid(a, &wn))
        return -1;
    out->x = wn.cx + wn.x0;
    out->y = wn.cy + wn.y0;
    out->r = wn.r;
    out->inner = wn.inner;
    out->ring = wn.ring;
    out->fit = 0;
    out->inliers = 0;

    edges ed;
    edge_points(a, &wn, &ed);
    if (set->beyond_frac > 0 && ed.n >= 8)
        drop_bright_beyond(&ed, wn.inner, set->beyond_frac);
    int lid = 0;
    if (set->lid_line && ed.n >= 12) {
        const int kept = drop_lid_line(ed.x, ed.y, ed.gx, ed.gy, ed.n, wn.cx + wn.x0, wn.cy + wn.y0, wn.r);
        lid = kept < ed.n;
        ed.n = kept;
    }
    if (ed.n < 8)
        return 0;
    int n = ransac(set, &ed, out->x, out->y, wn.r);
    if (n < 8)
        n = near_median_radius(&ed, out->x, out->y);
    if (n < 8)
        return 0;
    fit_outline(set, &ed, n, lid, out);
    return 0;
}
