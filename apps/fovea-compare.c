/* fovea-compare: luma PSNR and SSIM of two PNGs (core/metrics.h), over the whole image, a disc
 * (the fovea) or outside it (the periphery). How reference and filtered frames are compared. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "image.h"
#include "metrics.h"

static const char *prog = "fovea-compare";

static void usage(FILE *f)
{
    fprintf(f, "usage: fovea-compare A.png B.png [--fovea CX,CY,R | --periphery CX,CY,R]\n"
               "Prints the luma PSNR (dB) and the mean SSIM of B against A:\n"
               "  psnr_db VALUE   (inf for identical images)\n"
               "  ssim VALUE      (Wang et al. 2004: 11x11 Gaussian window, sigma 1.5, K1 0.01,\n"
               "                  K2 0.03, on Rec. 709 luma of the 8-bit values; pixels whose\n"
               "                  window lies inside the image)\n"
               "  --fovea CX,CY,R      only pixels whose centre is within R pixels of (CX, CY)\n"
               "  --periphery CX,CY,R  only pixels outside that disc\n"
               "                  (pixel coordinates: x right, y down, (0,0) the top-left corner)\n"
               "  --help          this text\n");
}

/* CX,CY,R: three finite numbers, R > 0. */
static fv_region parse_region(const char *flag, const char *s, int outside)
{
    double v[3];
    const char *p = s;
    for (int i = 0; i < 3; i++) {
        char *end;
        v[i] = strtod(p, &end);
        if (end == p || !isfinite(v[i]) || *end != (i < 2 ? ',' : '\0'))
            fv_usage_error(prog, "%s: '%s' is not CX,CY,R (three numbers, pixels)", flag, s);
        p = end + 1;
    }
    if (!(v[2] > 0.0))
        fv_usage_error(prog, "%s: radius %g must be positive", flag, v[2]);
    return fv_region_disc((float)v[0], (float)v[1], (float)v[2], outside);
}

int main(int argc, char **argv)
{
    enum { OPT_FOVEA = 1, OPT_PERIPHERY, OPT_HELP };
    static const struct option opts[] = {{"fovea", required_argument, 0, OPT_FOVEA},
                                         {"periphery", required_argument, 0, OPT_PERIPHERY},
                                         {"help", no_argument, 0, OPT_HELP}, {0, 0, 0, 0}};
    fv_region reg;
    const char *reg_flag = NULL, *reg_arg = NULL;
    opterr = 0;
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case OPT_FOVEA:
        case OPT_PERIPHERY:
            if (reg_flag)
                fv_usage_error(prog, "give one of --fovea, --periphery (once)");
            reg_flag = o == OPT_FOVEA ? "--fovea" : "--periphery";
            reg_arg = optarg;
            reg = parse_region(reg_flag, optarg, o == OPT_PERIPHERY);
            break;
        case OPT_HELP: usage(stdout); return FV_EXIT_OK;
        case '?': fv_bad_option(prog, argv);
        default: fv_usage_error(prog, "unhandled option (see --help)");
        }
    }
    if (argc - optind != 2)
        fv_usage_error(prog, "expected two PNG files A.png B.png, got %d (see --help)", argc - optind);
    const char *pa = argv[optind], *pb = argv[optind + 1];
    char err[512];
    int wa, ha, wb, hb;
    uint8_t *a = fv_read_png(pa, &wa, &ha, err, sizeof err);
    if (!a)
        fv_usage_error(prog, "%s", err);
    uint8_t *b = fv_read_png(pb, &wb, &hb, err, sizeof err);
    if (!b) {
        free(a);
        fv_usage_error(prog, "%s", err);
    }
    if (wa != wb || ha != hb) {
        free(a);
        free(b);
        fv_usage_error(prog, "%s is %dx%d but %s is %dx%d: sizes must match", pa, wa, ha, pb, wb, hb);
    }
    const fv_region *r = reg_flag ? &reg : NULL;
    const double psnr = fv_luma_psnr(a, b, wa, ha, (ptrdiff_t)wa * 3, r);
    const double ssim = fv_luma_ssim(a, b, wa, ha, (ptrdiff_t)wa * 3, r);
    free(a);
    free(b);
    if (isnan(psnr))
        fv_usage_error(prog, "%s %s: the region holds no pixel of the %dx%d image", reg_flag, reg_arg, wa, ha);
    if (isnan(ssim))
        fv_usage_error(prog, "%s%s%s: no pixel%s has its whole 11x11 SSIM window inside the %dx%d image",
                       reg_flag ? reg_flag : "", reg_flag ? " " : "", reg_flag ? reg_arg : "",
                       reg_flag ? " of the region" : "", wa, ha);
    printf("psnr_db %.3f\nssim %.6f\n", psnr, ssim);
    return FV_EXIT_OK;
}
