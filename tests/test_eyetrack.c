/* fovea eye tracker tests: ellipse fit against known ellipses; the tracker against the synthetic
 * renderer's ground truth (clean, noisy / low-contrast / partly covered, blinks); calibration
 * against a known polynomial; the whole chain gaze -> synthetic frames -> tracker ->
 * calibration -> gaze in degrees; the gaze filter; calibration files. Deterministic. Frames are
 * 320x240 with 2x2 supersampling and few in number, to stay quick under ASan and qemu. */
#define _XOPEN_SOURCE 700 /* realpath */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

#include "calibfile.h"
#include "eyesrc.h"
#include "eyetrack/calib.h"
#include "eyetrack/eyetrack.h"
#include "eyetrack/gazefilter.h"
#include "eyetrack/synth.h"

#define W 320
#define H 240

static uint64_t rng = 0xe7e7e7ull;
static float rnd(void) { return fv_test_randf(&rng); }

static int cmp_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}
static float median(float *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_float);
    return n % 2 ? v[n / 2] : 0.5f * (v[n / 2 - 1] + v[n / 2]);
}

/* ------------------------------------------------------------------ ellipse */

static void test_ellipse_fit(void **state)
{
    (void)state;
    rng = 0x1111ull; /* each test its own draws, whatever runs before it */
    for (int k = 0; k < 50; k++) {
        const double cx = 20 + 200 * rnd(), cy = 20 + 200 * rnd(), a = 3 + 40 * rnd(), b = a * (0.3 + 0.7 * rnd());
        const double th = 3.14159265358979 * rnd();
        float x[64], y[64];
        const int n = 6 + (int)(rnd() * 58);
        const double arc = k % 3 == 0 ? 3.14159265358979 : 6.28318530717959; /* half arcs too */
        for (int i = 0; i < n; i++) {
            const double t = arc * i / n;
            x[i] = (float)(cx + a * cos(t) * cos(th) - b * sin(t) * sin(th));
            y[i] = (float)(cy + a * cos(t) * sin(th) + b * sin(t) * cos(th));
        }
        fv_ellipse e;
        assert_int_equal(fv_ellipse_fit(x, y, n, &e), 0);
        /* float inputs: errors of ~1e-5 relative */
        const double tol = 1e-3 * (1 + a);
        if (fabs(e.cx - cx) > tol || fabs(e.cy - cy) > tol || fabs(e.a - a) > tol || fabs(e.b - b) > tol)
            fail_msg("ellipse %d: got c=(%g,%g) a=%g b=%g, want (%g,%g) %g %g", k, e.cx, e.cy, e.a, e.b, cx, cy, a, b);
        if (a - b > 0.05 * a) { /* the angle is defined (mod pi) */
            double d = fmod(fabs(e.angle - th), 3.14159265358979);
            d = fmin(d, 3.14159265358979 - d);
            assert_true(d < 1e-3);
        }
        for (int i = 0; i < n; i++)
            assert_true(fv_ellipse_distance(&e, x[i], y[i]) < tol);
        assert_true(fabs(fv_ellipse_distance(&e, e.cx + (e.a + 2) * cos(e.angle), e.cy + (e.a + 2) * sin(e.angle)) - 2) < 1e-6);
    }
    float lx[10], ly[10];
    for (int i = 0; i < 10; i++)
        lx[i] = (float)i, ly[i] = 2.0f * i + 1; /* collinear: no ellipse */
    fv_ellipse e;
    assert_int_equal(fv_ellipse_fit(lx, ly, 10, &e), -1);
    assert_int_equal(fv_ellipse_fit(lx, ly, 4, &e), -1);
}

/* ------------------------------------------------------------------ tracker on synthetic frames */

typedef struct {
    float pupil_err, glint_max_err;
    int glints_visible, glints_matched, found, status;
} frame_eval;

static frame_eval eval_frame(fv_eye_tracker *t, const fv_synth_params *p, const fv_synth_state *s, uint64_t seed,
                             int history, uint8_t *img)
{
    fv_synth_truth gt;
    fv_synth_render(p, s, seed, img, p->w, &gt);
    fv_eye_result r;
    assert_int_equal((history ? fv_track_frame : fv_track_image)(t, img, p->w, p->h, p->w, &r), 0);
    frame_eval e = { 0 };
    e.found = r.found;
    e.status = r.status;
    e.pupil_err = r.found ? hypotf(r.pupil_x - gt.pupil_x, r.pupil_y - gt.pupil_y) : INFINITY;
    for (int k = 0; k < gt.n_glints; k++) {
        if (!gt.glint_visible[k])
            continue;
        e.glints_visible++;
        float best = INFINITY;
        for (int j = 0; j < r.n_glints; j++)
            best = fminf(best, hypotf(r.glints[j].x - gt.glint_x[k], r.glints[j].y - gt.glint_y[k]));
        if (best < 1.0f) {
            e.glints_matched++;
            e.glint_max_err = fmaxf(e.glint_max_err, best);
        }
    }
    return e;
}

static void test_synthetic_clean(void **state)
{
    (void)state;
    rng = 0x2222ull; /* each test its own draws, whatever runs before it */
    fv_synth_params p;
    fv_synth_default_params(&p, W, H);
    p.noise_sigma = 0;
    p.supersample = 2;
    uint8_t *img = malloc(W * H);
    fv_eye_tracker *t = fv_eye_create(NULL, FV_EYE_MODE_HEADSET);
    assert_non_null(t);
    enum { N = 9 };
    float err[N];
    int vis = 0, matched = 0;
    for (int i = 0; i < N; i++) {
        p.n_leds = 2 + i % 5;
        const fv_synth_state s = { -20.0f + 40.0f * rnd(), -12.0f + 24.0f * rnd(), 1.6f + 1.2f * rnd(), 1.0f };
        const frame_eval e = eval_frame(t, &p, &s, (uint64_t)i, 0, img);
        assert_true(e.found);
        err[i] = e.pupil_err;
        vis += e.glints_visible;
        matched += e.glints_matched;
        printf("[ eyetrack ] clean %d: gaze (%.1f, %.1f) pupil %.2f mm: error %.3f px, glints %d/%d (max err %.2f px)\n",
               i, (double)s.yaw_deg, (double)s.pitch_deg, (double)s.pupil_mm, (double)e.pupil_err, e.glints_matched,
               e.glints_visible, (double)e.glint_max_err);
        assert_true(e.pupil_err < 1.0f);
    }
    const float med = median(err, N);
    printf("[ eyetrack ] clean frames: median pupil error %.3f px (bound 0.5), glints found %d of %d visible\n",
           (double)med, matched, vis);
    assert_true(med < 0.5f);
    assert_true(vis > 0);
    assert_true(matched * 10 >= vis * 9); /* >= 90% of the visible glints within 1 px */
    fv_eye_destroy(t);
    free(img);
}

static void test_synthetic_noisy(void **state)
{
    (void)state;
    rng = 0x3333ull; /* each test its own draws, whatever runs before it */
    fv_synth_params p;
    fv_synth_default_params(&p, W, H);
    p.supersample = 2;
    uint8_t *img = malloc(W * H);
    fv_eye_tracker *t = fv_eye_create(NULL, FV_EYE_MODE_HEADSET);
    enum { N = 9 };
    float err[N];
    for (int i = 0; i < N; i++) {
        /* heavy noise, low contrast (dim), lids half over the pupil on every third frame */
        p.noise_sigma = 6.0f + 4.0f * (i % 3);
        p.brightness = i % 2 ? 0.55f : 1.0f;
        /* every third frame looks up into a half-closed lid: part of the pupil is covered */
        const int lid = i % 3 == 2;
        const fv_synth_state s = { -15.0f + 30.0f * rnd(), lid ? 5.0f + 6.0f * rnd() : -8.0f + 16.0f * rnd(),
                                   1.8f + 0.8f * rnd(), lid ? 0.5f : 1.0f };
        fv_synth_truth gt;
        fv_synth_truth_of(&p, &s, &gt);
        const frame_eval e = eval_frame(t, &p, &s, 100u + (uint64_t)i, 0, img);
        err[i] = e.pupil_err;
        printf("[ eyetrack ] noisy %d: gaze (%.1f, %.1f) pupil %.2f mm sigma %.0f brightness %.2f open %.1f (pupil %.0f%% "
               "visible): error %.3f px\n",
               i, (double)s.yaw_deg, (double)s.pitch_deg, (double)s.pupil_mm, (double)p.noise_sigma,
               (double)p.brightness, (double)s.open, 100.0 * gt.pupil_visible, (double)e.pupil_err);
        assert_true(e.found);
        /* stated bounds per frame: 3 px with the whole pupil in view, 8 px when the lid covers
         * part of it (with sigma 14 and dim light the lid's shadow merges with the pupil) */
        assert_true(e.pupil_err < (gt.pupil_visible >= 0.99f ? 3.0f : 8.0f));
    }
    const float med = median(err, N);
    printf("[ eyetrack ] noisy frames: median pupil error %.3f px (bound 1.0)\n", (double)med);
    assert_true(med < 1.0f);
    fv_eye_destroy(t);
    free(img);
}

/* Pupils partly under the upper lid, and fully in view, over the seeded "lid set" of poses a
 * headset sees (fv_synth_lid_set_frame: gaze +-20 deg, pupil 1.6-2.8 mm, 2-6 LEDs, sensor noise
 * 2-14 grey levels, brightness 0.55-1; every other frame looks up 3-13 deg into a lid opened
 * 0.35-0.65). Stated bounds per visibility bin (measured when written, 320x240: full view median
 * 0.12 px, p90 0.29 px; 70-99% in view median 0.66 px, 78% within 3 px; 50-70% median 4.0 px,
 * printed, not bounded). The tracker before the lid work (no lid line, no gradient support,
 * edges at a level's crossing) scored p90 1.49 px in full view and median 2.45 px, 53% within
 * 3 px under the lid: these bounds fail it. */
static void test_partial_occlusion(void **state)
{
    (void)state;
    uint64_t set = 1; /* = build/tools/eval_eye --frames 160 */
    fv_synth_params p;
    fv_synth_default_params(&p, W, H);
    p.supersample = 2;
    uint8_t *img = malloc(W * H);
    fv_eye_tracker *t = fv_eye_create(NULL, FV_EYE_MODE_HEADSET);
    assert_non_null(img);
    assert_non_null(t);
    enum { N = 160 };
    float full[N], lid[N], deep[N];
    int nf = 0, nl = 0, nd = 0;
    for (int i = 0; i < N; i++) {
        fv_synth_state s;
        fv_synth_lid_set_frame(&set, i, &p, &s);
        fv_synth_truth gt;
        fv_synth_truth_of(&p, &s, &gt);
        const frame_eval e = eval_frame(t, &p, &s, 1000u + (uint64_t)i, 0, img);
        const float err = e.found ? e.pupil_err : 1e3f;
        if (gt.pupil_visible >= 0.99f)
            full[nf++] = err;
        else if (gt.pupil_visible >= 0.7f)
            lid[nl++] = err;
        else if (gt.pupil_visible >= 0.5f)
            deep[nd++] = err;
    }
    float *bins[3] = { full, lid, deep };
    const int counts[3] = { nf, nl, nd };
    const char *names[3] = { "full view", "70-99% in view", "50-70% in view" };
    float med[3], p90[3], in3[3];
    for (int b = 0; b < 3; b++) {
        assert_true(counts[b] >= 10);
        int k = 0;
        for (int i = 0; i < counts[b]; i++)
            k += bins[b][i] <= 3.0f;
        in3[b] = (float)k / (float)counts[b];
        med[b] = median(bins[b], counts[b]); /* sorts */
        p90[b] = bins[b][counts[b] * 9 / 10];
        printf("[ eyetrack ] lid set, %-14s %3d frames: median error %.2f px, p90 %.2f px, max %.2f px, %.0f%% within 3 px\n",
               names[b], counts[b], (double)med[b], (double)p90[b], (double)bins[b][counts[b] - 1], 100.0 * in3[b]);
    }
    assert_true(med[0] < 0.3f && p90[0] < 0.6f);
    assert_true(med[1] < 1.5f && in3[1] >= 0.7f);
    fv_eye_destroy(t);
    free(img);
}

/* The same poses through spectacles (fv_synth_specs_set_frame: LED reflections on the lens that
 * do not move with the eye, tint, a dark rim crossing the image): the rim is not taken for the
 * pupil (the sides test of the search; before it 57.7 % of the eval_eye set was within 5 px, the
 * rim winning most misses) and a lens reflection is rarely taken for a corneal glint (area). Set of
 * build/tools/eval_eye --specs --frames 160. */
static void test_spectacles(void **state)
{
    (void)state;
    uint64_t set = 1;
    fv_synth_params p;
    fv_synth_default_params(&p, W, H);
    p.supersample = 2;
    uint8_t *img = malloc(W * H);
    fv_eye_tracker *t = fv_eye_create(NULL, FV_EYE_MODE_HEADSET);
    int n = 0, w5 = 0, far = 0, glint_big = 0, glints = 0;
    for (int i = 0; i < 160; i++) {
        fv_synth_state s;
        fv_synth_specs_set_frame(&set, i, &p, &s);
        fv_synth_truth gt;
        fv_synth_render(&p, &s, 1000u + (uint64_t)i, img, W, &gt);
        if (gt.pupil_visible < 0.5f)
            continue;
        fv_eye_result r;
        assert_int_equal(fv_track_image(t, img, W, H, W, &r), 0);
        const float e = r.found && r.status == FV_EYE_OK ? hypotf(r.pupil_x - gt.pupil_x, r.pupil_y - gt.pupil_y) : 1e3f;
        n++, w5 += e <= 5.0f, far += e > 30.0f;
        /* a glint kept must not be a lens reflection (its centre within the reflection's disc) */
        for (int k = 0; k < r.n_glints && e <= 3.0f; k++, glints++)
            for (int j = 0; j < p.n_leds; j++) {
                float rx, ry, rr;
                fv_synth_specs_reflection(&p, j, &rx, &ry, &rr);
                if (hypotf(r.glints[k].x - rx, r.glints[k].y - ry) < rr) {
                    glint_big++;
                    break;
                }
            }
    }
    printf("[ eyetrack ] spectacles: %d frames, %.1f%% within 5 px, %d more than 30 px off (a rim or a reflection), "
           "%d of %d glints kept are lens reflections\n",
           n, 100.0 * w5 / n, far, glint_big, glints);
    assert_true(n >= 120);
    assert_true(w5 >= 0.82 * n);
    assert_true(far <= 0.06 * n);
    assert_true(glint_big <= glints / 50);
    fv_eye_destroy(t);
    free(img);
}

/* An MRL-like crop through spectacles (crop mode): bright skin above a dark brow, the frame's
 * bright rim under it, and below the rim the eye behind a tinted lens: a pupil only 5-9 grey
 * levels darker than its iris. The brow's box has a far brighter ring than the pupil's (the
 * forehead and the rim); before the crop mode clipped bright pixels and refused bands it won
 * every crop here. Pupil, brow height, rim brightness and noise vary over 12 crops; the
 * reported centre must be within 3 px of the pupil's (the crop mode reports a box centre put on
 * a pixel centre and moved 5 % toward the crop's centre: 1-2 px by construction). */
static void crop_specs_image(uint8_t *img, int w, int h, float px, float py, int brow_y, int rim, int pupil_dark,
                             uint64_t *seed)
{
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float v;
            if (y < brow_y)
                v = 88.0f; /* forehead */
            else if (y < brow_y + 12)
                v = 46.0f; /* brow, across the whole crop */
            else if (y < brow_y + 16)
                v = 70.0f;
            else if (y < brow_y + 19)
                v = (float)rim; /* the frame's rim */
            else {          /* behind the lens */
                const float d = hypotf((float)x + 0.5f - px, (float)y + 0.5f - py);
                v = d < 5.0f ? 52.0f - (float)pupil_dark : d < 11.0f ? 52.0f : 58.0f;
            }
            v += 2.0f * (fv_test_randf(seed) + fv_test_randf(seed) - 1.0f);
            img[(size_t)y * w + x] = (uint8_t)lrintf(v);
        }
}

static void test_crop_spectacles(void **state)
{
    (void)state;
    enum { CW = 90, CH = 96 };
    uint8_t img[CW * CH];
    uint64_t seed = 77;
    fv_eye_tracker *t = fv_eye_create(NULL, FV_EYE_MODE_CROP);
    int ok = 0;
    float worst = 0.0f;
    for (int i = 0; i < 12; i++) {
        const float px = 38.0f + 2.0f * (float)(i % 6), py = 62.0f + (float)(i % 4);
        const int brow_y = 10 + i % 5, rim = 110 + 10 * (i % 3), dark = 5 + i % 5;
        crop_specs_image(img, CW, CH, px, py, brow_y, rim, dark, &seed);
        fv_eye_result r;
        assert_int_equal(fv_track_image(t, img, CW, CH, CW, &r), 0);
        const float e = r.found ? hypotf(r.pupil_x - px, r.pupil_y - py) : INFINITY;
        worst = fmaxf(worst, e);
        ok += e <= 3.0f;
    }
    printf("[ eyetrack ] crops through spectacles: %d of 12 within 3 px of the pupil, worst %.1f px\n", ok, worst);
    assert_int_equal(ok, 12);
    fv_eye_destroy(t);
}

/* The MRL glasses crops' commonest miss (docs/eyetrack.md, "A reflection beside the box"): behind
 * a tinted lens the pupil is hardly darker than its iris, and a wider patch beside it (the iris's
 * shadowed side, a darker part of the lens) wins the box search although the corneal reflection
 * sits on the pupil. Drawn: skin 56, iris 51 (radius 13), pupil 47 (radius 4.5) with a 2x2
 * reflection of 100 just above its centre, a patch of 45 (radius 5) 9 px to its left, noise; 12
 * pupil positions. With the reflection every answer must be within 3 px of the pupil (before the
 * spot rule: 0 of 12, all ~9 px off on the patch); without it the patch still wins (the rule
 * acts on a reflection, not on darkness). */
static void crop_beside_image(uint8_t *img, int w, int h, float px, float py, int reflection, uint64_t *seed)
{
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float X = (float)x + 0.5f, Y = (float)y + 0.5f;
            const float d = hypotf(X - px, Y - py), dp = hypotf(X - (px - 9.0f), Y - (py + 1.0f));
            float v = d < 4.5f ? 47.0f : dp < 5.0f ? 45.0f : d < 13.0f ? 51.0f : 56.0f;
            if (reflection && fabsf(X - (px + 1.0f)) < 1.0f && fabsf(Y - (py - 3.0f)) < 1.0f)
                v = 100.0f;
            v += 2.0f * (fv_test_randf(seed) + fv_test_randf(seed) - 1.0f);
            img[(size_t)y * w + x] = (uint8_t)lrintf(v);
        }
}

static void test_crop_reflection_beside(void **state)
{
    (void)state;
    enum { CW = 88, CH = 88 };
    uint8_t img[CW * CH];
    uint64_t seed = 5;
    fv_eye_tracker *t = fv_eye_create(NULL, FV_EYE_MODE_CROP);
    for (int refl = 1; refl >= 0; refl--) {
        int on_pupil = 0, on_patch = 0;
        float worst = 0.0f;
        for (int i = 0; i < 12; i++) {
            const float px = 42.5f + (float)(i % 4), py = 45.0f + (float)(i % 3);
            crop_beside_image(img, CW, CH, px, py, refl, &seed);
            fv_eye_result r;
            assert_int_equal(fv_track_image(t, img, CW, CH, CW, &r), 0);
            assert_true(r.found);
            const float e = hypotf(r.pupil_x - px, r.pupil_y - py);
            worst = fmaxf(worst, e);
            on_pupil += e <= 3.0f;
            on_patch += hypotf(r.pupil_x - (px - 9.0f), r.pupil_y - (py + 1.0f)) <= 3.0f;
        }
        printf("[ eyetrack ] darker patch beside the pupil, reflection %s: %d of 12 within 3 px of the pupil "
               "(worst %.1f px), %d on the patch\n", refl ? "on the pupil" : "none", on_pupil, (double)worst, on_patch);
        assert_int_equal(refl ? on_pupil : on_patch, 12);
    }
    fv_eye_destroy(t);
}

/* A tinted lens scales the pupil's contrast by its transmission (~0.7): a pupil 2.5 grey levels
 * darker than its surround (pixels alternately 2 and 3 darker) is reported in crop mode
 * (threshold 2) and lost in headset mode (3); 1.5 is lost in both, 3.5 found in both. */
static void test_low_contrast_lost(void **state)
{
    (void)state;
    enum { CW = 80, CH = 80 };
    uint8_t img[CW * CH];
    const int lo[3] = { 1, 2, 3 };              /* the pupil's pixels: lo or lo + 1 darker */
    const int want_crop[3] = { 0, 1, 1 }, want_headset[3] = { 0, 0, 1 };
    for (int k = 0; k < 3; k++) {
        for (int y = 0; y < CH; y++)
            for (int x = 0; x < CW; x++)
                img[y * CW + x] = hypotf((float)x + 0.5f - 40.0f, (float)y + 0.5f - 40.0f) < 7.0f
                                      ? (uint8_t)(60 - lo[k] - ((x + y) & 1))
                                      : 60;
        fv_eye_result rc, rh;
        fv_eye_tracker *tc = fv_eye_create(NULL, FV_EYE_MODE_CROP), *th = fv_eye_create(NULL, FV_EYE_MODE_HEADSET);
        assert_int_equal(fv_track_image(tc, img, CW, CH, CW, &rc), 0);
        assert_int_equal(fv_track_image(th, img, CW, CH, CW, &rh), 0);
        printf("[ eyetrack ] pupil %d.5 grey levels dark: crop found %d (contrast %.2f), headset found %d (contrast %.2f)\n",
               lo[k], rc.found, (double)rc.contrast, rh.found, (double)rh.contrast);
        assert_int_equal(rc.found, want_crop[k]);
        assert_int_equal(rh.found, want_headset[k]);
        if (rc.found)
            assert_true(hypotf(rc.pupil_x - 40.0f, rc.pupil_y - 40.0f) <= 2.0f);
        fv_eye_destroy(tc);
        fv_eye_destroy(th);
    }
}

static void test_blinks(void **state)
{
    (void)state;
    fv_synth_params p;
    fv_synth_default_params(&p, W, H);
    p.supersample = 1;
    uint8_t *img = malloc(W * H);
    fv_eye_tracker *t = fv_eye_create(NULL, FV_EYE_MODE_HEADSET);
    /* open, closing, closed, opening, open */
    static const float open[] = { 1, 1, 1, 1, 0.3f, 0.0f, 0.0f, 0.0f, 0.3f, 1, 1 };
    const int n = (int)(sizeof open / sizeof open[0]);
    for (int i = 0; i < n; i++) {
        const fv_synth_state s = { 5.0f, -3.0f, 2.2f, open[i] };
        const frame_eval e = eval_frame(t, &p, &s, 200u + (uint64_t)i, 1, img);
        printf("[ eyetrack ] blink sequence %d: open %.1f -> status %d error %.2f\n", i, (double)open[i], e.status,
               (double)e.pupil_err);
        if (open[i] == 0.0f)
            assert_int_not_equal(e.status, FV_EYE_OK); /* flagged as blink / lost */
        if (open[i] == 1.0f) {
            assert_int_equal(e.status, FV_EYE_OK);
            assert_true(e.pupil_err < 1.0f);
        }
    }
    /* without history a closed eye still gives no confident pupil */
    fv_eye_reset(t);
    const fv_synth_state closed = { 0, 0, 2.2f, 0.0f };
    fv_synth_truth gt;
    fv_synth_render(&p, &closed, 7, img, W, &gt);
    fv_eye_result r;
    assert_int_equal(fv_track_image(t, img, W, H, W, &r), 0);
    printf("[ eyetrack ] closed eye, no history: found %d confidence %.2f\n", r.found, (double)r.confidence);
    fv_eye_destroy(t);
    free(img);
}

static void test_bad_args(void **state)
{
    (void)state;
    fv_eye_tracker *t = fv_eye_create(NULL, FV_EYE_MODE_AUTO);
    uint8_t img[64 * 64];
    memset(img, 128, sizeof img);
    fv_eye_result r;
    assert_int_equal(fv_track_frame(t, NULL, 64, 64, 64, &r), -1);
    assert_int_equal(fv_track_frame(t, img, 4, 64, 64, &r), -1);
    assert_int_equal(fv_track_frame(t, img, 64, 64, 32, &r), -1);
    /* a flat grey image: no pupil */
    assert_int_equal(fv_track_frame(t, img, 64, 64, 64, &r), 0);
    assert_int_equal(r.found, 0);
    assert_true(r.confidence == 0.0f);
    fv_eye_destroy(t);
    fv_eye_destroy(NULL);
}

/* Odd sizes, strides, unaligned rows and degenerate content: no crash, no read outside the
 * rows given (the buffer is exact-size: ASan would see it), results inside the image. */
static void test_robustness(void **state)
{
    (void)state;
    rng = 0x4444ull; /* each test its own draws, whatever runs before it */
    static const int sz[][2] = { { 8, 8 }, { 8, 300 }, { 300, 8 }, { 17, 13 }, { 161, 99 }, { 97, 161 }, { 640, 480 } };
    fv_eye_tracker *ts[3]; /* every mode on every size */
    for (int m = 0; m < 3; m++)
        ts[m] = fv_eye_create(NULL, (fv_eye_mode)m);
    for (size_t k = 0; k < sizeof sz / sizeof sz[0]; k++) {
        const int w = sz[k][0], h = sz[k][1];
        const ptrdiff_t stride = w + 3;
        for (int content = 0; content < 5; content++) {
            const size_t bytes = (size_t)stride * (size_t)(h - 1) + (size_t)w + 1;
            uint8_t *buf = malloc(bytes), *img = buf + 1; /* odd address, exact size */
            assert_non_null(buf);
            for (int y = 0; y < h; y++)
                for (int x = 0; x < stride && (size_t)(y * stride + x) < bytes - 1; x++) {
                    const uint64_t r = fv_test_rand(&rng);
                    img[y * stride + x] = content == 0 ? 0 : content == 1 ? 255 : content == 2 ? (uint8_t)r
                                          : content == 3 ? (uint8_t)(x + y) : ((x / 3 + y / 3) & 1 ? 255 : 0);
                }
            fv_eye_result r;
            for (int run = 0; run < 6; run++) {
                fv_eye_tracker *t = ts[run / 2];
                assert_int_equal((run % 2 ? fv_track_frame : fv_track_image)(t, img, w, h, stride, &r), 0);
                assert_int_equal(r.mode, fv_eye_resolve_mode((fv_eye_mode)(run / 2), w, h));
                assert_true(r.confidence >= 0.0f && r.confidence <= 1.0f);
                assert_true(r.n_glints >= 0 && r.n_glints <= FV_EYE_MAX_GLINTS);
                if (r.found)
                    assert_true(r.pupil_x >= 0 && r.pupil_x <= w && r.pupil_y >= 0 && r.pupil_y <= h);
                if (content < 2) /* flat: nothing to find */
                    assert_int_equal(r.found, 0);
            }
            free(buf);
        }
    }
    for (int m = 0; m < 3; m++)
        fv_eye_destroy(ts[m]);
}

/* ------------------------------------------------------------------ modes */

/* Tracks one clean synthetic frame of w x h in mode m; the result, its error against the truth
 * and the true pupil radius (pixels). */
static fv_eye_result track_synth(fv_eye_mode m, int w, int h, float *err, float *r_px)
{
    fv_synth_params p;
    fv_synth_default_params(&p, w, h);
    p.noise_sigma = 0;
    p.supersample = 2;
    const fv_synth_state s = { 6.0f, -4.0f, 2.2f, 1.0f };
    uint8_t *img = malloc((size_t)w * h);
    assert_non_null(img);
    fv_synth_truth gt;
    fv_synth_render(&p, &s, 7u, img, w, &gt);
    fv_eye_tracker *t = fv_eye_create(NULL, m);
    assert_non_null(t);
    fv_eye_result r;
    assert_int_equal(fv_track_image(t, img, w, h, w, &r), 0);
    fv_eye_destroy(t);
    free(img);
    *err = r.found ? hypotf(r.pupil_x - gt.pupil_x, r.pupil_y - gt.pupil_y) : INFINITY;
    *r_px = gt.pupil_r_px;
    return r;
}

/* AUTO is the size rule from before there were modes (crop up to a short side of 160 px,
 * headset above) and tracks exactly as the mode it picks; explicit modes ignore the size. */
static void test_mode_auto(void **state)
{
    (void)state;
    static const int sz[][3] = { { 8, 8, FV_EYE_MODE_CROP },        { 160, 120, FV_EYE_MODE_CROP },
                                 { 160, 4000, FV_EYE_MODE_CROP },   { 4000, 160, FV_EYE_MODE_CROP },
                                 { 161, 161, FV_EYE_MODE_HEADSET }, { 161, 4000, FV_EYE_MODE_HEADSET },
                                 { 640, 480, FV_EYE_MODE_HEADSET } };
    for (size_t k = 0; k < sizeof sz / sizeof sz[0]; k++) {
        const int w = sz[k][0], h = sz[k][1];
        assert_int_equal(fv_eye_resolve_mode(FV_EYE_MODE_AUTO, w, h), sz[k][2]);
        assert_int_equal(fv_eye_resolve_mode(FV_EYE_MODE_HEADSET, w, h), FV_EYE_MODE_HEADSET);
        assert_int_equal(fv_eye_resolve_mode(FV_EYE_MODE_CROP, w, h), FV_EYE_MODE_CROP);
    }
    /* either side of the threshold, AUTO's result is the picked mode's to the bit (the result
     * struct has no padding; the tracker zeroes it first) */
    static const int fr[][3] = { { 160, 120, FV_EYE_MODE_CROP }, { 168, 162, FV_EYE_MODE_HEADSET } };
    for (int k = 0; k < 2; k++) {
        float ea, ep, rad;
        const fv_eye_result ra = track_synth(FV_EYE_MODE_AUTO, fr[k][0], fr[k][1], &ea, &rad);
        const fv_eye_result rp = track_synth((fv_eye_mode)fr[k][2], fr[k][0], fr[k][1], &ep, &rad);
        assert_int_equal(ra.mode, fr[k][2]);
        assert_true(ra.found);
        assert_memory_equal(&ra, &rp, sizeof ra);
    }
}

/* An explicit mode is honoured whatever the size: a crop-sized frame in headset mode takes the
 * headset path (an ellipse fit, sub-pixel), a headset-sized one in crop mode the crop path (the
 * box's centre on a pixel centre, pulled toward a glint: on a headset frame it is only
 * inside the pupil, which is why headset cameras want headset mode). */
static void test_mode_explicit(void **state)
{
    (void)state;
    float e, rad;
    fv_eye_result r = track_synth(FV_EYE_MODE_HEADSET, 160, 120, &e, &rad);
    printf("[ eyetrack ] 160x120 in headset mode: error %.3f px, ellipse %d\n", (double)e, r.ellipse_fit);
    assert_int_equal(r.mode, FV_EYE_MODE_HEADSET);
    assert_int_equal(r.ellipse_fit, 1);
    assert_true(e < 0.5f);
    float ec;
    const fv_eye_result rc = track_synth(FV_EYE_MODE_CROP, 160, 120, &ec, &rad);
    assert_int_equal(rc.mode, FV_EYE_MODE_CROP);
    assert_int_equal(rc.ellipse_fit, 0);
    assert_true(r.pupil_x != rc.pupil_x || r.pupil_y != rc.pupil_y);

    r = track_synth(FV_EYE_MODE_CROP, 320, 240, &e, &rad);
    printf("[ eyetrack ] 320x240 in crop mode: error %.3f px, pupil radius %.1f px\n", (double)e, (double)rad);
    assert_int_equal(r.mode, FV_EYE_MODE_CROP);
    assert_true(r.found);
    assert_int_equal(r.ellipse_fit, 0);
    assert_true(r.pupil_x - floorf(r.pupil_x) == 0.5f && r.pupil_y - floorf(r.pupil_y) == 0.5f);
    assert_true(e < rad);
    assert_true(r.pupil_a_px > 0);
}

/* The crop mode's settings are the ones tuned on the MRL crops (docs/eyetrack.md); the names
 * round-trip. */
static void test_mode_settings(void **state)
{
    (void)state;
    const fv_eye_mode_settings *c = fv_eye_mode_get_settings(FV_EYE_MODE_CROP);
    assert_ptr_equal(c, &fv_eye_crop_settings);
    assert_int_equal(c->mode, FV_EYE_MODE_CROP);
    assert_true(c->centre_weight == 0.05f);
    assert_true(c->glint_weight == 0.3f);
    assert_int_equal(c->spot_min_grey, 20);
    assert_int_equal(c->report_box_centre, 1);
    assert_int_equal(c->refine_on_search_image, 1);
    assert_int_equal(c->centroid_iters, 2);
    assert_true(c->min_aspect == 0.3);
    assert_int_equal(c->ransac_iters, 0);
    assert_int_equal(c->search_sides, 1); /* spectacles: the relaxed sides test, clipping, tint */
    assert_true(c->sides_frac == 0.3f && c->sides_min_grey == 3.0f);
    assert_int_equal(c->search_clip_grey, 20);
    assert_true(c->lost_contrast == 2.0f);
    const fv_eye_mode_settings *hs = fv_eye_mode_get_settings(FV_EYE_MODE_HEADSET);
    assert_ptr_equal(hs, &fv_eye_headset_settings);
    assert_int_equal(hs->mode, FV_EYE_MODE_HEADSET);
    assert_int_equal(hs->report_box_centre, 0);
    assert_true(hs->centre_weight == 0.0f && hs->glint_weight == 0.0f);
    assert_int_equal(hs->refine_max_side, 320);
    assert_int_equal(hs->ransac_iters, 64);
    assert_true(hs->min_aspect == 0.6);
    assert_int_equal(hs->search_sides, 1);
    assert_true(hs->sides_frac == 0.5f && hs->sides_min_grey == 10.0f);
    assert_int_equal(hs->search_clip_grey, 0);
    assert_true(hs->lost_contrast == 3.0f);
    assert_null(fv_eye_mode_get_settings(FV_EYE_MODE_AUTO));
    static const char *names[] = { "auto", "headset", "crop" };
    for (int m = 0; m < 3; m++) {
        fv_eye_mode got = FV_EYE_MODE_CROP;
        assert_string_equal(fv_eye_mode_name((fv_eye_mode)m), names[m]);
        assert_int_equal(fv_eye_mode_parse(names[m], &got), 0);
        assert_int_equal(got, m);
    }
    fv_eye_mode got = FV_EYE_MODE_HEADSET;
    assert_int_equal(fv_eye_mode_parse("Crop", &got), -1);
    assert_int_equal(fv_eye_mode_parse("", &got), -1);
    assert_int_equal(fv_eye_mode_parse(NULL, &got), -1);
    assert_int_equal(got, FV_EYE_MODE_HEADSET);
    assert_null(fv_eye_mode_name((fv_eye_mode)7));
    /* an unknown mode at creation falls back to AUTO */
    fv_eye_tracker *t = fv_eye_create(NULL, (fv_eye_mode)7);
    assert_non_null(t);
    uint8_t img[64 * 64];
    memset(img, 128, sizeof img);
    fv_eye_result r;
    assert_int_equal(fv_track_image(t, img, 64, 64, 64, &r), 0);
    assert_int_equal(r.mode, FV_EYE_MODE_CROP);
    fv_eye_destroy(t);
}

/* ------------------------------------------------------------------ calibration */

static void poly(const double a[6], double u, double v, double *out)
{
    *out = a[0] + a[1] * u + a[2] * v + a[3] * u * v + a[4] * u * u + a[5] * v * v;
}

static void test_calib_recovers_polynomial(void **state)
{
    (void)state;
    rng = 0x5555ull; /* each test its own draws, whatever runs before it */
    /* a known mapping from the input (pixels) to gaze (deg), in the normalised terms */
    const double A[6] = { 1.5, 18.0, -0.7, 0.9, -1.2, 0.4 }, B[6] = { -2.0, 0.5, -12.0, 0.3, 0.8, -1.1 };
    enum { N = 27 };
    float ix[N], iy[N], yaw[N], pitch[N];
    for (int i = 0; i < N; i++) { /* 3x3 grid, 3 jittered samples per point */
        ix[i] = 100.0f + 12.0f * (float)(i % 3 - 1) + (rnd() - 0.5f);
        iy[i] = 80.0f + 9.0f * (float)((i / 3) % 3 - 1) + (rnd() - 0.5f);
    }
    fv_calib c;
    /* the fit's normalisation is computed from the inputs: evaluate the truth with the same */
    double mx = 0, my = 0, s = 0;
    for (int i = 0; i < N; i++)
        mx += ix[i], my += iy[i];
    mx /= N, my /= N;
    for (int i = 0; i < N; i++)
        s = fmax(s, fmax(fabs(ix[i] - mx), fabs(iy[i] - my)));
    for (int i = 0; i < N; i++) {
        double g;
        poly(A, (ix[i] - mx) / s, (iy[i] - my) / s, &g);
        yaw[i] = (float)g;
        poly(B, (ix[i] - mx) / s, (iy[i] - my) / s, &g);
        pitch[i] = (float)g;
    }
    float res[N];
    assert_int_equal(fv_calib_fit(&c, FV_CALIB_PUPIL_GLINT, ix, iy, yaw, pitch, N, res), 0);
    for (int k = 0; k < 6; k++) {
        if (fabs(c.a[k] - A[k]) > 1e-3 || fabs(c.b[k] - B[k]) > 1e-3)
            fail_msg("coefficient %d: got %g %g, want %g %g", k, c.a[k], c.b[k], A[k], B[k]);
    }
    printf("[ eyetrack ] calibration on an exact polynomial: rms %.2e deg, max %.2e deg\n", c.rms_deg, c.max_deg);
    assert_true(c.rms_deg < 1e-3);
    /* one gross outlier (a blink frame's junk) is dropped and the mapping still recovered */
    yaw[5] += 20.0f;
    assert_int_equal(fv_calib_fit(&c, FV_CALIB_PUPIL_GLINT, ix, iy, yaw, pitch, N, res), 0);
    assert_int_equal(c.n_used, N - 1);
    assert_true(res[5] > 10.0f);
    for (int k = 0; k < 6; k++)
        assert_true(fabs(c.a[k] - A[k]) < 1e-3 && fabs(c.b[k] - B[k]) < 1e-3);
    /* degenerate: all inputs on a line cannot determine 6 coefficients */
    for (int i = 0; i < N; i++)
        iy[i] = ix[i];
    assert_int_equal(fv_calib_fit(&c, FV_CALIB_PUPIL, ix, iy, yaw, pitch, N, NULL), -1);
    assert_int_equal(fv_calib_fit(&c, FV_CALIB_PUPIL, ix, iy, yaw, pitch, 5, NULL), -1);
    /* angles: 90 degrees between straight ahead and yaw 90; small angles accurate */
    assert_true(fabs(fv_gaze_angle_deg(0, 0, 90, 0) - 90) < 1e-9);
    assert_true(fabs(fv_gaze_angle_deg(10, 0, 10, 0.001) - 0.001) < 1e-9);
    float ty[9], tp[9];
    fv_calib_targets_3x3(15, 10, ty, tp);
    assert_true(ty[0] == -15 && tp[0] == 10 && ty[4] == 0 && tp[4] == 0 && ty[8] == 15 && tp[8] == -10);
}

static void test_calib_file(void **state)
{
    (void)state;
    fv_calib c = { 0 }, d;
    c.input = FV_CALIB_PUPIL;
    c.u0 = 1.25, c.v0 = -3.5, c.s = 7.0;
    for (int k = 0; k < 6; k++)
        c.a[k] = 0.1 * k - 0.3, c.b[k] = 1.0 / (k + 3);
    c.rms_deg = 0.25, c.max_deg = 0.5, c.n_used = 9;
    char path[] = "/tmp/fovea_calib_XXXXXX";
    const int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    char err[256];
    assert_int_equal(fv_calib_save(&c, path, err, sizeof err), 0);
    assert_int_equal(fv_calib_load(&d, path, err, sizeof err), 0);
    assert_int_equal(d.input, c.input);
    assert_memory_equal(d.a, c.a, sizeof c.a); /* %.17g round-trips exactly */
    assert_memory_equal(d.b, c.b, sizeof c.b);
    assert_true(d.u0 == c.u0 && d.v0 == c.v0 && d.s == c.s && d.n_used == 9);
    static const struct { const char *text, *want; } bad[] = {
        { "", "missing 'fovea-calibration 1'" },
        { "fovea-calibration 2\n", "line 1: expected 'fovea-calibration 1'" },
        { "fovea-calibration 1\ninput eye\n", "line 2: input must be" },
        { "fovea-calibration 1\ninput pupil\nnorm 1 2 0\n", "line 3: norm needs" },
        { "fovea-calibration 1\ninput pupil\nnorm 1 2 3\nyaw_deg 1 2 3 4 5\n", "line 4: yaw_deg needs 6 numbers" },
        { "fovea-calibration 1\ninput pupil\nnorm 1 2 3\nyaw_deg 1 2 3 4 5 6\n", "missing pitch_deg" },
        { "fovea-calibration 1\nbogus 1\n", "line 2: unknown key 'bogus'" },
        /* values checked at the type they are used in (an int, a float gaze), not only as finite doubles */
        { "fovea-calibration 1\nsamples 1e300\n", "line 2: samples 1e+300 out of range" },
        { "fovea-calibration 1\nsamples 2.5\n", "line 2: samples 2.5 out of range" },
        { "fovea-calibration 1\nsamples -1\n", "line 2: samples -1 out of range" },
        { "fovea-calibration 1\nrms_deg 1e40\n", "line 2: rms_deg 1e+40 out of range" },
        { "fovea-calibration 1\ninput pupil\nnorm 1e300 2 3\n", "line 3: norm 1e+300 2 3 out of range" },
        { "fovea-calibration 1\ninput pupil\nnorm 1 2 3\nyaw_deg 1 2 3 4 5 1e39\n", "line 4: yaw_deg coefficient 6" },
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(fv_calib_parse(&d, bad[i].text, err, sizeof err), -1);
        if (!strstr(err, bad[i].want))
            fail_msg("parse error '%s' lacks '%s'", err, bad[i].want);
    }
    FILE *f = fopen(path, "w");
    fputs("fovea-calibration 1\ninput pupil\nnorm x\n", f);
    fclose(f);
    assert_int_equal(fv_calib_load(&d, path, err, sizeof err), -1);
    assert_non_null(strstr(err, path));
    assert_non_null(strstr(err, "line 3"));
    unlink(path);
    assert_int_equal(fv_calib_load(&d, path, err, sizeof err), -1);
    assert_non_null(strstr(err, "No such file"));
}

/* ------------------------------------------------------------------ end to end */

static void test_end_to_end(void **state)
{
    (void)state;
    rng = 0x6666ull; /* each test its own draws, whatever runs before it */
    fv_synth_params p;
    fv_synth_default_params(&p, W, H);
    p.supersample = 2;
    p.noise_sigma = 3.0f;
    uint8_t *img = malloc(W * H);
    fv_eye_tracker *t = fv_eye_create(NULL, FV_EYE_MODE_HEADSET);
    /* calibration: the 3x3 targets, 2 frames each, pupil size drifting */
    enum { PER = 2, NC = 9 * PER, NT = 12 };
    float ty[9], tp[9], gx[NC], gy[NC], px[NC], py[NC], yaw[NC], pitch[NC];
    fv_calib_targets_3x3(18.0f, 12.0f, ty, tp);
    int ng = 0, np = 0;
    float gyaw[NC], gpitch[NC];
    for (int i = 0; i < NC; i++) {
        const fv_synth_state s = { ty[i / PER], tp[i / PER], 2.0f + 0.3f * sinf((float)i), 1.0f };
        fv_synth_truth gt;
        fv_synth_render(&p, &s, 300u + (uint64_t)i, img, W, &gt);
        fv_eye_result r;
        assert_int_equal(fv_track_image(t, img, W, H, W, &r), 0);
        assert_true(r.found);
        px[np] = r.pupil_x, py[np] = r.pupil_y, yaw[np] = s.yaw_deg, pitch[np] = s.pitch_deg, np++;
        if (r.has_pg)
            gx[ng] = r.pg_x, gy[ng] = r.pg_y, gyaw[ng] = s.yaw_deg, gpitch[ng] = s.pitch_deg, ng++;
    }
    fv_calib cg, cp;
    assert_true(ng >= 12);
    assert_int_equal(fv_calib_fit(&cg, FV_CALIB_PUPIL_GLINT, gx, gy, gyaw, gpitch, ng, NULL), 0);
    assert_int_equal(fv_calib_fit(&cp, FV_CALIB_PUPIL, px, py, yaw, pitch, np, NULL), 0);
    printf("[ eyetrack ] calibration residuals: pupil-glint rms %.3f max %.3f deg (%d samples); pupil only rms %.3f max %.3f deg\n",
           cg.rms_deg, cg.max_deg, ng, cp.rms_deg, cp.max_deg);
    /* test gazes inside the calibrated range, different pupil sizes and noise */
    float eg[NT], ep[NT];
    int ne = 0;
    for (int i = 0; i < NT; i++) {
        const fv_synth_state s = { -16.0f + 32.0f * rnd(), -10.0f + 20.0f * rnd(), 1.8f + 0.8f * rnd(), 1.0f };
        fv_synth_truth gt;
        fv_synth_render(&p, &s, 400u + (uint64_t)i, img, W, &gt);
        fv_eye_result r;
        assert_int_equal(fv_track_image(t, img, W, H, W, &r), 0);
        assert_true(r.found);
        float a, b;
        fv_calib_apply(&cp, r.pupil_x, r.pupil_y, &a, &b);
        ep[i] = (float)fv_gaze_angle_deg(a, b, s.yaw_deg, s.pitch_deg);
        if (r.has_pg) {
            fv_calib_apply(&cg, r.pg_x, r.pg_y, &a, &b);
            eg[ne++] = (float)fv_gaze_angle_deg(a, b, s.yaw_deg, s.pitch_deg);
        }
    }
    float mg = 0, xg = 0, mp = 0, xp = 0;
    for (int i = 0; i < ne; i++)
        mg += eg[i] / ne, xg = fmaxf(xg, eg[i]);
    for (int i = 0; i < NT; i++)
        mp += ep[i] / NT, xp = fmaxf(xp, ep[i]);
    printf("[ eyetrack ] end to end gaze error: pupil-glint mean %.3f max %.3f deg (%d frames); pupil only mean %.3f max %.3f deg\n",
           (double)mg, (double)xg, ne, (double)mp, (double)xp);
    assert_true(ne >= NT - 2);
    assert_true(mg < 1.0f && xg < 2.0f);
    assert_true(mp < 1.0f && xp < 2.0f);
    fv_eye_destroy(t);
    free(img);
}

/* ------------------------------------------------------------------ gaze filter */

static void test_gaze_filter(void **state)
{
    (void)state;
    rng = 0x7777ull; /* each test its own draws, whatever runs before it */
    fv_gaze_filter f;
    fv_gaze_filter_init(&f, NULL);
    fv_gaze_out o;
    const double dt = 1000.0 / 120.0;
    double t = 0;
    /* fixation at (5, -2) with 0.2 deg rms jitter per axis: the output jitters much less */
    double si = 0, so = 0;
    int n = 0;
    for (int i = 0; i < 120; i++, t += dt) {
        const float jx = 0.2f * (rnd() - 0.5f) * 3.46f, jy = 0.2f * (rnd() - 0.5f) * 3.46f;
        fv_gaze_filter_update(&f, t, 1, 5.0f + jx, -2.0f + jy, 0.9f, &o);
        if (i >= 60) {
            assert_int_equal(o.state, FV_GAZE_FIXATION);
            si += (double)jx * jx + (double)jy * jy;
            so += (o.yaw_deg - 5.0) * (o.yaw_deg - 5.0) + (o.pitch_deg + 2.0) * (o.pitch_deg + 2.0);
            n++;
        }
    }
    printf("[ eyetrack ] 1-euro in fixation: rms jitter %.3f -> %.3f deg\n", sqrt(si / n), sqrt(so / n));
    assert_true(sqrt(so / n) < 0.5 * sqrt(si / n));
    /* saccade of 15 deg over 5 samples (~360 deg/s): followed without lag */
    for (int i = 1; i <= 5; i++, t += dt) {
        fv_gaze_filter_update(&f, t, 1, 5.0f + 3.0f * i, -2.0f, 0.9f, &o);
        assert_int_equal(o.state, FV_GAZE_SACCADE);
        assert_true(fabsf(o.yaw_deg - (5.0f + 3.0f * i)) < 1e-4f);
    }
    /* a single wild sample (40 deg away in one frame: 4800 deg/s) is rejected */
    fv_gaze_filter_update(&f, t, 1, 20.0f, -2.0f, 0.9f, &o), t += dt;
    fv_gaze_filter_update(&f, t, 1, -20.0f, 20.0f, 0.9f, &o), t += dt;
    assert_true(fabsf(o.yaw_deg - 20.0f) < 0.5f && fabsf(o.pitch_deg + 2.0f) < 0.5f);
    fv_gaze_filter_update(&f, t, 1, 20.0f, -2.0f, 0.9f, &o), t += dt;
    assert_true(fabsf(o.yaw_deg - 20.0f) < 0.5f);
    /* ...but a jump that stays (tracker re-locked, 3 agreeing samples) is accepted */
    for (int i = 0; i < 3; i++, t += dt)
        fv_gaze_filter_update(&f, t, 1, -10.0f, 5.0f, 0.9f, &o);
    assert_true(fabsf(o.yaw_deg + 10.0f) < 1e-4f && fabsf(o.pitch_deg - 5.0f) < 1e-4f);
    /* blink: hold the last good gaze with falling confidence, then LOST */
    const float gy = o.yaw_deg, gp = o.pitch_deg;
    float last_conf = 1.0f;
    const double t_blink = t;
    for (; t < t_blink + 400.0; t += dt) {
        fv_gaze_filter_update(&f, t, 0, 0, 0, 0, &o);
        assert_true(o.yaw_deg == gy && o.pitch_deg == gp);
        if (t - t_blink < 290.0) {
            assert_int_equal(o.state, FV_GAZE_HOLD);
            assert_true(o.confidence <= last_conf && o.confidence > 0.0f);
            last_conf = o.confidence;
        }
    }
    assert_int_equal(o.state, FV_GAZE_LOST);
    assert_true(o.confidence == 0.0f);
    /* the renderer's fovea scale */
    assert_true(fv_fovea_radius_scale(1.0f) == 1.0f && fv_fovea_radius_scale(0.8f) == 1.0f);
    assert_true(fv_fovea_radius_scale(0.0f) == 2.0f && fv_fovea_radius_scale(NAN) == 2.0f);
    assert_true(fabsf(fv_fovea_radius_scale(0.5f) - 1.5f) < 1e-6f);
    assert_true(fv_fovea_radius_scale(0.6f) < fv_fovea_radius_scale(0.4f));
}

/* ------------------------------------------------------------------ the bundled video */

/* assets/eye_synth.y4m (made at build time by tools/gen_eye from the bundled gaze trace) through
 * the Y4M reader and the tracker with history, against assets/eye_synth.csv. */
static void test_bundled_video(void **state)
{
    (void)state;
    char err[512];
    fv_eyesrc *src;
    if (fv_eyesrc_open_y4m(&src, "assets/eye_synth.y4m", err, sizeof err))
        fail_msg("%s (run from the repository root after make)", err);
    FILE *f = fopen("assets/eye_synth.csv", "r");
    assert_non_null(f);
    char line[2048];
    assert_non_null(fgets(line, sizeof line, f)); /* header */
    fv_eye_tracker *t = fv_eye_create(NULL, FV_EYE_MODE_HEADSET);
    float err_px[512];
    int n_open = 0, vis = 0, matched = 0, closed = 0, closed_flagged = 0, open_ok = 0, frames = 0;
    fv_eye_frame fr;
    int rc;
    while ((rc = fv_eyesrc_next(src, &fr, err, sizeof err)) == 1) {
        assert_non_null(fgets(line, sizeof line, f));
        /* frame,t_ms,yaw,pitch,open,blink,pupil_x,pupil_y,pupil_r_px,pupil_visible,n_glints,g0_x,g0_y,... */
        float v[11], gx[6], gy[6];
        int gv[6];
        char *p = line;
        for (int k = 0; k < 11; k++) {
            v[k] = strtof(p, &p);
            assert_true(*p == ',');
            p++;
        }
        for (int k = 0; k < 6; k++) {
            gv[k] = *p != ',';
            gx[k] = gv[k] ? strtof(p, &p) : 0;
            p++;
            gy[k] = gv[k] ? strtof(p, &p) : 0;
            if (*p == ',')
                p++;
        }
        fv_eye_result r;
        assert_int_equal(fv_track_frame(t, fr.luma, fr.w, fr.h, fr.stride, &r), 0);
        frames++;
        if (v[9] >= 0.99f) { /* pupil fully visible */
            open_ok += r.status == FV_EYE_OK;
            err_px[n_open++] = r.found ? hypotf(r.pupil_x - v[6], r.pupil_y - v[7]) : INFINITY;
            for (int k = 0; k < 6; k++) {
                if (!gv[k])
                    continue;
                vis++;
                for (int j = 0; j < r.n_glints; j++)
                    if (hypotf(r.glints[j].x - gx[k], r.glints[j].y - gy[k]) < 1.0f) {
                        matched++;
                        break;
                    }
            }
        }
        if (v[9] == 0.0f) { /* pupil completely covered */
            closed++;
            closed_flagged += r.status != FV_EYE_OK;
        }
    }
    assert_int_equal(rc, 0);
    fclose(f);
    float sorted[512];
    memcpy(sorted, err_px, (size_t)n_open * sizeof *sorted);
    const float med = median(sorted, n_open), worst = sorted[n_open - 1];
    printf("[ eyetrack ] bundled video: %d frames; pupil fully visible in %d: median error %.3f px, max %.3f px, "
           "status OK in %d; glints found %d of %d visible (within 1 px); pupil covered in %d: %d flagged blink/lost\n",
           frames, n_open, (double)med, (double)worst, open_ok, matched, vis, closed, closed_flagged);
    assert_true(frames >= 60 && n_open >= 40 && closed >= 2);
    assert_true(med < 0.5f);
    assert_true(worst < 2.0f);
    assert_true(matched * 10 >= vis * 9);
    assert_int_equal(closed_flagged, closed);
    assert_true(open_ok * 10 >= n_open * 9);
    fv_eye_destroy(t);
    fv_eyesrc_close(src);
}

/* ------------------------------------------------------------------ real infrared crops */

/* Every 15th labelled MRL image (~300, both sensors) through the list reader and the tracker:
 * a regression guard on the figures docs/eyetrack.md reports for all 4,485 (79.8% within 5 px,
 * 54.2% within 3 px there). Skipped when ../shared is not there. */
static void test_mrl_subset(void **state)
{
    (void)state;
    char rel[1024], dirp[4096], list[4200], line[2048], err[512];
    snprintf(rel, sizeof rel, "%s/assets/eyes/mrl-dev", fv_test_shared());
    FILE *in = NULL;
    if (realpath(rel, dirp)) { /* the subset list lives elsewhere: absolute paths */
        snprintf(list, sizeof list, "%s/pupil.txt", dirp);
        in = fopen(list, "r");
    }
    if (!in) {
        printf("[ eyetrack ] %s/pupil.txt not found: MRL subset skipped\n", rel);
        skip();
    }
    char sub[] = "/tmp/fovea_mrl_XXXXXX";
    const int fd = mkstemp(sub);
    assert_true(fd >= 0);
    FILE *out = fdopen(fd, "w");
    int i = 0;
    while (fgets(line, sizeof line, in))
        if (i++ % 15 == 0)
            fprintf(out, "%s/%s", dirp, line);
    fclose(in);
    fclose(out);
    fv_eyesrc *src;
    const int orc = fv_eyesrc_open_list(&src, sub, err, sizeof err);
    unlink(sub); /* read in full by the open */
    if (orc)
        fail_msg("%s", err);
    /* auto, as fovea-track by default: the few crops over 160 px take the headset path */
    fv_eye_tracker *t = fv_eye_create(NULL, FV_EYE_MODE_AUTO);
    int n = 0, w3 = 0, w5 = 0, found = 0;
    fv_eye_frame fr;
    int rc;
    while ((rc = fv_eyesrc_next(src, &fr, err, sizeof err)) == 1) {
        fv_eye_result r;
        assert_true(fr.has_label);
        assert_int_equal(fv_track_image(t, fr.luma, fr.w, fr.h, fr.stride, &r), 0);
        const float e = r.found ? hypotf(r.pupil_x - fr.label_x, r.pupil_y - fr.label_y) : INFINITY;
        n++, found += r.found, w3 += e <= 3.0f, w5 += e <= 5.0f;
    }
    if (rc < 0)
        fail_msg("%s", err);
    fv_eyesrc_close(src);
    fv_eye_destroy(t);
    printf("[ eyetrack ] MRL subset: %d images, found %d, within 3 px %.1f%%, within 5 px %.1f%% (bounds 55%%, 81%%)\n",
           n, found, 100.0 * w3 / n, 100.0 * w5 / n);
    assert_true(n >= 250);
    assert_true(w3 >= 0.55 * n);
    assert_true(w5 >= 0.81 * n);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ellipse_fit),
        cmocka_unit_test(test_bad_args),
        cmocka_unit_test(test_robustness),
        cmocka_unit_test(test_mode_auto),
        cmocka_unit_test(test_mode_explicit),
        cmocka_unit_test(test_mode_settings),
        cmocka_unit_test(test_synthetic_clean),
        cmocka_unit_test(test_synthetic_noisy),
        cmocka_unit_test(test_partial_occlusion),
        cmocka_unit_test(test_spectacles),
        cmocka_unit_test(test_crop_spectacles),
        cmocka_unit_test(test_crop_reflection_beside),
        cmocka_unit_test(test_low_contrast_lost),
        cmocka_unit_test(test_blinks),
        cmocka_unit_test(test_calib_recovers_polynomial),
        cmocka_unit_test(test_calib_file),
        cmocka_unit_test(test_end_to_end),
        cmocka_unit_test(test_gaze_filter),
        cmocka_unit_test(test_bundled_video),
        cmocka_unit_test(test_mrl_subset),
    };
    return cmocka_run_group_tests_name("eyetrack", tests, NULL, NULL);
}
