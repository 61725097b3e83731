/* gen_eye: synthetic infrared eye video (YUV4MPEG2 Cmono) plus per-frame ground truth, from the
 * 3D eye model in core/eyetrack/synth.c, driven by a gaze trace. The bundled one is made at build
 * time (Makefile, EYE_SYNTH rule):
 *
 *   build/tools/gen_eye --trace assets/gaze_sweep.csv --out assets/eye_synth.y4m --truth assets/eye_synth.csv
 *
 * Trace: the project's format (t_ms,gaze_x,gaze_y; normalised image coordinates), mapped
 * linearly to eye rotation: gaze_x 0..1 -> yaw -25..+25 deg, gaze_y 0..1 -> pitch +20..-20 deg.
 * Without --trace the eye fixates a 3x3 grid of targets in turn. Frame i is at
 * t = t_first + i * 1000 / fps. The pupil radius oscillates between 1.6 and 3.0 mm (a slow
 * hippus); a blink (lids close and reopen over 9 frames) starts every --blink-every frames.
 *
 * Ground truth CSV (header line): frame,t_ms,yaw_deg,pitch_deg,open,blink,pupil_x,pupil_y,
 * pupil_r_px,pupil_visible,n_glints,g0_x,g0_y,...,g5_x,g5_y (pixels, corner origin: pixel (i,j)
 * has its centre at (i+0.5, j+0.5); an invisible glint's fields are empty).
 * Deterministic. Exit status: 0 success, 2 bad usage or bad trace, 1 cannot write. Files are
 * written to NAME.tmp and renamed when complete. */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "eyetrack/synth.h"
#include "tracefile.h"

static const char *prog = "gen_eye";

static _Noreturn void die(int st, const char *fmt, const char *a, const char *b)
{
    fprintf(stderr, "%s: ", prog);
    fprintf(stderr, fmt, a, b);
    fputc('\n', stderr);
    exit(st);
}

static long num(const char *flag, const char *s, long lo, long hi)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end || errno || v < lo || v > hi)
        die(2, "%s: '%s' is not a whole number in range", flag, s);
    return v;
}

int main(int argc, char **argv)
{
    const char *trace_path = NULL, *out = NULL, *truth_path = NULL;
    int w = 320, h = 240, leds = 4, blink_every = 45, fps = 90, ss = 2;
    long frames = -1, seed = 1;
    double noise = 2.0;
    static const struct option opts[] = {
        {"trace", required_argument, 0, 't'}, {"out", required_argument, 0, 'o'},
        {"truth", required_argument, 0, 'g'}, {"size", required_argument, 0, 's'},
        {"frames", required_argument, 0, 'n'}, {"leds", required_argument, 0, 'l'},
        {"noise", required_argument, 0, 'z'}, {"seed", required_argument, 0, 'r'},
        {"blink-every", required_argument, 0, 'b'}, {"fps", required_argument, 0, 'f'},
        {"supersample", required_argument, 0, 'a'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    opterr = 0;
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case 't': trace_path = optarg; break;
        case 'o': out = optarg; break;
        case 'g': truth_path = optarg; break;
        case 's':
            if (sscanf(optarg, "%dx%d", &w, &h) != 2 || w < 32 || h < 32 || w > 4096 || h > 4096)
                die(2, "--size: '%s' is not WxH in 32..4096%s", optarg, "");
            break;
        case 'n': frames = num("--frames", optarg, 1, 100000); break;
        case 'l': leds = (int)num("--leds", optarg, 2, FV_SYNTH_MAX_LEDS); break;
        case 'z': {
            char *end;
            noise = strtod(optarg, &end);
            if (end == optarg || *end || !(noise >= 0 && noise <= 100))
                die(2, "--noise: '%s' is not a number in [0, 100]%s", optarg, "");
            break;
        }
        case 'r': seed = num("--seed", optarg, 0, 1L << 30); break;
        case 'b': blink_every = (int)num("--blink-every", optarg, 0, 100000); break;
        case 'f': fps = (int)num("--fps", optarg, 1, 1000); break;
        case 'a': ss = (int)num("--supersample", optarg, 1, 8); break;
        case 'h':
            printf("usage: gen_eye --out FILE.y4m --truth FILE.csv [--trace FILE] [--frames N] [--size WxH]\n"
                   "               [--leds 2..6] [--noise SIGMA] [--seed N] [--blink-every N] [--fps N]\n"
                   "               [--supersample N]\n");
            return 0;
        default: die(2, "%s: unknown option or missing argument%s", argv[optind - 1], "");
        }
    }
    if (!out || !truth_path)
        die(2, "--out FILE.y4m and --truth FILE.csv are required%s%s", "", "");
    fv_trace tr = { 0 };
    char err[512];
    if (trace_path && fv_trace_load(&tr, trace_path, err, sizeof err))
        die(2, "%s%s", err, "");
    if (frames < 0)
        frames = trace_path ? (long)floor((tr.s[tr.n - 1].t_ms - tr.s[0].t_ms) * fps / 1000.0) + 1 : 90;

    fv_synth_params p;
    fv_synth_default_params(&p, w, h);
    p.n_leds = leds;
    p.noise_sigma = (float)noise;
    p.seed = (uint64_t)seed * 0x9e3779b97f4a7c15ull;
    p.supersample = ss;
    char tmp_v[4200], tmp_t[4200];
    snprintf(tmp_v, sizeof tmp_v, "%s.tmp", out);
    snprintf(tmp_t, sizeof tmp_t, "%s.tmp", truth_path);
    FILE *fv = fopen(tmp_v, "wb"), *ft = fopen(tmp_t, "w");
    if (!fv || !ft)
        die(1, "cannot write %s: %s", !fv ? tmp_v : tmp_t, strerror(errno));
    uint8_t *img = malloc((size_t)w * h);
    if (!img)
        die(1, "out of memory%s%s", "", "");
    fprintf(fv, "YUV4MPEG2 W%d H%d F%d:1 Ip A1:1 Cmono XFOVEA=gen_eye\n", w, h, fps);
    fprintf(ft, "frame,t_ms,yaw_deg,pitch_deg,open,blink,pupil_x,pupil_y,pupil_r_px,pupil_visible,n_glints");
    for (int k = 0; k < FV_SYNTH_MAX_LEDS; k++)
        fprintf(ft, ",g%d_x,g%d_y", k, k);
    fputc('\n', ft);
    const double t0 = trace_path ? tr.s[0].t_ms : 0.0;
    for (long i = 0; i < frames; i++) {
        const double t = t0 + i * 1000.0 / fps;
        fv_synth_state s;
        if (trace_path) {
            fv_trace_sample smp;
            fv_trace_at(&tr, t, &smp);
            s.yaw_deg = (smp.gaze_x - 0.5f) * 50.0f;
            s.pitch_deg = (0.5f - smp.gaze_y) * 40.0f;
        } else { /* 3x3 grid, 10 frames per target */
            const long k = (i / 10) % 9;
            s.yaw_deg = (float)(k % 3 - 1) * 15.0f;
            s.pitch_deg = (float)(1 - k / 3) * 10.0f;
        }
        s.pupil_mm = (float)(2.3 + 0.7 * sin(t * 2.0 * 3.14159265358979 / 1300.0));
        s.open = 1.0f;
        if (blink_every > 0 && i % blink_every >= blink_every - 9) {
            const int b = (int)(i % blink_every) - (blink_every - 9); /* 0..8 */
            static const float prof[9] = { 0.7f, 0.35f, 0.05f, 0.0f, 0.0f, 0.15f, 0.4f, 0.65f, 0.85f };
            s.open = prof[b];
        }
        fv_synth_truth gt;
        fv_synth_render(&p, &s, (uint64_t)seed * 1000003u + (uint64_t)i, img, w, &gt);
        fputs("FRAME\n", fv);
        fwrite(img, 1, (size_t)w * h, fv);
        fprintf(ft, "%ld,%.3f,%.4f,%.4f,%.3f,%d,%.4f,%.4f,%.4f,%.3f,%d", i, t, (double)s.yaw_deg,
                (double)s.pitch_deg, (double)s.open, s.open < 0.5f, (double)gt.pupil_x, (double)gt.pupil_y,
                (double)gt.pupil_r_px, (double)gt.pupil_visible, gt.n_glints);
        for (int k = 0; k < FV_SYNTH_MAX_LEDS; k++) {
            if (k < gt.n_glints && gt.glint_visible[k])
                fprintf(ft, ",%.4f,%.4f", (double)gt.glint_x[k], (double)gt.glint_y[k]);
            else
                fputs(",,", ft);
        }
        fputc('\n', ft);
    }
    free(img);
    fv_trace_free(&tr);
    const int bad = ferror(fv) | ferror(ft);
    if ((fclose(fv) | fclose(ft)) || bad) {
        remove(tmp_v), remove(tmp_t);
        die(1, "write error on %s or %s", out, truth_path);
    }
    if (rename(tmp_v, out) || rename(tmp_t, truth_path))
        die(1, "cannot rename to %s: %s", out, strerror(errno));
    return 0;
}
