/* fovea: the ray-generation kernel for x86 (raygen_dsp.h): core/x86/raygen_sse41.c and
 * raygen_avx2.c each include this once after defining FV_X86_W (4 or 8 lanes) and
 * FV_X86_FN(name). The reference's operations in its order (no FMA): exact. */
#if !defined(FV_X86_W) || !defined(FV_X86_FN)
#error "define FV_X86_W and FV_X86_FN before including x86/raygen_tmpl.h"
#endif

#include <immintrin.h>
#include <string.h>

#include "raygen_dsp.h"

#if FV_X86_W == 8
typedef __m256 V;
typedef __m256i VI;
static inline VI load_px(const uint8_t *p)
{
    int64_t b;
    memcpy(&b, p, 8);
    return _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(b));
}
#define VS _mm256_set1_ps
#define VADD _mm256_add_ps
#define VSUB _mm256_sub_ps
#define VMUL _mm256_mul_ps
#define VST _mm256_storeu_ps
#define VCVT _mm256_cvtepi32_ps
#define IAND(a, m) _mm256_and_si256(a, _mm256_set1_epi32(m))
#define ISHR(a, s) _mm256_srli_epi32(a, s)
#define IADD(a, b) _mm256_add_epi32(a, _mm256_set1_epi32(b))
#else
typedef __m128 V;
typedef __m128i VI;
static inline VI load_px(const uint8_t *p)
{
    int32_t b;
    memcpy(&b, p, 4);
    return _mm_cvtepu8_epi32(_mm_cvtsi32_si128(b));
}
#define VS _mm_set1_ps
#define VADD _mm_add_ps
#define VSUB _mm_sub_ps
#define VMUL _mm_mul_ps
#define VST _mm_storeu_ps
#define VCVT _mm_cvtepi32_ps
#define IAND(a, m) _mm_and_si128(a, _mm_set1_epi32(m))
#define ISHR(a, s) _mm_srli_epi32(a, s)
#define IADD(a, b) _mm_add_epi32(a, _mm_set1_epi32(b))
#endif

static void FV_X86_FN(camera_rays)(const fv_raygen_cam *c, const uint8_t *px, int x0, int y0, float *dx, float *dy,
                                   float *dz, int n)
{
    for (int i = 0; i < n; i += FV_X86_W) {
        const VI p = load_px(px + i);
        const V fx = VCVT(IADD(IAND(p, 15), x0)), fy = VCVT(IADD(ISHR(p, 4), y0));
        const V tx = VADD(VS(c->tan_left), VMUL(VADD(fx, VS(c->ox)), VS(c->px_tan)));
        const V ty = VSUB(VS(c->tan_top), VMUL(VADD(fy, VS(c->oy)), VS(c->px_tan)));
        float *d[3] = {dx, dy, dz};
        for (int k = 0; k < 3; k++)
            VST(d[k] + i, VSUB(VADD(VMUL(tx, VS(c->right[k])), VMUL(ty, VS(c->up[k]))), VS(c->back[k])));
    }
}
