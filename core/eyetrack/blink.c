/* Confidence, loss and blinks. fv_track_frame keeps a running reference of the pupil's darkness,
 * contrast and radius; a frame whose blob is much less dark, has much less contrast, is much
 * smaller or is a sliver is a blink (lashes, the lid crease), not the pupil. */
#include "base/util.h"
#include "eyetrack/track_impl.h"

void fv_et_judge(fv_et_history *ref, const fv_et_pupil *p, int history, float lost_contrast, fv_eye_result *r)
{
    /* confidence: contrast (grey levels) and how much of the outline the fit explains */
    const float cc = fv_clampf((r->contrast - 4.0f) / 24.0f, 0.0f, 1.0f);
    const float fit = p->fit ? fv_clampf(p->inliers / 0.6f, 0.0f, 1.0f) : 0.5f;
    r->confidence = cc * (0.4f + 0.6f * fit);

    if (r->contrast < lost_contrast) {
        r->status = FV_EYE_LOST;
        r->found = 0;
    }
    if (history && r->status == FV_EYE_OK) {
        /* a blink: what is found is not the pupil the tracker has been seeing: much less dark
         * (lashes, lid crease), much less contrast, much smaller, or a sliver */
        const float flat = p->fit ? (float)(p->e.b / p->e.a) : 1.0f;
        const float span = ref->ring - ref->inner;
        if (ref->n >= 3 && (p->inner > ref->inner + 0.4f * span || r->contrast < 0.45f * ref->contrast ||
                            p->r < 0.45f * ref->radius || flat < 0.3f)) {
            r->status = FV_EYE_BLINK; /* what was found is not a pupil: no position */
            r->found = 0;
            r->has_pg = 0;
            r->confidence *= 0.25f;
        } else {
            const float a = ref->n < 10 ? 1.0f / (ref->n + 1) : 0.1f;
            ref->contrast += a * (r->contrast - ref->contrast);
            ref->radius += a * (p->r - ref->radius);
            ref->inner += a * (p->inner - ref->inner);
            ref->ring += a * (p->ring - ref->ring);
            ref->n++;
        }
    } else if (history && r->status == FV_EYE_LOST && ref->n >= 3) {
        r->status = FV_EYE_BLINK;
    }
}
