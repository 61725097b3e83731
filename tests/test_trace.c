/* Gaze / head traces: parsing from memory (core/trace.c), interpolation, and the file loader
 * (platform/tracefile.c). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "output.h"
#include "testutil.h"
#include "trace.h"
#include "tracefile.h"

static int parse(fv_trace *t, const char *text, char *err)
{
    return fv_trace_parse(t, text, strlen(text), "t.csv", err, 256);
}

static void test_good(void **st)
{
    (void)st;
    fv_trace t;
    char err[256];
    assert_int_equal(parse(&t, "# comment\nt_ms,gaze_x,gaze_y\n\n0,0.2,0.4\r\n 10 , 0.6 , 0.8\n# end\n", err), 0);
    assert_int_equal(t.n, 2);
    assert_false(t.has_head);
    fv_trace_sample s;
    fv_trace_at(&t, 2.5, &s);
    assert_float_equal(s.gaze_x, 0.3f, 1e-6);
    assert_float_equal(s.gaze_y, 0.5f, 1e-6);
    fv_trace_at(&t, -5.0, &s); /* held at the ends */
    assert_float_equal(s.gaze_x, 0.2f, 0.0f);
    fv_trace_at(&t, 99.0, &s);
    assert_float_equal(s.gaze_y, 0.8f, 0.0f);
    fv_trace_free(&t);
}

static void test_head(void **st)
{
    (void)st;
    fv_trace t;
    char err[256];
    /* 0 -> 90 degrees about +Y (quaternion given unnormalised, x2) */
    assert_int_equal(parse(&t,
                           "t_ms,gaze_x,gaze_y,head_px,head_py,head_pz,head_qx,head_qy,head_qz,head_qw\n"
                           "0,0.5,0.5,0,1.6,0,0,0,0,2\n"
                           "100,0.5,0.5,1,1.6,-2,0,1.41421356,0,1.41421356\n",
                           err),
                     0);
    assert_true(t.has_head);
    assert_float_equal(t.s[0].head.quat[3], 1.0f, 1e-6);
    fv_trace_sample s;
    fv_trace_at(&t, 50.0, &s);
    assert_float_equal(s.head.pos[0], 0.5f, 1e-6);
    assert_float_equal(s.head.pos[2], -1.0f, 1e-6);
    /* halfway: 45 degrees about +Y */
    assert_float_equal(s.head.quat[1], sinf(0.3926991f), 1e-5);
    assert_float_equal(s.head.quat[3], cosf(0.3926991f), 1e-5);
    fv_trace_free(&t);
}

static void test_bad(void **st)
{
    (void)st;
    const char *bad[] = {
        "",                                                   /* empty */
        "# only a comment\n",                                 /* no header */
        "t_ms,gaze_x,gaze_y\n",                               /* no samples */
        "time,x,y\n0,0.5,0.5\n",                              /* wrong header */
        "t_ms,gaze_x,gaze_y\n0,0.5,0.5\n11,0.5\n",            /* truncated line */
        "t_ms,gaze_x,gaze_y\n0,0.5,0.5,7\n",                  /* extra field */
        "t_ms,gaze_x,gaze_y\n0,0.5,nan\n",                    /* not finite */
        "t_ms,gaze_x,gaze_y\n0,0.5,0.5x\n",                   /* junk after a number */
        "t_ms,gaze_x,gaze_y\n0,0.5,\n",                       /* empty field */
        "t_ms,gaze_x,gaze_y\n10,0.5,0.5\n5,0.5,0.5\n",        /* time going backwards */
        "t_ms,gaze_x,gaze_y\n0,40,0.5\n",                     /* absurd gaze */
        "t_ms,gaze_x,gaze_y,head_px\n0,0.5,0.5,1\n",          /* partial head columns */
        "t_ms,gaze_x,gaze_y,head_px,head_py,head_pz,head_qx,head_qy,head_qz,head_qw\n0,0.5,0.5,0,0,0,0,0,0,0\n",
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        fv_trace t;
        char err[256] = "";
        assert_int_equal(parse(&t, bad[i], err), -1);
        assert_true(strlen(err) > 5);
        assert_null(t.s);
    }
}

/* The messages users see: name and line number, the same text as before the loader moved. */
static void test_messages(void **st)
{
    (void)st;
    static const struct {
        const char *text, *want;
    } cases[] = {
        {"", "t.csv: no header line (t_ms,gaze_x,gaze_y)"},
        {"t_ms,gaze_x,gaze_y\n", "t.csv: no samples after the header"},
        {"# c\ntime,x,y\n0,0.5,0.5\n", "t.csv:2: header must start with t_ms,gaze_x,gaze_y"},
        {"t_ms,gaze_x,gaze_y,head_px\n", "t.csv:1: header has 4 columns; expected 3, or 10 with head pose"},
        {"t_ms,gaze_x,gaze_y,head_px,head_py,head_pz,head_qx,head_qy,head_qw,head_qz\n",
         "t.csv:1: column 9 is 'head_qw', expected 'head_qz'"},
        {"t_ms,gaze_x,gaze_y\n0,0.5,0.5\n11,0.5\n", "t.csv:3: 2 fields, expected 3 (truncated or malformed line)"},
        {"t_ms,gaze_x,gaze_y\n0,0.5,0.5,7\n", "t.csv:2: 4 fields, expected 3 (truncated or malformed line)"},
        {"t_ms,gaze_x,gaze_y\n0,0.5,abc\n", "t.csv:2: field 3 ('abc') is not a finite number"},
        {"t_ms,gaze_x,gaze_y\n0,0.5,\n", "t.csv:2: field 3 ('') is not a finite number"},
        {"t_ms,gaze_x,gaze_y\n10,0.5,0.5\n5,0.5,0.5\n", "t.csv:3: t_ms goes backwards (5 after 10)"},
        {"t_ms,gaze_x,gaze_y\n0,40,0.5\n", "t.csv:2: gaze (40, 0.5) is far outside the normalised image [0,1]"},
        {"t_ms,gaze_x,gaze_y,head_px,head_py,head_pz,head_qx,head_qy,head_qz,head_qw\n0,0.5,0.5,0,0,0,0,0,0,0\n",
         "t.csv:2: head quaternion has length 0, expected about 1"},
        /* finite as a double, infinite as the float it becomes (Embree aborted on such a ray origin) */
        {"t_ms,gaze_x,gaze_y,head_px,head_py,head_pz,head_qx,head_qy,head_qz,head_qw\n0,0.5,0.5,0,1e30,0,0,0,0,1\n",
         "t.csv:2: head position head_py = 1e+30 m out of range (|p| <= 1e+06 m)"},
        {"t_ms,gaze_x,gaze_y\n1e300,0.5,0.5\n", "t.csv:2: t_ms 1e+300 out of range (|t_ms| <= 1e+12)"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        fv_trace t;
        char err[256] = "";
        assert_int_equal(parse(&t, cases[i].text, err), -1);
        assert_string_equal(err, cases[i].want);
    }
    /* len bounds the text: a cut after the first sample's line parses, a NUL inside is refused */
    const char *text = "t_ms,gaze_x,gaze_y\n0,0.5,0.5\n10,0.6,0.5\n";
    fv_trace t;
    char err[256];
    assert_int_equal(fv_trace_parse(&t, text, 29, "cut.csv", err, sizeof err), 0);
    assert_int_equal(t.n, 1);
    fv_trace_free(&t);
    assert_int_equal(fv_trace_parse(&t, "t_ms,gaze_x,gaze_y\n0,0.5\0,0.5\n", 29, "nul.csv", err, sizeof err), -1);
    assert_string_equal(err, "nul.csv: not a text file (NUL byte)");
    assert_null(t.s);
}

/* platform/tracefile.c: reads the file and names it in the parser's messages. */
static void test_load(void **st)
{
    (void)st;
    fv_trace t;
    char err[512];
    assert_int_equal(fv_trace_load(&t, "/nonexistent/trace.csv", err, sizeof err), -1);
    assert_string_equal(err, "/nonexistent/trace.csv: No such file or directory");
    assert_null(t.s);
    assert_int_equal(fv_trace_load(&t, "/tmp", err, sizeof err), -1);
    assert_string_equal(err, "/tmp: is a directory");
    /* an endless device stops at its first NUL byte, after one 64 KiB step, not at the size limit */
    assert_int_equal(fv_trace_load(&t, "/dev/zero", err, sizeof err), -1);
    assert_string_equal(err, "/dev/zero: not a text file (NUL byte)");

    char path[] = "/tmp/fovea_trace_XXXXXX";
    fv_test_temp_file(path, "t_ms,gaze_x,gaze_y\n0,0.25,0.5\n10,0.75,0.5\n20,0.5\n");
    char want[256];
    snprintf(want, sizeof want, "%s:4: 2 fields, expected 3 (truncated or malformed line)", path);
    assert_int_equal(fv_trace_load(&t, path, err, sizeof err), -1);
    assert_string_equal(err, want);
    fv_test_write_file(path, "t_ms,gaze_x,gaze_y\n0,0.25,0.5\n10,0.75,0.5\n");
    assert_int_equal(fv_trace_load(&t, path, err, sizeof err), 0);
    unlink(path);
    assert_int_equal(t.n, 2);
    fv_trace_sample s;
    fv_trace_at(&t, 5.0, &s);
    assert_float_equal(s.gaze_x, 0.5f, 1e-6);
    fv_trace_free(&t);

    /* a regular file over the limit is refused by its size, before anything is read: a sparse
     * 2 GiB file (no disk blocks) and, through the reader itself, a 64-byte file with a 63-byte limit */
    char big[] = "/tmp/fovea_trace_big_XXXXXX";
    fv_test_temp_file(big, "t_ms,gaze_x,gaze_y\n");
    assert_int_equal(truncate(big, (off_t)2 << 30), 0);
    assert_int_equal(fv_trace_load(&t, big, err, sizeof err), -1);
    snprintf(want, sizeof want, "%s: 2147483648 bytes, larger than the 1024 MiB limit", big);
    assert_string_equal(err, want);
    fv_test_write_file(big, "0123456789012345678901234567890123456789012345678901234567890123");
    size_t len;
    assert_null(fv_read_file_alloc(big, 63, &len, err, sizeof err));
    char *buf = fv_read_file_alloc(big, 64, &len, err, sizeof err);
    assert_non_null(buf);
    assert_int_equal(len, 64);
    free(buf);
    unlink(big);
}

/* a trace played in a loop: 100..400 ms is a 300 ms span */
static void test_loop(void **state)
{
    (void)state;
    static const char text[] = "t_ms,gaze_x,gaze_y\n100,0.5,0.5\n250,0.4,0.5\n400,0.6,0.5\n";
    fv_trace tr;
    char err[256];
    assert_int_equal(fv_trace_parse(&tr, text, sizeof text - 1, "loop", err, sizeof err), 0);
    assert_float_equal(fv_trace_loop_ms(&tr, 0.0), 100.0, 1e-9);
    assert_float_equal(fv_trace_loop_ms(&tr, 299.0), 399.0, 1e-9);
    assert_float_equal(fv_trace_loop_ms(&tr, 300.0), 100.0, 1e-9);
    assert_float_equal(fv_trace_loop_ms(&tr, 1000.0), 200.0, 1e-9);
    fv_trace_free(&tr);
    static const char one[] = "t_ms,gaze_x,gaze_y\n42,0.5,0.5\n";
    assert_int_equal(fv_trace_parse(&tr, one, sizeof one - 1, "one", err, sizeof err), 0);
    assert_float_equal(fv_trace_loop_ms(&tr, 1234.0), 42.0, 0.0);
    fv_trace_free(&tr);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_good),
        cmocka_unit_test(test_loop),
        cmocka_unit_test(test_head),
        cmocka_unit_test(test_bad),
        cmocka_unit_test(test_messages),
        cmocka_unit_test(test_load),
    };
    return cmocka_run_group_tests_name("trace", tests, NULL, NULL);
}
