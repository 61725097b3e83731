/* fovea: the vectorised blends' driver (core/reproject_dsp.h's taa_blend), shared by the ISA files
 * that define TAA_OWN_BLEND. Included once per ISA file after it defines:
 *   TAA_FN(name)       its function names
 *   TAA_GROUP_LANES    samples a group (8 for AVX2, 4 for SSE4.1 and NEON)
 *   TAA_GROUP_DIST     groups between a group's projection and its taps (its history in flight)
 *   TAA_GROUP_RING     a power of two > TAA_GROUP_DIST
 *   taa_group          a projected group waiting for its taps
 *   group_project(f, t, rgbd, off, xs, ys, n, keep_sample, &fdx, &fdy, &fn, taa_group *g)
 *                      projects n <= TAA_GROUP_LANES listed samples, adds their flow, prefetches
 *                      their history; 0 when none needs taps
 *   group_taps(f, t, rgbd, const taa_group *g)  the group's taps and blends
 * and optionally
 *   TAA_LIST_ROW(wgt_row, ro, x0, y, w, rgbd_row, off, xs, ys, n)
 *                      lists the row's samples (weight 1) into off / xs / ys from n on, in pixel
 *                      order, returns the new n; may write up to 7 entries past it (the arrays
 *                      have room); without it, a tzcnt loop over sample_mask's bits
 * Blends change only their own samples' colours, which no projection reads: the result does not
 * depend on the distance. */
#define TAA_CHUNK_ROWS 16 /* rows listed before their groups run (64 x 16 samples at most) */

static void TAA_FN(taa_blend)(const struct fv_taa_frame *f, const struct fv_taa_tile *t, float *rgbd_blk,
                              const float *wgt_blk, ptrdiff_t stride, int x0, int y0, int w, int h,
                              struct fv_taa_flow *flow)
{
    float fdx = flow->dx, fdy = flow->dy, fn = flow->n;
    const int keep_sample = t->alpha >= 1.0f;
    /* The samples of up to 16 rows are listed first and grouped afterwards: the groups' vector
     * loads of the lists would otherwise wait on the just-made 4-byte stores (store forwarding
     * fails; perf showed 7 % of the AVX2 blend on one such load). */
    int32_t off[64 * TAA_CHUNK_ROWS + 8], xs[64 * TAA_CHUNK_ROWS + 8], ys[64 * TAA_CHUNK_ROWS + 8];
    taa_group ring[TAA_GROUP_RING];
    unsigned head = 0, tail = 0;
    for (int r0 = 0; r0 < h; r0 += TAA_CHUNK_ROWS) {
        int n = 0;
        for (int r = r0; r < h && r < r0 + TAA_CHUNK_ROWS; r++) {
            const int32_t ro = (int32_t)(r * stride), y = y0 + r;
#ifdef TAA_LIST_ROW /* the ISA's listing: the same entries (it may write up to 7 past them) */
            n = TAA_LIST_ROW(wgt_blk + r * stride, ro, x0, y, w, rgbd_blk + 4 * (ptrdiff_t)ro, off, xs, ys, n);
            continue;
#endif
            uint64_t m = sample_mask(wgt_blk + r * stride, w);
            while (m) {
                const int i = __builtin_ctzll(m);
                m &= m - 1;
                off[n] = ro + i;
                xs[n] = x0 + i;
                ys[n] = y;
                n++;
                __builtin_prefetch(rgbd_blk + 4 * (ptrdiff_t)(ro + i)); /* the sample: hot after shading, cold in checkasm --bench */
            }
        }
        const int last = n & ~(TAA_GROUP_LANES - 1);
        for (int k = n; k < ((n + TAA_GROUP_LANES - 1) & ~(TAA_GROUP_LANES - 1)); k++)
            off[k] = off[last], xs[k] = xs[last], ys[k] = ys[last]; /* idle lanes repeat the group's first sample */
        for (int k = 0; k < n; k += TAA_GROUP_LANES) {
            const int nk = n - k < TAA_GROUP_LANES ? n - k : TAA_GROUP_LANES;
            if (group_project(f, t, rgbd_blk, off + k, xs + k, ys + k, nk, keep_sample, &fdx, &fdy, &fn,
                              &ring[head % TAA_GROUP_RING]))
                head++;
            if (head - tail > TAA_GROUP_DIST)
                group_taps(f, t, rgbd_blk, &ring[tail++ % TAA_GROUP_RING]);
        }
    }
    while (tail != head)
        group_taps(f, t, rgbd_blk, &ring[tail++ % TAA_GROUP_RING]);
    flow->dx = fdx;
    flow->dy = fdy;
    flow->n = fn;
}
