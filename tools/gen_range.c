/* gen_range: writes fovea's bundled test scene, a "space shooting range" modelled on the
 * benchmark scene of Weier et al. 2018 ("a long tunnel extended by the different targets";
 * targets labelled one at 0.5-1 m, labelled two at 1-6 m, a big blue ball labelled three at
 * 6 m), as a binary glTF 2.0 file (.glb), written by hand.
 *
 *   gen_range --out FILE      (the Makefile runs: gen_range --out assets/range.glb)
 *
 * glTF conventions: metres, +Y up, right-handed, the camera looks down -Z.
 *   - camera node "eye" at (0, 1.6, 0), identity rotation, yfov 100 deg, aspect 1280/1440,
 *     znear 0.05 (no zfar: infinite projection);
 *   - tunnel x in [-1.5, 1.5], y in [0, 3], z from +0.5 (behind the eye) to -40, closed by a
 *     checkered end wall; checkered floor and wall panels, vertical ribs on the walls every 0.5 m,
 *     a grid of small studs on the floor, lamp fixtures on the ceiling, arches every 4 m from -8 m;
 *     all surfaces tessellated, normals facing into the tunnel;
 *   - targets (one mesh each, centred at the origin, placed by the node's translation):
 *     label 1 (0.5-1 m), label 2 (1-6 m), label 3 (the big blue ball, 6 m), and a few far
 *     depth markers (10-30 m, left of the ball, which hides the far right of the tunnel).
 * No lights (the renderer's head light is used), no textures: one material per base colour.
 * 227,568 triangles (the count Weier et al. give for theirs); POSITION + NORMAL (float VEC3)
 * + u32 indices; one mesh per material for the tunnel and one per target.
 *
 * Deterministic: same bytes on every run and every host (no time, no libm trigonometry: a local
 * sin/cos from + and * only, a fixed-seed local PRNG, ISO C float arithmetic).
 * The output is written to FILE.tmp and renamed to FILE, so no half-written file is left.
 * Exit status: 0 success, 2 bad usage, 1 cannot write. */

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define EYE_X 0.0
#define EYE_Y 1.6
#define EYE_Z 0.0

/* Tunnel extent. */
#define TUN_X0 (-1.5)
#define TUN_X1 1.5
#define TUN_Y0 0.0
#define TUN_Y1 3.0
#define TUN_Z_NEAR 0.5
#define TUN_Z_FAR (-40.0)

static const double PI = 3.14159265358979323846;

/* ---------------------------------------------------------------- small utilities */

static void die_oom(void)
{
    fprintf(stderr, "gen_range: out of memory\n");
    exit(1);
}

static void *xrealloc(void *p, size_t n)
{
    void *q = realloc(p, n ? n : 1);
    if (!q)
        die_oom();
    return q;
}

/* sin and cos from + and * only, so vertex positions are bit-identical on every host
 * (the library's sin/cos may differ in the last bit between platforms). */
static void det_sincos(double x, double *s, double *c)
{
    const double half_pi_hi = 1.57079632679489655800e+00; /* pi/2 split in two parts */
    const double half_pi_lo = 6.12323399573676603587e-17;
    double kf = x * (2.0 / PI);
    long k = (long)(kf < 0 ? kf - 0.5 : kf + 0.5);
    double r = (x - (double)k * half_pi_hi) - (double)k * half_pi_lo; /* |r| <= pi/4 */
    double r2 = r * r;
    double sr = r * (1.0 + r2 * (-1.0 / 6 + r2 * (1.0 / 120 + r2 * (-1.0 / 5040 + r2 * (1.0 / 362880
                + r2 * (-1.0 / 39916800 + r2 * (1.0 / 6227020800.0 + r2 * (-1.0 / 1307674368000.0))))))));
    double cr = 1.0 + r2 * (-0.5 + r2 * (1.0 / 24 + r2 * (-1.0 / 720 + r2 * (1.0 / 40320
                + r2 * (-1.0 / 3628800 + r2 * (1.0 / 479001600.0 + r2 * (-1.0 / 87178291200.0)))))));
    switch (((k % 4) + 4) % 4) {
    case 0: *s = sr; *c = cr; break;
    case 1: *s = cr; *c = -sr; break;
    case 2: *s = -sr; *c = -cr; break;
    default: *s = -cr; *c = sr; break;
    }
}

/* splitmix64 with a fixed seed. */
static uint64_t rng_state = 0x5eed0f0e0a2018ull;
static double rng_unit(void) /* [0,1) */
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

typedef struct { double x, y, z; } v3;
static v3 V(double x, double y, double z) { v3 r = {x, y, z}; return r; }
static v3 vadd(v3 a, v3 b) { return V(a.x + b.x, a.y + b.y, a.z + b.z); }
static v3 vsub(v3 a, v3 b) { return V(a.x - b.x, a.y - b.y, a.z - b.z); }
static v3 vmul(v3 a, double s) { return V(a.x * s, a.y * s, a.z * s); }
static double vdot(v3 a, v3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static v3 vcross(v3 a, v3 b)
{
    return V(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/* ---------------------------------------------------------------- meshes */

typedef struct {
    float *pos, *nrm;
    uint32_t *idx;
    size_t nv, cap_v, ni, cap_i;
} geo;

static uint32_t geo_vertex(geo *g, v3 p, v3 n)
{
    if (g->nv == g->cap_v) {
        g->cap_v = g->cap_v ? g->cap_v * 2 : 1024;
        g->pos = xrealloc(g->pos, g->cap_v * 3 * sizeof(float));
        g->nrm = xrealloc(g->nrm, g->cap_v * 3 * sizeof(float));
    }
    float *P = g->pos + 3 * g->nv, *N = g->nrm + 3 * g->nv;
    P[0] = (float)p.x; P[1] = (float)p.y; P[2] = (float)p.z;
    N[0] = (float)n.x; N[1] = (float)n.y; N[2] = (float)n.z;
    return (uint32_t)g->nv++;
}

static v3 geo_pos(const geo *g, uint32_t i)
{
    return V(g->pos[3 * i], g->pos[3 * i + 1], g->pos[3 * i + 2]);
}
static v3 geo_nrm(const geo *g, uint32_t i)
{
    return V(g->nrm[3 * i], g->nrm[3 * i + 1], g->nrm[3 * i + 2]);
}

/* Adds a triangle, wound counter-clockwise as seen from the side its vertex normals face
 * (glTF front faces), whatever order the caller gave. */
static void geo_tri(geo *g, uint32_t a, uint32_t b, uint32_t c)
{
    v3 pa = geo_pos(g, a), pb = geo_pos(g, b), pc = geo_pos(g, c);
    v3 fn = vcross(vsub(pb, pa), vsub(pc, pa));
    v3 vn = vadd(vadd(geo_nrm(g, a), geo_nrm(g, b)), geo_nrm(g, c));
    if (vdot(fn, vn) < 0) {
        uint32_t t = b;
        b = c;
        c = t;
    }
    if (g->ni + 3 > g->cap_i) {
        g->cap_i = g->cap_i ? g->cap_i * 2 : 3072;
        g->idx = xrealloc(g->idx, g->cap_i * sizeof(uint32_t));
    }
    g->idx[g->ni++] = a;
    g->idx[g->ni++] = b;
    g->idx[g->ni++] = c;
}

/* A flat rectangle o + s*U + t*V (s, t in [0,1]) split into nu x nv quads, normal n. */
static void add_grid(geo *g, v3 o, v3 U, v3 Vv, int nu, int nv, v3 n)
{
    uint32_t base = (uint32_t)g->nv;
    for (int j = 0; j <= nv; j++)
        for (int i = 0; i <= nu; i++)
            geo_vertex(g, vadd(o, vadd(vmul(U, (double)i / nu), vmul(Vv, (double)j / nv))), n);
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            uint32_t a = base + (uint32_t)(j * (nu + 1) + i);
            uint32_t b = a + 1, c = a + (uint32_t)(nu + 1) + 1, d = a + (uint32_t)(nu + 1);
            geo_tri(g, a, b, c);
            geo_tri(g, a, c, d);
        }
}

/* Rotates vertices [from, nv) by rot_y radians about +Y, then moves them by t. */
static void geo_place(geo *g, size_t from, double rot_y, v3 t)
{
    double s, c;
    det_sincos(rot_y, &s, &c);
    for (size_t i = from; i < g->nv; i++) {
        float *P = g->pos + 3 * i, *N = g->nrm + 3 * i;
        double px = P[0], pz = P[2], nx = N[0], nz = N[2];
        P[0] = (float)(c * px + s * pz + t.x);
        P[1] = (float)(P[1] + t.y);
        P[2] = (float)(c * pz - s * px + t.z);
        N[0] = (float)(c * nx + s * nz);
        N[2] = (float)(c * nz - s * nx);
    }
}

/* Box faces. */
enum { PX = 1, NX = 2, PY = 4, NY = 8, PZ = 16, NZ = 32, ALL_FACES = 63 };

static int cells(double len, double cell)
{
    int n = (int)(len / cell + 0.5);
    return n < 1 ? 1 : n;
}

/* Half extent of a box with half extents h along the axis-aligned unit vector a. */
static double half_along(v3 a, v3 h)
{
    return fabs(a.x) * h.x + fabs(a.y) * h.y + fabs(a.z) * h.z;
}

/* A box of half extents h centred at c, rotated by rot_y radians about its vertical axis;
 * only the faces in `faces` (outward normals), each split into quads of about `cell` metres. */
static void add_box(geo *g, v3 c, v3 h, double rot_y, int faces, double cell)
{
    static const struct { int bit; v3 n, u, v; } F[6] = {
        {PX, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},  {NX, {-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
        {PY, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}},  {NY, {0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
        {PZ, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {NZ, {0, 0, -1}, {0, 1, 0}, {1, 0, 0}},
    };
    size_t from = g->nv;
    for (int f = 0; f < 6; f++) {
        if (!(faces & F[f].bit))
            continue;
        v3 n = F[f].n, u = F[f].u, v = F[f].v;
        double hn = half_along(n, h), hu = half_along(u, h), hv = half_along(v, h);
        v3 o = vsub(vsub(vmul(n, hn), vmul(u, hu)), vmul(v, hv));
        add_grid(g, o, vmul(u, 2 * hu), vmul(v, 2 * hv), cells(2 * hu, cell), cells(2 * hv, cell), n);
    }
    geo_place(g, from, rot_y, c);
}

/* A UV sphere of radius r centred at c: `slices` around, `stacks` from pole to pole, one vertex
 * per pole; 2 * slices * (stacks - 1) triangles. */
static void add_sphere(geo *g, v3 c, double r, int slices, int stacks)
{
    uint32_t top = geo_vertex(g, vadd(c, V(0, r, 0)), V(0, 1, 0));
    uint32_t ring0 = (uint32_t)g->nv;
    for (int k = 1; k < stacks; k++) {
        double st, ct;
        det_sincos(PI * k / stacks, &st, &ct);
        for (int j = 0; j < slices; j++) {
            double sp, cp;
            det_sincos(2 * PI * j / slices, &sp, &cp);
            v3 n = V(st * cp, ct, -st * sp);
            geo_vertex(g, vadd(c, vmul(n, r)), n);
        }
    }
    uint32_t bottom = geo_vertex(g, vadd(c, V(0, -r, 0)), V(0, -1, 0));
    uint32_t S = (uint32_t)slices;
    for (uint32_t j = 0; j < S; j++) {
        uint32_t j1 = (j + 1) % S;
        geo_tri(g, top, ring0 + j, ring0 + j1);
        for (int k = 0; k + 2 < stacks; k++) {
            uint32_t a = ring0 + (uint32_t)k * S, b = a + S;
            geo_tri(g, a + j, b + j, b + j1);
            geo_tri(g, a + j, b + j1, a + j1);
        }
        uint32_t last = ring0 + (uint32_t)(stacks - 2) * S;
        geo_tri(g, bottom, last + j1, last + j);
    }
}

/* ---------------------------------------------------------------- materials and the scene */

typedef struct { const char *name; float rgba[4]; float roughness; } material_def;
enum {
    M_FLOOR_DARK, M_FLOOR_LIGHT, M_WALL_A, M_WALL_B, M_RIB, M_CEILING, M_LAMP, M_STUD,
    M_END_A, M_END_B, M_ARCH, M_RED, M_YELLOW, M_GREEN, M_ORANGE, M_PURPLE, M_CYAN,
    M_MAGENTA, M_LIME, M_BLUE, M_WHITE, M_COUNT
};
static const material_def MATS[M_COUNT] = {
    [M_FLOOR_DARK] = {"floor_dark", {0.08f, 0.08f, 0.10f, 1}, 0.9f},
    [M_FLOOR_LIGHT] = {"floor_light", {0.55f, 0.55f, 0.58f, 1}, 0.9f},
    [M_WALL_A] = {"wall_panel_a", {0.18f, 0.28f, 0.45f, 1}, 0.8f},
    [M_WALL_B] = {"wall_panel_b", {0.40f, 0.48f, 0.62f, 1}, 0.8f},
    [M_RIB] = {"wall_rib", {0.85f, 0.45f, 0.10f, 1}, 0.6f},
    [M_CEILING] = {"ceiling", {0.20f, 0.20f, 0.22f, 1}, 0.9f},
    [M_LAMP] = {"lamp", {0.95f, 0.92f, 0.80f, 1}, 0.5f},
    [M_STUD] = {"floor_stud", {0.90f, 0.85f, 0.25f, 1}, 0.6f},
    [M_END_A] = {"end_wall_light", {0.85f, 0.85f, 0.85f, 1}, 0.8f},
    [M_END_B] = {"end_wall_dark", {0.04f, 0.04f, 0.04f, 1}, 0.8f},
    [M_ARCH] = {"arch", {0.55f, 0.12f, 0.12f, 1}, 0.7f},
    [M_RED] = {"target_red", {0.85f, 0.06f, 0.05f, 1}, 0.5f},
    [M_YELLOW] = {"target_yellow", {0.90f, 0.75f, 0.05f, 1}, 0.5f},
    [M_GREEN] = {"target_green", {0.08f, 0.70f, 0.15f, 1}, 0.5f},
    [M_ORANGE] = {"target_orange", {0.95f, 0.40f, 0.04f, 1}, 0.5f},
    [M_PURPLE] = {"target_purple", {0.45f, 0.12f, 0.70f, 1}, 0.5f},
    [M_CYAN] = {"target_cyan", {0.04f, 0.65f, 0.75f, 1}, 0.5f},
    [M_MAGENTA] = {"target_magenta", {0.80f, 0.08f, 0.55f, 1}, 0.5f},
    [M_LIME] = {"target_lime", {0.55f, 0.85f, 0.08f, 1}, 0.5f},
    [M_BLUE] = {"ball_blue", {0.04f, 0.12f, 0.90f, 1}, 0.3f},
    [M_WHITE] = {"marker_white", {0.80f, 0.80f, 0.80f, 1}, 0.6f},
};

typedef struct {
    char name[40];
    int material;
    int label;      /* Weier's target label (1, 2, 3), 4 = far depth marker, 0 = tunnel */
    v3 t;           /* node translation */
    geo g;
} mesh;

#define MAX_MESHES 64
static mesh meshes[MAX_MESHES];
static int mesh_count;

static mesh *new_mesh(const char *name, int material, int label, v3 t)
{
    if (mesh_count == MAX_MESHES) {
        fprintf(stderr, "gen_range: too many meshes\n");
        exit(1);
    }
    mesh *m = &meshes[mesh_count++];
    snprintf(m->name, sizeof m->name, "%s", name);
    m->material = material;
    m->label = label;
    m->t = t;
    return m;
}

/* The tunnel is built in world space, merged into one mesh per material. */
static geo *tunnel_geo(int material)
{
    for (int i = 0; i < mesh_count; i++)
        if (meshes[i].label == 0 && meshes[i].material == material)
            return &meshes[i].g;
    char name[40];
    snprintf(name, sizeof name, "tunnel_%s", MATS[material].name);
    return &new_mesh(name, material, 0, V(0, 0, 0))->g;
}

static void build_tunnel(void)
{
    const double tile = 0.5;
    const int nx = 6, nz = 81; /* 3 m x 40.5 m of 0.5 m tiles */

    /* Floor: 0.5 m checker, each tile 4 x 4 quads. Ceiling: same tiles, one colour. */
    for (int iz = 0; iz < nz; iz++)
        for (int ix = 0; ix < nx; ix++) {
            double x0 = TUN_X0 + tile * ix, z1 = TUN_Z_NEAR - tile * (iz + 1);
            add_grid(tunnel_geo((ix + iz) & 1 ? M_FLOOR_LIGHT : M_FLOOR_DARK), V(x0, TUN_Y0, z1),
                     V(tile, 0, 0), V(0, 0, tile), 4, 4, V(0, 1, 0));
            add_grid(tunnel_geo(M_CEILING), V(x0, TUN_Y1, z1), V(tile, 0, 0), V(0, 0, tile), 4, 4,
                     V(0, -1, 0));
        }

    /* Walls: 0.5 m x 0.75 m panels in two colours, each 4 x 6 quads; a vertical rib (4 cm
     * square, its front and sides tessellated every 12.5 cm) on every panel seam. */
    for (int side = 0; side < 2; side++) {
        double x = side ? TUN_X1 : TUN_X0, inward = side ? -1 : 1;
        for (int iz = 0; iz < nz; iz++)
            for (int iy = 0; iy < 4; iy++) {
                double z1 = TUN_Z_NEAR - tile * (iz + 1);
                add_grid(tunnel_geo((iz + iy + side) & 1 ? M_WALL_B : M_WALL_A),
                         V(x, TUN_Y0 + 0.75 * iy, z1), V(0, 0, tile), V(0, 0.75, 0), 4, 6,
                         V(inward, 0, 0));
            }
        for (int k = 1; k < nz; k++)
            add_box(tunnel_geo(M_RIB), V(x + inward * 0.02, 1.5, TUN_Z_NEAR - tile * k),
                    V(0.02, 1.5, 0.02), 0, (side ? NX : PX) | PZ | NZ, 0.125);
    }

    /* A grid of small studs on the floor, 25 cm x 50 cm apart, 1.5-4 cm high. */
    for (int iz = 0; iz < 80; iz++)
        for (int ix = 0; ix < 11; ix++) {
            double hh = 0.015 + 0.025 * rng_unit();
            add_box(tunnel_geo(M_STUD), V(-1.25 + 0.25 * ix, hh / 2, -0.25 - 0.5 * iz),
                    V(0.02, hh / 2, 0.02), 0, ALL_FACES & ~NY, 1.0);
        }

    /* Two rows of lamp fixtures under the ceiling, one per metre. */
    for (int k = 0; k < 40; k++)
        for (int side = 0; side < 2; side++)
            add_box(tunnel_geo(M_LAMP), V(side ? 0.6 : -0.6, TUN_Y1 - 0.03, -0.5 - 1.0 * k),
                    V(0.1, 0.03, 0.3), 0, ALL_FACES & ~PY, 0.1);

    /* The end wall: 25 cm checker. */
    for (int iy = 0; iy < 12; iy++)
        for (int ix = 0; ix < 12; ix++)
            add_grid(tunnel_geo((ix + iy) & 1 ? M_END_B : M_END_A),
                     V(TUN_X0 + 0.25 * ix, TUN_Y0 + 0.25 * iy, TUN_Z_FAR), V(0.25, 0, 0),
                     V(0, 0.25, 0), 2, 2, V(0, 0, 1));

    /* Arches (two legs and a beam, 20 cm thick) every 4 m from 8 m to 36 m. */
    for (int k = 0; k < 8; k++) {
        double z = -8.0 - 4.0 * k;
        add_box(tunnel_geo(M_ARCH), V(TUN_X0 + 0.1, 1.4, z), V(0.1, 1.4, 0.1), 0, PX | PZ | NZ, 0.1);
        add_box(tunnel_geo(M_ARCH), V(TUN_X1 - 0.1, 1.4, z), V(0.1, 1.4, 0.1), 0, NX | PZ | NZ, 0.1);
        add_box(tunnel_geo(M_ARCH), V(0, 2.9, z), V(1.5, 0.1, 0.1), 0, NY | PZ | NZ, 0.1);
    }
}

/* The targets: one mesh each, built around the origin and placed by the node translation.
 * (tools/gen_trace.c aims the bundled gaze trace at TARGET_NEAR and TARGET_BALL.) */
#define TARGET_NEAR_X (-0.32)
#define TARGET_NEAR_Y 1.28
#define TARGET_NEAR_Z (-0.62)
#define TARGET_BALL_X 0.6
#define TARGET_BALL_Y 1.35
#define TARGET_BALL_Z (-6.0)

typedef struct {
    const char *name;
    int label, material;
    double x, y, z;
    double size;      /* sphere radius or box half edge */
    int is_box;
    double rot_y_deg; /* boxes */
    int detail;       /* spheres: slices (stacks = slices / 2); boxes: quads per edge */
} target;

static const target TARGETS[] = {
    /* label 1: 0.5-1 m, low and to the sides */
    {"target1_red_sphere", 1, M_RED, TARGET_NEAR_X, TARGET_NEAR_Y, TARGET_NEAR_Z, 0.07, 0, 0, 96},
    {"target1_yellow_box", 1, M_YELLOW, 0.36, 1.22, -0.70, 0.06, 1, 30, 13},
    {"target1_green_sphere", 1, M_GREEN, 0.18, 1.08, -0.78, 0.06, 0, 0, 96},
    {"target1_orange_box", 1, M_ORANGE, -0.15, 0.95, -0.72, 0.05, 1, -20, 10},
    /* label 2: 1-6 m, alternating sides */
    {"target2_green_sphere", 2, M_GREEN, -0.85, 1.95, -1.6, 0.15, 0, 0, 64},
    {"target2_purple_box", 2, M_PURPLE, 0.75, 1.05, -2.1, 0.14, 1, 20, 11},
    {"target2_cyan_sphere", 2, M_CYAN, -0.55, 0.80, -2.8, 0.18, 0, 0, 64},
    {"target2_magenta_sphere", 2, M_MAGENTA, 0.95, 2.25, -3.3, 0.22, 0, 0, 64},
    {"target2_lime_box", 2, M_LIME, -1.0, 1.50, -3.9, 0.18, 1, 45, 14},
    {"target2_yellow_box", 2, M_YELLOW, 1.05, 1.20, -4.6, 0.15, 1, 10, 12},
    {"target2_orange_sphere", 2, M_ORANGE, -0.45, 2.45, -5.0, 0.20, 0, 0, 64},
    {"target2_red_sphere", 2, M_RED, -0.90, 0.55, -5.4, 0.20, 0, 0, 64},
    /* label 3: the big blue ball at 6 m */
    {"target3_blue_ball", 3, M_BLUE, TARGET_BALL_X, TARGET_BALL_Y, TARGET_BALL_Z, 0.5, 0, 0, 254},
    /* depth markers further down the tunnel, left of the ball (which hides the right half of the
     * far tunnel from the default viewpoint), between the arches */
    {"marker_sphere_10m", 4, M_WHITE, -0.8, 2.0, -10.0, 0.30, 0, 0, 56},
    {"marker_box_14m", 4, M_WHITE, -0.9, 0.7, -14.0, 0.25, 1, 30, 10},
    {"marker_sphere_22m", 4, M_WHITE, -0.5, 2.2, -22.0, 0.30, 0, 0, 56},
    {"marker_box_30m", 4, M_WHITE, -0.8, 1.0, -30.0, 0.30, 1, 0, 12},
};

static void build_targets(void)
{
    for (size_t i = 0; i < sizeof TARGETS / sizeof TARGETS[0]; i++) {
        const target *t = &TARGETS[i];
        mesh *m = new_mesh(t->name, t->material, t->label, V(t->x, t->y, t->z));
        if (t->is_box)
            add_box(&m->g, V(0, 0, 0), V(t->size, t->size, t->size), t->rot_y_deg * (PI / 180),
                    ALL_FACES, 2 * t->size / t->detail);
        else
            add_sphere(&m->g, V(0, 0, 0), t->size, t->detail, t->detail / 2);
    }
}

/* ---------------------------------------------------------------- output */

typedef struct { char *p; size_t n, cap; } buf;

static void buf_put(buf *b, const void *d, size_t n)
{
    if (b->n + n > b->cap) {
        while (b->n + n > b->cap)
            b->cap = b->cap ? b->cap * 2 : 65536;
        b->p = xrealloc(b->p, b->cap);
    }
    memcpy(b->p + b->n, d, n);
    b->n += n;
}

static void buf_u32(buf *b, uint32_t v) /* little-endian on every host */
{
    unsigned char c[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                          (unsigned char)(v >> 24)};
    buf_put(b, c, 4);
}

static void buf_f32(buf *b, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    buf_u32(b, v);
}

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void buf_printf(buf *b, const char *fmt, ...)
{
    char tmp[512];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= sizeof tmp) {
        fprintf(stderr, "gen_range: internal error (JSON fragment too long)\n");
        exit(1);
    }
    buf_put(b, tmp, (size_t)n);
}

/* Shortest decimal that reads back as the same double / float (JSON numbers, locale "C"). */
static const char *num_d(char *s, double v)
{
    for (int prec = 1; prec <= 17; prec++) {
        snprintf(s, 32, "%.*g", prec, v);
        if (strtod(s, NULL) == v)
            break;
    }
    return s;
}
static const char *num_f(char *s, float v)
{
    for (int prec = 1; prec <= 9; prec++) {
        snprintf(s, 32, "%.*g", prec, (double)v);
        if (strtof(s, NULL) == v)
            break;
    }
    return s;
}

static const char *thousands(char *s, unsigned long long v)
{
    char t[32];
    int n = snprintf(t, sizeof t, "%llu", v), j = 0;
    for (int i = 0; i < n; i++) {
        if (i > 0 && (n - i) % 3 == 0)
            s[j++] = ',';
        s[j++] = t[i];
    }
    s[j] = 0;
    return s;
}

static void build_glb(buf *out, size_t *tri_count)
{
    buf bin = {0}, js = {0};
    char a[32], b[32], c[32];
    size_t tris = 0;

    /* BIN: per mesh positions, normals, indices (all 4-byte items, so everything stays aligned). */
    size_t off[MAX_MESHES][3];
    for (int i = 0; i < mesh_count; i++) {
        const geo *g = &meshes[i].g;
        off[i][0] = bin.n;
        for (size_t k = 0; k < 3 * g->nv; k++)
            buf_f32(&bin, g->pos[k]);
        off[i][1] = bin.n;
        for (size_t k = 0; k < 3 * g->nv; k++)
            buf_f32(&bin, g->nrm[k]);
        off[i][2] = bin.n;
        for (size_t k = 0; k < g->ni; k++)
            buf_u32(&bin, g->idx[k]);
        tris += g->ni / 3;
    }
    if (bin.n > 0xffffffffu - 64) {
        fprintf(stderr, "gen_range: scene too large for a .glb\n");
        exit(1);
    }

    buf_printf(&js, "{\"asset\":{\"version\":\"2.0\",\"generator\":\"fovea tools/gen_range.c\","
                    "\"copyright\":\"generated test scene after Weier et al. 2018\"},");
    buf_printf(&js, "\"scene\":0,\"scenes\":[{\"name\":\"space_shooting_range\",\"nodes\":[");
    for (int i = 0; i <= mesh_count; i++)
        buf_printf(&js, "%s%d", i ? "," : "", i);
    buf_printf(&js, "]}],");

    buf_printf(&js, "\"cameras\":[{\"name\":\"eye\",\"type\":\"perspective\",\"perspective\":{"
                    "\"yfov\":%s,\"aspectRatio\":%s,\"znear\":%s}}],",
               num_d(a, 100.0 * PI / 180.0), num_d(b, 1280.0 / 1440.0), num_d(c, 0.05));

    buf_printf(&js, "\"nodes\":[{\"name\":\"eye\",\"camera\":0,\"translation\":[%s,%s,%s],"
                    "\"rotation\":[0,0,0,1]}",
               num_d(a, EYE_X), num_d(b, EYE_Y), num_d(c, EYE_Z));
    for (int i = 0; i < mesh_count; i++) {
        const mesh *m = &meshes[i];
        buf_printf(&js, ",{\"name\":\"%s\",\"mesh\":%d", m->name, i);
        if (m->t.x != 0 || m->t.y != 0 || m->t.z != 0)
            buf_printf(&js, ",\"translation\":[%s,%s,%s]", num_d(a, m->t.x), num_d(b, m->t.y),
                       num_d(c, m->t.z));
        if (m->label)
            buf_printf(&js, ",\"extras\":{\"label\":%d}", m->label);
        buf_printf(&js, "}");
    }
    buf_printf(&js, "],");

    buf_printf(&js, "\"meshes\":[");
    for (int i = 0; i < mesh_count; i++)
        buf_printf(&js, "%s{\"name\":\"%s\",\"primitives\":[{\"attributes\":{\"POSITION\":%d,"
                        "\"NORMAL\":%d},\"indices\":%d,\"material\":%d,\"mode\":4}]}",
                   i ? "," : "", meshes[i].name, 3 * i, 3 * i + 1, 3 * i + 2, meshes[i].material);
    buf_printf(&js, "],");

    buf_printf(&js, "\"materials\":[");
    for (int i = 0; i < M_COUNT; i++) {
        const material_def *m = &MATS[i];
        char d[32];
        buf_printf(&js, "%s{\"name\":\"%s\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[%s,%s,%s,%s],"
                        "\"metallicFactor\":0,",
                   i ? "," : "", m->name, num_f(a, m->rgba[0]), num_f(b, m->rgba[1]),
                   num_f(c, m->rgba[2]), num_f(d, m->rgba[3]));
        buf_printf(&js, "\"roughnessFactor\":%s}}", num_f(a, m->roughness));
    }
    buf_printf(&js, "],");

    buf_printf(&js, "\"accessors\":[");
    for (int i = 0; i < mesh_count; i++) {
        const geo *g = &meshes[i].g;
        float lo[3], hi[3];
        for (int k = 0; k < 3; k++)
            lo[k] = hi[k] = g->pos[k];
        for (size_t v = 0; v < g->nv; v++)
            for (int k = 0; k < 3; k++) {
                float p = g->pos[3 * v + k];
                if (p < lo[k]) lo[k] = p;
                if (p > hi[k]) hi[k] = p;
            }
        /* min/max: the float's exact value in shortest double form, so it compares equal to the
         * data whether a reader keeps JSON numbers as doubles or rounds them to float. */
        char d[32], e[32], f[32];
        buf_printf(&js, "%s{\"bufferView\":%d,\"componentType\":5126,\"count\":%zu,\"type\":\"VEC3\","
                        "\"min\":[%s,%s,%s],",
                   i ? "," : "", 3 * i, g->nv, num_d(a, lo[0]), num_d(b, lo[1]), num_d(c, lo[2]));
        buf_printf(&js, "\"max\":[%s,%s,%s]},", num_d(d, hi[0]), num_d(e, hi[1]), num_d(f, hi[2]));
        buf_printf(&js, "{\"bufferView\":%d,\"componentType\":5126,\"count\":%zu,\"type\":\"VEC3\"},",
                   3 * i + 1, g->nv);
        buf_printf(&js, "{\"bufferView\":%d,\"componentType\":5125,\"count\":%zu,\"type\":\"SCALAR\"}",
                   3 * i + 2, g->ni);
    }
    buf_printf(&js, "],");

    buf_printf(&js, "\"bufferViews\":[");
    for (int i = 0; i < mesh_count; i++) {
        const geo *g = &meshes[i].g;
        buf_printf(&js, "%s{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"target\":34962},",
                   i ? "," : "", off[i][0], 12 * g->nv);
        buf_printf(&js, "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"target\":34962},",
                   off[i][1], 12 * g->nv);
        buf_printf(&js, "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"target\":34963}",
                   off[i][2], 4 * g->ni);
    }
    buf_printf(&js, "],\"buffers\":[{\"byteLength\":%zu}]}", bin.n);

    while (js.n % 4)
        buf_put(&js, " ", 1);
    while (bin.n % 4)
        buf_put(&bin, "", 1);

    size_t total = 12 + 8 + js.n + 8 + bin.n;
    buf_u32(out, 0x46546C67u); /* "glTF" */
    buf_u32(out, 2);
    buf_u32(out, (uint32_t)total);
    buf_u32(out, (uint32_t)js.n);
    buf_u32(out, 0x4E4F534Au); /* "JSON" */
    buf_put(out, js.p, js.n);
    buf_u32(out, (uint32_t)bin.n);
    buf_u32(out, 0x004E4942u); /* "BIN\0" */
    buf_put(out, bin.p, bin.n);
    free(js.p);
    free(bin.p);
    *tri_count = tris;
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: gen_range --out FILE\n"
            "Writes fovea's bundled test scene, a \"space shooting range\" after Weier et al. 2018,\n"
            "as a binary glTF 2.0 file (deterministic: the same bytes on every run).\n"
            "  --out FILE   where to write the .glb (written to FILE.tmp, then renamed)\n"
            "  --help       this text\n"
            "Exit status: 0 success, 2 bad usage, 1 the file cannot be written.\n");
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
                fprintf(stderr, "gen_range: --out needs a FILE (try --help)\n");
                return 2;
            }
            out = argv[++i];
        } else if (!strncmp(argv[i], "--out=", 6)) {
            out = argv[i] + 6;
        } else {
            fprintf(stderr, "gen_range: unknown argument '%s' (try --help)\n", argv[i]);
            return 2;
        }
    }
    if (!out || !*out) {
        fprintf(stderr, "gen_range: --out FILE is required (try --help)\n");
        return 2;
    }

    build_tunnel();
    build_targets();
    buf glb = {0};
    size_t tris = 0;
    build_glb(&glb, &tris);

    size_t len = strlen(out);
    char *tmp = xrealloc(NULL, len + 5);
    memcpy(tmp, out, len);
    memcpy(tmp + len, ".tmp", 5);
    FILE *f = fopen(tmp, "wb");
    int err = 0;
    if (!f) {
        err = errno;
    } else {
        if (fwrite(glb.p, 1, glb.n, f) != glb.n || fflush(f) != 0)
            err = errno ? errno : EIO;
        if (fclose(f) != 0 && !err)
            err = errno ? errno : EIO;
        if (!err && rename(tmp, out) != 0)
            err = errno;
        if (err)
            remove(tmp);
    }
    if (err) {
        fprintf(stderr, "gen_range: cannot write %s: %s\n", out, strerror(err));
        free(tmp);
        return 1;
    }
    char t1[32], t2[32];
    printf("%s: %s triangles, %d meshes, %s bytes\n", out, thousands(t1, tris), mesh_count,
           thousands(t2, glb.n));
    free(tmp);
    free(glb.p);
    for (int i = 0; i < mesh_count; i++) {
        free(meshes[i].g.pos);
        free(meshes[i].g.nrm);
        free(meshes[i].g.idx);
    }
    return 0;
}
