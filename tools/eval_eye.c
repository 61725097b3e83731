/* eval_eye: pupil-centre accuracy of the tracker on a seeded random set of synthetic
 * headset-camera frames (core/eyetrack/synth.c), split by how much of the pupil the lid leaves
 * in view. The set is the one tests/test_eyetrack.c bounds at 320x240 (test_partial_occlusion)
 * made at any size: gaze +-20 deg, pupil 1.6-2.8 mm, 2-6 LEDs, sensor noise 2-14 grey levels,
 * brightness 0.55-1; every other frame looks up (3-13 deg) into a lid opened 0.35-0.65.
 *
 *   build/tools/eval_eye [--size WxH] [--frames N] [--seed N] [--history] [--mode M]
 *
 * --history: each frame is tracked with fv_track_frame after the tracker (reset) has seen the
 * same eye with the lids open for 4 frames, as a headset sees it before the lid comes down;
 * without it, fv_track_image (no history). A frame flagged BLINK counts as a miss.
 * --frames 160 is the set tests/test_eyetrack.c bounds (test_partial_occlusion).
 * --mode: the tracker's mode (auto, headset, crop); headset by default, the frames being a
 * headset camera's at any size.
 *
 * Prints, per bin (full view, 70-99%, 50-70% in view; frames under 50% are skipped), the
 * frames, median / p90 / max error in pixels and the share within 1 and 3 px, and the time
 * per frame spent tracking (one thread, best kernels; the tracker's output does not depend on
 * them). Deterministic except for the time. Exit status: 0, 1 out of memory, 2 bad usage. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "base/clock.h"
#include "eyetrack/eyetrack.h"
#include "eyetrack/synth.h"

static const char *prog = "eval_eye";

static void usage(FILE *f)
{
    fprintf(f, "usage: %s [--size WxH] [--frames N] [--seed N] [--history]\n"
               "  --size WxH   frame size (default 320x240; 64..4096 each side)\n"
               "  --frames N   frames drawn before the visibility split (default 400; 1..100000)\n"
               "  --seed N     random set (default 1)\n"
               "  --history    track each frame after 4 open-eye frames of the same eye\n"
               "  --specs      the same poses through spectacles (fv_synth_specs_set_frame: lens\n"
               "               reflections, tint, a rim); also reports the pupil-glint vector's error\n"
               "  --mode M     tracker mode: headset (default), crop or auto\n",
            prog);
}

static _Noreturn void bad(const char *what, const char *arg)
{
    fprintf(stderr, "%s: %s: '%s' (--help for usage)\n", prog, what, arg);
    exit(2);
}

static long num(const char *flag, const char *s, long lo, long hi)
{
    char *end;
    const long v = strtol(s, &end, 10);
    if (end == s || *end || v < lo || v > hi)
        bad(flag, s);
    return v;
}

static int cmp_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}


int main(int argc, char **argv)
{
    int w = 320, h = 240, frames = 400;
    long seed = 1;
    int history = 0, specs = 0;
    fv_eye_mode mode = FV_EYE_MODE_HEADSET;
    static const struct option opts[] = { { "size", required_argument, 0, 's' },
                                          { "frames", required_argument, 0, 'n' },
                                          { "seed", required_argument, 0, 'r' },
                                          { "history", no_argument, 0, 'H' }, { "specs", no_argument, 0, 'S' },
                                          { "mode", required_argument, 0, 'm' },
                                          { "help", no_argument, 0, 'h' },
                                          { 0, 0, 0, 0 } };
    int c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
        switch (c) {
        case 's': {
            char tail;
            if (sscanf(optarg, "%dx%d%c", &w, &h, &tail) != 2 || w < 64 || h < 64 || w > 4096 || h > 4096)
                bad("bad --size (WxH, 64..4096)", optarg);
            break;
        }
        case 'n': frames = (int)num("bad --frames (1..100000)", optarg, 1, 100000); break;
        case 'r': seed = num("bad --seed", optarg, 0, 0x7fffffffL); break;
        case 'H': history = 1; break;
        case 'S': specs = 1; break;
        case 'm':
            if (fv_eye_mode_parse(optarg, &mode))
                bad("bad --mode (auto, headset, crop)", optarg);
            break;
        case 'h': usage(stdout); return 0;
        default: bad("unknown option or missing argument", argv[optind - 1]);
        }
    }
    if (optind != argc)
        bad("unexpected argument", argv[optind]);
    fv_synth_params p;
    fv_synth_default_params(&p, w, h);
    p.supersample = 2;
    uint8_t *img = malloc((size_t)w * h);
    float *err[3];
    for (int b = 0; b < 3; b++)
        err[b] = malloc(sizeof(float) * (size_t)frames);
    fv_eye_tracker *t = fv_eye_create(NULL, mode);
    if (!img || !err[0] || !err[1] || !err[2] || !t) {
        fprintf(stderr, "%s: out of memory\n", prog);
        return 1;
    }
    uint64_t rng = (uint64_t)seed;
    const int progress = isatty(2);
    int n[3] = { 0, 0, 0 }, pg_n = 0, pg_ok = 0, w5 = 0, all = 0;
    double track_s = 0;
    int tracked = 0;
    for (int i = 0; i < frames; i++) {
        fv_synth_state s;
        if (specs)
            fv_synth_specs_set_frame(&rng, i, &p, &s);
        else
            fv_synth_lid_set_frame(&rng, i, &p, &s);
        fv_synth_truth gt;
        fv_synth_render(&p, &s, 1000u + (uint64_t)i, img, w, &gt);
        if (gt.pupil_visible < 0.5f)
            continue;
        fv_eye_result r;
        if (history) {
            fv_eye_reset(t);
            const fv_synth_state o = { s.yaw_deg, s.pitch_deg, s.pupil_mm, 1.0f };
            for (int k = 0; k < 4; k++) {
                fv_synth_truth og;
                fv_synth_render(&p, &o, 5000u + 8u * (uint64_t)i + (uint64_t)k, img, w, &og);
                fv_track_frame(t, img, w, h, w, &r);
            }
            fv_synth_render(&p, &s, 1000u + (uint64_t)i, img, w, &gt);
        }
        const double t0 = (1e-9 * (double)fv_time_ns());
        (history ? fv_track_frame : fv_track_image)(t, img, w, h, w, &r);
        track_s += (1e-9 * (double)fv_time_ns()) - t0, tracked++;
        const float e = r.found && r.status == FV_EYE_OK ? hypotf(r.pupil_x - gt.pupil_x, r.pupil_y - gt.pupil_y) : INFINITY;
        const int b = gt.pupil_visible >= 0.99f ? 0 : gt.pupil_visible >= 0.7f ? 1 : 2;
        err[b][n[b]++] = e;
        /* the pupil-glint vector against the truth's (pupil minus the visible glints' mean) */
        float gx = 0, gy = 0;
        int ng = 0;
        for (int k = 0; k < gt.n_glints; k++)
            if (gt.glint_visible[k])
                gx += gt.glint_x[k], gy += gt.glint_y[k], ng++;
        if (ng) {
            pg_n++;
            if (e <= 3.0f && r.has_pg)
                pg_ok += hypotf(r.pg_x - (gt.pupil_x - gx / ng), r.pg_y - (gt.pupil_y - gy / ng)) <= 1.0f;
        }
        w5 += e <= 5.0f, all++;
        if (progress && i % 50 == 49)
            fprintf(stderr, "\r%s: %d / %d frames", prog, i + 1, frames);
    }
    if (progress)
        fprintf(stderr, "\r%*s\r", 40, "");
    printf("%s: %dx%d, %d frames drawn, seed %ld%s%s%s%s\n", prog, w, h, frames, seed,
           specs ? ", through spectacles" : "", history ? ", after 4 open-eye frames" : "", mode == FV_EYE_MODE_HEADSET ? "" : ", mode ",
           mode == FV_EYE_MODE_HEADSET ? "" : fv_eye_mode_name(mode));
    static const char *names[3] = { "full view", "70-99% in view", "50-70% in view" };
    for (int b = 0; b < 3; b++) {
        if (!n[b]) {
            printf("  %-15s    0 frames\n", names[b]);
            continue;
        }
        qsort(err[b], (size_t)n[b], sizeof(float), cmp_float);
        int k1 = 0, k3 = 0;
        for (int i = 0; i < n[b]; i++)
            k1 += err[b][i] <= 1.0f, k3 += err[b][i] <= 3.0f;
        printf("  %-15s %4d frames: median %.2f px, p90 %.2f px, max %.2f px, within 1 px %.0f%%, within 3 px %.0f%%\n",
               names[b], n[b], (double)err[b][n[b] / 2], (double)err[b][n[b] * 9 / 10], (double)err[b][n[b] - 1],
               100.0 * k1 / n[b], 100.0 * k3 / n[b]);
    }
    if (all)
        printf("  all %d frames: pupil within 5 px %.1f%%; pupil-glint vector within 1 px of the truth's %.1f%% "
               "(of %d frames with a visible glint)\n", all, 100.0 * w5 / all, pg_n ? 100.0 * pg_ok / pg_n : 0.0, pg_n);
    if (tracked)
        printf("  time per frame (tracking only, one thread): %.3f ms\n", 1e3 * track_s / tracked);
    fv_eye_destroy(t);
    free(img);
    for (int b = 0; b < 3; b++)
        free(err[b]);
    return 0;
}
