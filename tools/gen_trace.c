/* gen_trace: writes the bundled gaze trace assets/gaze_sweep.csv for `make run` (120 frames at
 * 90 Hz over the scene from tools/gen_range.c). The CSV is committed; regenerate it with
 *
 *   build/tools/gen_trace --out assets/gaze_sweep.csv
 *
 * Format: `t_ms,gaze_x,gaze_y`, gaze in normalised image coordinates (x right, y down, [0,1]),
 * head fixed at the scene's default viewpoint (its camera node: eye at (0, 1.6, 0) looking down
 * -Z, vertical FOV 100 deg, 1280x1440). The path: fixate the centre, saccade to a label-1
 * target at 0.77 m and dwell 25 frames, saccade to the blue ball at 6 m and dwell 25 frames,
 * saccade to the right, sweep smoothly across to the left over three label-2 spheres, saccade
 * back to the centre. Saccades follow a minimum-jerk profile; fixations carry a small drift/tremor.
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

static void project(const double p[3], double *x, double *y)
{
    double t = tan(YFOV_DEG * 0.5 * PI / 180.0), dz = -(p[2] - EYE[2]);
    *x = 0.5 + (p[0] - EYE[0]) / dz / (2 * t * ASPECT);
    *y = 0.5 - (p[1] - EYE[1]) / dz / (2 * t);
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
            "usage: gen_trace --out FILE\n"
            "Writes fovea's bundled gaze trace (120 frames at 90 Hz over the gen_range scene) as CSV\n"
            "t_ms,gaze_x,gaze_y (normalised image coordinates, x right, y down).\n"
            "  --out FILE   where to write it (FILE.tmp, then renamed), or - for stdout\n"
            "  --help       this text\n"
            "Exit status: 0 success, 2 bad usage, 1 the file cannot be written.\n");
}

static void write_trace(FILE *f)
{
    pt centre = {0.5, 0.5}, near, ball, sweep_r = {0.84, 0.415}, sweep_l = {0.16, 0.41};
    project(TARGET_NEAR, &near.x, &near.y);
    project(TARGET_BALL, &ball.x, &ball.y);

    fprintf(f, "# fovea bundled gaze trace (tools/gen_trace.c): %d frames at %.0f Hz over assets/range.glb.\n",
            FRAMES, HZ);
    fprintf(f, "# gaze_x, gaze_y: normalised image coordinates of the left eye's image, x right, y down, in [0,1].\n");
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
    fprintf(f, "t_ms,gaze_x,gaze_y\n");

    for (int i = 0; i < FRAMES; i++) {
        double t = i * 1000.0 / HZ;
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
        fprintf(f, "%.3f,%.5f,%.5f\n", t, clamp01(g.x), clamp01(g.y));
    }
}

int main(int argc, char **argv)
{
    const char *out = NULL;
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
        write_trace(stdout);
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
        write_trace(f);
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
