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

/* Spectacles between the eye and the camera (they move with the headset, i.e. the camera):
 * the lens dims the eye (transmit), each LED leaves a large reflection on the lens surface at a
 * place fixed in the camera image (LED ring x refl_scale + offset, radius refl_r_mm, level
 * refl_level; they do not move with the eye, unlike corneal glints), and the frame's rim crosses
 * the image as a dark curved band y = rim_y_mm + rim_curve x^2 (mm, camera image plane, y up),
 * rim_half_mm thick either side, grey rim_grey; the lens is above the rim (outside it, no tint). */
typedef struct fv_synth_specs {
    int on;
    float transmit;
    float refl_scale, refl_dx_mm, refl_dy_mm, refl_r_mm, refl_level;
    float rim_y_mm, rim_curve, rim_half_mm, rim_grey;
} fv_synth_specs;

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
    fv_synth_specs specs;  /* off by default */
} fv_synth_params;

/* Plausible spectacles (on): transmit 0.85, reflections 0.9 mm at 0.45 x the LED ring, rim 8 mm
 * below the eye's centre, 1.2 mm either side, grey 40. */
void fv_synth_specs_default(fv_synth_specs *sp);
/* Where LED k's reflection on the spectacle lens is centred in the image (pixels, corner origin),
 * and its radius in pixels. */
void fv_synth_specs_reflection(const fv_synth_params *p, int k, float *x, float *y, float *r_px);


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
/* Frame i of the "spectacle set" (measured by tools/eval_eye --specs): the lid set's poses
 * (fv_synth_lid_set_frame) seen through spectacles whose reflections sit anywhere within 7 mm
 * of the camera axis (often on or beside the pupil), whose rim runs 3-9 mm below or above the
 * eye's centre (every third frame above), tilted and curved at random, transmitting 0.7-0.95. */
void fv_synth_specs_set_frame(uint64_t *rng, int i, fv_synth_params *p, fv_synth_state *s);

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
