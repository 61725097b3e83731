/* fovea eye tracker, the driver: runs the steps on a frame (docs/eyetrack.md has the
 * measurements behind the choices).
 *
 * 1. search.c: the darkest compact blob contrasting with its ring, on the frame halved to a
 *    short side <= 160 with its reflections inpainted.
 * 2. refine.c: levels, centroid and, from edge points, an ellipse, in a window around it.
 * 3. glints.c: small bright blobs of the raw image close to the pupil.
 * 4. The reported centre: headset mode, the ellipse's (else the centroid); crop mode, the search
 *    box's centre nudged toward the crop's centre and a reflection.
 * 5. blink.c: confidence, loss and blinks against the tracker's running reference.
 * The mode (eyetrack.h) is the tracker's, or for AUTO decided per frame by its size; its settings
 * (mode.c) say what steps 2 and 4 do. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/util.h"
#include "eyetrack/track_impl.h"

void fv_eye_default_params(fv_eye_params *p)
{
    p->isa_mask = ~0u;
    p->min_radius_frac = 0.035f;
    p->max_radius_frac = 0.17f;
    p->border_frac = 0.1f;
    p->centre_prior = 20.0f;
    p->max_glints = FV_EYE_MAX_GLINTS;
}

fv_eye_tracker *fv_eye_create(const fv_eye_params *p, fv_eye_mode mode)
{
    fv_eye_tracker *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    if (p)
        t->p = *p;
    else
        fv_eye_default_params(&t->p);
    t->mode = fv_eye_mode_name(mode) ? mode : FV_EYE_MODE_AUTO;
    if (t->p.max_glints < 0 || t->p.max_glints > FV_EYE_MAX_GLINTS)
        t->p.max_glints = FV_EYE_MAX_GLINTS;
    fv_eyetrack_dsp_init(&t->dsp, t->p.isa_mask);
    return t;
}

void fv_eye_destroy(fv_eye_tracker *t)
{
    if (!t)
        return;
    free(t->mem);
    free(t);
}

void fv_eye_reset(fv_eye_tracker *t)
{
    t->ref = (fv_et_history){ 0 };
}

/* The frame's scratch, carved from the tracker's buffer; 0, or -1 on no memory. */
static int scratch(fv_eye_tracker *t, int w, int h, fv_et_scratch *s)
{
    const size_t px = (size_t)w * h;
    const size_t ii_bytes = ((size_t)(w + 1) * (h + 1)) * sizeof(uint32_t);
    const size_t row_bytes = (size_t)w * sizeof(float);
    const size_t gl_bytes = 2 * FV_EYE_MAX_GLINTS * sizeof(fv_eye_glint);
    const size_t bytes = 3 * px + ii_bytes + px * sizeof(int) + row_bytes + 64 + gl_bytes;
    if (bytes > t->cap) {
        void *m = realloc(t->mem, bytes);
        if (!m)
            return -1;
        t->mem = m;
        t->cap = bytes;
    }
    uint8_t *m = t->mem;
    s->ii = (uint32_t *)m;
    s->stack = (int *)(m + ii_bytes);
    s->rowf = (float *)(m + ii_bytes + px * sizeof(int));
    s->gl = (fv_eye_glint *)(m + ii_bytes + px * sizeof(int) + row_bytes);
    s->work = m + ii_bytes + px * sizeof(int) + row_bytes + gl_bytes;
    s->mask = s->work + px;
    s->lowres = s->mask + px;
    return 0;
}

/* Step 2 on the image the mode refines on: the search image (crop mode: inpainted already), or
 * the frame halved while its short side exceeds refine_max_side, never below the search
 * image's scale (lowres is free after the search). The result in full-resolution pixels; when
 * no dark region stands out in the window, the search's answer with no fit. */
static void refine_pupil(const fv_eye_tracker *t, const fv_eye_mode_settings *set, const uint8_t *luma, int w, int h,
                         ptrdiff_t stride, const fv_et_candidate *c, const fv_et_scratch *s, fv_et_pupil *p)
{
    const int reuse = set->refine_on_search_image;
    const size_t px = (size_t)w * h;
    const uint8_t *rsrc = reuse ? s->work : luma;
    int rw = reuse ? c->sw : w, rh = reuse ? c->sh : h, rs = reuse ? c->scale : 1;
    ptrdiff_t rst = reuse ? c->sw : stride;
    while (!reuse && fv_mini(rw, rh) > set->refine_max_side && rs < c->scale) {
        uint8_t *dst = rsrc == s->lowres ? s->lowres + px / 2 : s->lowres;
        const int nw = rw / 2, nh = rh / 2;
        for (int y = 0; y < nh; y++)
            t->dsp.et_down2_row(dst + (size_t)y * nw, rsrc + (2 * y) * rst, rsrc + (2 * y + 1) * rst, nw);
        rsrc = dst, rst = nw, rw = nw, rh = nh, rs *= 2;
    }
    fv_et_refine_args a = { &t->dsp, set, rsrc, rw, rh, rst, *c, reuse ? s->lowres : s->work, s->mask, s->stack,
                            (int *)s->ii, s->rowf };
    a.c.x /= (float)rs, a.c.y /= (float)rs, a.c.r /= (float)rs, a.c.scale /= rs;
    if (fv_et_refine(&a, p)) {
        /* no dark region stands out in the window: keep the search's answer, flagged low */
        p->x = c->x, p->y = c->y, p->r = c->r, p->inner = c->inner, p->ring = c->ring, p->fit = 0, p->inliers = 0;
    } else if (rs > 1) {
        const float f = (float)rs;
        p->x *= f, p->y *= f, p->r *= f;
        p->e.cx *= f, p->e.cy *= f, p->e.a *= f, p->e.b *= f;
    }
}

/* Step 4, crop mode: the box centre, moved toward the crop's centre (the crop is the eye
 * detector's own estimate: on MRL the labels sit ~8% of the way from the detection to the
 * centre) and toward a corneal reflection inside the box (it hides part of the pupil, and its
 * inpainted area looks less dark than the pupil, which pushes the box away from it), then on a
 * pixel centre again like the box it came from. */
static void crop_centre(const fv_eye_mode_settings *set, const uint8_t *luma, int w, int h, ptrdiff_t stride,
                        const fv_et_candidate *c, fv_eye_result *r)
{
    const float a = set->centre_weight, gw = set->glint_weight;
    float px = c->x + a * (0.5f * (float)w - c->x), py = c->y + a * (0.5f * (float)h - c->y);
    float gx, gy;
    if (gw > 0 && fv_et_bright_spot(luma, w, h, stride, c->x, c->y, c->r, set->spot_min_grey, &gx, &gy))
        px += gw * (gx - c->x), py += gw * (gy - c->y);
    r->pupil_x = floorf(px) + 0.5f;
    r->pupil_y = floorf(py) + 0.5f;
}

static int track(fv_eye_tracker *t, const uint8_t *luma, int w, int h, ptrdiff_t stride, fv_eye_result *r,
                 int history)
{
    if (!t || !luma || !r || w < 8 || h < 8 || w > 8192 || h > 8192 || stride < w)
        return -1;
    memset(r, 0, sizeof *r);
    r->status = FV_EYE_LOST;
    fv_et_scratch s;
    if (scratch(t, w, h, &s))
        return -1;
    r->mode = fv_eye_resolve_mode(t->mode, w, h);
    const fv_eye_mode_settings *set = fv_eye_mode_get_settings(r->mode);

    const fv_et_candidate c = fv_et_search(&t->dsp, &t->p, luma, w, h, stride, &s, set);
    if (!c.ok)
        return 0;
    fv_et_pupil p;
    refine_pupil(t, set, luma, w, h, stride, &c, &s, &p);
    const int ng = fv_et_find_glints(&t->dsp, luma, w, h, stride, &p, t->p.max_glints, s.work, s.stack, s.gl);
    if (set->report_box_centre) {
        crop_centre(set, luma, w, h, stride, &c, r);
    } else if (p.fit) {
        r->pupil_x = (float)p.e.cx;
        r->pupil_y = (float)p.e.cy;
        r->ellipse_fit = 1;
    } else {
        r->pupil_x = p.x;
        r->pupil_y = p.y;
    }
    if (p.fit) {
        r->pupil_a_px = (float)p.e.a;
        r->pupil_b_px = (float)p.e.b;
        r->pupil_angle_rad = (float)p.e.angle;
    } else {
        r->pupil_a_px = r->pupil_b_px = p.r;
    }
    r->contrast = p.ring - p.inner;
    r->found = 1;
    r->status = FV_EYE_OK;

    r->n_glints = ng;
    memcpy(r->glints, s.gl, (size_t)r->n_glints * sizeof *s.gl);
    if (r->n_glints) {
        float gx = 0, gy = 0;
        for (int i = 0; i < r->n_glints; i++)
            gx += r->glints[i].x, gy += r->glints[i].y;
        r->has_pg = 1;
        r->pg_x = r->pupil_x - gx / r->n_glints;
        r->pg_y = r->pupil_y - gy / r->n_glints;
    }
    fv_et_judge(&t->ref, &p, history, set->lost_contrast, r);
    return 0;
}

int fv_track_frame(fv_eye_tracker *t, const uint8_t *luma, int w, int h, ptrdiff_t stride, fv_eye_result *r)
{
    return track(t, luma, w, h, stride, r, 1);
}

int fv_track_image(fv_eye_tracker *t, const uint8_t *luma, int w, int h, ptrdiff_t stride, fv_eye_result *r)
{
    return track(t, luma, w, h, stride, r, 0);
}
