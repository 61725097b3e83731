#include "raycast.h"

#include <math.h>

const float fv_background_rgb[3] = {0.02f, 0.025f, 0.035f};

/* Pixels of a tile in 4x2 blocks, so a full packet of 8 is a compact 4x2 footprint and a
 * sparse tile's packets still gather nearby pixels (coherent rays). */
static const unsigned char *tile_order(void)
{
    static const unsigned char order[FV_TILE * FV_TILE][2] = {
#define B(bx, by) {bx*4+0,by*2+0},{bx*4+1,by*2+0},{bx*4+2,by*2+0},{bx*4+3,by*2+0}, \
                  {bx*4+0,by*2+1},{bx*4+1,by*2+1},{bx*4+2,by*2+1},{bx*4+3,by*2+1}
#define R(by) B(0,by),B(1,by),B(2,by),B(3,by)
        R(0), R(1), R(2), R(3), R(4), R(5), R(6), R(7)
#undef R
#undef B
    };
    return &order[0][0];
}

long fv_raycast_tile(const fv_scene *scene, const fv_camera *cam, const fv_pyr_level *l0, int x0, int y0, int tw, int th,
                     const uint32_t rows[FV_TILE])
{
    const unsigned char *order = tile_order();
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    ictx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    struct RTCRayHit8 rh;
    int valid[8];
    int px[8], py[8];
    long rays = 0;
    int k = 0;
    for (int i = 0; i <= FV_TILE * FV_TILE; i++) {
        if (i < FV_TILE * FV_TILE) {
            int lx = order[2 * i], ly = order[2 * i + 1];
            if (lx >= tw || ly >= th || !((rows[ly] >> lx) & 1u))
                continue;
            px[k] = x0 + lx;
            py[k] = y0 + ly;
            float d[3];
            fv_camera_ray(cam, (float)px[k] + 0.5f, (float)py[k] + 0.5f, d);
            fv_ray8_set(&rh, k, cam->eye_pos, d);
            valid[k] = -1;
            if (++k < 8)
                continue;
        }
        if (k == 0)
            break;
        for (int q = k; q < 8; q++)
            valid[q] = 0;
        rtcIntersect8(valid, fv_scene_rtc(scene), &ictx, &rh);
        for (int q = 0; q < k; q++) {
            float *dst = l0->rgbd + 4 * (py[q] * l0->stride + px[q]);
            if (rh.hit.geomID[q] == RTC_INVALID_GEOMETRY_ID) {
                dst[0] = fv_background_rgb[0];
                dst[1] = fv_background_rgb[1];
                dst[2] = fv_background_rgb[2];
                dst[3] = FV_DEPTH_MISS_M;
            } else {
                float org[3] = {rh.ray.org_x[q], rh.ray.org_y[q], rh.ray.org_z[q]};
                float dir[3] = {rh.ray.dir_x[q], rh.ray.dir_y[q], rh.ray.dir_z[q]};
                float len = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
                float t = rh.ray.tfar[q];
                fv_scene_shade(scene, rh.hit.geomID[q], rh.hit.primID[q], rh.hit.u[q], rh.hit.v[q], org, dir, t,
                               cam->px_tan / len, cam->eye_pos, dst);
                dst[3] = t < FV_DEPTH_MISS_M ? t : FV_DEPTH_MISS_M; /* t is the view depth: dir.z_eye = -1 */
            }
            l0->wgt[py[q] * l0->stride + px[q]] = 1.0f;
        }
        rays += k;
        k = 0;
    }
    return rays;
}
