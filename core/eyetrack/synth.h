/* fovea eye tracker: synthetic infrared eye images from a 3D eye model, with ground truth.
 * Used by tools/gen_eye (the bundled video) and by the tests (no I/O here).
 *
 * Model (millimetres; eyeball centre at the origin, +Z towards the camera, +Y up): eyeball
 * sphere R = 12; cornea sphere R = 7.8 centred 5.6 along the gaze; iris disc (radius 6) in the
 * plane 10.4 along the gaze, textured with radial fibres and a collarette; pupil disc of
 * variable radius in that plane; IR LEDs on a ring around the camera giving corneal
 * reflections (the mirror point on the cornea sphere); an almond eyelid aperture that closes
 * for blinks, with lashes along the upper lid; skin shading; Gaussian sensor noise.
 * Camera: scaled orthographic (telecentric) looking down -Z, so the projected pupil centre is
 * exactly the centre of the pupil ellipse; corneal refraction of the pupil is not modelled. */
#ifndef FOVEA_EYETRACK_SYNTH_H
#define FOVEA_EYETRACK_SYNTH_H

#include <stddef.h>
#include <stdint.h>

#define FV_SYNTH_MAX_LEDS 6

typedef struct fv_synth_params {
    int w, h;
    float px_per_mm;     /* image scale */
    int n_leds;          /* 2 .. 6 */
    float led_ring_mm;   /* LED ring radius around the camera axis */
    float led_dist_mm;   /* LED plane distance from the eyeball centre */
    float noise_sigma;   /* grey levels */
    float brightness;    /* skin / sclera level scale (1 = nominal) */
    int supersample;     /* n x n samples per pixel */
    uint64_t seed;       /* iris texture and lash pattern (the subject) */
    float cam_shift_mm[2]; /* the camera and its LED ring displaced from the nominal place (x right, y up):
                              a headset slipping on the face; default 0 */
} fv_synth_params;

typedef struct fv_synth_state {
    float yaw_deg, pitch_deg; /* gaze: + yaw = towards +x of the image, + pitch = up */
    float pupil_mm;           /* pupil radius */
    float open;               /* eyelid opening: 1 open, 0 closed */
} fv_synth_state;

typedef struct fv_synth_truth {
    float pupil_x, pupil_y;  /* pixels, corner origin (pixel centres at +0.5) */
    float pupil_r_px;        /* pupil radius in pixels (major semi-axis of its image) */
    float pupil_visible;     /* fraction of the pupil disc inside the lid aperture */
    int n_glints;            /* = n_leds */
    float glint_x[FV_SYNTH_MAX_LEDS], glint_y[FV_SYNTH_MAX_LEDS];
    int glint_visible[FV_SYNTH_MAX_LEDS];
} fv_synth_truth;

void fv_synth_default_params(fv_synth_params *p, int w, int h);
/* Ground truth only (cheap). */
void fv_synth_truth_of(const fv_synth_params *p, const fv_synth_state *s, fv_synth_truth *t);
/* Renders one frame into img (w x h, stride bytes per row); noise_seed varies per frame. */
void fv_synth_render(const fv_synth_params *p, const fv_synth_state *s, uint64_t noise_seed, uint8_t *img,
                     ptrdiff_t stride, fv_synth_truth *t);

/* Frame i of the "lid set" (bounded by tests/test_eyetrack.c, measured by tools/eval_eye.c):
 * poses a headset camera sees, drawn from *rng (splitmix64 state): gaze yaw +-20 deg, pupil
 * 1.6-2.8 mm, 2-6 LEDs, sensor noise 2-14 grey levels, brightness 0.55-1; odd i look up 3-13 deg
 * into a lid opened 0.35-0.65, even i pitch +-10 deg with the lids open. Sets p's noise_sigma,
 * brightness and n_leds, and *s. */
void fv_synth_lid_set_frame(uint64_t *rng, int i, fv_synth_params *p, fv_synth_state *s);

/* A scripted wearer following a schedule of targets (a calibration run): target k is shown from
 * k * dwell_ms on; the eye stays on the previous one for reaction_ms, makes a saccade of
 * saccade_ms, then fixates with fixational drift and tremor of about jitter_deg (smooth,
 * deterministic from seed). Blinks (lids closing over 80 ms, reopening over 120 ms) start at
 * blink_ms[i]; in a "wander" slot the eye keeps drifting +-3 deg instead of fixating. */
#define FV_SYNTH_SCRIPT_MAX 64
typedef struct fv_synth_script {
    int n;                                   /* targets */
    float yaw_deg[FV_SYNTH_SCRIPT_MAX], pitch_deg[FV_SYNTH_SCRIPT_MAX];
    float dwell_ms, reaction_ms, saccade_ms, jitter_deg;
    int n_blinks;
    float blink_ms[FV_SYNTH_SCRIPT_MAX];     /* onsets, from the first target's onset */
    uint32_t wander_mask;                    /* bit k: no fixation in slot k */
    uint64_t seed;
} fv_synth_script;

/* Defaults: reaction 220 ms, saccade 45 ms, jitter 0.05 deg, no blinks, no wandering. */
void fv_synth_script_default(fv_synth_script *sc, float dwell_ms);
/* The eye at t_ms from the first onset (before it: looking at the first target). The pupil
 * radius follows a slow hippus around 2.2 mm. */
void fv_synth_script_state(const fv_synth_script *sc, double t_ms, fv_synth_state *s);

#endif
