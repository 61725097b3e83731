/* Writes a sampling pattern to PNG (white: the pixel is cast; grey: cast in another phase of the
 * rotation; black: never), with the gaze marked, to look at what a sampler does.
 *   sampling_png --sampling weier|liu --out FILE.png [--size WxH] [--fov DEG] [--gaze X,Y]
 *                [--phase K] [--union on|off] [--crop X0,Y0,CW,CH] [--zoom Z]
 * X, Y: normalised gaze (default 0.5,0.5); --union shows every phase of the rotation in grey;
 * --crop writes only that pixel rectangle, each pixel as a ZxZ block (--zoom, default 1). */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera.h"
#include "cli.h"
#include "output.h"
#include "sampling.h"

int main(int argc, char **argv)
{
    const char *prog = "sampling_png", *out = NULL;
    int w = 1280, h = 1440, kind = FV_SAMPLER_WEIER, phase = 0, uni = 0, zoom = 1;
    int crop[4] = {0, 0, 0, 0};
    float fov = 100.0f, gx = 0.5f, gy = 0.5f;
    static const struct option lo[] = {{"sampling", required_argument, 0, 's'}, {"out", required_argument, 0, 'o'},
                                       {"size", required_argument, 0, 'z'},     {"fov", required_argument, 0, 'f'},
                                       {"gaze", required_argument, 0, 'g'},     {"phase", required_argument, 0, 'p'},
                                       {"union", required_argument, 0, 'u'},    {"help", no_argument, 0, 'h'},
                                       {"crop", required_argument, 0, 'c'},     {"zoom", required_argument, 0, 'Z'},
                                       {0, 0, 0, 0}};
    int o;
    while ((o = getopt_long(argc, argv, "", lo, NULL)) != -1) {
        switch (o) {
        case 's':
            if (fv_sampler_kind_parse(optarg, &kind))
                fv_usage_error(prog, "--sampling: '%s' is not one of weier, liu", optarg);
            break;
        case 'o': out = optarg; break;
        case 'z': fv_arg_size(prog, "--size", optarg, &w, &h); break;
        case 'f': fov = fv_arg_float(prog, "--fov", optarg, 10.0f, 160.0f); break;
        case 'g':
            if (sscanf(optarg, "%f,%f", &gx, &gy) != 2 || !(gx >= 0.0f && gx <= 1.0f && gy >= 0.0f && gy <= 1.0f))
                fv_usage_error(prog, "--gaze: '%s' is not X,Y in [0,1]", optarg);
            break;
        case 'p': phase = (int)fv_arg_long(prog, "--phase", optarg, 0, 1000); break;
        case 'u': uni = fv_arg_onoff(prog, "--union", optarg); break;
        case 'c':
            if (sscanf(optarg, "%d,%d,%d,%d", &crop[0], &crop[1], &crop[2], &crop[3]) != 4 || crop[0] < 0 ||
                crop[1] < 0 || crop[2] < 1 || crop[3] < 1)
                fv_usage_error(prog, "--crop: '%s' is not X0,Y0,W,H", optarg);
            break;
        case 'Z': zoom = (int)fv_arg_long(prog, "--zoom", optarg, 1, 16); break;
        case 'h':
            printf("usage: %s --sampling weier|liu --out FILE.png [--size WxH] [--fov DEG] [--gaze X,Y] [--phase K]"
                   " [--union on|off]\n",
                   prog);
            return FV_EXIT_OK;
        default: fv_bad_option(prog, argv);
        }
    }
    if (!out)
        fv_usage_error(prog, "--out FILE.png is required (see --help)");
    fv_camera_desc d;
    fv_camera_desc_default(&d);
    d.width = w;
    d.height = h;
    d.fov_y_deg = fov;
    fv_camera cam;
    const fv_pose pose = {{0, 0, 0}, {0, 0, 0, 1}};
    fv_sampling_params p;
    fv_sampling_params_default(&p);
    p.kind = kind;
    p.rotate = 1;
    fv_sampler s;
    if (fv_camera_setup(&cam, &d, &pose) || fv_sampler_init(&s, w, h, cam.focal_px, &p))
        fv_fail(prog, FV_EXIT_FAIL, "cannot set up a %dx%d sampler", w, h);
    uint8_t *rgb = calloc((size_t)w * h, 3);
    if (!rgb)
        fv_fail(prog, FV_EXIT_FAIL, "out of memory");
    const int px = (int)floorf(gx * (float)w), py = (int)floorf(gy * (float)h);
    long n = 0;
    for (int k = uni ? 0 : phase; k < (uni ? s.phases : phase + 1); k++)
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x += 64) {
                const int m = w - x < 64 ? w - x : 64;
                const uint64_t b = fv_sampler_row(&s, x, y, m, px, py, k);
                for (int i = 0; i < m; i++)
                    if ((b >> i) & 1) {
                        uint8_t *q = rgb + 3 * ((size_t)y * w + x + i);
                        const uint8_t v = k == phase ? 255 : 96;
                        if (q[0] < v)
                            q[0] = q[1] = q[2] = v;
                        n += k == phase;
                    }
            }
    for (int t = -6; t <= 6; t++) /* red cross at the gaze */
        for (int c = 0; c < 2; c++) {
            const int x = px + (c ? t : 0), y = py + (c ? 0 : t);
            if (x >= 0 && y >= 0 && x < w && y < h) {
                uint8_t *q = rgb + 3 * ((size_t)y * w + x);
                q[0] = 255;
                q[1] = q[2] = 0;
            }
        }
    if (!crop[2]) {
        crop[2] = w;
        crop[3] = h;
    }
    if (crop[0] + crop[2] > w || crop[1] + crop[3] > h)
        fv_usage_error(prog, "--crop: the rectangle leaves the %dx%d image", w, h);
    const int ow = crop[2] * zoom, oh = crop[3] * zoom;
    uint8_t *img = malloc((size_t)ow * oh * 3);
    if (!img)
        fv_fail(prog, FV_EXIT_FAIL, "out of memory");
    for (int y = 0; y < oh; y++)
        for (int x = 0; x < ow; x++)
            memcpy(img + 3 * ((size_t)y * ow + x), rgb + 3 * ((size_t)(crop[1] + y / zoom) * w + crop[0] + x / zoom), 3);
    char err[256];
    if (fv_write_png(out, img, ow, oh, (ptrdiff_t)ow * 3, err, sizeof err))
        fv_fail(prog, FV_EXIT_FAIL, "%s", err);
    free(img);
    printf("%s: %s, phase %d of %d: %ld samples of %d (%.3f)\n", prog, fv_sampler_names[kind], phase, s.phases, n,
           w * h, (double)n / ((double)w * h));
    if (kind == FV_SAMPLER_LIU)
        printf("  lambda_0 %.3f, n_phi %d, drho %.4f, full disc %.1f px (%.1f deg), matched to %ld\n", s.liu_l0,
               s.liu_nphi, s.liu_drho, s.liu_sat_px, s.liu_sat_px / s.ppd, s.liu_target);
    free(rgb);
    fv_sampler_free(&s);
    return FV_EXIT_OK;
}
