/* fovea HIL: the known image the KMS check flips to and the host compares the QEMU screendump
 * against (tests/hil/guest.c draws it in the guest and checks the PPM on the host). */
#ifndef FOVEA_HIL_PATTERN_H
#define FOVEA_HIL_PATTERN_H

#include <stdint.h>

/* 0x00RRGGBB at pixel (x, y) of a w x h image: horizontal and vertical ramps, a checkerboard in
 * blue and a one-pixel frame, so a shifted, scaled, cropped or channel-swapped readback fails. */
static inline uint32_t fv_hil_pattern(int x, int y, int w, int h)
{
    if (x == 0 || y == 0 || x == w - 1 || y == h - 1)
        return 0xffffffu;
    uint32_t r = (uint32_t)(x * 255 / (w - 1));
    uint32_t g = (uint32_t)(y * 255 / (h - 1));
    uint32_t b = (((x >> 5) ^ (y >> 5)) & 1) ? 0xe0u : 0x20u;
    return r << 16 | g << 8 | b;
}

/* The image shown before the flip (the flip must replace it). */
static inline uint32_t fv_hil_pattern_before(int x, int y)
{
    return ((x ^ y) & 8) ? 0x402000u : 0x004020u;
}

#endif
