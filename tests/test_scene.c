/* Scene tests: the builder (hits, shading, textures, normals, lights, default view), the
 * glTF loader (hierarchy, camera, the shared scenes) and hostile files (truncated,
 * corrupted, out-of-range), which must fail cleanly. Expected values are worked out by
 * hand in the comments, or counted from the files with an independent script. */
#include "testutil.h"

#include "scene.h"
#include "testscene.h"
#include "shade_dsp.h"
#include "blend.h"
#include "texture_tap.h" /* the packet shading's inline taps (internal) */

#include <stb/stb_image_write.h>

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define SQ2 0.70710678f

static void assert_near_msg(float got, float want, float tol, const char *what, int line)
{
    if (!(fabsf(got - want) <= tol)) {
        print_error("line %d: %s = %.7g, expected %.7g (tol %g)\n", line, what, (double)got, (double)want, (double)tol);
        fail();
    }
}
#define assert_near(got, want, tol) assert_near_msg((got), (want), (tol), #got, __LINE__)

static void assert_rgb(const float rgb[3], float r, float g, float b, float tol, int line)
{
    assert_near_msg(rgb[0], r, tol, "r", line);
    assert_near_msg(rgb[1], g, tol, "g", line);
    assert_near_msg(rgb[2], b, tol, "b", line);
}

/* ---- helpers --------------------------------------------------------------------------- */

typedef struct hit {
    float t, u, v;
    unsigned geom, prim;
} hit;

/* One ray through rtcIntersect1; returns 1 on a hit. */
static int cast(const fv_scene *s, const float o[3], const float d[3], hit *h)
{
    memset(h, 0, sizeof *h); /* cmocka's fail() is not noreturn: keep callers' reads defined */
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = o[0], rh.ray.org_y = o[1], rh.ray.org_z = o[2];
    rh.ray.dir_x = d[0], rh.ray.dir_y = d[1], rh.ray.dir_z = d[2];
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = INFINITY;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    fv_scene_intersect1(s, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return 0;
    h->t = rh.ray.tfar, h->u = rh.hit.u, h->v = rh.hit.v, h->geom = rh.hit.geomID, h->prim = rh.hit.primID;
    return 1;
}

/* Casts and shades with the head light at the ray origin; asserts a hit. */
static void cast_shade(const fv_scene *s, const float o[3], const float d[3], float footprint, hit *h, float rgb[3])
{
    assert_true(cast(s, o, d, h));
    fv_scene_shade(s, h->geom, h->prim, h->u, h->v, o, d, h->t, footprint, o, rgb);
}

static fv_mesh_desc mesh(const float *pos, size_t nv, const uint32_t *idx, size_t ni)
{
    fv_mesh_desc m;
    memset(&m, 0, sizeof m);
    m.positions = pos, m.vertex_count = nv, m.indices = idx, m.index_count = ni;
    m.base_color[0] = m.base_color[1] = m.base_color[2] = m.base_color[3] = 1.0f;
    m.texture = -1;
    return m;
}

static fv_scene *commit_or_fail(fv_scene *s)
{
    char err[256] = "";
    assert_int_equal(fv_scene_commit(s, err, sizeof err), 0);
    return s;
}

static double srgb_to_linear(int c)
{
    const double x = c / 255.0;
    return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}

static char *path_join(char *buf, size_t n, const char *a, const char *b)
{
    snprintf(buf, n, "%s/%s", a, b);
    return buf;
}

/* The path of a sample scene shipped in assets/scenes/ (assets/scenes/README.md: copied from the
 * shared assets with their licences, so a plain clone runs these tests too). Missing is a failure. */
static char *shared_scene(char *buf, size_t n, const char *rel)
{
    snprintf(buf, n, "assets/scenes/%s", rel);
    FILE *f = fopen(buf, "rb");
    if (!f)
        fail_msg("%s not found (run the tests from the project root)", buf);
    fclose(f);
    return buf;
}

static unsigned char *read_all(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        print_error("cannot open %s\n", path);
        fail();
    }
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc((size_t)n + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    b[n] = 0;
    *len = (size_t)n;
    return b;
}

static void write_all(const char *path, const void *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, len, f), len);
    assert_int_equal(fclose(f), 0);
}

static char *tmpdir_make(void)
{
    char tmpl[] = "/tmp/fv_scene_test_XXXXXX";
    assert_non_null(mkdtemp(tmpl));
    return strdup(tmpl);
}

static void tmpdir_remove(char *dir)
{
    DIR *d = opendir(dir);
    if (d) {
        struct dirent *e;
        char p[512];
        while ((e = readdir(d)))
            if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) unlink(path_join(p, sizeof p, dir, e->d_name));
        closedir(d);
    }
    rmdir(dir);
    free(dir);
}

/* Loading must fail with a one-line reason (and, under ASan, without touching bad memory).
 * Returns 1 if it did, else prints why not and returns 0. */
static int load_fails(const char *path, const char *must_contain)
{
    char err[512];
    memset(err, 'x', sizeof err);
    fv_scene *s = fv_scene_load(path, err, sizeof err);
    if (s) {
        print_error("%s loaded but should have failed\n", path);
        fv_scene_free(s);
        return 0;
    }
    const size_t n = strnlen(err, sizeof err);
    if (n == 0 || n == sizeof err) {
        print_error("%s: no error message\n", path);
        return 0;
    }
    for (size_t i = 0; i < n; i++)
        if ((unsigned char)err[i] < 0x20) {
            print_error("%s: error message is not one line\n", path);
            return 0;
        }
    if (must_contain && !strstr(err, must_contain)) {
        print_error("error \"%s\" does not mention \"%s\"\n", err, must_contain);
        return 0;
    }
    return 1;
}
#define expect_load_fails(path, must_contain) assert_true(load_fails((path), (must_contain)))

/* Loading may succeed or fail, but a failure must carry a reason. */
static void load_any(const char *path)
{
    char err[512] = "";
    fv_scene *s = fv_scene_load(path, err, sizeof err);
    if (s) fv_scene_free(s);
    else assert_true(strlen(err) > 0);
}

static char *base64(const unsigned char *d, size_t n)
{
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *o = malloc(4 * ((n + 2) / 3) + 1), *p = o;
    assert_non_null(o);
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)d[i] << 16 | (i + 1 < n ? (uint32_t)d[i + 1] << 8 : 0) | (i + 2 < n ? d[i + 2] : 0);
        *p++ = tab[v >> 18 & 63];
        *p++ = tab[v >> 12 & 63];
        *p++ = i + 1 < n ? tab[v >> 6 & 63] : '=';
        *p++ = i + 2 < n ? tab[v & 63] : '=';
    }
    *p = 0;
    return o;
}

/* Writes dir/name as a .gltf with bin as its one embedded buffer plus the given JSON members. */
static void write_gltf(const char *path, const void *bin, size_t bin_len, const char *members)
{
    char *b64 = base64(bin, bin_len);
    size_t n = strlen(b64) + strlen(members) + 256;
    char *json = malloc(n);
    assert_non_null(json);
    snprintf(json, n,
             "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":%zu,"
             "\"uri\":\"data:application/octet-stream;base64,%s\"}],%s}",
             bin_len, b64, members);
    write_all(path, json, strlen(json));
    free(json);
    free(b64);
}

/* The textured quad the material tests load: positions [-1,1]^2 at z = 0 (48 bytes), the given
 * uv (32 bytes), two triangles as uint16 indices (12 bytes), in one 92-byte buffer. */
static void quad_buffer(unsigned char bin[92], const float uv[8])
{
    static const float pos[12] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    static const uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
    memcpy(bin, pos, 48);
    memcpy(bin + 48, uv, 32);
    memcpy(bin + 80, idx, 12);
}

/* ---- builder: hits and shading ------------------------------------------------------- */

/* Quad [-1,1]^2 at z=0, colour (0.8, 0.4, 0.2). A ray from (0.25, 0.25, 3) with dir
 * (0,0,-2) reaches z=0 at t = 3/2. The head light sits at the ray origin, straight above
 * the hit: lambert 1, so colour = base * (0.15 + 1). */
static void test_builder_quad_hit_and_headlight(void **state)
{
    (void)state;
    const float pos[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    const uint32_t idx[] = {0, 1, 2, 0, 2, 3};
    fv_scene *s = fv_scene_create();
    assert_non_null(s);
    fv_mesh_desc m = mesh(pos, 4, idx, 6);
    m.base_color[0] = 0.8f, m.base_color[1] = 0.4f, m.base_color[2] = 0.2f;
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    commit_or_fail(s);
    assert_int_equal(fv_scene_triangle_count(s), 2);
    assert_int_equal(fv_scene_light_count(s), 0);

    const float o[3] = {0.25f, 0.25f, 3}, d[3] = {0, 0, -2};
    hit h;
    float rgb[3];
    cast_shade(s, o, d, 0.0f, &h, rgb);
    assert_near(h.t, 1.5f, 1e-5f);
    assert_rgb(rgb, 0.8f * 1.15f, 0.4f * 1.15f, 0.2f * 1.15f, 1e-5f, __LINE__);

    /* Oblique head light: the eye is 3 off along x and 4 up, so cos = 4/5 at the hit
     * (0.25, 0.25, 0): colour = base * (0.15 + 0.8). From below the normal flips (double-sided). */
    const float o2[3] = {3.25f, 0.25f, 4}, d2[3] = {-3, 0, -4};
    cast_shade(s, o2, d2, 0.0f, &h, rgb);
    assert_near(h.t, 1.0f, 1e-5f);
    assert_rgb(rgb, 0.8f * 0.95f, 0.4f * 0.95f, 0.2f * 0.95f, 1e-5f, __LINE__);
    const float o3[3] = {0.25f, 0.25f, -4}, d3[3] = {0, 0, 1};
    cast_shade(s, o3, d3, 0.0f, &h, rgb);
    assert_near(h.t, 4.0f, 1e-5f);
    assert_rgb(rgb, 0.8f * 1.15f, 0.4f * 1.15f, 0.2f * 1.15f, 1e-5f, __LINE__);

    /* A miss stays a miss. */
    const float o4[3] = {1.5f, 0, 3};
    assert_false(cast(s, o4, d, &h));
    fv_scene_free(s);
}

/* Non-indexed triangle moved by the desc transform (column-major, translation (0,0,-2)):
 * a ray from the origin down -Z hits at t = 2; bounds follow the transform. */
static void test_builder_transform_non_indexed(void **state)
{
    (void)state;
    const float pos[] = {-1, -1, 0, 1, -1, 0, 0, 1, 0};
    fv_scene *s = fv_scene_create();
    fv_mesh_desc m = mesh(pos, 3, NULL, 0);
    m.transform[0] = m.transform[5] = m.transform[10] = m.transform[15] = 1.0f;
    m.transform[14] = -2.0f;
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    commit_or_fail(s);
    float lo[3], hi[3];
    fv_scene_bounds(s, lo, hi);
    assert_near(lo[0], -1, 0), assert_near(lo[1], -1, 0), assert_near(lo[2], -2, 0);
    assert_near(hi[0], 1, 0), assert_near(hi[1], 1, 0), assert_near(hi[2], -2, 0);
    const float o[3] = {0, 0, 0}, d[3] = {0, 0, -1};
    hit h;
    assert_true(cast(s, o, d, &h));
    assert_near(h.t, 2.0f, 1e-6f);
    assert_int_equal(h.geom, 0);
    fv_scene_free(s);
}

/* Smooth area-weighted normals. Triangle 0 (A,B,C) = (0,0,0),(2,0,0),(0,2,0) has
 * e1 x e2 = (0,0,4); triangle 1 (A,D,B) with D = (0,0,1) has (0,0,1) x (2,0,0) = (0,2,0).
 * Shared A and B get normalize(0,2,4) = (0, 1/sqrt5, 2/sqrt5); C gets (0,0,1), D (0,1,0).
 * Shading with the eye straight above (+Z) gives base * (0.15 + n.z). */
static void test_builder_computed_normals(void **state)
{
    (void)state;
    const float pos[] = {0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 1};
    const uint32_t idx[] = {0, 1, 2, 0, 3, 1};
    fv_scene *s = fv_scene_create();
    fv_mesh_desc m = mesh(pos, 4, idx, 6);
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    commit_or_fail(s);
    float rgb[3];
    const float up[3] = {0, 0, -1};
    const float eye_a[3] = {0, 0, 3}; /* vertex A of triangle 0: u = v = 0 */
    fv_scene_shade(s, 0, 0, 0, 0, eye_a, up, 3, 0, eye_a, rgb);
    const float want_a = 0.15f + 2.0f / sqrtf(5.0f);
    assert_rgb(rgb, want_a, want_a, want_a, 1e-5f, __LINE__);
    const float eye_b[3] = {2, 0, 3}; /* vertex B = vertex 1 of triangle 0: u = 1 */
    fv_scene_shade(s, 0, 0, 1, 0, eye_b, up, 3, 0, eye_b, rgb);
    assert_rgb(rgb, want_a, want_a, want_a, 1e-5f, __LINE__);
    const float eye_c[3] = {0, 2, 3}; /* vertex C: v = 1 */
    fv_scene_shade(s, 0, 0, 0, 1, eye_c, up, 3, 0, eye_c, rgb);
    assert_rgb(rgb, 1.15f, 1.15f, 1.15f, 1e-5f, __LINE__);
    /* D = vertex 1 of triangle 1, normal (0,1,0): lit from +Y fully, from +Z not at all. */
    const float eye_d[3] = {0, 3, 1}, toward_d[3] = {0, -1, 0};
    fv_scene_shade(s, 0, 1, 1, 0, eye_d, toward_d, 3, 0, eye_d, rgb);
    assert_rgb(rgb, 1.15f, 1.15f, 1.15f, 1e-5f, __LINE__);
    const float eye_d2[3] = {0, 0, 4};
    fv_scene_shade(s, 0, 1, 1, 0, eye_d2, up, 3, 0, eye_d2, rgb);
    assert_rgb(rgb, 0.15f, 0.15f, 0.15f, 1e-5f, __LINE__);
    fv_scene_free(s);
}

/* Given normals go through the inverse-transpose. Normal (1,1,0)/sqrt2 under scale (2,1,1)
 * becomes normalize(1/2, 1, 0) = (1,2,0)/sqrt5 (a plain transform would give (2,1,0)/sqrt5).
 * The scaled triangle (0,0,0),(2,0,0),(0,1,0) is hit at p = (0.5,0.25,0) from the eye at
 * p + (1,2,2): L = (1,2,2)/3, lambert = 5/(3 sqrt5) = sqrt5/3. */
static void test_builder_normals_inverse_transpose(void **state)
{
    (void)state;
    const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const float nrm[] = {SQ2, SQ2, 0, SQ2, SQ2, 0, SQ2, SQ2, 0};
    fv_scene *s = fv_scene_create();
    fv_mesh_desc m = mesh(pos, 3, NULL, 0);
    m.normals = nrm;
    m.transform[0] = 2, m.transform[5] = 1, m.transform[10] = 1, m.transform[15] = 1;
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    commit_or_fail(s);
    const float o[3] = {1.5f, 2.25f, 2}, d[3] = {-1, -2, -2};
    hit h;
    float rgb[3];
    cast_shade(s, o, d, 0, &h, rgb);
    assert_near(h.t, 1.0f, 1e-5f);
    assert_near(h.u, 0.25f, 1e-5f);
    assert_near(h.v, 0.25f, 1e-5f);
    const float want = 0.15f + sqrtf(5.0f) / 3.0f;
    assert_rgb(rgb, want, want, want, 1e-5f, __LINE__);
    fv_scene_free(s);
}

/* ---- builder: textures --------------------------------------------------------------- */

/* Triangle (0,0,0),(1,0,0),(0,1,0) with uvs equal to its xy, so the barycentric (u,v) passed
 * to shade are the texture coordinates. Head light straight above: colour = texel * 1.15. */
static fv_scene *textured_triangle(const uint8_t *texels, int w, int h)
{
    static const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    static const float uv[] = {0, 0, 1, 0, 0, 1};
    fv_scene *s = fv_scene_create();
    assert_non_null(s);
    int t = fv_scene_add_texture(s, texels, w, h);
    assert_int_equal(t, 0);
    fv_mesh_desc m = mesh(pos, 3, NULL, 0);
    m.uvs = uv;
    m.texture = t;
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    return commit_or_fail(s);
}

static void shade_uv(const fv_scene *s, float u, float v, float footprint, float rgb[3])
{
    const float o[3] = {u, v, 1}, d[3] = {0, 0, -1};
    fv_scene_shade(s, 0, 0, u, v, o, d, 1.0f, footprint, o, rgb);
}

/* 4x2 texture; texel (x,y) has sRGB channels given below. At texel centres the bilinear
 * sample is the texel; halfway between two centres it is their linear average; at u = 0
 * REPEAT blends column 3 with column 0, at v = 0 row 1 with row 0; u = 1.25 equals 0.25. */
static void test_texture_bilinear_wrap(void **state)
{
    (void)state;
    static const int val[2][4][3] = {
        {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 255}},
        {{128, 128, 128}, {64, 32, 16}, {200, 100, 50}, {10, 20, 30}},
    };
    uint8_t tex[2 * 4 * 4];
    for (int y = 0; y < 2; y++)
        for (int x = 0; x < 4; x++) {
            for (int c = 0; c < 3; c++) tex[(y * 4 + x) * 4 + c] = (uint8_t)val[y][x][c];
            tex[(y * 4 + x) * 4 + 3] = 255;
        }
    fv_scene *s = textured_triangle(tex, 4, 2);
    float rgb[3];
#define LIN(y, x, c) ((float)srgb_to_linear(val[y][x][c]) * 1.15f)
    for (int y = 0; y < 2; y++)
        for (int x = 0; x < 4; x++) {
            shade_uv(s, (x + 0.5f) / 4, (y + 0.5f) / 2, 0, rgb);
            assert_rgb(rgb, LIN(y, x, 0), LIN(y, x, 1), LIN(y, x, 2), 1e-5f, __LINE__);
        }
    shade_uv(s, 0.25f, 0.25f, 0, rgb); /* between (0,0) and (1,0) */
    assert_rgb(rgb, 0.5f * (LIN(0, 0, 0) + LIN(0, 1, 0)), 0.5f * (LIN(0, 0, 1) + LIN(0, 1, 1)),
               0.5f * (LIN(0, 0, 2) + LIN(0, 1, 2)), 1e-5f, __LINE__);
    shade_uv(s, 0.0f, 0.25f, 0, rgb); /* wraps: (3,0) with (0,0) */
    assert_rgb(rgb, 0.5f * (LIN(0, 3, 0) + LIN(0, 0, 0)), 0.5f * (LIN(0, 3, 1) + LIN(0, 0, 1)),
               0.5f * (LIN(0, 3, 2) + LIN(0, 0, 2)), 1e-5f, __LINE__);
    shade_uv(s, 0.625f, 0.0f, 0, rgb); /* column 2, wraps vertically: row 1 with row 0 */
    assert_rgb(rgb, 0.5f * (LIN(1, 2, 0) + LIN(0, 2, 0)), 0.5f * (LIN(1, 2, 1) + LIN(0, 2, 1)),
               0.5f * (LIN(1, 2, 2) + LIN(0, 2, 2)), 1e-5f, __LINE__);
    float rgb2[3];
    shade_uv(s, 0.125f, 0.25f, 0, rgb);
    shade_uv(s, 1.125f, -0.75f, 0, rgb2);
    assert_rgb(rgb2, rgb[0], rgb[1], rgb[2], 1e-5f, __LINE__);
#undef LIN
    fv_scene_free(s);
}

/* The taps one map shares with another of the same size and wrap modes (fv_tex_taps_rebase, the
 * packet shading's shortcut) are the ones computed for the other map directly: same texels of
 * the other texture, same weights, for coordinates across and beyond [0, 1], NaN, every level
 * and lod range, every wrap mode; and a texture of another size is not the same layout. */
static void test_texture_taps_rebase(void **state)
{
    (void)state;
    uint8_t a[8 * 4 * 4], b[8 * 4 * 4], c[4 * 4 * 4];
    for (int i = 0; i < (int)sizeof a; i++) a[i] = (uint8_t)(i * 7), b[i] = (uint8_t)(255 - i * 3);
    memset(c, 9, sizeof c);
    fv_scene *s = fv_scene_create();
    assert_non_null(s);
    assert_int_equal(fv_scene_add_texture(s, a, 8, 4), 0);
    assert_int_equal(fv_scene_add_texture_linear(s, b, 8, 4), 1);
    assert_int_equal(fv_scene_add_texture(s, c, 4, 4), 2);
    const fv_texture *ta = &s->textures[0], *tb = &s->textures[1];
    assert_false(fv_tex_same_layout(ta, &s->textures[2]));
    uint64_t seed = 5;
    static const fv_wrap modes[3] = {FV_WRAP_REPEAT, FV_WRAP_CLAMP, FV_WRAP_MIRROR};
    int two_levels = 0;
    for (int m = 0; m < 9; m++) {
        for (int k = 0; k < 2; k++)
            assert_int_equal(fv_scene_set_texture_wrap(s, k, modes[m % 3], modes[m / 3]), 0);
        assert_true(fv_tex_same_layout(ta, tb));
        for (int it = 0; it < 2000; it++) {
            float u = -2.0f + 5.0f * fv_test_randf(&seed), v = -2.0f + 5.0f * fv_test_randf(&seed);
            float lod = -1.0f + 8.0f * fv_test_randf(&seed); /* levels 0 .. 3, and beyond the last */
            if (it % 97 == 0) u = NAN;
            if (it % 89 == 0) lod = NAN;
            if (it % 83 == 0) lod = (float)(it % 4); /* whole levels: f = 0 */
            fv_tex_taps ra, want, got;
            fv_tex_taps_at(ta, u, v, lod, &ra);
            fv_tex_taps_at(tb, u, v, lod, &want);
            fv_tex_taps_rebase(ta, tb, &ra, &got);
            assert_memory_equal(&got.f, &want.f, sizeof want.f);
            for (int l = 0; l < (want.f > 0.0f ? 2 : 1); l++) {
                for (int i = 0; i < 4; i++)
                    assert_ptr_equal(got.tap[l].p[i], want.tap[l].p[i]);
                assert_memory_equal(&got.tap[l].fx, &want.tap[l].fx, sizeof want.tap[l].fx);
                assert_memory_equal(&got.tap[l].fy, &want.tap[l].fy, sizeof want.tap[l].fy);
            }
            two_levels += want.f > 0.0f;
        }
    }
    assert_true(two_levels > 1000);
    fv_scene_free(s);
}

/* Mip selection. The triangle has world area 1/2 and uv area 1/2, so a W x H texture has
 * sqrt(W*H) texels per metre. With t*|dir| = 1 and a perpendicular hit the footprint is
 * footprint_rad metres, so lod = log2(footprint_rad * sqrt(W*H)). */
static void test_texture_mips(void **state)
{
    (void)state;
    /* 4x4 grey ramp, texel (x,y) = 16*(y*4+x) in every channel. Level 1 is 2x2 (2x2 box
     * averages), level 2 is 1x1 (the mean of all 16). */
    uint8_t tex[4 * 4 * 4];
    double lin[4][4], mean = 0;
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 4; x++) {
            const int g = 16 * (y * 4 + x);
            for (int c = 0; c < 3; c++) tex[(y * 4 + x) * 4 + c] = (uint8_t)g;
            tex[(y * 4 + x) * 4 + 3] = 255;
            lin[y][x] = srgb_to_linear(g);
            mean += lin[y][x] / 16;
        }
    fv_scene *s = textured_triangle(tex, 4, 4);
    float rgb[3];
    const double l1_00 = (lin[0][0] + lin[0][1] + lin[1][0] + lin[1][1]) / 4;
    shade_uv(s, 0.25f, 0.25f, 0.5f, rgb); /* 0.5 m * 4 texels/m = 2 texels: lod 1 */
    assert_near(rgb[1], (float)(l1_00 * 1.15), 1e-5f);
    shade_uv(s, 0.25f, 0.25f, 0.5f * sqrtf(2.0f), rgb); /* lod 1.5: halfway to level 2 */
    assert_near(rgb[1], (float)(0.5 * (l1_00 + mean) * 1.15), 1e-4f);
    shade_uv(s, 0.3f, 0.8f, 1000.0f, rgb); /* far beyond the chain: the 1x1 level */
    assert_near(rgb[0], (float)(mean * 1.15), 1e-5f);
    shade_uv(s, 0.125f, 0.125f, 0.1f, rgb); /* under a texel: level 0 */
    assert_near(rgb[2], (float)(lin[0][0] * 1.15), 1e-5f);
    /* Grazing hit: cos(theta) = 0.1 widens the footprint 10x; 0.05 m -> 0.5 m -> lod 1.
     * At uv (0.375, 0.375) level 0 would be texel (1,1) exactly; level 1 (2x2) is sampled at
     * x = y = 0.25 texels: weights 9/16, 3/16, 3/16, 1/16 over its four texels. */
    double l1[2][2];
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++)
            l1[j][i] = (lin[2 * j][2 * i] + lin[2 * j][2 * i + 1] + lin[2 * j + 1][2 * i] + lin[2 * j + 1][2 * i + 1]) / 4;
    const double want_graze = (9 * l1[0][0] + 3 * l1[0][1] + 3 * l1[1][0] + l1[1][1]) / 16;
    const float o[3] = {0.375f + 0.99498744f, 0.375f, 0.1f}, d[3] = {-0.99498744f, 0, -0.1f};
    float rgb_graze[3];
    fv_scene_shade(s, 0, 0, 0.375f, 0.375f, o, d, 1.0f, 0.05f, o, rgb_graze);
    assert_near(rgb_graze[0], (float)(want_graze * (0.15 + 0.1)), 1e-5f); /* lambert = cos = 0.1 */
    fv_scene_free(s);

    /* Odd 5x3: level 1 is 2x1; its texel 0 averages columns 0-1 and texel 1 folds in the odd
     * last column (columns 2-4), all 3 rows each. lod 1 at uv (0.75, 0.5) is texel 1 exactly. */
    uint8_t odd[5 * 3 * 4];
    double right = 0;
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < 5; x++) {
            const int g = 20 * x + 60 * y;
            for (int c = 0; c < 3; c++) odd[(y * 5 + x) * 4 + c] = (uint8_t)g;
            odd[(y * 5 + x) * 4 + 3] = 255;
            if (x >= 2) right += srgb_to_linear(g) / 9;
        }
    s = textured_triangle(odd, 5, 3);
    shade_uv(s, 0.75f, 0.5f, 2.0f / sqrtf(15.0f), rgb);
    assert_near(rgb[0], (float)(right * 1.15), 1e-4f);
    fv_scene_free(s);
}

/* ---- builder: validation ------------------------------------------------------------- */

static void test_builder_rejects_bad_meshes(void **state)
{
    (void)state;
    const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const float nan_pos[] = {0, 0, 0, NAN, 0, 0, 0, 1, 0};
    const uint32_t oob[] = {0, 1, 3};
    const uint32_t two[] = {0, 1};
    const float uv[] = {0, 0, 1, 0, 0, 1};
    fv_scene *s = fv_scene_create();
    char err[256];
    fv_mesh_desc m;
    struct {
        fv_mesh_desc d;
        const char *why;
    } bad[8];
    int n = 0;
    m = mesh(pos, 3, oob, 3), bad[n].d = m, bad[n++].why = "out-of-range index";
    m = mesh(pos, 3, two, 2), bad[n].d = m, bad[n++].why = "index count not a multiple of 3";
    m = mesh(pos, 2, NULL, 0), bad[n].d = m, bad[n++].why = "vertex count not a multiple of 3";
    m = mesh(nan_pos, 3, NULL, 0), bad[n].d = m, bad[n++].why = "NaN position";
    m = mesh(pos, 3, NULL, 0), m.texture = 0, m.uvs = uv, bad[n].d = m, bad[n++].why = "missing texture";
    m = mesh(NULL, 3, NULL, 0), bad[n].d = m, bad[n++].why = "no positions";
    m = mesh(pos, 3, NULL, 0), m.base_color[1] = INFINITY, bad[n].d = m, bad[n++].why = "infinite colour";
    for (int i = 0; i < n; i++) {
        err[0] = 0;
        if (fv_scene_add_mesh(s, &bad[i].d, err, sizeof err) != -1 || !err[0]) {
            print_error("accepted: %s\n", bad[i].why);
            fail();
        }
    }
    assert_non_null(strstr(err, "colour"));
    /* The scene is still usable: the first good mesh gets geometry 0, the next 1. */
    m = mesh(pos, 3, NULL, 0);
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    m.transform[0] = m.transform[5] = m.transform[10] = m.transform[15] = 1;
    m.transform[14] = -1;
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    commit_or_fail(s);
    assert_int_equal(fv_scene_triangle_count(s), 2);
    const float o[3] = {0.25f, 0.25f, 1}, d[3] = {0, 0, -1};
    hit h;
    assert_true(cast(s, o, d, &h));
    assert_int_equal(h.geom, 0);
    assert_near(h.t, 1.0f, 1e-6f);
    const float o2[3] = {0.25f, 0.25f, -0.5f};
    assert_true(cast(s, o2, d, &h));
    assert_int_equal(h.geom, 1);
    assert_near(h.t, 0.5f, 1e-6f);
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), -1); /* after commit */
    fv_scene_free(s);
}

/* ---- builder: KHR lights ------------------------------------------------------------- */

static fv_scene *lit_quad(const fv_light *l, int nlights)
{
    static const float pos[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    static const uint32_t idx[] = {0, 1, 2, 0, 2, 3};
    fv_scene *s = fv_scene_create();
    fv_mesh_desc m = mesh(pos, 4, idx, 6);
    m.base_color[0] = 0.5f, m.base_color[1] = 1.0f, m.base_color[2] = 0.25f;
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    for (int i = 0; i < nlights; i++) fv_scene_add_light(s, &l[i]);
    return commit_or_fail(s);
}

/* Shades the quad point (x, y, 0) seen from straight above. */
static void shade_at(const fv_scene *s, float x, float y, float rgb[3])
{
    const float o[3] = {x, y, 5}, d[3] = {0, 0, -1};
    hit h;
    cast_shade(s, o, d, 0, &h, rgb);
}

/* Bounds centre of the quad is the origin. The exposure makes the brightest light give
 * irradiance 1 there: for a directional light of intensity 10 and colour (1, 0.5, 0.25)
 * the exposure is 1/10, and a light straight down gives base * (0.15 + colour). */
static void test_lights_directional(void **state)
{
    (void)state;
    fv_light l;
    memset(&l, 0, sizeof l);
    l.type = FV_LIGHT_DIRECTIONAL;
    l.color[0] = 1, l.color[1] = 0.5f, l.color[2] = 0.25f;
    l.intensity = 10;
    l.dir[2] = -3; /* not normalised on purpose */
    fv_scene *s = lit_quad(&l, 1);
    assert_int_equal(fv_scene_light_count(s), 1);
    fv_light got;
    assert_int_equal(fv_scene_get_light(s, 0, &got), 0);
    assert_near(got.dir[2], -1.0f, 1e-6f);
    assert_int_equal(fv_scene_get_light(s, 1, &got), -1);
    float rgb[3];
    shade_at(s, 0.3f, -0.2f, rgb);
    assert_rgb(rgb, 0.5f * 1.15f, 1.0f * 0.65f, 0.25f * 0.4f, 1e-5f, __LINE__);
    fv_scene_free(s);
    /* Tilted 60 degrees from the normal: lambert 1/2. */
    l.dir[0] = sqrtf(3.0f), l.dir[2] = -1;
    s = lit_quad(&l, 1);
    shade_at(s, 0.3f, -0.2f, rgb);
    assert_rgb(rgb, 0.5f * 0.65f, 1.0f * 0.4f, 0.25f * 0.275f, 1e-5f, __LINE__);
    fv_scene_free(s);
}

/* Point light of intensity 8 at (0,0,2): irradiance 8/4 = 2 at the centre, exposure 1/2.
 * At the centre: 8 * 1/4 * 1/2 = 1. At (0.5,0,0): d^2 = 4.25, lambert = 2/sqrt(4.25), so
 * 8 * 0.5 * 2 / 4.25^1.5. With range 3 the window 1-(d/3)^4 applies at both places. A spot
 * with outer cone 0.1 rad pointing down lights the centre fully but not (0.5,0,0), whose
 * angle off the axis is atan(0.25) = 0.245 rad. */
static void test_lights_point_spot(void **state)
{
    (void)state;
    fv_light l;
    memset(&l, 0, sizeof l);
    l.type = FV_LIGHT_POINT;
    l.color[0] = l.color[1] = l.color[2] = 1;
    l.intensity = 8;
    l.pos[2] = 2;
    fv_scene *s = lit_quad(&l, 1);
    float rgb[3];
    shade_at(s, 0, 0, rgb);
    assert_rgb(rgb, 0.5f * 1.15f, 1.15f, 0.25f * 1.15f, 1e-5f, __LINE__);
    shade_at(s, 0.5f, 0, rgb);
    const float e = (float)(8.0 * 0.5 * 2.0 / pow(4.25, 1.5));
    assert_near(rgb[1], 0.15f + e, 1e-5f);
    fv_scene_free(s);

    l.range = 3;
    s = lit_quad(&l, 1);
    const double win0 = 1 - pow(2.0 / 3.0, 4), win1 = 1 - pow(4.25 / 9.0, 2);
    const double exposure = 1.0 / (8.0 * win0 / 4.0);
    shade_at(s, 0.5f, 0, rgb);
    assert_near(rgb[1], (float)(0.15 + 8.0 * win1 / 4.25 * (2.0 / sqrt(4.25)) * exposure), 1e-5f);
    fv_scene_free(s);

    l.type = FV_LIGHT_SPOT;
    l.range = 0;
    l.dir[2] = -1;
    l.inner_cone = 0.05f, l.outer_cone = 0.1f;
    s = lit_quad(&l, 1);
    shade_at(s, 0, 0, rgb);
    assert_near(rgb[1], 1.15f, 1e-5f);
    shade_at(s, 0.5f, 0, rgb);
    assert_near(rgb[1], 0.15f, 1e-6f);
    fv_scene_free(s);
}

/* ---- default view -------------------------------------------------------------------- */

/* Bounds [-1,1]^3 around (1,2,3): bounding sphere radius sqrt3. With a 90 degree vertical
 * FOV and aspect 1 the sphere fits at distance sqrt3/sin(45 deg) = sqrt6; with aspect 0.5
 * the horizontal half-angle atan(0.5) is narrower: sqrt3/sin(atan 0.5) = sqrt3*sqrt5. */
static void test_default_view_frames_bounds(void **state)
{
    (void)state;
    const float pos[] = {0, 1, 2, 2, 3, 4, 0, 3, 2};
    fv_scene *s = fv_scene_create();
    fv_mesh_desc m = mesh(pos, 3, NULL, 0);
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    commit_or_fail(s);
    float p[3], q[4];
    assert_int_equal(fv_scene_default_view(s, 90.0f, 1.0f, p, q), 0);
    assert_near(p[0], 1, 1e-6f), assert_near(p[1], 2, 1e-6f), assert_near(p[2], 3 + sqrtf(6.0f), 1e-5f);
    assert_near(q[0], 0, 0), assert_near(q[1], 0, 0), assert_near(q[2], 0, 0), assert_near(q[3], 1, 0);
    assert_int_equal(fv_scene_default_view(s, 90.0f, 0.5f, p, q), 0);
    assert_near(p[2], 3 + sqrtf(15.0f), 1e-5f);
    /* Looking down -Z from there the triangle is in front: (0.5, 2.5) is inside its xy shadow. */
    const float d[3] = {0, 0, -1}, o[3] = {0.5f, 2.5f, p[2]};
    hit h;
    assert_true(cast(s, o, d, &h));
    fv_scene_free(s);
}

/* ---- glTF files ---------------------------------------------------------------------- */

/* tests/data/scene/hierarchy.gltf: triangle (0,0,0),(1,0,0),(0,1,0), colour (0.5,0.25,1).
 * Node "child" rotates it 90 deg about +Y ((x,y,z) -> (z,y,-x)) under "parent" translated by
 * (0,0,-5): world (0,0,-5),(0,0,-6),(0,1,-5), in the plane x = 0, computed normal
 * (0,0,-1) x (0,1,0) = (1,0,0). Node "matrix" scales by 2 and moves by (10,0,0):
 * (10,0,0),(12,0,0),(10,2,0). A lines primitive and a node outside the scene add nothing. */
static void test_gltf_hierarchy(void **state)
{
    (void)state;
    char err[512];
    fv_scene *s = fv_scene_load("tests/data/scene/hierarchy.gltf", err, sizeof err);
    if (!s) print_error("%s\n", err);
    assert_non_null(s);
    assert_string_equal(err, "");
    assert_int_equal(fv_scene_triangle_count(s), 2);
    assert_int_equal(fv_scene_light_count(s), 0);
    float lo[3], hi[3];
    fv_scene_bounds(s, lo, hi);
    const float want_lo[3] = {0, 0, -6}, want_hi[3] = {12, 2, 0};
    for (int k = 0; k < 3; k++) assert_near(lo[k], want_lo[k], 1e-6f), assert_near(hi[k], want_hi[k], 1e-6f);

    /* (5, 0.25, -5.25) along -X hits (0, 0.25, -5.25) = A' + 0.25 (B'-A') + 0.25 (C'-A'). */
    const float o[3] = {5, 0.25f, -5.25f}, d[3] = {-1, 0, 0};
    hit h;
    float rgb[3];
    cast_shade(s, o, d, 0, &h, rgb);
    assert_near(h.t, 5.0f, 1e-5f);
    assert_near(h.u, 0.25f, 1e-5f);
    assert_near(h.v, 0.25f, 1e-5f);
    /* The material gives only baseColorFactor, so metallic and roughness take the glTF
     * defaults (1, 1): a rough metal. Head-on (n = l = v = h) with a2 = 1: D = 1/pi, V = 1/4,
     * F = base, so the head light adds pi V D base = base/4 and the ambient 0.15 base. */
    assert_rgb(rgb, 0.5f * 0.4f, 0.25f * 0.4f, 0.4f, 1e-5f, __LINE__);
    /* Without the rotation the triangle would be in the plane z = -5 at x in [0,1]. */
    const float o2[3] = {0.25f, 0.25f, 0}, d2[3] = {0, 0, -1};
    assert_false(cast(s, o2, d2, &h));
    /* The matrix node: (10.5, 0.5) is at u = v = 0.25 of the doubled triangle. */
    const float o3[3] = {10.5f, 0.5f, 5};
    assert_true(cast(s, o3, d2, &h));
    assert_near(h.t, 5.0f, 1e-5f);
    assert_near(h.u, 0.25f, 1e-5f);
    assert_near(h.v, 0.25f, 1e-5f);
    const float o4[3] = {100.25f, 0.25f, 5}; /* the unreferenced node's copy does not exist */
    assert_false(cast(s, o4, d2, &h));
    float p[3], q[4];
    assert_int_equal(fv_scene_default_view(s, 60, 1, p, q), 0);
    fv_scene_free(s);
}

/* tests/data/scene/camera.gltf: an orthographic camera (ignored), then node "rig" at (1,2,3)
 * rotated 90 deg about +Y with child camera "cam" at local (0,0,2): world position
 * (1,2,3) + R*(0,0,2) = (3,2,3), rotation quat (0, sin45, 0, cos45). A later camera is
 * ignored. */
static void test_gltf_camera(void **state)
{
    (void)state;
    char err[512];
    fv_scene *s = fv_scene_load("tests/data/scene/camera.gltf", err, sizeof err);
    if (!s) print_error("%s\n", err);
    assert_non_null(s);
    float p[3], q[4];
    assert_int_equal(fv_scene_default_view(s, 60, 1.5f, p, q), 1);
    assert_near(p[0], 3, 1e-5f), assert_near(p[1], 2, 1e-5f), assert_near(p[2], 3, 1e-5f);
    const float sg = q[3] < 0 ? -1.0f : 1.0f; /* q and -q are the same rotation */
    assert_near(sg * q[0], 0, 1e-5f), assert_near(sg * q[1], SQ2, 1e-5f);
    assert_near(sg * q[2], 0, 1e-5f), assert_near(sg * q[3], SQ2, 1e-5f);
    fv_scene_free(s);
}

/* Expected counts from summing index counts / 3 over the TRIANGLES primitives of the nodes
 * reachable from the default scene (python3 json check of the accessors). */
static fv_scene *load_shared(const char *rel, size_t want_tris)
{
    char path[512], err[512];
    fv_scene *s = fv_scene_load(shared_scene(path, sizeof path, rel), err, sizeof err);
    if (!s) print_error("%s\n", err);
    assert_non_null(s);
    assert_int_equal(fv_scene_triangle_count(s), want_tris);
    return s;
}

static void test_load_flight_helmet(void **state)
{
    (void)state;
    fv_scene *s = load_shared("FlightHelmet/FlightHelmet.gltf", 94722);
    assert_int_equal(fv_scene_light_count(s), 0);
    float lo[3], hi[3], p[3], q[4];
    fv_scene_bounds(s, lo, hi);
    assert_true(hi[1] - lo[1] > 0.5f && hi[1] - lo[1] < 1.0f); /* a helmet about 0.7 m tall */
    assert_int_equal(fv_scene_default_view(s, 60, 1, p, q), 0);
    assert_near(p[0], 0.5f * (lo[0] + hi[0]), 1e-6f);
    assert_near(p[1], 0.5f * (lo[1] + hi[1]), 1e-6f);
    assert_true(p[2] > hi[2]);
    /* Looking at the centre from there hits the helmet, and the textured hit is lit. */
    const float d[3] = {0, 0, -1};
    hit h;
    float rgb[3];
    cast_shade(s, p, d, 0.001f, &h, rgb);
    assert_true(rgb[0] + rgb[1] + rgb[2] > 0.0f);
    fv_scene_free(s);
}

static void test_load_damaged_helmet(void **state)
{
    (void)state;
    fv_scene *s = load_shared("DamagedHelmet/DamagedHelmet.gltf", 15452);
    assert_int_equal(fv_scene_light_count(s), 0);
    fv_scene_free(s);
}

/* DepthOfFieldExample.glb has one KHR_lights_punctual directional light "Sun" of intensity
 * 6830 on a node with rotation q = (-0.7903, -0.1289, 0.1781, 0.5719): its direction is
 * R(q) * (0,0,-1) = (0.42885, -0.85809, 0.28243) (python). */
static void test_load_dof_glb_lights(void **state)
{
    (void)state;
    fv_scene *s = load_shared("DepthOfFieldExample/DepthOfFieldExample.glb", 10610);
    assert_true(fv_scene_light_count(s) > 0);
    assert_int_equal(fv_scene_light_count(s), 1);
    fv_light l;
    assert_int_equal(fv_scene_get_light(s, 0, &l), 0);
    assert_int_equal(l.type, FV_LIGHT_DIRECTIONAL);
    assert_near(l.intensity, 6830.0f, 0);
    assert_near(l.dir[0], 0.42885029f, 1e-5f);
    assert_near(l.dir[1], -0.85809007f, 1e-5f);
    assert_near(l.dir[2], 0.28243381f, 1e-5f);
    /* The exposure tames 6830: straight down onto the board, irradiance stays near 1. */
    const float o[3] = {0.3f, 5, 0.2f}, d[3] = {0, -1, 0};
    hit h;
    float rgb[3];
    cast_shade(s, o, d, 0, &h, rgb);
    for (int k = 0; k < 3; k++) assert_true(rgb[k] >= 0.0f && rgb[k] <= 1.2f);
    fv_scene_free(s);
}

/* ---- packet shading ------------------------------------------------------------------ */

/* fv_scene_shade_packet gives fv_scene_shade's bits lane by lane, with every ISA's kernel: for
 * packets of 1..16 random hits and misses of a scene seen from its default view. */
static void check_packets(const fv_scene *s, uint64_t seed)
{
    float lo[3], hi[3], p[3], q[4];
    fv_scene_bounds(s, lo, hi);
    fv_scene_default_view(s, 60, 1, p, q);
    const float px_tan = 0.0015f;
    static const unsigned isas[] = {FV_ISA_C, FV_ISA_SSE41, FV_ISA_AVX2, FV_ISA_NEON};
    int shaded = 0, degenerate_or_hit = 0;
    for (int it = 0; it < 400; it++) {
        const int n = 1 + (int)(fv_test_rand(&seed) % 16);
        unsigned geom[16], prim[16];
        float u[16], v[16], t[16], dir[3][16];
        for (int l = 0; l < 16; l++) {
            float d[3];
            for (int k = 0; k < 3; k++)
                d[k] = 0.5f * (lo[k] + hi[k]) - p[k] + (fv_test_randf(&seed) - 0.5f) * 1.5f * (hi[k] - lo[k]);
            hit h;
            if (!cast(s, p, d, &h))
                h.geom = RTC_INVALID_GEOMETRY_ID;
            if (it % 4 == 0 && l < 2) /* packets starting with misses */
                h.geom = RTC_INVALID_GEOMETRY_ID;
            geom[l] = h.geom, prim[l] = h.prim, u[l] = h.u, v[l] = h.v, t[l] = h.t;
            for (int k = 0; k < 3; k++) dir[k][l] = d[k];
        }
        const fv_hit_packet hp = {geom, prim, u, v, t, {dir[0], dir[1], dir[2]}};
        fv_scene_shade_prefetch(s, geom, prim, n); /* as the ray stage does, misses anywhere */
        for (size_t i = 0; i < sizeof isas / sizeof isas[0]; i++) {
            if (isas[i] && !(fv_cpu_isas() & isas[i]))
                continue;
            fv_shade_dsp dsp;
            fv_shade_dsp_init(&dsp, isas[i] ? isas[i] : FV_ISA_C);
            float rgb[3][16];
            fv_scene_shade_packet(s, &dsp, &hp, n, px_tan, p, rgb);
            for (int l = 0; l < n; l++) {
                if (geom[l] == RTC_INVALID_GEOMETRY_ID)
                    continue;
                const float d[3] = {dir[0][l], dir[1][l], dir[2][l]};
                const float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                float want[3];
                fv_scene_shade(s, geom[l], prim[l], u[l], v[l], p, d, t[l], px_tan / len, p, want);
                for (int k = 0; k < 3; k++)
                    if (memcmp(&want[k], &rgb[k][l], sizeof(float))) {
                        print_error("%s lane %d of %d channel %d: packet %.9g, scalar %.9g\n", fv_isa_name(isas[i]), l,
                                    n, k, (double)rgb[k][l], (double)want[k]);
                        fail();
                    }
                shaded++;
                degenerate_or_hit += want[0] + want[1] + want[2] > 0.0f;
            }
        }
    }
    assert_true(shaded > 1000);
    assert_true(degenerate_or_hit > 0);
}

static void test_packet_shading_matches_scalar(void **state)
{
    (void)state;
    fv_scene *s = load_shared("FlightHelmet/FlightHelmet.gltf", 94722); /* textured, head light */
    check_packets(s, 1);
    fv_scene_free(s);
    s = load_shared("DepthOfFieldExample/DepthOfFieldExample.glb", 10610); /* a KHR light */
    check_packets(s, 2);
    fv_scene_free(s);
    /* zero vertex normals: every hit takes the scalar path's face normal; and a point and a
     * spot light */
    static const float pos[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    static const float nrm[] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    static const uint32_t idx[] = {0, 1, 2, 0, 2, 3};
    s = fv_scene_create();
    fv_mesh_desc m = mesh(pos, 4, idx, 6);
    m.normals = nrm;
    char err[256];
    assert_int_equal(fv_scene_add_mesh(s, &m, err, sizeof err), 0);
    const fv_light l[2] = {{.type = FV_LIGHT_POINT, .color = {1, 1, 1}, .intensity = 5, .pos = {0, 0, 2}, .range = 4},
                           {.type = FV_LIGHT_SPOT, .color = {1, 0.5f, 0.5f}, .intensity = 9, .pos = {0.5f, 0, 3},
                            .dir = {0, 0, -1}, .inner_cone = 0.3f, .outer_cone = 0.6f}};
    for (int i = 0; i < 2; i++) fv_scene_add_light(s, &l[i]);
    s = commit_or_fail(s);
    check_packets(s, 3);
    fv_scene_free(s);
    /* one plain mesh, geometry 0, in two scenes one after the other (the second may reuse the
     * first's memory): packets on one such mesh take its material from a per-thread cache, which
     * must not serve the first scene's colour to the second */
    static const float rgb[2][3] = {{0.9f, 0.1f, 0.1f}, {0.1f, 0.8f, 0.3f}};
    for (int c = 0; c < 2; c++) {
        s = fv_scene_create();
        fv_test_add_quad(s, -1, -1, 1, 1, 0, rgb[c], -1);
        s = commit_or_fail(s);
        check_packets(s, 4 + (uint64_t)c);
        fv_scene_free(s);
    }
}

/* ---- glTF materials ------------------------------------------------------------------ */

/* Four unit-normal quads [-1,1]^2 at z = 0 (nodes at x = 0, 3, 6, 9), each with its own
 * material, seen head-on from z = 5 with the head light at the eye (n = l = v = h, Schlick
 * weight 0). Expected values (tests/test_brdf.c works the BRDF out the same way):
 *   0 dielectric base 0.5 roughness 0.5: pi V D = 4, 0.96 x 0.5 + 0.04 x 4 = 0.64; ambient
 *     0.15 (0.96 x 0.5 + 0.04) = 0.078: 0.718
 *   1 metal base 0.5 roughness 0.5: 4 x 0.5 = 2; ambient 0.15 x 0.5: 2.075
 *   2 black rough dielectric, emissive (0.2, 0.4, 0.1) x KHR_materials_emissive_strength 5:
 *     0.04 x 1/4 + 0.15 x 0.04 + emission = (1.016, 2.016, 0.516)
 *   3 KHR_materials_specular specularFactor 0, base 0.5: matte, 0.5 + 0.075 = 0.575 */
static void test_gltf_pbr_materials(void **state)
{
    (void)state;
    unsigned char bin[60];
    const float pos[12] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    const uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
    memcpy(bin, pos, 48);
    memcpy(bin + 48, idx, 12);
    const char *json =
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
        "\"min\":[-1,-1,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
        "\"extensionsUsed\":[\"KHR_materials_emissive_strength\",\"KHR_materials_specular\"],"
        "\"materials\":["
        "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.5,0.5,1],\"metallicFactor\":0,\"roughnessFactor\":0.5}},"
        "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.5,0.5,1],\"metallicFactor\":1,\"roughnessFactor\":0.5}},"
        "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0,0,0,1],\"metallicFactor\":0},\"emissiveFactor\":[0.2,0.4,0.1],"
        "\"extensions\":{\"KHR_materials_emissive_strength\":{\"emissiveStrength\":5}}},"
        "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.5,0.5,1],\"metallicFactor\":0},"
        "\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0}}}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":0}]},"
        "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":1}]},"
        "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":2}]},"
        "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":3}]}],"
        "\"nodes\":[{\"mesh\":0},{\"mesh\":1,\"translation\":[3,0,0]},{\"mesh\":2,\"translation\":[6,0,0]},"
        "{\"mesh\":3,\"translation\":[9,0,0]}],\"scenes\":[{\"nodes\":[0,1,2,3]}],\"scene\":0";
    char *dir = tmpdir_make(), p[512], err[512];
    path_join(p, sizeof p, dir, "pbr.gltf");
    write_gltf(p, bin, sizeof bin, json);
    fv_scene *s = fv_scene_load(p, err, sizeof err);
    if (!s) print_error("%s\n", err);
    assert_non_null(s);
    static const float want[4][3] = {{0.718f, 0.718f, 0.718f}, {2.075f, 2.075f, 2.075f},
                                     {1.016f, 2.016f, 0.516f}, {0.575f, 0.575f, 0.575f}};
    for (int i = 0; i < 4; i++) {
        const float o[3] = {3.0f * (float)i + 0.3f, -0.2f, 5}, d[3] = {0, 0, -1};
        hit h;
        float rgb[3];
        cast_shade(s, o, d, 0, &h, rgb);
        assert_int_equal(h.geom, (unsigned)i);
        assert_rgb(rgb, want[i][0], want[i][1], want[i][2], 2e-6f * 4, __LINE__);
    }
    check_packets(s, 4); /* every ISA's kernel gives these bits from other directions too */
    fv_scene_free(s);

    /* out-of-range factors are refused, naming them */
    char bad[4096];
    snprintf(bad, sizeof bad, "%s", json);
    char *m = strstr(bad, "\"metallicFactor\":1");
    assert_non_null(m);
    memcpy(m, "\"metallicFactor\":2", 18);
    write_gltf(p, bin, sizeof bin, bad);
    expect_load_fails(p, "metallicFactor");
    const char *e5 = strstr(json, "\"emissiveStrength\":5");
    assert_non_null(e5);
    snprintf(bad, sizeof bad, "%.*s\"emissiveStrength\":-5%s", (int)(e5 - json), json, e5 + 20);
    write_gltf(p, bin, sizeof bin, bad);
    expect_load_fails(p, "negative emissiveStrength");
    tmpdir_remove(dir);
}

/* A quad [-1,1]^2 (uv = ((x+1)/2, (y+1)/2)) with 2x1 maps, sampled at texel centres (u 0.25 and
 * 0.75, v 0.5) head-on with the head light; base colour factor 0.5, roughness factor 0.5.
 * metallicRoughnessTexture (linear; G roughness, B metallic) also the occlusionTexture (R):
 *   left  (0, 255, 0): roughness 0.5, dielectric, occlusion 0 (no ambient): 0.64
 *   right (255, 255, 255): roughness 0.5, metal, occlusion 1: 2 + 0.15 x 0.5 = 2.075
 * emissiveTexture (sRGB) (255, 0, 0) left, black right, emissiveFactor 1: left gains (1, 0, 0).
 * The head-on values are worked out in test_gltf_pbr_materials. */
static void test_gltf_material_maps(void **state)
{
    (void)state;
    char *dir = tmpdir_make(), p[512], err[512];
    const unsigned char mr[8] = {0, 255, 0, 255, 255, 255, 255, 255}, em[8] = {255, 0, 0, 255, 0, 0, 0, 255};
    path_join(p, sizeof p, dir, "mr.png");
    assert_true(stbi_write_png(p, 2, 1, 4, mr, 8) != 0);
    path_join(p, sizeof p, dir, "em.png");
    assert_true(stbi_write_png(p, 2, 1, 4, em, 8) != 0);
    unsigned char bin[92];
    static const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    quad_buffer(bin, uv);
    const char *json =
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":32},"
        "{\"buffer\":0,\"byteOffset\":80,\"byteLength\":12}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
        "\"min\":[-1,-1,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
        "{\"bufferView\":2,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
        "\"images\":[{\"uri\":\"mr.png\"},{\"uri\":\"em.png\"}],\"textures\":[{\"source\":0},{\"source\":1}],"
        "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.5,0.5,1],\"roughnessFactor\":0.5,"
        "\"metallicRoughnessTexture\":{\"index\":0}},\"occlusionTexture\":{\"index\":0},"
        "\"emissiveTexture\":{\"index\":1},\"emissiveFactor\":[1,1,1]}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"indices\":2,\"material\":0}]}],"
        "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0";
    path_join(p, sizeof p, dir, "maps.gltf");
    write_gltf(p, bin, sizeof bin, json);
    fv_scene *s = fv_scene_load(p, err, sizeof err);
    if (!s) print_error("%s\n", err);
    assert_non_null(s);
    const float d[3] = {0, 0, -1}, left[3] = {-0.5f, 0, 5}, right[3] = {0.5f, 0, 5};
    hit h;
    float rgb[3];
    cast_shade(s, left, d, 0, &h, rgb);
    assert_rgb(rgb, 1.64f, 0.64f, 0.64f, 1e-5f, __LINE__);
    cast_shade(s, right, d, 0, &h, rgb);
    assert_rgb(rgb, 2.075f, 2.075f, 2.075f, 1e-5f, __LINE__);
    check_packets(s, 5); /* the maps through the packet path: the same bits */
    fv_scene_free(s);
    /* The occlusion read from the same texture as metallic-roughness (the packet path fetches
     * those texels once) but through its own uv transform, half a texture to the side: its own
     * texels, as the scalar path fetches them (left half: occlusion from the right texel). */
    char json2[4096];
    snprintf(json2, sizeof json2, "\"extensionsUsed\":[\"KHR_texture_transform\"],%s", json);
    char *occ = strstr(json2, "\"occlusionTexture\":{\"index\":0}");
    assert_non_null(occ);
    const char *xf = "\"occlusionTexture\":{\"index\":0,\"extensions\":{\"KHR_texture_transform\":{\"offset\":[0.5,0]}}}";
    char tail[4096];
    snprintf(tail, sizeof tail, "%s", occ + strlen("\"occlusionTexture\":{\"index\":0}"));
    snprintf(occ, sizeof json2 - (size_t)(occ - json2), "%s%s", xf, tail);
    write_gltf(p, bin, sizeof bin, json2);
    s = fv_scene_load(p, err, sizeof err);
    if (!s) print_error("%s\n", err);
    assert_non_null(s);
    check_packets(s, 15);
    fv_scene_free(s);
    tmpdir_remove(dir);
}

/* Casts 16 rays (lane q: origin o[q % 4], direction d) through fv_scene_intersect16 and writes their
 * hit distances (INFINITY for a miss). */
static void cast16(const fv_scene *s, const float o[4][3], const float d[3], float t[16])
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    _Alignas(64) struct RTCRayHit16 rh;
    memset(&rh, 0, sizeof rh);
    _Alignas(64) int valid[16];
    for (int q = 0; q < 16; q++) {
        valid[q] = -1;
        rh.ray.org_x[q] = o[q % 4][0], rh.ray.org_y[q] = o[q % 4][1], rh.ray.org_z[q] = o[q % 4][2];
        rh.ray.dir_x[q] = d[0], rh.ray.dir_y[q] = d[1], rh.ray.dir_z[q] = d[2];
        rh.ray.tfar[q] = INFINITY, rh.ray.mask[q] = 0xFFFFFFFFu;
        rh.hit.geomID[q] = RTC_INVALID_GEOMETRY_ID;
    }
    fv_scene_intersect16(s, valid, &ctx, &rh);
    for (int q = 0; q < 16; q++) t[q] = rh.hit.geomID[q] == RTC_INVALID_GEOMETRY_ID ? INFINITY : rh.ray.tfar[q];
}

/* Alpha MASK (cutoff 0.6) in the ray query: a quad at z = 0 whose 2x1 base colour texture has
 * alpha 0 on the left half and 1 on the right, in front of a wall at z = -2 (the same quad,
 * opaque). From z = 5 straight down, a ray through the left half passes the cut-out and reaches
 * the wall (t = 7), one through the right half stops at the quad (t = 5), through rtcIntersect1
 * and rtcIntersect16 alike. A third, untextured quad at z = 2 (x + 3) with base alpha 0.5 <
 * 0.6 lets every ray through; the same quad as BLEND is passed by a plain ray query too (the
 * ray stage composites it: test_gltf_alpha_blend). */
static void test_gltf_alpha_mask(void **state)
{
    (void)state;
    char *dir = tmpdir_make(), p[512], err[512];
    const unsigned char px[8] = {255, 255, 255, 0, 255, 255, 255, 255};
    path_join(p, sizeof p, dir, "a.png");
    assert_true(stbi_write_png(p, 2, 1, 4, px, 8) != 0);
    unsigned char bin[92];
    static const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    quad_buffer(bin, uv);
    char json[4096];
    for (int blend = 0; blend < 2; blend++) {
        snprintf(json, sizeof json,
                 "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":32},"
                 "{\"buffer\":0,\"byteOffset\":80,\"byteLength\":12}],"
                 "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
                 "\"min\":[-1,-1,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
                 "{\"bufferView\":2,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
                 "\"images\":[{\"uri\":\"a.png\"}],\"textures\":[{\"source\":0}],"
                 "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}},\"alphaMode\":\"MASK\","
                 "\"alphaCutoff\":0.6},{},"
                 "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,0.5]},\"alphaMode\":\"%s\",\"alphaCutoff\":0.6}],"
                 "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"indices\":2,\"material\":0}]},"
                 "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":2,\"material\":1}]},"
                 "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":2,\"material\":2}]}],"
                 "\"nodes\":[{\"mesh\":0},{\"mesh\":1,\"translation\":[0,0,-2]},{\"mesh\":1,\"translation\":[3,0,-2]},"
                 "{\"mesh\":2,\"translation\":[3,0,2]}],\"scenes\":[{\"nodes\":[0,1,2,3]}],\"scene\":0",
                 blend ? "BLEND" : "MASK");
        path_join(p, sizeof p, dir, "mask.gltf");
        write_gltf(p, bin, sizeof bin, json);
        fv_scene *s = fv_scene_load(p, err, sizeof err);
        if (!s) print_error("%s\n", err);
        assert_non_null(s);
        const float d[3] = {0, 0, -1}, xs[4] = {-0.5f, 0.5f, 2.5f, 3.5f};
        const float want_t[2][4] = {{7, 5, 7, 7}, {7, 5, 7, 7}};
        hit h;
        for (int i = 0; i < 4; i++) {
            const float o[3] = {xs[i], 0.1f, 5};
            assert_true(cast(s, o, d, &h));
            assert_near(h.t, want_t[blend][i], 1e-5f);
        }
        /* the same rays as one packet of 16 (4 copies each) */
        const float o4[4][3] = {{xs[0], 0.1f, 5}, {xs[1], 0.1f, 5}, {xs[2], 0.1f, 5}, {xs[3], 0.1f, 5}};
        float t16[16];
        cast16(s, o4, d, t16);
        for (int q = 0; q < 16; q++) assert_near(t16[q], want_t[blend][q % 4], 1e-5f);
        fv_scene_free(s);
    }
    /* a cutoff out of range is refused */
    char *c = strstr(json, "\"alphaCutoff\":0.6");
    memcpy(c, "\"alphaCutoff\":1.6", 17);
    write_gltf(p, bin, sizeof bin, json);
    expect_load_fails(p, "alphaCutoff");
    tmpdir_remove(dir);
}


/* doubleSided: the quad [-1,1]^2 at z = 0 (corners counter-clockwise seen from +z: its front
 * faces +z) as a default (single-sided) material at x = 0 and as a doubleSided one at x = 3,
 * each with a single-sided wall at z = +2 turned 180 degrees about y (so it faces -z).
 * Rays from z = -5 along +z meet the quads' back faces at t = 5: through the single-sided one
 * they reach the wall's front at t = 7, the double-sided one stops them at t = 5. Rays from
 * z = 1 along -z hit both quads' fronts at t = 1. rtcIntersect1 and rtcIntersect16 alike. From
 * z = 5 along -z the wall is seen from behind (passed) and the double-sided quad's front is hit
 * at t = 5: it shades as its back does from z = -5 (the normal turned to face the ray; the
 * head light at the eye, the same distance and angle). */
static void test_gltf_double_sided(void **state)
{
    (void)state;
    char *dir = tmpdir_make(), p[512], err[512];
    unsigned char bin[92];
    static const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    quad_buffer(bin, uv);
    const char *json =
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":80,\"byteLength\":12}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
        "\"min\":[-1,-1,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
        "\"materials\":[{\"pbrMetallicRoughness\":{\"metallicFactor\":0}},"
        "{\"pbrMetallicRoughness\":{\"metallicFactor\":0},\"doubleSided\":true}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":0}]},"
        "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":1}]},"
        "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
        "\"nodes\":[{\"mesh\":0},{\"mesh\":1,\"translation\":[3,0,0]},"
        "{\"mesh\":2,\"translation\":[0,0,2],\"rotation\":[0,1,0,0]},"
        "{\"mesh\":2,\"translation\":[3,0,2],\"rotation\":[0,1,0,0]}],"
        "\"scenes\":[{\"nodes\":[0,1,2,3]}],\"scene\":0";
    path_join(p, sizeof p, dir, "sides.gltf");
    write_gltf(p, bin, sizeof bin, json);
    fv_scene *s = fv_scene_load(p, err, sizeof err);
    if (!s) print_error("%s\n", err);
    assert_non_null(s);
    const float back[3] = {0, 0, 1}, front[3] = {0, 0, -1};
    const float ob[4][3] = {{-0.5f, 0.1f, -5}, {0.5f, -0.3f, -5}, {2.5f, 0.1f, -5}, {3.5f, -0.3f, -5}};
    const float of[4][3] = {{-0.5f, 0.1f, 1}, {0.5f, -0.3f, 1}, {2.5f, 0.1f, 1}, {3.5f, -0.3f, 1}};
    const float want_back[4] = {7, 7, 5, 5}, want_front[4] = {1, 1, 1, 1};
    hit h;
    for (int i = 0; i < 4; i++) {
        assert_true(cast(s, ob[i], back, &h));
        assert_near(h.t, want_back[i], 1e-5f);
        assert_true(cast(s, of[i], front, &h));
        assert_near(h.t, want_front[i], 1e-5f);
    }
    float t16[16];
    cast16(s, ob, back, t16);
    for (int q = 0; q < 16; q++) assert_near(t16[q], want_back[q % 4], 1e-5f);
    cast16(s, of, front, t16);
    for (int q = 0; q < 16; q++) assert_near(t16[q], want_front[q % 4], 1e-5f);
    /* the double-sided quad from behind and from the front, both at distance 5 */
    const float o_back[3] = {3, 0, -5}, o_front[3] = {3, 0, 5};
    float rgb_b[3], rgb_f[3];
    cast_shade(s, o_back, back, 0, &h, rgb_b);
    assert_near(h.t, 5, 1e-5f);
    cast_shade(s, o_front, front, 0, &h, rgb_f);
    assert_near(h.t, 5, 1e-5f);
    assert_true(rgb_b[0] > 0.5f);
    assert_rgb(rgb_b, rgb_f[0], rgb_f[1], rgb_f[2], 1e-6f, __LINE__);
    fv_scene_free(s);
    tmpdir_remove(dir);
}

/* Normal maps: the quad [-1,1]^2 at z = 0 with uv = (x + 1, y + 1) / 2, so dp/du = +x and
 * dp/dv = +y: tangent +x, bitangent +y, normal +z. Its 2x1 normal map (linear) tilts the normal
 * towards +x on the left half (texel (218, 128, 218): m = (2 c / 255 - 1) = (0.7098, 0.0039,
 * 0.7098), 45 degrees) and towards +y on the right (128, 218, 218). One directional light
 * towards l = (2, 1, 2) / 3 (irradiance 1 after the exposure), a matte white material
 * (metallic 0, specularFactor 0): rgb = 0.15 + n.l with n = m / |m| in (t, b, n), so about
 * left (2 + 2) / (3 sqrt 2) = 0.9428 + 0.15, right (1 + 2) / (3 sqrt 2) = 0.7071 + 0.15 (the
 * expected values below are worked from the bytes exactly). A tangent of the wrong sign gives
 * 0 on the left; x and y swapped give 0.7071 and 0.9428; the bitangent's sign wrong gives
 * (-1 + 2) / (3 sqrt 2) = 0.2357 on the right. Three ways: tangents generated from the uvs (no
 * TANGENT), TANGENT (1, 0, 0, +1) from the file (the same frame), and TANGENT (1, 0, 0, -1)
 * (bitangent -y: the right half's tilt mirrored). Then normalTexture.scale 0.5: left
 * m = (0.3549, 0.0020, 0.7098), a 26.6-degree tilt: n.l = (0.7098 + 0.0020 + 1.4196) / 3 / 0.7936
 * = 0.8953; right m = (0.0020, 0.3549, 0.7098): (0.0039 + 0.3549 + 1.4196) / 3 / 0.7936 = 0.7470. And check_packets: the packet path gives the scalar path's bits. */
static void test_gltf_normal_map(void **state)
{
    (void)state;
    char *dir = tmpdir_make(), p[512], err[512];
    const unsigned char nm[8] = {218, 128, 218, 255, 128, 218, 218, 255};
    path_join(p, sizeof p, dir, "n.png");
    assert_true(stbi_write_png(p, 2, 1, 4, nm, 8) != 0);
    unsigned char bin[156];
    static const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    quad_buffer(bin, uv);
    const double l[3] = {2.0 / 3, 1.0 / 3, 2.0 / 3};
    for (int variant = 0; variant < 4; variant++) {
        const float w = variant == 2 ? -1.0f : 1.0f, tan[16] = {1, 0, 0, w, 1, 0, 0, w, 1, 0, 0, w, 1, 0, 0, w};
        memcpy(bin + 92, tan, 64);
        const double scale = variant == 3 ? 0.5 : 1.0;
        char json[4096];
        snprintf(json, sizeof json,
                 "\"extensionsUsed\":[\"KHR_materials_specular\",\"KHR_lights_punctual\"],"
                 "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"directional\",\"intensity\":2}]}},"
                 "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":32},"
                 "{\"buffer\":0,\"byteOffset\":80,\"byteLength\":12},{\"buffer\":0,\"byteOffset\":92,\"byteLength\":64}],"
                 "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
                 "\"min\":[-1,-1,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
                 "{\"bufferView\":2,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"},"
                 "{\"bufferView\":3,\"componentType\":5126,\"count\":4,\"type\":\"VEC4\"}],"
                 "\"images\":[{\"uri\":\"n.png\"}],\"textures\":[{\"source\":0}],"
                 "\"materials\":[{\"pbrMetallicRoughness\":{\"metallicFactor\":0},\"normalTexture\":{\"index\":0%s},"
                 "\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0}}}],"
                 "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1%s},\"indices\":2,"
                 "\"material\":0}]}],"
                 "\"nodes\":[{\"mesh\":0},{\"rotation\":[-0.18257419,0.36514837,0,0.91287093],"
                 "\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}],\"scenes\":[{\"nodes\":[0,1]}],\"scene\":0",
                 variant == 3 ? ",\"scale\":0.5" : "", variant == 1 || variant == 2 ? ",\"TANGENT\":3" : "");
        path_join(p, sizeof p, dir, "nm.gltf");
        write_gltf(p, bin, sizeof bin, json);
        fv_scene *s = fv_scene_load(p, err, sizeof err);
        if (!s) print_error("%s\n", err);
        assert_non_null(s);
        fv_light lt;
        assert_int_equal(fv_scene_get_light(s, 0, &lt), 0); /* the node turns -z to -l */
        for (int k = 0; k < 3; k++) assert_near(lt.dir[k], (float)-l[k], 1e-6f);
        for (int half = 0; half < 2; half++) {
            const unsigned char *c = nm + 4 * half;
            double m[3] = {(2.0 * c[0] / 255 - 1) * scale, (2.0 * c[1] / 255 - 1) * scale, 2.0 * c[2] / 255 - 1};
            if (w < 0) m[1] = -m[1]; /* bitangent -y */
            const double ml = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
            const double nl = (m[0] * l[0] + m[1] * l[1] + m[2] * l[2]) / ml;
            static const double by_hand[4][2] = {{0.9428, 0.7071}, {0.9428, 0.7071}, {0.9428, 0.2357}, {0.8953, 0.7470}};
            assert_near((float)nl, (float)by_hand[variant][half], 3e-3f); /* the comment's values */
            const float o[3] = {half ? 0.5f : -0.5f, 0, 5}, d[3] = {0, 0, -1};
            hit h;
            float rgb[3];
            cast_shade(s, o, d, 0, &h, rgb);
            const float want = (float)(0.15 + nl);
            assert_rgb(rgb, want, want, want, 2e-5f, __LINE__);
        }
        check_packets(s, 40 + (uint64_t)variant);
        fv_scene_free(s);
    }
    tmpdir_remove(dir);
}

/* Shadows (fv_scene_set_shadows): a ground quad y = 0 over [-4, 4]^2, a unit box [-0.5, 0.5] x
 * [0, 1] x [-0.5, 0.5] on it, matte white (builder meshes), one directional light travelling
 * along (-1, -1, 0) (towards the light: l = (1, 1, 0) / sqrt 2, irradiance 1). A ground point
 * (x, 0, z) sees the light along (x + s, s, z), s > 0, which passes through the box iff
 * |z| < 0.5 and x + s in [-0.5, 0.5] for some s in [0, 1]: x in [-1.5, 0.5]; outside the box's
 * foot that is x in (-1.5, -0.5): the shadow. Seen from 50 m above (matte: the view direction
 * does not matter; the light is not the head light): lit 0.15 + n.l = 0.15 + 0.7071, shadowed 0.15. Through fv_scene_shade and the packet path (every ISA), and
 * with shadows off everything is lit. */
static void test_shadows(void **state)
{
    (void)state;
    static const float ground[] = {-4, 0, -4, 4, 0, -4, 4, 0, 4, -4, 0, 4};
    static const uint32_t gidx[] = {0, 1, 2, 0, 2, 3};
    static const float box[] = {-0.5f, 0, -0.5f, 0.5f, 0, -0.5f, 0.5f, 1, -0.5f, -0.5f, 1, -0.5f,
                                -0.5f, 0, 0.5f,  0.5f, 0, 0.5f,  0.5f, 1, 0.5f,  -0.5f, 1, 0.5f};
    static const uint32_t bidx[] = {0, 1, 2, 0, 2, 3, 4, 6, 5, 4, 7, 6, 0, 4, 5, 0, 5, 1,
                                    3, 2, 6, 3, 6, 7, 0, 3, 7, 0, 7, 4, 1, 5, 6, 1, 6, 2};
    static const float flat_up[] = {0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0};
    fv_scene *s = fv_scene_create();
    char err[256];
    fv_mesh_desc g = mesh(ground, 4, gidx, 6), b = mesh(box, 8, bidx, 36);
    g.normals = flat_up;
    assert_int_equal(fv_scene_add_mesh(s, &g, err, sizeof err), 0);
    assert_int_equal(fv_scene_add_mesh(s, &b, err, sizeof err), 0);
    const fv_light l = {.type = FV_LIGHT_DIRECTIONAL, .color = {1, 1, 1}, .intensity = 3, .dir = {-1, -1, 0}};
    fv_scene_add_light(s, &l);
    s = commit_or_fail(s);
    const float lit = 0.15f + SQ2, dark = 0.15f;
    /* ground points, and expected with shadows on: (-1, 0), (-1.4, 0.4), (-0.6, -0.45) in the
     * shadow; (-1.6, 0), (-1, 0.6), (1, 0) beside it (the box's smooth computed normals are not
     * the faces', so its own faces are left out) */
    const float pts[6][2] = {{-1, 0}, {-1.4f, 0.4f}, {-1.6f, 0}, {-1, 0.6f}, {1, 0}, {-0.6f, -0.45f}};
    const float want_on[6] = {dark, dark, lit, lit, lit, dark};
    for (int on = 0; on < 2; on++) {
        assert_int_equal(fv_scene_set_shadows(s, on), 0);
        const float eye[3] = {0, 50, 0}; /* high enough that no ray to these points meets the box */
        unsigned geom[16], prim[16];
        float u[16], v[16], t[16], dir[3][16];
        for (int i = 0; i < 6; i++) {
            const float d[3] = {pts[i][0], -50, pts[i][1]};
            hit h;
            float rgb[3];
            cast_shade(s, eye, d, 0, &h, rgb);
            const float want = on ? want_on[i] : lit;
            assert_rgb(rgb, want, want, want, 1e-5f, __LINE__);
            for (int q = i; q < 16; q += 6) {
                geom[q] = h.geom, prim[q] = h.prim, u[q] = h.u, v[q] = h.v, t[q] = h.t;
                for (int k = 0; k < 3; k++) dir[k][q] = d[k];
            }
        }
        const fv_hit_packet hp = {geom, prim, u, v, t, {dir[0], dir[1], dir[2]}};
        static const unsigned isas[] = {FV_ISA_C, FV_ISA_SSE41, FV_ISA_AVX2, FV_ISA_NEON};
        for (size_t i = 0; i < sizeof isas / sizeof isas[0]; i++) {
            if (isas[i] && !(fv_cpu_isas() & isas[i])) continue;
            fv_shade_dsp dsp;
            fv_shade_dsp_init(&dsp, isas[i] ? isas[i] : FV_ISA_C);
            float rgb[3][16];
            fv_scene_shade_packet(s, &dsp, &hp, 16, 0.001f, eye, rgb);
            for (int q = 0; q < 16; q++) {
                const float want = on ? want_on[q % 6] : lit;
                for (int k = 0; k < 3; k++) assert_near(rgb[k][q], want, 1e-5f);
            }
        }
        check_packets(s, 50 + (uint64_t)on);
    }
    fv_scene_free(s);
}

/* Alpha BLEND composited front to back (core/blend.c): matte (metallic 0, specularFactor 0)
 * quads [-1,1]^2 seen from the eye (0, 0.1, 5) with the head light, rays through (x, 0.1, 0),
 * direction (x / 5, 0, -1): an opaque-shaded layer is base x (0.15 + n.v), n.v = 1 / sqrt(1 +
 * x^2 / 25), written c below (1.1450 at x = -0.5, 1.1078 at x = 1.5): a red pane of alpha 0.4 at z = 0 and a blue opaque wall at z = -2, both
 * over x in [-1, 1], and a green pane of alpha 0.5 at z = 1 over x in [1, 3]. Lanes (rays from (x, 0.1, 5) along -z):
 *   x = -0.5: red over blue: 0.4 (c, 0, 0) + 0.6 (0, 0, c), depth 7 (the wall at x = -0.7)
 *   x =  1.5: green (at x = 1.2) over nothing: 0.5 (0, c, 0) + 0.5 background, depth 4
 *   x = -3:   nothing: a miss
 * and, with the green pane moved over the red one (node at x = 0), x = -0.5: green, then red,
 * then blue: 0.5 G + 0.5 (0.4 R + 0.6 B) = (0.2 c, 0.5 c, 0.3 c), and x = 1.5 misses. Through the ray stage's calls
 * (fv_blend_begin, rtcIntersect16, fv_scene_shade_packet, fv_blend_composite). */
static void test_gltf_alpha_blend(void **state)
{
    (void)state;
    char *dir = tmpdir_make(), p[512], err[512];
    unsigned char bin[92];
    static const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    quad_buffer(bin, uv);
    for (int stacked = 0; stacked < 2; stacked++) {
        char json[4096];
        snprintf(json, sizeof json,
                 "\"extensionsUsed\":[\"KHR_materials_specular\"],"
                 "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":80,\"byteLength\":12}],"
                 "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
                 "\"min\":[-1,-1,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
                 "\"materials\":["
                 "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,0,0,0.4],\"metallicFactor\":0},\"alphaMode\":\"BLEND\","
                 "\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0}}},"
                 "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0,1,0,0.5],\"metallicFactor\":0},\"alphaMode\":\"BLEND\","
                 "\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0}}},"
                 "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0,0,1,1],\"metallicFactor\":0},"
                 "\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0}}}],"
                 "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":0}]},"
                 "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":1}]},"
                 "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":2}]}],"
                 "\"nodes\":[{\"mesh\":0},{\"mesh\":1,\"translation\":[%d,0,1]},{\"mesh\":2,\"translation\":[0,0,-2]}],"
                 "\"scenes\":[{\"nodes\":[0,1,2]}],\"scene\":0",
                 stacked ? 0 : 2);
        path_join(p, sizeof p, dir, "blend.gltf");
        write_gltf(p, bin, sizeof bin, json);
        fv_scene *s = fv_scene_load(p, err, sizeof err);
        if (!s) print_error("%s\n", err);
        assert_non_null(s);
        assert_true(fv_scene_has_blend(s));
        const float xs[3] = {-0.5f, 1.5f, -3}, eye[3] = {0, 0.1f, 5};
        _Alignas(64) struct RTCRayHit16 rh;
        memset(&rh, 0, sizeof rh);
        _Alignas(64) int valid[16];
        for (int q = 0; q < 16; q++) {
            valid[q] = -1;
            rh.ray.org_x[q] = eye[0], rh.ray.org_y[q] = eye[1], rh.ray.org_z[q] = eye[2];
            rh.ray.dir_x[q] = xs[q % 3] / 5, rh.ray.dir_y[q] = 0, rh.ray.dir_z[q] = -1; /* through (x, 0.1, 0) */
            rh.ray.tfar[q] = INFINITY, rh.ray.mask[q] = 0xFFFFFFFFu, rh.ray.id[q] = (unsigned)q;
            rh.hit.geomID[q] = RTC_INVALID_GEOMETRY_ID;
        }
        struct RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        fv_blend_packet lanes;
        fv_blend_begin(&lanes);
        fv_scene_intersect16(s, valid, &ctx, &rh);
        fv_blend_end();
        fv_shade_dsp dsp;
        fv_shade_dsp_init(&dsp, FV_ISA_C);
        const fv_hit_packet hp = {rh.hit.geomID, rh.hit.primID, rh.hit.u, rh.hit.v, rh.ray.tfar,
                                  {rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z}};
        float rgb[3][16];
        fv_scene_shade_packet(s, &dsp, &hp, 16, 0.001f, eye, rgb);
        const float bg[3] = {0.02f, 0.025f, 0.035f};
        const float *const dirs[3] = {rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z};
        fv_blend_composite(s, &lanes, rh.hit.geomID, rh.ray.tfar, NULL, dirs, 16, 0.001f, eye, bg, rgb);
        for (int q = 0; q < 16; q++) {
            const int i = q % 3;
            if (i == 2 || (i == 1 && stacked)) { /* a miss stays a miss (with the green pane moved, x = 1.5
                                                    * crosses nothing) */
                assert_true(rh.hit.geomID[q] == RTC_INVALID_GEOMETRY_ID);
                continue;
            }
            assert_true(rh.hit.geomID[q] != RTC_INVALID_GEOMETRY_ID);
            const float c = 0.15f + 1.0f / sqrtf(1.0f + xs[i] * xs[i] / 25); /* n.v off the axis */
            float want[3], want_t;
            if (i == 0 && !stacked) want[0] = 0.4f * c, want[1] = 0, want[2] = 0.6f * c, want_t = 7;
            else if (i == 0) want[0] = 0.5f * 0.4f * c, want[1] = 0.5f * c, want[2] = 0.5f * 0.6f * c, want_t = 7;
            else if (!stacked) want[0] = 0.5f * bg[0], want[1] = 0.5f * c + 0.5f * bg[1], want[2] = 0.5f * bg[2], want_t = 4;
            else want[0] = 0.5f * bg[0], want[1] = 0.5f * c + 0.5f * bg[1], want[2] = 0.5f * bg[2], want_t = 4;
            for (int k = 0; k < 3; k++) assert_near(rgb[k][q], want[k], 1e-5f);
            assert_near(rh.ray.tfar[q], want_t, 1e-5f);
        }
        fv_scene_free(s);
    }
    tmpdir_remove(dir);
}

/* COLOR_0 multiplies the base colour, interpolated: corners red, green, blue, white (VEC4
 * float; alpha dropped) on the quad [-1,1]^2, matte (specularFactor 0, metallic 0), head-on:
 * base x (1 + 0.15). (0.5, -0.5) lies in triangle (0, 1, 2) at u = 0.5, v = 0.25, w = 0.25:
 * colour (0.25, 0.5, 0.25) x 1.15. In triangle (0, 2, 3), (-0.5, 0.5) is at u = 0.25
 * (corner 2, blue) and v = 0.5 (corner 3, white): (0.75, 0.5, 0.75) x 1.15. */
static void test_gltf_vertex_colours(void **state)
{
    (void)state;
    unsigned char bin[124];
    const float pos[12] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    const float col[16] = {1, 0, 0, 0.5f, 0, 1, 0, 1, 0, 0, 1, 1, 1, 1, 1, 1};
    const uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
    memcpy(bin, pos, 48);
    memcpy(bin + 48, col, 64);
    memcpy(bin + 112, idx, 12);
    const char *json =
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":64},"
        "{\"buffer\":0,\"byteOffset\":112,\"byteLength\":12}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
        "\"min\":[-1,-1,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC4\"},"
        "{\"bufferView\":2,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
        "\"materials\":[{\"pbrMetallicRoughness\":{\"metallicFactor\":0},"
        "\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0}}}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"COLOR_0\":1},\"indices\":2,\"material\":0}]}],"
        "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0";
    char *dir = tmpdir_make(), p[512], err[512];
    path_join(p, sizeof p, dir, "col.gltf");
    write_gltf(p, bin, sizeof bin, json);
    fv_scene *s = fv_scene_load(p, err, sizeof err);
    if (!s) print_error("%s\n", err);
    assert_non_null(s);
    const float d[3] = {0, 0, -1}, a[3] = {0.5f, -0.5f, 5}, b[3] = {-0.5f, 0.5f, 5};
    hit h;
    float rgb[3];
    cast_shade(s, a, d, 0, &h, rgb);
    assert_rgb(rgb, 0.25f * 1.15f, 0.5f * 1.15f, 0.25f * 1.15f, 1e-5f, __LINE__);
    cast_shade(s, b, d, 0, &h, rgb);
    assert_rgb(rgb, 0.75f * 1.15f, 0.5f * 1.15f, 0.75f * 1.15f, 1e-5f, __LINE__);
    check_packets(s, 6);
    fv_scene_free(s);
    tmpdir_remove(dir);
}

/* Sampler wrap modes: a quad [-1,1]^2 with u = 1.5 x + 0.5 (so u runs -1 .. 2) and a 2x1 base
 * colour texture black | white, matte, head-on (rgb = 1.15 x texel), at lod 0. With
 * x = -8/15 (u = -0.3) and x = 0.8 (u = 1.7), the bilinear tap x = u w - 0.5 gives:
 *   REPEAT: u -> 0.7 (x 0.9: 0.1 black + 0.9 white = 0.9) both times
 *   CLAMP_TO_EDGE: u -> 0 (x -0.5, both taps the black edge texel: 0) and 1 (white: 1)
 *   MIRRORED_REPEAT: -0.3 -> 0.3 and 1.7 -> 0.3 (x 0.1: 0.9 black + 0.1 white = 0.1)
 * The v coordinate (0.5) samples the only row. */
static void test_gltf_sampler_wrap(void **state)
{
    (void)state;
    char *dir = tmpdir_make(), p[512], err[512];
    const unsigned char px[8] = {0, 0, 0, 255, 255, 255, 255, 255};
    path_join(p, sizeof p, dir, "bw.png");
    assert_true(stbi_write_png(p, 2, 1, 4, px, 8) != 0);
    unsigned char bin[92];
    static const float uv[8] = {-1, 0.5f, 2, 0.5f, 2, 0.5f, -1, 0.5f};
    quad_buffer(bin, uv);
    static const int gl[3] = {10497, 33071, 33648};
    static const float want[3][2] = {{0.9f, 0.9f}, {0.0f, 1.0f}, {0.1f, 0.1f}};
    for (int mode = 0; mode < 3; mode++) {
        char json[4096];
        snprintf(json, sizeof json,
                 "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":32},"
                 "{\"buffer\":0,\"byteOffset\":80,\"byteLength\":12}],"
                 "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
                 "\"min\":[-1,-1,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
                 "{\"bufferView\":2,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
                 "\"images\":[{\"uri\":\"bw.png\"}],\"samplers\":[{\"wrapS\":%d,\"wrapT\":%d}],"
                 "\"textures\":[{\"source\":0,\"sampler\":0}],"
                 "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicFactor\":0},"
                 "\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0}}}],"
                 "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"indices\":2,\"material\":0}]}],"
                 "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0",
                 gl[mode], gl[(mode + 1) % 3]);
        path_join(p, sizeof p, dir, "wrap.gltf");
        write_gltf(p, bin, sizeof bin, json);
        fv_scene *s = fv_scene_load(p, err, sizeof err);
        if (!s) print_error("%s\n", err);
        assert_non_null(s);
        const float d[3] = {0, 0, -1}, xs[2] = {-8.0f / 15.0f, 0.8f};
        for (int i = 0; i < 2; i++) {
            const float o[3] = {xs[i], 0.3f, 5};
            hit h;
            float rgb[3];
            cast_shade(s, o, d, 0, &h, rgb);
            assert_near(rgb[1], 1.15f * want[mode][i], 1e-4f);
        }
        check_packets(s, 7 + (uint64_t)mode);
        fv_scene_free(s);
    }
    tmpdir_remove(dir);
}

/* Sampler filters (glTF magFilter / minFilter), on a 4x1 linear texture whose red texels are
 * 0, 64, 128, 255 (/255): magnified (lod 0) at u = 0.3 the bilinear tap blends texels 0 and 1
 * (x = 0.7), NEAREST gives texel 1 (u w = 1.2) exactly; minified, no mipmaps: level 0 whatever
 * the lod; NEAREST mipmap: the nearest level (lod 0.7 -> 1, 0.4 -> 0) at its texel centre
 * (u = 0.25 on level 1, 0.375 on level 0) exactly; NEAREST within levels blended linearly:
 * texel 1 of level 0 and texel 0 of level 1 (u 2 = 0.6), half each at lod 0.5. Then the glTF
 * sampler: the wrap test's quad with magFilter NEAREST gives white (texel 1) where the
 * bilinear tap gave 0.9. */
static void test_texture_filters(void **state)
{
    (void)state;
    fv_scene *s = fv_scene_create();
    const uint8_t px[16] = {0, 0, 0, 255, 64, 64, 64, 255, 128, 128, 128, 255, 255, 255, 255, 255};
    const int id = fv_scene_add_texture_linear(s, px, 4, 1);
    assert_true(id >= 0);
    const fv_texture *t = &s->textures[id];
    const float *l0 = t->level[0], *l1 = t->level[1];
    float o[4];
    fv_texture_sample(t, 0.3f, 0.5f, 0.0f, o); /* trilinear: a blend */
    assert_true(o[0] > l0[0] && o[0] < l0[4]);
    assert_int_equal(fv_scene_set_texture_filter(s, id, 1, 0, FV_MIP_LINEAR), 0);
    fv_texture_sample(t, 0.3f, 0.5f, 0.0f, o);
    assert_true(o[0] == l0[4]);
    assert_int_equal(fv_scene_set_texture_filter(s, id, 0, 1, FV_MIP_NONE), 0);
    fv_texture_sample(t, 0.3f, 0.5f, 1.3f, o);
    assert_true(o[0] == l0[4]);
    assert_int_equal(fv_scene_set_texture_filter(s, id, 0, 0, FV_MIP_NEAREST), 0);
    fv_texture_sample(t, 0.25f, 0.5f, 0.7f, o);
    assert_true(o[0] == l1[0]);
    fv_texture_sample(t, 0.375f, 0.5f, 0.4f, o);
    assert_true(o[0] == l0[4]);
    assert_int_equal(fv_scene_set_texture_filter(s, id, 0, 1, FV_MIP_LINEAR), 0);
    fv_texture_sample(t, 0.3f, 0.5f, 0.5f, o);
    assert_true(o[0] == l0[4] + (l1[0] - l0[4]) * 0.5f);
    assert_int_equal(fv_scene_set_texture_filter(s, id + 1, 0, 0, FV_MIP_LINEAR), -1);
    fv_scene_free(s);

    char *dir = tmpdir_make(), p[512], err[512];
    const unsigned char bw[8] = {0, 0, 0, 255, 255, 255, 255, 255};
    path_join(p, sizeof p, dir, "bw.png");
    assert_true(stbi_write_png(p, 2, 1, 4, bw, 8) != 0);
    unsigned char bin[92];
    static const float uv[8] = {-1, 0.5f, 2, 0.5f, 2, 0.5f, -1, 0.5f};
    quad_buffer(bin, uv);
    const char *json =
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":32},"
        "{\"buffer\":0,\"byteOffset\":80,\"byteLength\":12}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
        "\"min\":[-1,-1,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
        "{\"bufferView\":2,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
        "\"images\":[{\"uri\":\"bw.png\"}],\"samplers\":[{\"magFilter\":9728,\"minFilter\":9984}],"
        "\"textures\":[{\"source\":0,\"sampler\":0}],"
        "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicFactor\":0},"
        "\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0}}}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"indices\":2,\"material\":0}]}],"
        "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0";
    path_join(p, sizeof p, dir, "filter.gltf");
    write_gltf(p, bin, sizeof bin, json);
    s = fv_scene_load(p, err, sizeof err);
    if (!s) print_error("%s\n", err);
    assert_non_null(s);
    assert_int_equal(s->textures[0].mag_nearest, 1);
    assert_int_equal(s->textures[0].min_nearest, 1);
    assert_int_equal(s->textures[0].mip, FV_MIP_NEAREST);
    const float d[3] = {0, 0, -1}, xs[2] = {-8.0f / 15.0f, 0.8f};
    for (int i = 0; i < 2; i++) {
        const float org[3] = {xs[i], 0.3f, 5};
        hit h;
        float rgb[3];
        cast_shade(s, org, d, 0, &h, rgb);
        assert_near(rgb[1], 1.15f * 1.0f, 1e-4f);
    }
    check_packets(s, 31);
    fv_scene_free(s);
    tmpdir_remove(dir);
}

/* KHR_texture_transform on the base colour: a quad [-1,1]^2 with u = (x + 1)/2, v = 0.5 and the
 * 2x1 black | white texture (REPEAT), matte, head-on (rgb = 1.15 x texel). At x = -0.5 and 0.5
 * (u = 0.25 and 0.75, the texel centres):
 *   none: 0, 1;   offset [0.5, 0]: u' = 0.75, 1.25 -> white, black: 1, 0
 *   rotation pi: u' = -u, v' = -v: 0.75 and 0.25: 1, 0
 *   scale [0.5, 1]: u' = 0.125 (tap x = -0.25: 0.25 of the wrapped white texel) and 0.375
 *   (x = 0.25: 0.25 white): 0.25, 0.25 */
static void test_gltf_texture_transform(void **state)
{
    (void)state;
    char *dir = tmpdir_make(), p[512], err[512];
    const unsigned char px[8] = {0, 0, 0, 255, 255, 255, 255, 255};
    path_join(p, sizeof p, dir, "bw.png");
    assert_true(stbi_write_png(p, 2, 1, 4, px, 8) != 0);
    unsigned char bin[92];
    static const float uv[8] = {0, 0.5f, 1, 0.5f, 1, 0.5f, 0, 0.5f};
    quad_buffer(bin, uv);
    static const char *const xf[4] = {"", ",\"extensions\":{\"KHR_texture_transform\":{\"offset\":[0.5,0]}}",
                                      ",\"extensions\":{\"KHR_texture_transform\":{\"rotation\":3.14159265}}",
                                      ",\"extensions\":{\"KHR_texture_transform\":{\"scale\":[0.5,1]}}"};
    static const float want[4][2] = {{0, 1}, {1, 0}, {1, 0}, {0.25f, 0.25f}};
    for (int c = 0; c < 4; c++) {
        char json[4096];
        snprintf(json, sizeof json,
                 "\"extensionsUsed\":[\"KHR_texture_transform\"],\"extensionsRequired\":[\"KHR_texture_transform\"],"
                 "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":32},"
                 "{\"buffer\":0,\"byteOffset\":80,\"byteLength\":12}],"
                 "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
                 "\"min\":[-1,-1,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
                 "{\"bufferView\":2,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
                 "\"images\":[{\"uri\":\"bw.png\"}],\"textures\":[{\"source\":0}],"
                 "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0%s},\"metallicFactor\":0},"
                 "\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0}}}],"
                 "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"indices\":2,\"material\":0}]}],"
                 "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0",
                 xf[c]);
        path_join(p, sizeof p, dir, "xf.gltf");
        write_gltf(p, bin, sizeof bin, json);
        fv_scene *s = fv_scene_load(p, err, sizeof err);
        if (!s) print_error("%s\n", err);
        assert_non_null(s);
        const float d[3] = {0, 0, -1}, xs[2] = {-0.5f, 0.5f};
        for (int i = 0; i < 2; i++) {
            const float o[3] = {xs[i], 0.3f, 5};
            hit h;
            float rgb[3];
            cast_shade(s, o, d, 0, &h, rgb);
            assert_near(rgb[1], 1.15f * want[c][i], 1e-4f);
        }
        check_packets(s, 10 + (uint64_t)c);
        fv_scene_free(s);
    }
    tmpdir_remove(dir);
}

/* ---- hostile files ------------------------------------------------------------------- */

/* A scene's external files stay inside its folder tree (or --asset-root's): `..`, percent-escaped
 * `..`, a symbolic link out, an absolute path and a URI scheme are refused with a message naming
 * the URI; the same file inside the folder loads, and so does the outside one under a wider root. */
static void write_tri_scene(const char *path, const char *uri)
{
    char json[2048];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":36,\"uri\":\"%s\"}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
             "\"min\":[0,0,0],\"max\":[1,1,0]}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
             "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0}",
             uri);
    write_all(path, json, strlen(json));
}

static void test_scene_folder_confinement(void **state)
{
    (void)state;
    char *top = tmpdir_make(), sub[256], p[512], buf[512], q[600];
    static const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    write_all(path_join(buf, sizeof buf, top, "secret.bin"), tri, sizeof tri);
    path_join(sub, sizeof sub, top, "scene");
    assert_int_equal(mkdir(sub, 0700), 0);
    write_all(path_join(buf, sizeof buf, sub, "ok.bin"), tri, sizeof tri);
    path_join(p, sizeof p, sub, "s.gltf");

    write_tri_scene(p, "ok.bin");
    char err[1024];
    fv_scene *s = fv_scene_load(p, err, sizeof err);
    assert_non_null(s);
    fv_scene_free(s);

    write_tri_scene(p, "../secret.bin");
    expect_load_fails(p, "is outside the scene's folder");
    write_tri_scene(p, "%2e%2e/secret.bin");
    expect_load_fails(p, "is outside the scene's folder");
    assert_int_equal(symlink("../secret.bin", path_join(buf, sizeof buf, sub, "link.bin")), 0);
    write_tri_scene(p, "link.bin");
    expect_load_fails(p, "is outside the scene's folder");
    snprintf(q, sizeof q, "%s/secret.bin", top);
    write_tri_scene(p, q);
    expect_load_fails(p, "absolute paths and URI schemes other than data: are not allowed");
    write_tri_scene(p, "file:///etc/passwd");
    expect_load_fails(p, "file:///etc/passwd");

    /* --asset-root widens the tree: the file one level up now loads */
    write_tri_scene(p, "../secret.bin");
    s = fv_scene_load_in(p, top, err, sizeof err);
    if (!s)
        fail_msg("with the wider root: %s", err);
    fv_scene_free(s);

    unlink(path_join(buf, sizeof buf, sub, "link.bin"));
    unlink(path_join(buf, sizeof buf, sub, "ok.bin"));
    unlink(p);
    rmdir(sub);
    tmpdir_remove(top);
}

/* A texture PNG whose IDAT length lies is refused by the chunk check before stb_image reserves
 * what it claims (2 GiB for 83 bytes); the message names the image. */
static void test_texture_png_lying_length(void **state)
{
    (void)state;
    static const unsigned char png[] = { /* 1x1 RGBA PNG; IDAT's length set to 0x7fffff00 */
        0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R', 0, 0, 0, 1, 0, 0, 0, 1, 8, 6,
        0, 0, 0, 0x1f, 0x15, 0xc4, 0x89, 0x7f, 0xff, 0xff, 0x00, 'I', 'D', 'A', 'T', 0x78, 0x9c, 0x63, 0xf8, 0xcf,
        0xc0, 0xf0, 0x1f, 0x00, 0x05, 0x00, 0x01, 0xff, 0x89, 0x99, 0x3d, 0x1d, 0, 0, 0, 0, 'I', 'E', 'N', 'D',
        0xae, 0x42, 0x60, 0x82};
    char *b64 = base64(png, sizeof png), *dir = tmpdir_make(), p[512];
    static const float tri[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1};
    char *members = malloc(strlen(b64) + 1024);
    assert_non_null(members);
    sprintf(members,
            "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":24}],"
            "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
            "\"min\":[0,0,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"VEC2\"}],"
            "\"images\":[{\"uri\":\"data:image/png;base64,%s\"}],\"textures\":[{\"source\":0}],"
            "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}],"
            "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"material\":0}]}],"
            "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0",
            b64);
    write_gltf(path_join(p, sizeof p, dir, "lying.gltf"), tri, sizeof tri, members);
    expect_load_fails(p, "image 0: PNG chunk IDAT claims 2147483392 bytes");
    unlink(p);
    free(members);
    free(b64);
    tmpdir_remove(dir);
}

/* Triangle strips and fans (glTF modes 5 and 6), indexed or not, against the equivalent triangle
 * list written by hand from the specification's vertex order (3.7.2.1): strip triangle i is
 * (v_i, v_{i+1+i%2}, v_{i+2-i%2}), fan triangle i is (v_{i+1}, v_{i+2}, v_0). Rays on a grid must
 * hit the same triangle at the same distance with the same barycentrics (which fix the order). */
static fv_scene *mode_scene(const char *dir, const char *name, int mode, const uint8_t *idx, int nidx)
{
    /* 5 vertices: a zigzag (strip) that is also a convex fan around vertex 0 */
    static const float pos[15] = {0, 0, 0, 1, -1, 0, 1, 1, 0, -0.2f, 1.6f, 0, -1, 0.8f, 0};
    unsigned char bin[60 + 16];
    memcpy(bin, pos, sizeof pos);
    if (nidx) memcpy(bin + 60, idx, (size_t)nidx); /* idx is NULL for a non-indexed scene */
    char members[1024], p[512];
    snprintf(members, sizeof members,
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":60}%s],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":5,\"type\":\"VEC3\","
             "\"min\":[-1,-1,0],\"max\":[1,1.6,0]}%s],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"mode\":%d%s}]}],"
             "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0",
             nidx ? ",{\"buffer\":0,\"byteOffset\":60,\"byteLength\":16}" : "",
             nidx ? ",{\"bufferView\":1,\"componentType\":5121,\"count\":0,\"type\":\"SCALAR\"}" : "", mode,
             nidx ? ",\"indices\":1" : "");
    if (nidx) { /* the index count */
        char *c = strstr(members, "\"count\":0");
        char num[8];
        snprintf(num, sizeof num, "%d", nidx);
        memmove(c + 8 + strlen(num), c + 9, strlen(c + 9) + 1);
        memcpy(c + 8, num, strlen(num));
    }
    write_gltf(path_join(p, sizeof p, dir, name), bin, nidx ? 60 + 16 : 60, members);
    char err[512];
    fv_scene *sc = fv_scene_load(p, err, sizeof err);
    if (!sc)
        fail_msg("%s: %s", name, err);
    return sc;
}

static void same_hits(const fv_scene *a, const fv_scene *b, const char *what)
{
    int hits = 0;
    for (int y = 0; y < 24; y++)
        for (int x = 0; x < 24; x++) {
            const float o[3] = {-1.1f + 2.2f * (x + 0.5f) / 24, -1.1f + 2.8f * (y + 0.5f) / 24, 2}, d[3] = {0, 0, -1};
            hit ha, hb;
            const int ka = cast(a, o, d, &ha), kb = cast(b, o, d, &hb);
            if (ka != kb || (ka && (ha.prim != hb.prim || fabsf(ha.t - hb.t) > 1e-6f || fabsf(ha.u - hb.u) > 1e-6f ||
                                    fabsf(ha.v - hb.v) > 1e-6f)))
                fail_msg("%s: ray %d,%d differs (hit %d/%d prim %u/%u u %g/%g v %g/%g)", what, x, y, ka, kb, ha.prim,
                         hb.prim, ha.u, hb.u, ha.v, hb.v);
            hits += ka;
        }
    assert_true(hits > 100); /* the shape really is under the grid */
}

static void test_strip_fan_modes(void **state)
{
    (void)state;
    char *dir = tmpdir_make();
    static const uint8_t seq[5] = {0, 1, 2, 3, 4};
    static const uint8_t strip_list[9] = {0, 1, 2, 1, 3, 2, 2, 3, 4};
    static const uint8_t fan_list[9] = {1, 2, 0, 2, 3, 0, 3, 4, 0};
    fv_scene *ls = mode_scene(dir, "ls.gltf", 4, strip_list, 9), *lf = mode_scene(dir, "lf.gltf", 4, fan_list, 9);
    fv_scene *si = mode_scene(dir, "si.gltf", 5, seq, 5), *sn = mode_scene(dir, "sn.gltf", 5, NULL, 0);
    fv_scene *fi = mode_scene(dir, "fi.gltf", 6, seq, 5), *fn = mode_scene(dir, "fn.gltf", 6, NULL, 0);
    assert_int_equal(fv_scene_triangle_count(si), 3);
    assert_int_equal(fv_scene_triangle_count(fn), 3);
    same_hits(ls, si, "indexed strip");
    same_hits(ls, sn, "non-indexed strip");
    same_hits(lf, fi, "indexed fan");
    same_hits(lf, fn, "non-indexed fan");
    assert_string_equal(fv_scene_warning(si), "");
    fv_scene_free(ls), fv_scene_free(lf), fv_scene_free(si), fv_scene_free(sn), fv_scene_free(fi), fv_scene_free(fn);
    tmpdir_remove(dir);
}

/* Points and lines are skipped with one warning; unsupported versions and required extensions
 * fail with one line naming them (tinygltf said "asset object not found" and "accessor[0] invalid
 * bufferView"). */
static void test_modes_versions_extensions(void **state)
{
    (void)state;
    char *dir = tmpdir_make(), p[512];
    static const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    write_gltf(path_join(p, sizeof p, dir, "mixed.gltf"), pos, sizeof pos,
               "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
               "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
               "\"min\":[0,0,0],\"max\":[1,1,0]}],"
               "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"mode\":0},"
               "{\"attributes\":{\"POSITION\":0},\"mode\":1},{\"attributes\":{\"POSITION\":0}}]}],"
               "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0");
    char err[512];
    fv_scene *s = fv_scene_load(p, err, sizeof err);
    assert_non_null(s);
    assert_int_equal(fv_scene_triangle_count(s), 1);
    assert_string_equal(fv_scene_warning(s), "skipped 2 point or line primitives (only triangles are rendered)");
    fv_scene_free(s);

    static const char *const bad[][2] = {
        {"{\"asset\":{\"version\":\"1.0\"},\"meshes\":{}}", "glTF 1.0 is not supported, only glTF 2.0"},
        {"{\"meshes\":{\"m\":{}},\"accessors\":{}}", "no asset object: not a glTF 2.0 file"},
        {"{\"asset\":{\"generator\":\"x\",\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_draco_mesh_compression\"],"
         "\"extensionsRequired\":[\"KHR_draco_mesh_compression\"],\"accessors\":[{\"componentType\":5126,\"count\":3,"
         "\"type\":\"VEC3\"}]}",
         "required extension KHR_draco_mesh_compression is not supported (compressed meshes"},
        {"{\"extensionsRequired\":[\"KHR_lights_punctual\", \"EXT_texture_webp\"],\"asset\":{\"version\":\"2.0\"}}",
         "required extension EXT_texture_webp is not supported (texture format"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        write_all(path_join(p, sizeof p, dir, "bad.gltf"), bad[i][0], strlen(bad[i][0]));
        expect_load_fails(p, bad[i][1]);
    }
    unlink(path_join(p, sizeof p, dir, "mixed.gltf"));
    tmpdir_remove(dir);
}

static void test_missing_and_garbage(void **state)
{
    (void)state;
    char *dir = tmpdir_make(), p[512];
    expect_load_fails(path_join(p, sizeof p, dir, "does_not_exist.gltf"), NULL);
    expect_load_fails(dir, NULL); /* a directory */
    write_all(path_join(p, sizeof p, dir, "empty.gltf"), "", 0);
    expect_load_fails(p, NULL);
    const char *texts[] = {
        "{ this is not json",
        "[]",
        "{}",
        "{\"asset\":{\"version\":\"2.0\"}, \"nodes\": 5}",
        "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":4,\"uri\":\"data:application/octet-stream;base64,@@@@\"}]}",
        "glTF",
    };
    for (size_t i = 0; i < sizeof texts / sizeof *texts; i++) {
        write_all(path_join(p, sizeof p, dir, "garbage.gltf"), texts[i], strlen(texts[i]));
        expect_load_fails(p, NULL);
    }
    /* GLB header whose JSON chunk length wraps a 32-bit sum. */
    static const unsigned char hdr[] = "glTF\x02\0\0\0\x28\0\0\0\xf0\xff\xff\xffJSON{}  {}  {}  {}  {}";
    write_all(path_join(p, sizeof p, dir, "wrap.glb"), hdr, sizeof hdr - 1);
    expect_load_fails(p, NULL);
    /* Nesting deep enough to overflow a recursive converter. */
    const size_t depth = 200000;
    char *deep = malloc(2 * depth + 64);
    assert_non_null(deep);
    size_t n = (size_t)sprintf(deep, "{\"asset\":{\"version\":\"2.0\"},\"extras\":");
    memset(deep + n, '[', depth), n += depth;
    memset(deep + n, ']', depth), n += depth;
    deep[n++] = '}';
    write_all(path_join(p, sizeof p, dir, "deep.gltf"), deep, n);
    free(deep);
    expect_load_fails(p, "nested");
    /* Random bytes. */
    uint64_t rng = 42;
    unsigned char junk[4096];
    for (size_t i = 0; i < sizeof junk; i++) junk[i] = (unsigned char)fv_test_rand(&rng);
    write_all(path_join(p, sizeof p, dir, "junk.glb"), junk, sizeof junk);
    expect_load_fails(p, NULL);
    junk[0] = 'g', junk[1] = 'l', junk[2] = 'T', junk[3] = 'F';
    write_all(p, junk, sizeof junk);
    expect_load_fails(p, NULL);
    tmpdir_remove(dir);
}

static void test_truncated(void **state)
{
    (void)state;
    char p[512], src[512];
    size_t len;
    /* .glb cut anywhere: header, JSON chunk, BIN chunk, last byte. (The shared file first: a
     * skip must not leave the temporary folder behind.) */
    unsigned char *glb = read_all(shared_scene(src, sizeof src, "DepthOfFieldExample/DepthOfFieldExample.glb"), &len);
    char *dir = tmpdir_make();
    const size_t cuts[] = {3, 12, 19, 20, 100, len / 3, len / 2, len - 4, len - 1};
    for (size_t i = 0; i < sizeof cuts / sizeof *cuts; i++) {
        write_all(path_join(p, sizeof p, dir, "cut.glb"), glb, cuts[i]);
        expect_load_fails(p, NULL);
    }
    free(glb);
    /* .gltf JSON cut in the middle. */
    unsigned char *json = read_all(shared_scene(src, sizeof src, "FlightHelmet/FlightHelmet.gltf"), &len);
    write_all(path_join(p, sizeof p, dir, "FlightHelmet.gltf"), json, len / 2);
    expect_load_fails(p, NULL);
    free(json);
    /* .bin shorter than the buffer's byteLength. */
    json = read_all(shared_scene(src, sizeof src, "DamagedHelmet/DamagedHelmet.gltf"), &len);
    write_all(path_join(p, sizeof p, dir, "DamagedHelmet.gltf"), json, len);
    free(json);
    unsigned char *bin = read_all(shared_scene(src, sizeof src, "DamagedHelmet/DamagedHelmet.bin"), &len);
    write_all(path_join(p, sizeof p, dir, "DamagedHelmet.bin"), bin, len - 100);
    expect_load_fails(path_join(p, sizeof p, dir, "DamagedHelmet.gltf"), NULL);
    /* Full .bin but the base colour image is missing. */
    write_all(path_join(p, sizeof p, dir, "DamagedHelmet.bin"), bin, len);
    expect_load_fails(path_join(p, sizeof p, dir, "DamagedHelmet.gltf"), "image");
    free(bin);
    tmpdir_remove(dir);
}

/* Random byte flips must never crash; the file may still load (e.g. a flipped texel). */
static void test_corrupted_flips(void **state)
{
    (void)state;
    char p[512], src[512];
    size_t len;
    unsigned char *glb = read_all(shared_scene(src, sizeof src, "DepthOfFieldExample/DepthOfFieldExample.glb"), &len);
    char *dir = tmpdir_make();
    uint32_t json_len;
    memcpy(&json_len, glb + 12, 4);
    unsigned char *copy = malloc(len);
    assert_non_null(copy);
    uint64_t rng = 7;
    path_join(p, sizeof p, dir, "flip.glb");
    for (int iter = 0; iter < 16; iter++) {
        memcpy(copy, glb, len);
        /* Even iterations hit the header + JSON chunk, odd ones anywhere. */
        const size_t span = (iter & 1) ? len : 20 + (size_t)json_len + 8;
        for (int k = 0; k < 1 + iter; k++) copy[fv_test_rand(&rng) % span] ^= (unsigned char)(1u << (fv_test_rand(&rng) % 8));
        write_all(p, copy, len);
        load_any(p);
    }
    free(copy);
    free(glb);
    /* Flips in the small hand-written file, including its base64 buffer. */
    unsigned char *txt = read_all("tests/data/scene/hierarchy.gltf", &len);
    copy = malloc(len);
    assert_non_null(copy);
    path_join(p, sizeof p, dir, "flip.gltf");
    for (int iter = 0; iter < 64; iter++) {
        memcpy(copy, txt, len);
        for (int k = 0; k < 1 + iter % 4; k++) copy[fv_test_rand(&rng) % len] = (unsigned char)fv_test_rand(&rng);
        write_all(p, copy, len);
        load_any(p);
    }
    free(copy);
    free(txt);
    tmpdir_remove(dir);
}

/* Hand-made files whose JSON is valid but whose data is not. The buffer holds 3 float3
 * positions (36 bytes) then 3 u16 indices (+2 pad); POSITION_NAN's second vertex is NaN. */
static void test_invalid_data(void **state)
{
    (void)state;
    unsigned char bin[44 + 36];
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const float pos_nan[9] = {0, 0, 0, NAN, 0, 0, 0, 1, 0};
    const uint16_t idx[4] = {0, 1, 2, 0};
    memcpy(bin, pos, 36);
    memcpy(bin + 36, idx, 8);
    memcpy(bin + 44, pos_nan, 36);
#define VIEWS "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}," \
              "{\"buffer\":0,\"byteOffset\":44,\"byteLength\":36}],"
#define POS "{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}"
#define IDX(ct, count) "{\"bufferView\":1,\"componentType\":" #ct ",\"count\":" #count ",\"type\":\"SCALAR\"}"
#define SCENE "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0"
#define MESH(prim) "\"meshes\":[{\"primitives\":[" prim "]}],"
#define PRIM "{\"attributes\":{\"POSITION\":0},\"indices\":1}"
    static const struct {
        const char *members, *must_contain;
    } cases[] = {
        /* control: must load */
        {VIEWS "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH(PRIM) SCENE, NULL},
        /* index 2 read as u8 from bytes {0,0,1}: fine; as u32 it overruns the view */
        {VIEWS "\"accessors\":[" POS "," IDX(5125, 3) "]," MESH(PRIM) SCENE, "exceed"},
        /* out-of-range index: index 256 (bytes 0x00,0x01 of u16 {0,1} read as a u16 at offset 1) */
        {"\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":37,\"byteLength\":6}],"
         "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH(PRIM) SCENE, "index"},
        {VIEWS "\"accessors\":[" POS "," IDX(5123, 2) "]," MESH(PRIM) SCENE, "multiple of 3"},
        {VIEWS "\"accessors\":[" POS "," IDX(5126, 1) "]," MESH(PRIM) SCENE, "componentType"},
        {VIEWS "\"accessors\":[" POS "," IDX(5121, 3) "]," MESH(PRIM) SCENE, NULL}, /* u8 {0,0,1}: valid */
        {VIEWS "\"accessors\":[{\"bufferView\":2,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}," IDX(5123, 3)
               "]," MESH(PRIM) SCENE, "finite"},
        {VIEWS "\"accessors\":[{\"bufferView\":0,\"byteOffset\":4,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}," IDX(5123, 3)
               "]," MESH(PRIM) SCENE, "exceed"},
        {VIEWS "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC2\"}," IDX(5123, 3)
               "]," MESH(PRIM) SCENE, "components"},
        {"\"bufferViews\":[{\"buffer\":0,\"byteLength\":36,\"byteStride\":8},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],"
         "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH(PRIM) SCENE, "byteStride"},
        {"\"bufferViews\":[{\"buffer\":0,\"byteOffset\":60,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],"
         "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH(PRIM) SCENE, "exceeds buffer"},
        {VIEWS "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH(PRIM) "\"nodes\":[{\"mesh\":0,\"children\":[1]},{\"children\":[0]}],"
               "\"scenes\":[{\"nodes\":[0]}],\"scene\":0", "node"},
        {VIEWS "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH(PRIM) "\"nodes\":[{\"mesh\":0,\"children\":[7]}],"
               "\"scenes\":[{\"nodes\":[0]}],\"scene\":0", "child"},
        {VIEWS "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH(PRIM) "\"nodes\":[{\"mesh\":3}],\"scenes\":[{\"nodes\":[0]}]", "mesh"},
        {VIEWS "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH("{\"attributes\":{\"NORMAL\":0},\"indices\":1}") SCENE, "POSITION"},
        {VIEWS "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH("{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":2}") SCENE,
         "material"},
        {VIEWS "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH("{\"attributes\":{\"POSITION\":0},\"indices\":5}") SCENE, "accessor"},
        {VIEWS "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH(PRIM) "\"nodes\":[{\"mesh\":0,\"rotation\":[0,0,0]}],"
               "\"scenes\":[{\"nodes\":[0]}],\"scene\":0", "rotation"},
        {VIEWS "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH(PRIM) SCENE ",\"materials\":[{\"pbrMetallicRoughness\":"
               "{\"baseColorTexture\":{\"index\":0}}}],\"textures\":[{\"source\":0}],"
               "\"images\":[{\"bufferView\":9,\"mimeType\":\"image/png\"}]", "image"},
        /* image bufferView beyond its buffer (tinygltf does not check this itself) */
        {"\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6},"
         "{\"buffer\":0,\"byteOffset\":40,\"byteLength\":100000}],"
         "\"accessors\":[" POS "," IDX(5123, 3) "]," MESH(PRIM) SCENE ",\"images\":[{\"bufferView\":2,\"mimeType\":\"image/png\"}]",
         "image"},
    };
    char *dir = tmpdir_make(), p[512];
    path_join(p, sizeof p, dir, "case.gltf");
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        write_gltf(p, bin, sizeof bin, cases[i].members);
        const int should_load = i == 0 || i == 5;
        if (should_load) {
            char err[512];
            fv_scene *s = fv_scene_load(p, err, sizeof err);
            if (!s) print_error("case %zu: %s\n", i, err);
            assert_non_null(s);
            assert_int_equal(fv_scene_triangle_count(s), 1);
            fv_scene_free(s);
        } else if (!load_fails(p, cases[i].must_contain)) {
            print_error("case %zu\n", i);
            fail();
        }
    }
    tmpdir_remove(dir);
}

/* Sparse accessor: POSITION's vertex 1 (1,0,0) is replaced by (2,0,0), so the ray down -Z
 * at (1.5, 0.1) hits (it would miss the unsubstituted triangle). A sparse index >= count fails. */
static void test_gltf_sparse(void **state)
{
    (void)state;
    unsigned char bin[60];
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, moved[3] = {2, 0, 0};
    const uint16_t idx[4] = {0, 1, 2, 0};
    memset(bin, 0, sizeof bin);
    memcpy(bin, pos, 36);
    memcpy(bin + 36, idx, 8);
    bin[44] = 1; /* sparse index */
    memcpy(bin + 48, moved, 12);
    const char *json =
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6},"
        "{\"buffer\":0,\"byteOffset\":44,\"byteLength\":1},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"sparse\":{\"count\":1,"
        "\"indices\":{\"bufferView\":2,\"componentType\":5121},\"values\":{\"bufferView\":3}}},"
        "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
        "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0";
    char *dir = tmpdir_make(), p[512], err[512];
    path_join(p, sizeof p, dir, "sparse.gltf");
    write_gltf(p, bin, sizeof bin, json);
    fv_scene *s = fv_scene_load(p, err, sizeof err);
    if (!s) print_error("%s\n", err);
    assert_non_null(s);
    const float o[3] = {1.5f, 0.1f, 1}, d[3] = {0, 0, -1};
    hit h;
    assert_true(cast(s, o, d, &h));
    assert_near(h.t, 1.0f, 1e-6f);
    fv_scene_free(s);
    bin[44] = 3;
    write_gltf(p, bin, sizeof bin, json);
    expect_load_fails(p, "sparse index");
    tmpdir_remove(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_builder_quad_hit_and_headlight),
        cmocka_unit_test(test_builder_transform_non_indexed),
        cmocka_unit_test(test_builder_computed_normals),
        cmocka_unit_test(test_packet_shading_matches_scalar),
        cmocka_unit_test(test_builder_normals_inverse_transpose),
        cmocka_unit_test(test_texture_bilinear_wrap),
        cmocka_unit_test(test_texture_mips),
        cmocka_unit_test(test_texture_taps_rebase),
        cmocka_unit_test(test_builder_rejects_bad_meshes),
        cmocka_unit_test(test_lights_directional),
        cmocka_unit_test(test_lights_point_spot),
        cmocka_unit_test(test_default_view_frames_bounds),
        cmocka_unit_test(test_gltf_hierarchy),
        cmocka_unit_test(test_gltf_camera),
        cmocka_unit_test(test_gltf_sparse),
        cmocka_unit_test(test_gltf_pbr_materials),
        cmocka_unit_test(test_gltf_material_maps),
        cmocka_unit_test(test_gltf_alpha_mask),
        cmocka_unit_test(test_gltf_double_sided),
        cmocka_unit_test(test_gltf_normal_map),
        cmocka_unit_test(test_shadows),
        cmocka_unit_test(test_gltf_alpha_blend),
        cmocka_unit_test(test_gltf_vertex_colours),
        cmocka_unit_test(test_gltf_sampler_wrap),
        cmocka_unit_test(test_texture_filters),
        cmocka_unit_test(test_gltf_texture_transform),
        cmocka_unit_test(test_load_flight_helmet),
        cmocka_unit_test(test_load_damaged_helmet),
        cmocka_unit_test(test_load_dof_glb_lights),
        cmocka_unit_test(test_missing_and_garbage),
        cmocka_unit_test(test_strip_fan_modes),
        cmocka_unit_test(test_modes_versions_extensions),
        cmocka_unit_test(test_scene_folder_confinement),
        cmocka_unit_test(test_texture_png_lying_length),
        cmocka_unit_test(test_truncated),
        cmocka_unit_test(test_corrupted_flips),
        cmocka_unit_test(test_invalid_data),
    };
    return cmocka_run_group_tests_name("scene", tests, NULL, NULL);
}
