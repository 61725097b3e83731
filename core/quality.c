/* fovea-replay's quality bookkeeping (core/quality.h). */
#include "quality.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "metrics.h"

float fv_gaze_px(float g, int size) { return floorf(g * (float)size) + 0.5f; }

void fv_mean_add(fv_mean_acc *m, double v)
{
    if (isfinite(v)) {
        m->sum += v;
        m->n++;
    } else if (isinf(v)) {
        m->inf++;
    }
}

double fv_mean_get(const fv_mean_acc *m) { return m->n ? m->sum / (double)m->n : m->inf ? INFINITY : NAN; }

int fv_quality_init(fv_quality *q, int w, int h, int vs_full)
{
    memset(q, 0, sizeof *q);
    q->w = w;
    q->h = h;
    q->vs_full = vs_full;
    q->prev = malloc((size_t)w * h * 3);
    q->cur = malloc((size_t)w * h * 3);
    if (vs_full) {
        q->err_prev = malloc((size_t)w * h * sizeof(float));
        q->err_cur = malloc((size_t)w * h * sizeof(float));
    }
    return q->prev && q->cur && (!vs_full || (q->err_prev && q->err_cur)) ? 0 : -1;
}

void fv_quality_free(fv_quality *q)
{
    free(q->prev);
    free(q->cur);
    free(q->err_prev);
    free(q->err_cur);
    q->prev = q->cur = NULL;
    q->err_prev = q->err_cur = NULL;
}

void fv_quality_frame(fv_quality *q, const uint8_t *rgb, ptrdiff_t stride, const uint8_t *full, float gx, float gy,
                      float r0_px, float r1_px, fv_quality_row *row)
{
    const int W = q->w, H = q->h;
    const ptrdiff_t s = (ptrdiff_t)W * 3;
    row->dluma_periph = row->psnr_all = row->psnr_fovea = row->psnr_periph = row->flicker_periph = NAN;
    for (int y = 0; y < H; y++)
        memcpy(q->cur + (size_t)y * W * 3, rgb + (ptrdiff_t)y * stride, (size_t)W * 3);
    if (q->frames > 0) { /* outside r1 of both gazes: what the eye sees in its periphery both times */
        fv_region per = {gx, gy, r1_px, q->prev_gx, q->prev_gy, 1};
        row->dluma_periph = fv_luma_mad(q->prev, q->cur, W, H, s, &per);
    }
    if (q->vs_full && full) {
        fv_region fov = fv_region_disc(gx, gy, r0_px, 0), per = fv_region_disc(gx, gy, r1_px, 1);
        row->psnr_all = fv_luma_psnr(full, q->cur, W, H, s, NULL);
        row->psnr_fovea = fv_luma_psnr(full, q->cur, W, H, s, &fov);
        row->psnr_periph = fv_luma_psnr(full, q->cur, W, H, s, &per);
        fv_luma_error(full, q->cur, W, H, s, q->err_cur);
        if (q->frames > 0) {
            fv_region both = {gx, gy, r1_px, q->prev_gx, q->prev_gy, 1};
            row->flicker_periph = fv_mean_abs_diff(q->err_prev, q->err_cur, W, H, &both);
        }
        float *t = q->err_prev;
        q->err_prev = q->err_cur;
        q->err_cur = t;
    }
    uint8_t *t8 = q->prev;
    q->prev = q->cur;
    q->cur = t8;
    q->prev_gx = gx;
    q->prev_gy = gy;
    q->frames++;
    fv_mean_add(&q->dluma, row->dluma_periph);
    fv_mean_add(&q->psnr_all, row->psnr_all);
    fv_mean_add(&q->psnr_fovea, row->psnr_fovea);
    fv_mean_add(&q->psnr_periph, row->psnr_periph);
    fv_mean_add(&q->flicker, row->flicker_periph);
}
