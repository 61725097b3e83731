/* fovea: the timewarp kernel (one table per module; core/cpu.h has the pattern). C reference:
 * core/timewarp_ref.c; the per-pixel steps are the inline helpers below, which the ISA versions
 * also use for their row tails.
 *
 * tw_row: a backward warp of one display row. For display pixel centre (px, py) =
 *   (x0 + i + 0.5, y + 0.5), i in [0, n):
 *     A = r + px * ax with r = a0 + py * ay (per component, multiply then add, no FMA)
 *   A is the source camera's (U, V, Z) per metre of display depth along the pixel's ray, t its
 *   offset: a point at display depth z_d is at source (U, V, Z) = z_d A + t, source pixel
 *   (U / Z, V / Z) (fv_tw_proj with w = 1 / z_d). w = 0 (infinity) is the rotation homography.
 *   The display depth is found by a fixed-point iteration on the source's depth: w1 = the
 *   inverse depth fetched (nearest pixel) at q(0), w2 at q(w1), w3 at q(w2), each converted from
 *   the source's depth to the display's (fv_tw_fetch_w). Converged (|w3 - w2| <= tol max(w2, w3))
 *   the colour comes from q(w2); otherwise the pixel is a disocclusion (it sees what the source
 *   did not) and is filled from whichever of q(w1), q(w2) shows the farther surface (the
 *   background beside the hole, not the foreground that hid it). Colour: bilinear tap of the
 *   source's 8-bit RGB with 7-bit weights, integer arithmetic (fv_tw_pixel has the formula).
 *   Coordinates outside the source clamp to its edge. Returns the number of disoccluded pixels.
 *   Reads: src->rgb up to 16 bytes past a pixel (the plane must be readable 16 bytes past its
 *   last pixel, FV_TW_RGB_PAD), src->invd up to 15 elements past one (readable 32 bytes past its
 *   last element, FV_TW_INVD_PAD); h * stride must stay below 2^31 (bytes for rgb, elements for
 *   invd).
 *   Every ISA version gives the reference's bytes and count (the float steps are the same IEEE
 *   operations in the same order, true division, no FMA; the colour is integer).
 *
 * tw_spans: the block warp's resample (core/timewarp.c), the pieces of one display row: for each
 *   piece p of pieces[0, count), p->n bytes of packed RGB at one bilinear phase, fx, fy in
 *   [0, 63] (6-bit weights), from rows s0 = p->s0 and s1 = p->s1 into dst + p->dst. For k in [0, n):
 *     h0 = s0[k] (64 - fx) + s0[k + 3] fx, h1 likewise from s1 (s1 is the source row below s0),
 *     v = h0 + ((h1 - h0) fy 512 + 16384) >> 15   (arithmetic shift),
 *     dst[k] = (v 512 + 16384) >> 15 = (v + 32) >> 6.
 *   That is the exact bilinear value at the phase, rounded, within 1 level (pmulhrsw /
 *   vqrdmulh steps). Reads s0[0, n + 3), s1[0, n + 3), nothing more. Every ISA version gives the
 *   reference's bytes.
 *
 * tw_runs: the block warp's inner translated blocks on one display row (the "runners" of
 *   core/timewarp.c): for each run r of runs[0, count), in order, its piece for this row from
 *   its fixed-point translation (fv_tw_run_piece: phases fx, fy and source rows s0, s1 into
 *   rgb, a plane of rows of stride bytes), resampled exactly as tw_spans resamples that piece into
 *   dst + r->dst (r->n bytes), then r stepped to the next row (fv_tw_run_piece does). The same
 *   reads as tw_spans' pieces. Hints that change no byte: the source 3 rows below a piece's is prefetched where that
 *   row lies above pf_end (a byte offset into rgb: the plane's end), and the ISA versions keep a
 *   piece's horizontal pass of its lower row (s1 at fx) in hbuf + 2 r->dst (bytes; scratch of
 *   2 r->n bytes a run, the runs' ranges apart, 32-byte aligned where r->dst is 16-byte
 *   aligned) with its key in r->hoff, r->hfx, so the next row, which mostly reads that row as
 *   its upper one at the same phase, reuses it (half the multiplies). r->hoff = -1 (a run set
 *   up, or after the C reference, which keeps nothing): nothing kept. Every ISA version gives
 *   the reference's bytes and steps the runs as it does.
 *
 * tw_stream: copies n bytes from src (a row just composed in cache) to dst (the display image),
 *   exact; the x86 versions store around the cache (non-temporal stores): the display image is
 *   not read back by this thread, and a store that misses the cache would otherwise read the
 *   line first (a third of the warp's memory traffic). n = 0 (dst, src unused): the fence after
 *   a frame's rows (x86 sfence), so other threads see the stores.
 *
 * tw_minmax: the least and greatest element of a w x h rectangle of 16-bit values (rows of
 *   stride elements), w, h >= 1, into out[0], out[1]. Reads the rectangle only. Exact. */
#ifndef FOVEA_TIMEWARP_DSP_H
#define FOVEA_TIMEWARP_DSP_H

#include <stddef.h>
#include <stdint.h>

#include "cpu.h"

#define FV_TW_ZMIN 1e-6f          /* a source Z below this (behind the eye) is clamped to it */
#define FV_TW_DEN_MIN 0.0625f     /* floor of 1 - t_z w_s in the depth conversion */
#define FV_TW_INVD_PER_M 4096.0f  /* units of the 16-bit inverse depth per 1/m (16 / m max: 6.25 cm) */

typedef struct fv_tw_map {
    float a0[3], ax[3], ay[3]; /* A(px, py) = a0 + px ax + py ay */
    float t[3];                /* source (U, V, Z) = z_d A + t */
    float tol;                 /* disocclusion: relative inverse-depth mismatch (0.05) */
    float w_scale;             /* 1/m per unit of the source's inverse depth (1 / FV_TW_INVD_PER_M) */
    /* Both cameras' lens (fv_tw_map_set_lens; NULL = none): the rows above then map pinhole
     * coordinates (core/lens.h). The kernels never read it: the warp hands them the lens folded
     * into the rows of each FV_TW_LENS_CELL square (core/timewarp.h). */
    const struct fv_lens_map *lens;
} fv_tw_map;

typedef struct fv_tw_src {
    const uint8_t *rgb;    /* packed 8-bit RGB */
    ptrdiff_t rgb_stride;  /* bytes */
    const uint16_t *invd;  /* inverse view depth, FV_TW_INVD_PER_M units per 1/m */
    ptrdiff_t invd_stride; /* elements */
    int w, h;
} fv_tw_src;

typedef int (*fv_tw_row_fn)(uint8_t *restrict dst, int x0, int y, int n, const fv_tw_map *m, const fv_tw_src *s);

typedef struct fv_tw_piece {
    const uint8_t *s0, *s1; /* source bytes of the first display byte's top and bottom taps */
    int dst, n;             /* display bytes [dst, dst + n) of the row */
    int fx, fy;             /* 0..63 */
} fv_tw_piece;
typedef void (*fv_tw_spans_fn)(uint8_t *restrict dst, const fv_tw_piece *pieces, int count);
/* a translated block's rows: the translation of the next row to warp in 1/2^22 px, offset by
 * FV_TW_RUN_BIAS px and with the rounding to 1/64 px added (fv_tw_run_piece), its step a row,
 * and the source byte offset of the block's first column on that row at translation zero less
 * the bias's (FV_TW_RUN_BIAS (stride + 3)): the offset stays an integer, never a pointer out of
 * the plane */
#define FV_TW_RUN_BIAS ((int64_t)1 << 30)
typedef struct fv_tw_run {
    int64_t qu, qv, dqu, dqv;
    int64_t off;
    int64_t hoff; /* the horizontal pass kept (tw_runs): its source row's offset (as off), -1 none */
    int hfx;      /* and its phase */
    int dst, n;   /* display bytes [dst, dst + n) of the row */
} fv_tw_run;
typedef void (*fv_tw_runs_fn)(uint8_t *restrict dst, fv_tw_run *runs, int count, const uint8_t *rgb, ptrdiff_t stride,
                              ptrdiff_t pf_end, int16_t *hbuf);
typedef void (*fv_tw_minmax_fn)(const uint16_t *p, ptrdiff_t stride, int w, int h, unsigned out[2]);
typedef void (*fv_tw_stream_fn)(uint8_t *restrict dst, const uint8_t *restrict src, int n);

typedef struct fv_timewarp_dsp {
    fv_tw_row_fn tw_row;
    fv_tw_spans_fn tw_spans;
    fv_tw_runs_fn tw_runs;
    fv_tw_minmax_fn tw_minmax;
    fv_tw_stream_fn tw_stream;
} fv_timewarp_dsp;

void fv_timewarp_dsp_init(fv_timewarp_dsp *d, unsigned isa_mask);

/* ---- internal: reference, shared per-pixel steps and per-ISA fillers ---- */
int fv_tw_row_c(uint8_t *restrict dst, int x0, int y, int n, const fv_tw_map *m, const fv_tw_src *s);
void fv_tw_spans_c(uint8_t *restrict dst, const fv_tw_piece *pieces, int count);
void fv_tw_runs_c(uint8_t *restrict dst, fv_tw_run *runs, int count, const uint8_t *rgb, ptrdiff_t stride,
                  ptrdiff_t pf_end, int16_t *hbuf);
void fv_tw_minmax_c(const uint16_t *p, ptrdiff_t stride, int w, int h, unsigned out[2]);
void fv_tw_stream_c(uint8_t *restrict dst, const uint8_t *restrict src, int n);

/* tw_spans' step for one byte (the ISA versions' tails) */
static inline uint8_t fv_tw_span_px(int a, int b, int c, int d, int fx, int fy)
{
    const int h0 = a * (64 - fx) + b * fx, h1 = c * (64 - fx) + d * fx; /* a, c at x; b, d at x + 3 bytes */
    const int p = (h1 - h0) * (fy << 9) + 16384; /* |p| < 2^30 */
    const int v = h0 + (p >= 0 ? p >> 15 : -((-p + 32767) >> 15)); /* floor, as psraw */
    return (uint8_t)((v * 512 + 16384) >> 15);
}

/* tw_runs' step: run r's piece on this row (source rows s0, s1 = s0 + stride or, when fy = 0,
 * s0 again; phases fx, fy; its source offset in *off for the prefetch), then r on the next row.
 * u = qu >> 16 is the translation in 1/64 px plus 64 FV_TW_RUN_BIAS (qu biased so it stays
 * positive: right shifts of negatives are the compiler's choice in C) */
static inline const uint8_t *fv_tw_run_piece(fv_tw_run *r, const uint8_t *rgb, ptrdiff_t stride, int *fx, int *fy,
                                             int64_t *off)
{
    const int64_t u = r->qu >> 16, v = r->qv >> 16;
    r->qu += r->dqu, r->qv += r->dqv;
    *fx = (int)(u & 63), *fy = (int)(v & 63);
    *off = r->off + (v >> 6) * (int64_t)stride + 3 * (u >> 6);
    r->off += stride;
    return rgb + *off;
}

static inline float fv_tw_clampf(float v, float hi)
{
    v = v > 0.0f ? v : 0.0f; /* NaN -> 0 */
    return v < hi ? v : hi;
}
static inline void fv_tw_proj(const float A[3], const float t[3], float w, float *u, float *v)
{
    float nz = A[2] + t[2] * w;
    nz = nz > FV_TW_ZMIN ? nz : FV_TW_ZMIN;
    const float inv = 1.0f / nz;
    *u = (A[0] + t[0] * w) * inv;
    *v = (A[1] + t[1] * w) * inv;
}
/* the display inverse depth of the surface the source shows at the nearest pixel to (u, v):
 * source depth z_s = z_d A_z + t_z, so w_d = A_z w_s / (1 - t_z w_s) */
static inline float fv_tw_fetch_w(const fv_tw_map *m, const fv_tw_src *s, float az, float u, float v)
{
    const int ix = (int)fv_tw_clampf(u, (float)(s->w - 1)), iy = (int)fv_tw_clampf(v, (float)(s->h - 1));
    const float ws = (float)s->invd[(ptrdiff_t)iy * s->invd_stride + ix] * m->w_scale;
    float den = 1.0f - m->t[2] * ws;
    den = den > FV_TW_DEN_MIN ? den : FV_TW_DEN_MIN;
    return (az * ws) / den;
}
/* the bilinear tap at source pixel coordinates (u, v) */
static inline void fv_tw_tap(uint8_t *dst, const fv_tw_src *s, float u, float v)
{
    const float bu = fv_tw_clampf(u - 0.5f, (float)(s->w - 1)), bv = fv_tw_clampf(v - 0.5f, (float)(s->h - 1));
    const int x0 = (int)bu, y0 = (int)bv;
    const int fx = (int)((bu - (float)x0) * 128.0f), fy = (int)((bv - (float)y0) * 128.0f); /* 0..127 */
    const int x1 = x0 + (x0 < s->w - 1), y1 = y0 + (y0 < s->h - 1);
    const uint8_t *r0 = s->rgb + (ptrdiff_t)y0 * s->rgb_stride, *r1 = s->rgb + (ptrdiff_t)y1 * s->rgb_stride;
    for (int c = 0; c < 3; c++) {
        const int c00 = r0[3 * x0 + c], c10 = r0[3 * x1 + c], c01 = r1[3 * x0 + c], c11 = r1[3 * x1 + c];
        const int top = (c00 << 7) + (c10 - c00) * fx, bot = (c01 << 7) + (c11 - c01) * fx;
        dst[c] = (uint8_t)(((top << 7) + (bot - top) * fy + 8192) >> 14);
    }
}
/* one display pixel with A computed; 1 when disoccluded */
static inline int fv_tw_pixel(uint8_t *dst, const fv_tw_map *m, const fv_tw_src *s, const float A[3])
{
    float u0, v0, u1, v1, u2, v2;
    fv_tw_proj(A, m->t, 0.0f, &u0, &v0);
    const float w1 = fv_tw_fetch_w(m, s, A[2], u0, v0);
    fv_tw_proj(A, m->t, w1, &u1, &v1);
    const float w2 = fv_tw_fetch_w(m, s, A[2], u1, v1);
    fv_tw_proj(A, m->t, w2, &u2, &v2);
    const float w3 = fv_tw_fetch_w(m, s, A[2], u2, v2);
    const float d = w3 > w2 ? w3 - w2 : w2 - w3, mx = w3 > w2 ? w3 : w2;
    const int disocc = d > m->tol * mx;
    const int first = disocc && w2 < w3; /* q(w1) showed the farther surface (w2) */
    fv_tw_tap(dst, s, first ? u1 : u2, first ? v1 : v2);
    return disocc;
}

#if defined(__x86_64__)
void fv_timewarp_dsp_init_sse41(fv_timewarp_dsp *d);
void fv_timewarp_dsp_init_avx2(fv_timewarp_dsp *d);
#elif defined(__aarch64__)
void fv_timewarp_dsp_init_neon(fv_timewarp_dsp *d);
#endif

#endif
