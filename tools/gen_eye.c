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
 * --calibration DWELL_MS: instead of a trace, a wearer going through fovea-headset --calibrate's
 * schedule (core/eyetrack/calibproc.h: 9 grid targets then --valid N validation targets, each
 * DWELL_MS long) with reaction time, saccades and fixational jitter (fv_synth_script); the video
 * starts at the first target's onset and lasts the schedule plus one slot. --blink-at MS (repeatable)
 * adds blinks at those times; --shift-mm X,Y slips the camera; --led-dist-mm D and --px-per-mm S
 * change the eye-camera geometry.
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

#include "eyetrack/calibproc.h"
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
    int calib_dwell_ms = 0, n_valid = 4, n_blinks = 0;
    float shift[2] = {0, 0}, led_dist = 0, px_per_mm = 0, blink_at[FV_SYNTH_SCRIPT_MAX];
    static const struct option opts[] = {
        {"trace", required_argument, 0, 't'}, {"out", required_argument, 0, 'o'},
        {"truth", required_argument, 0, 'g'}, {"size", required_argument, 0, 's'},
        {"frames", required_argument, 0, 'n'}, {"leds", required_argument, 0, 'l'},
        {"noise", required_argument, 0, 'z'}, {"seed", required_argument, 0, 'r'},
        {"blink-every", required_argument, 0, 'b'}, {"fps", required_argument, 0, 'f'},
        {"supersample", required_argument, 0, 'a'}, {"calibration", required_argument, 0, 'C'},
        {"valid", required_argument, 0, 'V'}, {"blink-at", required_argument, 0, 'B'},
        {"shift-mm", required_argument, 0, 'S'}, {"led-dist-mm", required_argument, 0, 'D'},
        {"px-per-mm", required_argument, 0, 'P'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
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
        case 'C': calib_dwell_ms = (int)num("--calibration", optarg, 300, 10000); break;
        case 'V': n_valid = (int)num("--valid", optarg, 0, FV_CALPROC_MAX_VALID); break;
        case 'B':
            if (n_blinks == FV_SYNTH_SCRIPT_MAX)
                die(2, "--blink-at: at most 64%s%s", "", "");
            blink_at[n_blinks++] = (float)num("--blink-at", optarg, 0, 1000000);
            break;
        case 'S':
            if (sscanf(optarg, "%f,%f", &shift[0], &shift[1]) != 2 || !(fabsf(shift[0]) <= 10) || !(fabsf(shift[1]) <= 10))
                die(2, "--shift-mm: '%s' is not X,Y within +-10 mm%s", optarg, "");
            break;
        case 'D': led_dist = (float)num("--led-dist-mm", optarg, 15, 100); break;
        case 'P': px_per_mm = (float)num("--px-per-mm", optarg, 2, 60); break;
        case 'h':
            printf("usage: gen_eye --out FILE.y4m --truth FILE.csv [--trace FILE | --calibration DWELL_MS\n"
                   "               [--valid N] [--blink-at MS]...] [--frames N] [--size WxH] [--leds 2..6]\n"
                   "               [--noise SIGMA] [--seed N] [--blink-every N] [--fps N] [--supersample N]\n"
                   "               [--shift-mm X,Y] [--led-dist-mm D] [--px-per-mm S]\n");
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
    if (trace_path && calib_dwell_ms)
        die(2, "--trace and --calibration exclude each other%s%s", "", "");
    fv_synth_script sc;
    if (calib_dwell_ms) { /* the procedure's own schedule, so a replay of the video follows it */
        fv_calproc_params cp;
        fv_calproc_default_params(&cp);
        cp.dwell_ms = calib_dwell_ms;
        cp.n_valid = n_valid;
        cp.settle_ms = cp.settle_ms < calib_dwell_ms / 2 ? cp.settle_ms : calib_dwell_ms / 2;
        cp.fix_ms = cp.fix_ms < calib_dwell_ms / 4 ? cp.fix_ms : calib_dwell_ms / 4;
        fv_calproc *c = fv_calproc_create(&cp);
        if (!c)
            die(2, "--calibration: no schedule for these settings%s%s", "", "");
        fv_synth_script_default(&sc, (float)calib_dwell_ms);
        sc.n = fv_calproc_slots(c);
        for (int k = 0; k < sc.n; k++)
            fv_calproc_slot_target(c, k, &sc.yaw_deg[k], &sc.pitch_deg[k]);
        fv_calproc_destroy(c);
        sc.n_blinks = n_blinks;
        memcpy(sc.blink_ms, blink_at, sizeof blink_at);
        sc.seed = (uint64_t)seed;
    }
    if (frames < 0)
        frames = trace_path       ? (long)floor((tr.s[tr.n - 1].t_ms - tr.s[0].t_ms) * fps / 1000.0) + 1
                 : calib_dwell_ms ? (long)((sc.n + 1) * (long)calib_dwell_ms * fps / 1000)
                                  : 90;

    fv_synth_params p;
    fv_synth_default_params(&p, w, h);
    p.n_leds = leds;
    p.noise_sigma = (float)noise;
    p.seed = (uint64_t)seed * 0x9e3779b97f4a7c15ull;
    p.supersample = ss;
    p.cam_shift_mm[0] = shift[0], p.cam_shift_mm[1] = shift[1];
    if (led_dist > 0)
        p.led_dist_mm = led_dist;
    if (px_per_mm > 0)
        p.px_per_mm = px_per_mm;
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
        if (calib_dwell_ms) {
            fv_synth_script_state(&sc, t, &s);
        } else if (trace_path) {
            fv_trace_sample smp;
            fv_trace_at(&tr, t, &smp);
            s.yaw_deg = (smp.gaze_x - 0.5f) * 50.0f;
            s.pitch_deg = (0.5f - smp.gaze_y) * 40.0f;
        } else { /* 3x3 grid, 10 frames per target */
            const long k = (i / 10) % 9;
            s.yaw_deg = (float)(k % 3 - 1) * 15.0f;
            s.pitch_deg = (float)(1 - k / 3) * 10.0f;
        }
        if (!calib_dwell_ms) {
            s.pupil_mm = (float)(2.3 + 0.7 * sin(t * 2.0 * 3.14159265358979 / 1300.0));
            s.open = 1.0f;
        }
        if (!calib_dwell_ms && blink_every > 0 && i % blink_every >= blink_every - 9) {
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
