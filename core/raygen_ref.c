/* fovea: the C reference of the ray-generation kernel (raygen_dsp.h) and the table's init. */
#include "raygen_dsp.h"

void fv_camera_rays_c(const fv_raygen_cam *c, const uint8_t *px, int x0, int y0, float *dx, float *dy, float *dz, int n)
{
    for (int i = 0; i < n; i++) {
        const int p = px[i];
        const float tx = c->tan_left + ((float)(x0 + (p & 15)) + c->ox) * c->px_tan;
        const float ty = c->tan_top - ((float)(y0 + (p >> 4)) + c->oy) * c->px_tan;
        dx[i] = tx * c->right[0] + ty * c->up[0] - c->back[0];
        dy[i] = tx * c->right[1] + ty * c->up[1] - c->back[1];
        dz[i] = tx * c->right[2] + ty * c->up[2] - c->back[2];
    }
}

void fv_raygen_dsp_init(fv_raygen_dsp *d, unsigned isa_mask)
{
    const unsigned isas = isa_mask & fv_cpu_isas();
    d->camera_rays = fv_camera_rays_c;
#if defined(__x86_64__)
    if (isas & FV_ISA_SSE41)
        fv_raygen_dsp_init_sse41(d);
    if (isas & FV_ISA_AVX2)
        fv_raygen_dsp_init_avx2(d);
#elif defined(__aarch64__)
    if (isas & FV_ISA_NEON)
        fv_raygen_dsp_init_neon(d);
#else
    (void)isas;
#endif
}
