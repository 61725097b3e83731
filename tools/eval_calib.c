/* eval_calib: the calibration procedure (core/eyetrack/calibproc.c) on rendered scripted wearers
 * (core/eyetrack/synth.c) over several eye and camera geometries, through the real tracker, and
 * the gaze error after the camera slips without recalibrating; for three input features fitted
 * from the same frames: the slip-compensated pupil-glint feature (the default), the plain
 * pupil-glint vector (slip gain 1) and the pupil centre alone. Prints a Markdown table.
 *   build/tools/eval_calib [--slip-mm S] [--fps N]      (defaults 2, 60) */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "eyetrack/calibproc.h"
#include "eyetrack/eyetrack.h"
#include "eyetrack/synth.h"

typedef struct geometry {
    const char *name;
    int w, h, leds;
    float px_per_mm, led_dist_mm, noise;
    uint64_t seed;
} geometry;

int main(int argc, char **argv)
{
    float slip = 2.0f;
    int fps = 60;
    static const struct option opts[] = {{"slip-mm", required_argument, 0, 's'}, {"fps", required_argument, 0, 'f'},
                                         {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        if (o == 's')
            slip = strtof(optarg, NULL);
        else if (o == 'f')
            fps = atoi(optarg);
        else {
            fprintf(o == 'h' ? stdout : stderr, "usage: eval_calib [--slip-mm S] [--fps N]\n");
            return o == 'h' ? 0 : 2;
        }
    }
    if (!(slip >= 0 && slip <= 5) || fps < 20 || fps > 500) {
        fprintf(stderr, "eval_calib: --slip-mm 0..5, --fps 20..500\n");
        return 2;
    }
    /* the headsets' eye cameras differ in scale, LED count and LED distance; the last two rows
     * have the LEDs at 30 and 45 mm while the feature's slip gain assumes 35 mm */
    static const geometry geo[] = {
        {"320x240, 9.4 px/mm, 4 LEDs at 35 mm", 320, 240, 4, 0, 35, 2, 1},
        {"400x300, 12 px/mm, 2 LEDs at 35 mm", 400, 300, 2, 12, 35, 3, 2},
        {"640x480, 16 px/mm, 6 LEDs at 35 mm", 640, 480, 6, 16, 35, 4, 3},
        {"320x240, 9.4 px/mm, 4 LEDs at 30 mm", 320, 240, 4, 0, 30, 2, 4},
        {"320x240, 9.4 px/mm, 4 LEDs at 45 mm", 320, 240, 4, 0, 45, 2, 5},
    };
    printf("| geometry | validation mean / max deg (compensated) | after a %.1f mm slip: compensated | plain "
           "pupil-glint | pupil only |\n|---|---|---|---|---|\n",
           (double)slip);
    int fails = 0;
    for (size_t g = 0; g < sizeof geo / sizeof geo[0]; g++) {
        const geometry *G = &geo[g];
        fv_synth_params p;
        fv_synth_default_params(&p, G->w, G->h);
        p.supersample = 1, p.n_leds = G->leds, p.noise_sigma = G->noise, p.led_dist_mm = G->led_dist_mm;
        p.seed = G->seed * 0x9e3779b97f4a7c15ull;
        if (G->px_per_mm > 0)
            p.px_per_mm = G->px_per_mm;
        fv_calproc_params cp;
        fv_calproc_default_params(&cp);
        cp.dwell_ms = 1000;
        fv_calproc *c[3];
        c[0] = fv_calproc_create(&cp);
        cp.slip_gain = 1.0f;
        c[1] = fv_calproc_create(&cp);
        cp.input = FV_CALIB_PUPIL;
        c[2] = fv_calproc_create(&cp);
        fv_synth_script sc;
        fv_synth_script_default(&sc, 1000.0f);
        sc.seed = G->seed;
        sc.n = fv_calproc_slots(c[0]);
        for (int k = 0; k < sc.n; k++)
            fv_calproc_slot_target(c[0], k, &sc.yaw_deg[k], &sc.pitch_deg[k]);
        fv_eye_tracker *tr = fv_eye_create(NULL, FV_EYE_MODE_HEADSET);
        uint8_t *img = malloc((size_t)G->w * G->h);
        for (int m = 0; m < 3; m++)
            fv_calproc_start(c[m], 0);
        for (long i = 0;; i++) {
            const int64_t t = i * 1000000000LL / fps;
            int slot;
            float y, pt;
            if (!fv_calproc_target(c[0], t, &slot, &y, &pt))
                break;
            fv_synth_state s;
            fv_synth_script_state(&sc, (double)t * 1e-6, &s);
            fv_synth_truth tt;
            fv_synth_render(&p, &s, G->seed * 7919u + (uint64_t)i, img, G->w, &tt);
            fv_eye_result r;
            fv_track_frame(tr, img, G->w, G->h, G->w, &r);
            for (int m = 0; m < 3; m++)
                fv_calproc_feed(c[m], t, &r);
        }
        fv_calib cal[3];
        fv_calproc_report rep[3];
        char err[512];
        int ok[3];
        for (int m = 0; m < 3; m++)
            ok[m] = !fv_calproc_finish(c[m], &cal[m], &rep[m], err, sizeof err);
        double e[3] = {0, 0, 0};
        int n = 0;
        for (int dir = 0; dir < 3; dir++) { /* right, up, diagonal */
            const float a = dir == 2 ? slip * 0.70710678f : slip;
            p.cam_shift_mm[0] = dir != 1 ? a : 0.0f, p.cam_shift_mm[1] = dir != 0 ? a : 0.0f;
            for (int k = 0; k < sc.n; k++) {
                fv_eye_reset(tr);
                fv_synth_state s = {sc.yaw_deg[k], sc.pitch_deg[k], 2.2f, 1.0f};
                float acc[3][2] = {{0}};
                int got = 0;
                for (int f = 0; f < 5; f++) {
                    fv_synth_truth tt;
                    fv_synth_render(&p, &s, 99991u + (uint64_t)(k * 8 + f), img, G->w, &tt);
                    fv_eye_result r;
                    fv_track_frame(tr, img, G->w, G->h, G->w, &r);
                    float fx[3], fy[3];
                    int all = 1;
                    for (int m = 0; m < 3; m++)
                        all &= fv_calib_feature(&cal[m], &r, &fx[m], &fy[m]);
                    if (all) {
                        for (int m = 0; m < 3; m++)
                            acc[m][0] += fx[m], acc[m][1] += fy[m];
                        got++;
                    }
                }
                if (!got)
                    continue;
                for (int m = 0; m < 3; m++) {
                    float yaw, pitch;
                    fv_calib_apply(&cal[m], acc[m][0] / got, acc[m][1] / got, &yaw, &pitch);
                    e[m] += fv_gaze_angle_deg(yaw, pitch, s.yaw_deg, s.pitch_deg);
                }
                n++;
            }
        }
        if (!ok[0])
            fails++;
        printf("| %s | %s%.2f / %.2f | %.2f | %.2f | %.2f |\n", G->name, ok[0] ? "" : "REFUSED ",
               (double)rep[0].valid_mean_deg, (double)rep[0].valid_max_deg, n ? e[0] / n : NAN, n ? e[1] / n : NAN,
               n ? e[2] / n : NAN);
        fflush(stdout);
        free(img);
        fv_eye_destroy(tr);
        for (int m = 0; m < 3; m++)
            fv_calproc_destroy(c[m]);
    }
    return fails ? 1 : 0;
}
