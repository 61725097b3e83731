/* fovea eye tracker: synthetic infrared eye renderer (see synth.h for the model). Deterministic:
 * the same parameters, state and seeds give the same bytes on every machine (only float
 * arithmetic with -ffp-contract=off and libm sin/cos/sqrt/atan2/exp, which glibc rounds the same
 * on x86-64 and AArch64 for these calls; the bundled video is regenerated, not compared). */
#include "eyetrack/synth.h"

#include <math.h>
#include <string.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define EYE_R 12.0f
#define CORNEA_R 7.8f
#define CORNEA_OFF 5.6f
#define IRIS_R 6.0f
#define IRIS_D 10.4f /* sqrt(12^2 - 6^2) */

void fv_synth_default_params(fv_synth_params *p, int w, int h)
{
    memset(p, 0, sizeof *p);
    p->w = w;
    p->h = h;
    p->px_per_mm = (float)w / 34.0f; /* the image spans 34 mm: the eye aperture and some skin */
    p->n_leds = 4;
    p->led_ring_mm = 14.0f;
    p->led_dist_mm = 35.0f;
    p->noise_sigma = 2.0f;
    p->brightness = 1.0f;
    p->supersample = 3;
    p->seed = 0x5eed;
}

static uint64_t mix(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
static float hashf(uint64_t seed, int64_t a, int64_t b) /* [0,1) */
{
    return (float)(mix(seed ^ mix((uint64_t)a * 0x100000001b3ull + (uint64_t)b)) >> 40) * (1.0f / 16777216.0f);
}
/* Smooth value noise in [0,1) on an integer lattice. */
static float vnoise(uint64_t seed, float x, float y)
{
    const float fx = floorf(x), fy = floorf(y);
    const int64_t ix = (int64_t)fx, iy = (int64_t)fy;
    float tx = x - fx, ty = y - fy;
    tx = tx * tx * (3 - 2 * tx), ty = ty * ty * (3 - 2 * ty);
    const float a = hashf(seed, ix, iy), b = hashf(seed, ix + 1, iy);
    const float c = hashf(seed, ix, iy + 1), d = hashf(seed, ix + 1, iy + 1);
    return (a + tx * (b - a)) + ty * ((c + tx * (d - c)) - (a + tx * (b - a)));
}

typedef struct {
    float gx, gy, gz; /* gaze unit vector */
    float ix, iy;     /* iris / pupil centre (mm, image plane) */
    float lid_up0, lid_lo0;
    float gl_x[FV_SYNTH_MAX_LEDS], gl_y[FV_SYNTH_MAX_LEDS];
    int gl_vis[FV_SYNTH_MAX_LEDS];
} geom;

/* Lid aperture: upper and lower lid heights (mm) at image-plane x (mm). */
static float lid_upper(const geom *g, float x)
{
    const float u = x / 15.0f;
    return g->lid_up0 * (1.0f - u * u) + 0.6f * u;
}
static float lid_lower(const geom *g, float x)
{
    const float u = x / 15.0f;
    return g->lid_lo0 * (1.0f - u * u) + 0.6f * u;
}
static int in_aperture(const geom *g, float x, float y)
{
    return fabsf(x) < 15.0f && y < lid_upper(g, x) && y > lid_lower(g, x);
}

static void setup(const fv_synth_params *p, const fv_synth_state *s, geom *g)
{
    const float yaw = s->yaw_deg * (float)(M_PI / 180.0), pit = s->pitch_deg * (float)(M_PI / 180.0);
    g->gx = sinf(yaw) * cosf(pit);
    g->gy = sinf(pit);
    g->gz = cosf(yaw) * cosf(pit);
    g->ix = IRIS_D * g->gx;
    g->iy = IRIS_D * g->gy;
    /* closed: both lids meet at -3 mm */
    const float open = s->open < 0 ? 0 : s->open > 1 ? 1 : s->open;
    g->lid_lo0 = -6.5f + 3.5f * (1.0f - open);
    g->lid_up0 = -3.0f + 10.5f * open + 0.25f * s->pitch_deg * open * 0.2f;
    /* glints: mirror points on the cornea sphere for LEDs on a ring around the (orthographic,
     * direction +Z) camera */
    const float cx = CORNEA_OFF * g->gx, cy = CORNEA_OFF * g->gy, cz = CORNEA_OFF * g->gz;
    for (int k = 0; k < p->n_leds && k < FV_SYNTH_MAX_LEDS; k++) {
        const float a = (float)(2.0 * M_PI * (k + 0.5) / p->n_leds) + 0.3f;
        /* the LEDs sit on the camera's ring: they move with it when the headset slips */
        const float lx = p->led_ring_mm * cosf(a) + p->cam_shift_mm[0], ly = p->led_ring_mm * sinf(a) * 0.6f + p->cam_shift_mm[1],
                    lz = p->led_dist_mm;
        float dx = lx - cx, dy = ly - cy, dz = lz - cz;
        const float dl = sqrtf(dx * dx + dy * dy + dz * dz);
        float nx = dx / dl, ny = dy / dl, nz = dz / dl + 1.0f;
        const float nn = sqrtf(nx * nx + ny * ny + nz * nz);
        nx /= nn, ny /= nn, nz /= nn;
        g->gl_x[k] = cx + CORNEA_R * nx;
        g->gl_y[k] = cy + CORNEA_R * ny;
        /* on the corneal cap (within ~45 deg of the gaze) and not under a lid */
        const float cosang = nx * g->gx + ny * g->gy + nz * g->gz;
        g->gl_vis[k] = cosang > 0.72f && in_aperture(g, g->gl_x[k], g->gl_y[k]);
    }
}

static void truth(const fv_synth_params *p, const fv_synth_state *s, const geom *g, fv_synth_truth *t)
{
    memset(t, 0, sizeof *t);
    const float sc = p->px_per_mm;
    const float sx = p->cam_shift_mm[0], sy = p->cam_shift_mm[1]; /* camera slip: the eye moves the other way */
    t->pupil_x = (g->ix - sx) * sc + 0.5f * p->w;
    t->pupil_y = -(g->iy - sy) * sc + 0.5f * p->h;
    t->pupil_r_px = s->pupil_mm * sc;
    int in = 0, tot = 0;
    for (int i = 0; i < 16; i++) /* visible fraction of the pupil disc, by sampling its image */
        for (int j = 0; j < 16; j++) {
            const float u = (i + 0.5f) / 8.0f - 1.0f, v = (j + 0.5f) / 8.0f - 1.0f;
            if (u * u + v * v > 1.0f)
                continue;
            tot++;
            /* the disc's image: ellipse with minor axis along the gaze's image direction */
            const float gl = sqrtf(g->gx * g->gx + g->gy * g->gy);
            const float ex = gl > 1e-6f ? g->gx / gl : 1.0f, ey = gl > 1e-6f ? g->gy / gl : 0.0f;
            const float x = g->ix + s->pupil_mm * (u * g->gz * ex - v * ey);
            const float y = g->iy + s->pupil_mm * (u * g->gz * ey + v * ex);
            in += in_aperture(g, x, y);
        }
    t->pupil_visible = tot ? (float)in / tot : 0.0f;
    t->n_glints = p->n_leds;
    for (int k = 0; k < p->n_leds && k < FV_SYNTH_MAX_LEDS; k++) {
        t->glint_x[k] = (g->gl_x[k] - sx) * sc + 0.5f * p->w;
        t->glint_y[k] = -(g->gl_y[k] - sy) * sc + 0.5f * p->h;
        t->glint_visible[k] = g->gl_vis[k];
    }
}

void fv_synth_truth_of(const fv_synth_params *p, const fv_synth_state *s, fv_synth_truth *t)
{
    geom g;
    setup(p, s, &g);
    truth(p, s, &g, t);
}

/* Radiance (grey level, before noise and glints) at image-plane point (x, y) mm. */
static float shade(const fv_synth_params *p, const fv_synth_state *s, const geom *g, float x, float y)
{
    const float br = p->brightness;
    if (!in_aperture(g, x, y)) {
        /* skin: bright in IR, soft texture, darker crease above the upper lid */
        float v = 165.0f + 25.0f * vnoise(p->seed + 7, x * 0.8f, y * 0.8f);
        const float up = lid_upper(g, x);
        if (y >= up) {
            const float d = y - up;
            v -= 45.0f * expf(-d * 1.2f); /* lid margin shadow */
            /* lashes: dark curved strands rooted on the upper lid, 0 .. 2.5 mm long */
            if (d < 2.5f) {
                const float root = x - 0.35f * d * d * (x > 0 ? 1.0f : -1.0f) * 0.5f;
                const float cell = root * 2.2f, fc = cell - floorf(cell);
                const float len = 1.0f + 1.5f * hashf(p->seed + 11, (int64_t)floorf(cell), 0);
                if (fabsf(fc - 0.5f) < 0.16f && d < len)
                    v *= 0.35f;
            }
        } else {
            v -= 30.0f * expf(-(lid_lower(g, x) - y) * 1.5f);
        }
        return v * br;
    }
    /* eyeball: ray (x, y, z) down -Z; the iris plane: P . g = IRIS_D */
    const float z = (IRIS_D - x * g->gx - y * g->gy) / g->gz;
    const float qx = x - g->ix, qy = y - g->iy, qz = z - IRIS_D * g->gz;
    const float rho = sqrtf(qx * qx + qy * qy + qz * qz);
    float v;
    if (rho < s->pupil_mm) {
        v = 22.0f;
    } else if (rho < IRIS_R) {
        /* iris: in-plane angle from a basis of the plane */
        float ux = g->gz, uy = 0, uz = -g->gx; /* perpendicular to g, near +x */
        const float un = sqrtf(ux * ux + uz * uz);
        ux /= un, uz /= un;
        const float vx = g->gy * uz - g->gz * uy, vy = g->gz * ux - g->gx * uz, vz = g->gx * uy - g->gy * ux;
        const float ang = atan2f(qx * vx + qy * vy + qz * vz, qx * ux + qy * uy + qz * uz);
        const float fib = vnoise(p->seed + 3, (ang + (float)M_PI) * 18.0f, rho * 1.5f);
        const float t = (rho - s->pupil_mm) / (IRIS_R - s->pupil_mm);
        v = 70.0f + 40.0f * fib + 25.0f * expf(-(t - 0.35f) * (t - 0.35f) * 40.0f) - 20.0f * t * t;
        v *= br;
    } else {
        /* sclera, darkening towards the eyeball's limb */
        const float r2 = (x * x + y * y) / (EYE_R * EYE_R);
        v = (200.0f - 60.0f * r2) * br + 10.0f * vnoise(p->seed + 5, x * 1.5f, y * 1.5f);
    }
    /* shadow of the upper lid on the eye */
    const float du = lid_upper(g, x) - y;
    v *= 1.0f - 0.45f * expf(-du * 1.3f);
    return v;
}

static float uniform(uint64_t *st) /* [0,1) */
{
    return (float)(mix((*st)++) >> 40) * (1.0f / 16777216.0f);
}

void fv_synth_lid_set_frame(uint64_t *rng, int i, fv_synth_params *p, fv_synth_state *s)
{
    p->noise_sigma = 2.0f + 12.0f * uniform(rng);
    p->brightness = 0.55f + 0.45f * uniform(rng);
    p->n_leds = 2 + (int)(4.999f * uniform(rng));
    const int up = i % 2;
    s->yaw_deg = -20.0f + 40.0f * uniform(rng);
    s->pitch_deg = up ? 3.0f + 10.0f * uniform(rng) : -10.0f + 20.0f * uniform(rng);
    s->pupil_mm = 1.6f + 1.2f * uniform(rng);
    s->open = up ? 0.35f + 0.3f * uniform(rng) : 1.0f;
}

static float gauss(uint64_t *st)
{
    /* Box-Muller on splitmix64 */
    const float u1 = ((float)(mix((*st)++) >> 40) + 0.5f) * (1.0f / 16777216.0f);
    const float u2 = (float)(mix((*st)++) >> 40) * (1.0f / 16777216.0f);
    return sqrtf(-2.0f * logf(u1)) * cosf((float)(2.0 * M_PI) * u2);
}

void fv_synth_specs_default(fv_synth_specs *sp)
{
    memset(sp, 0, sizeof *sp);
    sp->on = 1;
    sp->transmit = 0.85f;
    sp->refl_scale = 0.45f;
    sp->refl_r_mm = 0.9f;
    sp->refl_level = 250.0f;
    sp->rim_y_mm = -8.0f;
    sp->rim_curve = 0.01f;
    sp->rim_half_mm = 1.2f;
    sp->rim_grey = 40.0f;
}

static void refl_centre(const fv_synth_params *p, int k, float *cx, float *cy) /* camera-plane mm */
{
    const fv_synth_specs *sp = &p->specs;
    const float a = (float)(2.0 * M_PI * (k + 0.5) / p->n_leds) + 0.3f;
    *cx = sp->refl_scale * p->led_ring_mm * cosf(a) + sp->refl_dx_mm;
    *cy = sp->refl_scale * p->led_ring_mm * sinf(a) * 0.6f + sp->refl_dy_mm;
}

void fv_synth_specs_reflection(const fv_synth_params *p, int k, float *x, float *y, float *r_px)
{
    float cx, cy;
    refl_centre(p, k, &cx, &cy);
    *x = cx * p->px_per_mm + 0.5f * p->w;
    *y = -cy * p->px_per_mm + 0.5f * p->h;
    *r_px = p->specs.refl_r_mm * p->px_per_mm;
}

/* pass 0: the lens's tint and the rim over the eye's radiance v at camera-plane point (x, y) mm;
 * pass 1: the LED reflections on the lens (after the corneal glints: the lens is in front) */
static float specs_over(const fv_synth_params *p, float v, float x, float y, int pass)
{
    const fv_synth_specs *sp = &p->specs;
    const float rim = sp->rim_y_mm + sp->rim_curve * x * x;
    const int above = sp->rim_y_mm < 0; /* a rim below the eye: the lens is above it, and vice versa */
    const int in_lens = above ? y > rim + sp->rim_half_mm : y < rim - sp->rim_half_mm;
    if (pass == 0) {
        if (fabsf(y - rim) <= sp->rim_half_mm)
            return sp->rim_grey * p->brightness;
        return in_lens ? v * sp->transmit : v;
    }
    if (!in_lens)
        return v;
    for (int k = 0; k < p->n_leds && k < FV_SYNTH_MAX_LEDS; k++) {
        float cx, cy;
        refl_centre(p, k, &cx, &cy);
        const float d = hypotf(x - cx, (y - cy) * 1.3f) / sp->refl_r_mm; /* slightly elongated */
        if (d < 1.4f) /* a flat-topped disc with a soft edge: a flat mirror's image of the LED */
            v = fmaxf(v, sp->refl_level * (d < 1.0f ? 1.0f : 1.0f - (d - 1.0f) / 0.4f));
    }
    return v;
}

void fv_synth_render(const fv_synth_params *p, const fv_synth_state *s, uint64_t noise_seed, uint8_t *img,
                     ptrdiff_t stride, fv_synth_truth *t)
{
    geom g;
    setup(p, s, &g);
    truth(p, s, &g, t);
    const float sc = p->px_per_mm, inv = 1.0f / sc;
    const int ss = p->supersample < 1 ? 1 : p->supersample;
    uint64_t st = mix(noise_seed ^ 0xabcdef);
    const float gsig = 0.35f * sc > 0.8f ? 0.35f * sc * 0.5f : 0.8f; /* glint spot: ~0.35 mm wide */
    for (int j = 0; j < p->h; j++) {
        uint8_t *row = img + j * stride;
        for (int i = 0; i < p->w; i++) {
            float acc = 0;
            for (int a = 0; a < ss; a++)
                for (int b = 0; b < ss; b++) {
                    const float px = i + (b + 0.5f) / ss, py = j + (a + 0.5f) / ss;
                    acc += shade(p, s, &g, (px - 0.5f * p->w) * inv + p->cam_shift_mm[0],
                                 -(py - 0.5f * p->h) * inv + p->cam_shift_mm[1]);
                }
            float v = acc / (float)(ss * ss);
            if (p->specs.on) /* spectacles, fixed to the camera: camera image-plane mm */
                v = specs_over(p, v, (i + 0.5f - 0.5f * p->w) * inv, -(j + 0.5f - 0.5f * p->h) * inv, 0);
            for (int k = 0; k < p->n_leds && k < FV_SYNTH_MAX_LEDS; k++) {
                if (!t->glint_visible[k])
                    continue;
                const float dx = i + 0.5f - t->glint_x[k], dy = j + 0.5f - t->glint_y[k];
                const float d2 = dx * dx + dy * dy;
                if (d2 < 25.0f * gsig * gsig)
                    v += 400.0f * expf(-d2 / (2.0f * gsig * gsig));
            }
            if (p->specs.on) /* the lens's own reflections, over everything behind it */
                v = specs_over(p, v, (i + 0.5f - 0.5f * p->w) * inv, -(j + 0.5f - 0.5f * p->h) * inv, 1);
            v += p->noise_sigma * gauss(&st);
            row[i] = (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : lrintf(v));
        }
    }
}

void fv_synth_script_default(fv_synth_script *sc, float dwell_ms)
{
    memset(sc, 0, sizeof *sc);
    sc->dwell_ms = dwell_ms;
    sc->reaction_ms = 220.0f;
    sc->saccade_ms = 45.0f;
    sc->jitter_deg = 0.05f;
    sc->seed = 0xca11b;
}

/* smooth deterministic jitter: a few incommensurate sines with seeded phases, amplitude ~1 */
static float jitter(uint64_t seed, int axis, double t_s)
{
    uint64_t st = mix(seed * 2 + (uint64_t)axis);
    double v = 0;
    static const double hz[3] = {0.7, 1.9, 5.3}, amp[3] = {0.6, 0.3, 0.1};
    for (int i = 0; i < 3; i++) {
        st = mix(st + 0x9e3779b97f4a7c15ull);
        v += amp[i] * sin(2.0 * M_PI * hz[i] * t_s + (double)(st >> 11) * (2.0 * M_PI / 9007199254740992.0));
    }
    return (float)v;
}

void fv_synth_script_state(const fv_synth_script *sc, double t_ms, fv_synth_state *s)
{
    const int n = sc->n < 1 ? 1 : sc->n > FV_SYNTH_SCRIPT_MAX ? FV_SYNTH_SCRIPT_MAX : sc->n;
    const double tt = t_ms < 0 ? 0 : t_ms;
    int k = (int)(tt / sc->dwell_ms);
    k = k >= n ? n - 1 : k;
    const double in = tt - k * (double)sc->dwell_ms;
    const int prev = k > 0 ? k - 1 : 0;
    float yaw = sc->yaw_deg[k], pitch = sc->pitch_deg[k];
    if (k > 0 && in < sc->reaction_ms + sc->saccade_ms) { /* still on the last target, or on the way */
        const double a = in <= sc->reaction_ms ? 0.0 : (in - sc->reaction_ms) / sc->saccade_ms;
        const double e = a * a * (3 - 2 * a); /* a smooth saccade profile */
        yaw = (float)(sc->yaw_deg[prev] + e * (sc->yaw_deg[k] - sc->yaw_deg[prev]));
        pitch = (float)(sc->pitch_deg[prev] + e * (sc->pitch_deg[k] - sc->pitch_deg[prev]));
    }
    const double ts = tt * 1e-3;
    float amp = sc->jitter_deg;
    if (k < 32 && (sc->wander_mask >> k & 1u))
        amp = 3.0f; /* looking around instead of at the target */
    s->yaw_deg = yaw + amp * jitter(sc->seed, 0, amp > 1.0f ? ts * 2.5 : ts);
    s->pitch_deg = pitch + amp * jitter(sc->seed, 1, amp > 1.0f ? ts * 2.5 : ts);
    s->pupil_mm = 2.2f + 0.3f * (float)sin(2.0 * M_PI * 0.15 * ts);
    s->open = 1.0f;
    for (int b = 0; b < sc->n_blinks && b < FV_SYNTH_SCRIPT_MAX; b++) {
        const double d = tt - sc->blink_ms[b];
        if (d >= 0 && d < 80)
            s->open = fminf(s->open, (float)(1.0 - d / 80.0));
        else if (d >= 80 && d < 200)
            s->open = fminf(s->open, (float)((d - 80.0) / 120.0));
    }
}

void fv_synth_specs_set_frame(uint64_t *rng, int i, fv_synth_params *p, fv_synth_state *s)
{
    fv_synth_lid_set_frame(rng, i, p, s);
    fv_synth_specs_default(&p->specs);
    fv_synth_specs *sp = &p->specs;
    sp->transmit = 0.7f + 0.25f * uniform(rng);
    sp->refl_scale = 0.3f + 0.4f * uniform(rng);
    sp->refl_dx_mm = -7.0f + 14.0f * uniform(rng);
    sp->refl_dy_mm = -5.0f + 10.0f * uniform(rng);
    sp->refl_r_mm = 0.6f + 0.8f * uniform(rng);
    const float depth = 3.0f + 6.0f * uniform(rng);
    sp->rim_y_mm = i % 3 == 2 ? depth + 4.0f : -depth;
    sp->rim_curve = (uniform(rng) - 0.3f) * 0.03f;
    sp->rim_half_mm = 0.8f + 1.2f * uniform(rng);
    sp->rim_grey = 25.0f + 40.0f * uniform(rng);
}
