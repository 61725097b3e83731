/* fovea: small integer and float helpers shared by every room (one copy, not one per file).
 * The clamps keep a NaN input as NaN (v < lo and v > hi are both false). */
#ifndef FOVEA_BASE_UTIL_H
#define FOVEA_BASE_UTIL_H

#include <stdint.h>

static inline int fv_mini(int a, int b) { return a < b ? a : b; }
static inline int fv_maxi(int a, int b) { return a > b ? a : b; }
static inline int fv_clampi(int v, int lo, int hi) { return v < lo ? lo : v > hi ? hi : v; }
static inline float fv_minf(float a, float b) { return a < b ? a : b; }
static inline float fv_maxf(float a, float b) { return a > b ? a : b; }
static inline float fv_clampf(float v, float lo, float hi) { return v < lo ? lo : v > hi ? hi : v; }
static inline int fv_div_ceil(int a, int b) { return (a + b - 1) / b; }
/* lowbias32 (C. Wellons): a cheap full-avalanche 32-bit integer mix, for per-pixel hashes */
static inline uint32_t fv_hash32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

#endif
