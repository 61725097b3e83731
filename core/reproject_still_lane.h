/* fovea: one lane of the still head's level-0 blend (taa_still in reproject_dsp.h): the C
 * reference's loop body and every ISA version's tail, so the bits agree by construction. */
#ifndef FOVEA_REPROJECT_STILL_LANE_H
#define FOVEA_REPROJECT_STILL_LANE_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

static inline void taa_still_lane(float *s, const float *h, ptrdiff_t plane, int k, float widen, float alpha,
                                  float inv_depth_tol, uint8_t *wide)
{
    const float d = s[3 * plane + k], rz = 1.0f / d, fp = (d * rz) * widen;
    wide[k] = fp >= 2.0f;
    if (fp >= 2.0f)
        return; /* the footprint reads coarser levels: the caller's taps */
    float a = 1.0f - fabsf(h[3 * plane + k] - d) * (rz * inv_depth_tol);
    a = a > 0.0f ? a : 0.0f;
    const float w = h[4 * plane + k] * a;
    if (!(w > 0.0f))
        return; /* no valid history: the sample stands alone */
    const float a1 = 1.0f - w, al = a1 > alpha ? a1 : alpha;
    for (int c = 0; c < 3; c++) {
        const float hc = (0.0f + w * h[c * plane + k]) / w;
        s[c * plane + k] = hc + al * (s[c * plane + k] - hc);
    }
}

#endif
