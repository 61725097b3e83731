/* gen_trace: writes the bundled gaze trace assets/gaze_sweep.csv for `make run` (120 frames at
 * 90 Hz over the scene from tools/gen_range.c). The CSV is committed; regenerate it with
 *
 *   build/tools/gen_trace --out assets/gaze_sweep.csv
 *
 * Format: `t_ms,gaze_x,gaze_y,head_px,head_py,head_pz,head_qx,head_qy,head_qz,head_qw`, gaze in
 * normalised image coordinates (x right, y down, [0,1]); the head sways gently around the scene's
 * default viewpoint (its camera node: eye at (0, 1.6, 0) looking down -Z, vertical FOV 100 deg,
 * 1280x1440) so temporal reprojection has motion to follow; --static-head writes the gaze only.
 * The path: fixate the centre, saccade to a label-1 target at 0.77 m and dwell 25 frames,
 * saccade to the blue ball at 6 m and dwell 25 frames, saccade to the right, sweep smoothly
 * across to the left over three label-2 spheres, saccade back to the centre. Saccades follow a minimum-jerk profile; fixations carry a small drift/tremor.
 * Deterministic. Exit status: 0 success, 2 bad usage, 1 cannot write. */

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Keep in sync with tools/gen_range.c (TARGET_NEAR_*, TARGET_BALL_*, the camera node). */
static const double EYE[3] = {0.0, 1.6, 0.0};
static const double TARGET_NEAR[3] = {-0.32, 1.28, -0.62}; /* target1_red_sphere, r 0.07 m */
static const double TARGET_BALL[3] = {0.6, 1.35, -6.0};    /* target3_blue_ball, r 0.5 m */
#define YFOV_DEG 100.0
#define ASPECT (1280.0 / 1440.0)
#define FRAMES 120
#define HZ 90.0

static const double PI = 3.14159265358979323846;

/* Head pose: the camera node's position plus a slow sway (a lateral shift and a yaw / pitch
 * swing), so reprojection has head motion to follow. Zero with --static-head. */
typedef struct {
    double pos[3], q[4]; /* q: x, y, z, w (yaw about +Y, then pitch about +X) */
} pose;
#define SWAY_YAW_DEG 4.0
#define SWAY_PITCH_DEG 1.5
#define SWAY_X_M 0.02
#define SWAY_PERIOD_MS 1333.0

static pose head_at(double t_ms, int moving)
{
    double a = moving ? sin(2 * PI * t_ms / SWAY_PERIOD_MS) : 0.0, b = moving ? sin(4 * PI * t_ms / SWAY_PERIOD_MS) : 0.0;
    double yaw = SWAY_YAW_DEG * PI / 180.0 * a, pitch = SWAY_PITCH_DEG * PI / 180.0 * b;
    double sy = sin(yaw / 2), cy = cos(yaw / 2), sp = sin(pitch / 2), cp = cos(pitch / 2);
    pose h = {{EYE[0] + SWAY_X_M * a, EYE[1], EYE[2]}, {cy * sp, sy * cp, -sy * sp, cy * cp}};
    return h;
}

/* v' = v + 2w (u x v) + 2 u x (u x v) for a unit quaternion (u, w); conj rotates world -> head */
static void qrot(const double q[4], int conj, const double v[3], double o[3])
{
    double ux = conj ? -q[0] : q[0], uy = conj ? -q[1] : q[1], uz = conj ? -q[2] : q[2], w = q[3];
    double cx = uy * v[2] - uz * v[1], cy = uz * v[0] - ux * v[2], cz = ux * v[1] - uy * v[0];
    o[0] = v[0] + 2 * (w * cx + uy * cz - uz * cy);
    o[1] = v[1] + 2 * (w * cy + uz * cx - ux * cz);
    o[2] = v[2] + 2 * (w * cz + ux * cy - uy * cx);
}

/* Where world point p appears in the image of head pose h (the eye follows fixated targets). */
static void project(const pose *h, const double p[3], double *x, double *y)
{
    double d[3] = {p[0] - h->pos[0], p[1] - h->pos[1], p[2] - h->pos[2]}, v[3];
    qrot(h->q, 1, d, v);
    double t = tan(YFOV_DEG * 0.5 * PI / 180.0), dz = -v[2];
    *x = 0.5 + v[0] / dz / (2 * t * ASPECT);
    *y = 0.5 - v[1] / dz / (2 * t);
}

static double dist(const double p[3])
{
    double dx = p[0] - EYE[0], dy = p[1] - EYE[1], dz = p[2] - EYE[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

static double min_jerk(double s) { return s * s * s * (10 + s * (-15 + 6 * s)); }
static double clamp01(double v) { return v < 0 ? 0 : v > 1 ? 1 : v; }

typedef struct { double x, y; } pt;

/* Small fixational drift and tremor (about 0.1-0.2 deg), a function of time only. */
static pt jitter(double t_ms)
{
    pt d = {0.0012 * sin(2 * PI * t_ms / 310.0) + 0.0005 * sin(2 * PI * t_ms / 47.0 + 1.3),
            0.0010 * sin(2 * PI * t_ms / 270.0 + 0.7) + 0.0005 * sin(2 * PI * t_ms / 53.0 + 2.1)};
    return d;
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: gen_trace --out FILE [--static-head]\n"
            "Writes fovea's bundled gaze trace (120 frames at 90 Hz over the gen_range scene) as CSV\n"
            "t_ms,gaze_x,gaze_y,head_px,head_py,head_pz,head_qx,head_qy,head_qz,head_qw (gaze in\n"
            "normalised image coordinates, x right, y down; head pose in world metres / quaternion).\n"
            "  --out FILE     where to write it (FILE.tmp, then renamed), or - for stdout\n"
            "  --static-head  no head motion and no head columns (gaze only)\n"
            "  --help       this text\n"
            "Exit status: 0 success, 2 bad usage, 1 the file cannot be written.\n");
}

static void write_trace(FILE *f, int moving)
{
    pt centre = {0.5, 0.5}, near, ball, sweep_r = {0.84, 0.415}, sweep_l = {0.16, 0.41};
    const pose rest = head_at(0.0, 0);
    project(&rest, TARGET_NEAR, &near.x, &near.y);
    project(&rest, TARGET_BALL, &ball.x, &ball.y);

    fprintf(f, "# fovea bundled gaze trace (tools/gen_trace.c): %d frames at %.0f Hz over assets/range.glb.\n",
            FRAMES, HZ);
    fprintf(f, "# gaze_x, gaze_y: normalised image coordinates of the left eye's image, x right, y down, in [0,1].\n");
    if (moving)
        fprintf(f, "# Head at the scene's camera node (0,1.6,0) looking down -Z (vertical FOV 100 deg, 1280x1440),\n"
                   "# swaying: yaw +-%.1f deg and x +-%.2f m with period %.0f ms, pitch +-%.1f deg at twice the rate.\n"
                   "# While fixating a target the gaze follows it in the image (vestibulo-ocular reflex).\n",
                SWAY_YAW_DEG, SWAY_X_M, SWAY_PERIOD_MS, SWAY_PITCH_DEG);
    else
        fprintf(f, "# Head fixed at the scene's camera node: eye (0,1.6,0) looking down -Z, vertical FOV 100 deg, 1280x1440.\n");
    fprintf(f, "# frames   0-7   fixate the image centre\n");
    fprintf(f, "# frames   8-15  saccade (minimum jerk) to target1_red_sphere, %.2f m, at (%.4f, %.4f)\n",
            dist(TARGET_NEAR), near.x, near.y);
    fprintf(f, "# frames  16-40  dwell near (25 frames) with small drift/tremor\n");
    fprintf(f, "# frames  41-48  saccade to target3_blue_ball, %.2f m, at (%.4f, %.4f)\n",
            dist(TARGET_BALL), ball.x, ball.y);
    fprintf(f, "# frames  49-73  dwell far (25 frames)\n");
    fprintf(f, "# frames  74-79  saccade to the right (%.2f, %.3f)\n", sweep_r.x, sweep_r.y);
    fprintf(f, "# frames  80-111 smooth sweep across the image to the left (%.2f, %.2f), over the label-2\n"
               "#                magenta (3.5 m), orange (5.1 m) and green (1.8 m) spheres\n",
            sweep_l.x, sweep_l.y);
    fprintf(f, "# frames 112-119 saccade back to the centre\n");
    fprintf(f, moving ? "t_ms,gaze_x,gaze_y,head_px,head_py,head_pz,head_qx,head_qy,head_qz,head_qw\n"
                      : "t_ms,gaze_x,gaze_y\n");

    for (int i = 0; i < FRAMES; i++) {
        double t = i * 1000.0 / HZ;
        const pose h = head_at(t, moving);
        /* the saccades' targets move with the head: re-project them for this pose */
        project(&h, TARGET_NEAR, &near.x, &near.y);
        project(&h, TARGET_BALL, &ball.x, &ball.y);
        pt g, a, b;
        double s;
        int fix = 0;
        if (i < 8) {
            g = centre; fix = 1;
        } else if (i < 16) {
            a = centre; b = near; s = min_jerk((i - 7) / 8.0);
            g.x = a.x + (b.x - a.x) * s; g.y = a.y + (b.y - a.y) * s;
        } else if (i < 41) {
            g = near; fix = 1;
        } else if (i < 49) {
            a = near; b = ball; s = min_jerk((i - 40) / 8.0);
            g.x = a.x + (b.x - a.x) * s; g.y = a.y + (b.y - a.y) * s;
        } else if (i < 74) {
            g = ball; fix = 1;
        } else if (i < 80) {
            a = ball; b = sweep_r; s = min_jerk((i - 73) / 6.0);
            g.x = a.x + (b.x - a.x) * s; g.y = a.y + (b.y - a.y) * s;
        } else if (i < 112) {
            /* pursuit-like sweep with eased velocity, bowing slightly downwards */
            s = 0.5 - 0.5 * cos(PI * (i - 79) / 32.0);
            g.x = sweep_r.x + (sweep_l.x - sweep_r.x) * s;
            g.y = sweep_r.y + (sweep_l.y - sweep_r.y) * s + 0.015 * sin(PI * s);
        } else {
            a = sweep_l; b = centre; s = min_jerk((i - 111) / 8.0);
            g.x = a.x + (b.x - a.x) * s; g.y = a.y + (b.y - a.y) * s;
        }
        if (fix) {
            pt d = jitter(t);
            g.x += d.x;
            g.y += d.y;
        }
        fprintf(f, "%.3f,%.5f,%.5f", t, clamp01(g.x), clamp01(g.y));
        if (moving)
            fprintf(f, ",%.5f,%.5f,%.5f,%.6f,%.6f,%.6f,%.6f", h.pos[0], h.pos[1], h.pos[2], h.q[0], h.q[1], h.q[2],
                    h.q[3]);
        fputc('\n', f);
    }
}

int main(int argc, char **argv)
{
    const char *out = NULL;
    int moving = 1;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(argv[i], "--out")) {
            if (i + 1 >= argc) {
                fprintf(stderr, "gen_trace: --out needs a FILE (try --help)\n");
                return 2;
            }
            out = argv[++i];
        } else if (!strcmp(argv[i], "--static-head")) {
            moving = 0;
        } else if (!strncmp(argv[i], "--out=", 6)) {
            out = argv[i] + 6;
        } else {
            fprintf(stderr, "gen_trace: unknown argument '%s' (try --help)\n", argv[i]);
            return 2;
        }
    }
    if (!out || !*out) {
        fprintf(stderr, "gen_trace: --out FILE is required (try --help)\n");
        return 2;
    }
    if (!strcmp(out, "-")) {
        write_trace(stdout, moving);
        if (fflush(stdout) != 0) {
            fprintf(stderr, "gen_trace: cannot write to stdout: %s\n", strerror(errno));
            return 1;
        }
        return 0;
    }

    size_t len = strlen(out);
    char *tmp = malloc(len + 5);
    if (!tmp) {
        fprintf(stderr, "gen_trace: out of memory\n");
        return 1;
    }
    memcpy(tmp, out, len);
    memcpy(tmp + len, ".tmp", 5);
    int err = 0;
    FILE *f = fopen(tmp, "w");
    if (!f) {
        err = errno;
    } else {
        write_trace(f, moving);
        if (ferror(f) || fflush(f) != 0)
            err = errno ? errno : EIO;
        if (fclose(f) != 0 && !err)
            err = errno ? errno : EIO;
        if (!err && rename(tmp, out) != 0)
            err = errno;
        if (err)
            remove(tmp);
    }
    free(tmp);
    if (err) {
        fprintf(stderr, "gen_trace: cannot write %s: %s\n", out, strerror(err));
        return 1;
    }
    return 0;
}
