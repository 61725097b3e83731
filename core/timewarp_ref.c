/* fovea: the timewarp kernel's C reference (contract: timewarp_dsp.h). */
#include "timewarp_dsp.h"

#include <string.h>

int fv_tw_row_c(uint8_t *restrict dst, int x0, int y, int n, const fv_tw_map *m, const fv_tw_src *s)
{
    const float py = (float)y + 0.5f;
    const float r[3] = {m->a0[0] + py * m->ay[0], m->a0[1] + py * m->ay[1], m->a0[2] + py * m->ay[2]};
    int holes = 0;
    for (int i = 0; i < n; i++) {
        const float px = (float)(x0 + i) + 0.5f;
        const float A[3] = {r[0] + px * m->ax[0], r[1] + px * m->ax[1], r[2] + px * m->ax[2]};
        holes += fv_tw_pixel(dst + 3 * i, m, s, A);
    }
    return holes;
}

void fv_tw_spans_c(uint8_t *restrict dst, const fv_tw_piece *pieces, int count)
{
    for (int i = 0; i < count; i++) {
        const fv_tw_piece *p = &pieces[i];
        uint8_t *o = dst + p->dst;
        for (int k = 0; k < p->n; k++)
            o[k] = fv_tw_span_px(p->s0[k], p->s0[k + 3], p->s1[k], p->s1[k + 3], p->fx, p->fy);
    }
}

void fv_tw_runs_c(uint8_t *restrict dst, fv_tw_run *runs, int count, const uint8_t *rgb, ptrdiff_t stride,
                  ptrdiff_t pf_end, int16_t *hbuf)
{
    (void)pf_end, (void)hbuf;
    for (int i = 0; i < count; i++) {
        runs[i].hoff = -1;
        int fx, fy;
        int64_t off;
        const uint8_t *s0 = fv_tw_run_piece(&runs[i], rgb, stride, &fx, &fy, &off), *s1 = fy ? s0 + stride : s0;
        uint8_t *o = dst + runs[i].dst;
        for (int k = 0; k < runs[i].n; k++)
            o[k] = fv_tw_span_px(s0[k], s0[k + 3], s1[k], s1[k + 3], fx, fy);
    }
}

void fv_tw_minmax_c(const uint16_t *p, ptrdiff_t stride, int w, int h, unsigned out[2])
{
    unsigned lo = 65535, hi = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const unsigned v = p[(ptrdiff_t)y * stride + x];
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
    out[0] = lo, out[1] = hi;
}

void fv_tw_stream_c(uint8_t *restrict dst, const uint8_t *restrict src, int n)
{
    if (n)
        memcpy(dst, src, (size_t)n);
}

void fv_timewarp_dsp_init(fv_timewarp_dsp *d, unsigned isa_mask)
{
    d->tw_row = fv_tw_row_c;
    d->tw_spans = fv_tw_spans_c;
    d->tw_runs = fv_tw_runs_c;
    d->tw_minmax = fv_tw_minmax_c;
    d->tw_stream = fv_tw_stream_c;
    const unsigned avail = isa_mask & fv_cpu_isas();
    (void)avail;
#if defined(__x86_64__)
    if (avail & FV_ISA_SSE41)
        fv_timewarp_dsp_init_sse41(d);
    if (avail & FV_ISA_AVX2)
        fv_timewarp_dsp_init_avx2(d);
#elif defined(__aarch64__)
    if (avail & FV_ISA_NEON)
        fv_timewarp_dsp_init_neon(d);
#endif
}
