/* fovea platform: eye sources. Y4M in every supported colour space gives back exactly the luma
 * written (so the chroma planes are skipped by the right amount), header parameters in any
 * order are tolerated, truncated / corrupt files give one-line errors naming the file and
 * frame; image lists with and without labels, comments, relative paths; the in-memory entries
 * give what the path ones give on the same bytes. */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

#include "eyesrc.h"

static char dir[64];

static void path_in(char *out, size_t len, const char *name)
{
    snprintf(out, len, "%s/%s", dir, name);
}

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/fovea_eyesrc_XXXXXX");
    return mkdtemp(dir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) == 0 ? 0 : -1;
}

/* w x h frames; luma of frame f, pixel i is (f * 31 + i * 7) & 255, chroma 0x80 */
static void write_y4m(const char *path, const char *header, int w, int h, int frames, size_t chroma)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(header, f);
    for (int k = 0; k < frames; k++) {
        fputs(k == 1 ? "FRAME Ixyz\n" : "FRAME\n", f); /* frame parameters are allowed */
        for (int i = 0; i < w * h; i++)
            fputc((k * 31 + i * 7) & 255, f);
        for (size_t i = 0; i < chroma; i++)
            fputc(0x80, f);
    }
    fclose(f);
}

static void test_y4m_colour_spaces(void **state)
{
    (void)state;
    const int w = 7, h = 5; /* odd: chroma planes are ceil(w/2) x ceil(h/2) */
    static const struct { const char *c; size_t chroma; } cs[] = {
        { "", 2 * 4 * 3 }, /* no C: 4:2:0 */
        { " C420jpeg", 2 * 4 * 3 }, { " C420paldv", 2 * 4 * 3 }, { " C420mpeg2", 2 * 4 * 3 },
        { " C420", 2 * 4 * 3 },       { " C422", 2 * 4 * 5 },     { " C444", 2 * 7 * 5 },
        { " Cmono", 0 },
    };
    for (size_t k = 0; k < sizeof cs / sizeof cs[0]; k++) {
        char path[128], hdr[128], err[256];
        path_in(path, sizeof path, "v.y4m");
        snprintf(hdr, sizeof hdr, "YUV4MPEG2 F30000:1001 A0:0 Ip W%d XCOLORRANGE=FULL H%d%s\n", w, h, cs[k].c);
        write_y4m(path, hdr, w, h, 3, cs[k].chroma);
        fv_eyesrc *s;
        if (fv_eyesrc_open_y4m(&s, path, err, sizeof err))
            fail_msg("%s: %s", cs[k].c, err);
        fv_eye_frame fr;
        for (int f = 0; f < 3; f++) {
            assert_int_equal(fv_eyesrc_next(s, &fr, err, sizeof err), 1);
            assert_int_equal(fr.w, w);
            assert_int_equal(fr.h, h);
            assert_int_equal(fr.index, f);
            for (int i = 0; i < w * h; i++)
                if (fr.luma[i] != ((f * 31 + i * 7) & 255))
                    fail_msg("%s frame %d pixel %d: %d", cs[k].c, f, i, fr.luma[i]);
        }
        assert_int_equal(fv_eyesrc_next(s, &fr, err, sizeof err), 0);
        assert_int_equal(fv_eyesrc_count(s), -1);
        fv_eyesrc_close(s);
    }
}

static void test_y4m_errors(void **state)
{
    (void)state;
    char path[128], err[256];
    path_in(path, sizeof path, "bad.y4m");
    fv_eyesrc *s;
    /* truncated in the second frame's chroma */
    write_y4m(path, "YUV4MPEG2 W4 H4 C420jpeg\n", 4, 4, 2, 8);
    /* 25-byte header, "FRAME\n" + 24 bytes, "FRAME Ixyz\n" + 24 bytes: cut 3 off the end */
    assert_int_equal(truncate(path, (off_t)(25 + 6 + 24 + 11 + 24 - 3)), 0);
    assert_int_equal(fv_eyesrc_open_y4m(&s, path, err, sizeof err), 0);
    fv_eye_frame fr;
    assert_int_equal(fv_eyesrc_next(s, &fr, err, sizeof err), 1);
    assert_int_equal(fv_eyesrc_next(s, &fr, err, sizeof err), -1);
    assert_non_null(strstr(err, "frame 1 is truncated (21 of 24 bytes)"));
    assert_non_null(strstr(err, path));
    assert_null(strchr(err, '\n'));
    fv_eyesrc_close(s);
    static const struct { const char *text, *want; } bad[] = {
        { "", "not a YUV4MPEG2 file" },
        { "YUV4MPEG W4 H4\n", "not a YUV4MPEG2 file" },
        { "YUV4MPEG2 W4 H4", "truncated or overlong" },
        { "YUV4MPEG2 W0 H4\n", "bad width" },
        { "YUV4MPEG2 W4 Hx\n", "bad height" },
        { "YUV4MPEG2 W4\n", "lacks W or H" },
        { "YUV4MPEG2 W4 H4 C420p10\n", "C420p10 is not supported" },
        { "YUV4MPEG2 W4 H4 C411\n", "C411 is not supported" },
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        FILE *f = fopen(path, "wb");
        fputs(bad[i].text, f);
        fclose(f);
        assert_int_equal(fv_eyesrc_open_y4m(&s, path, err, sizeof err), -1);
        if (!strstr(err, bad[i].want))
            fail_msg("header '%s': error '%s' lacks '%s'", bad[i].text, err, bad[i].want);
    }
    FILE *f = fopen(path, "wb");
    fputs("YUV4MPEG2 W2 H2 Cmono\nFRAME\nabcdFRAMX\nabcd", f);
    fclose(f);
    assert_int_equal(fv_eyesrc_open_y4m(&s, path, err, sizeof err), 0);
    assert_int_equal(fv_eyesrc_next(s, &fr, err, sizeof err), 1);
    assert_int_equal(fv_eyesrc_next(s, &fr, err, sizeof err), -1);
    assert_non_null(strstr(err, "frame 1: corrupt data (no FRAME marker)"));
    fv_eyesrc_close(s);
    path_in(path, sizeof path, "none.y4m");
    assert_int_equal(fv_eyesrc_open_y4m(&s, path, err, sizeof err), -1);
    assert_non_null(strstr(err, "No such file"));
}

static void test_image_list(void **state)
{
    (void)state;
    char path[128], img[128], err[256];
    /* a 3x2 PGM (stb reads PNM) */
    path_in(img, sizeof img, "a.pgm");
    FILE *f = fopen(img, "wb");
    fputs("P5 3 2 255\n", f);
    fwrite("\x01\x02\x03\x04\x05\x06", 1, 6, f);
    fclose(f);
    path_in(path, sizeof path, "list.txt");
    f = fopen(path, "w");
    fputs("# comment\n\na.pgm 1.5 0.25\n  a.pgm\t2 3  \na.pgm\n", f);
    fclose(f);
    fv_eyesrc *s;
    assert_int_equal(fv_eyesrc_open_list(&s, path, err, sizeof err), 0);
    assert_int_equal(fv_eyesrc_count(s), 3);
    assert_int_equal(fv_eyesrc_has_labels(s), 1);
    fv_eye_frame fr;
    assert_int_equal(fv_eyesrc_next(s, &fr, err, sizeof err), 1);
    assert_int_equal(fr.w, 3);
    assert_int_equal(fr.h, 2);
    assert_memory_equal(fr.luma, "\x01\x02\x03\x04\x05\x06", 6);
    assert_string_equal(fr.name, "a.pgm");
    assert_true(fr.has_label && fr.label_x == 1.5f && fr.label_y == 0.25f);
    assert_int_equal(fv_eyesrc_next(s, &fr, err, sizeof err), 1);
    assert_true(fr.has_label && fr.label_x == 2.0f && fr.label_y == 3.0f);
    assert_int_equal(fv_eyesrc_next(s, &fr, err, sizeof err), 1);
    assert_false(fr.has_label);
    assert_int_equal(fv_eyesrc_next(s, &fr, err, sizeof err), 0);
    fv_eyesrc_close(s);
    static const struct { const char *text, *want; } bad[] = {
        { "a.pgm 1\n", "list.txt:1: 2 fields, expected PATH [X Y]" },
        { "a.pgm\na.pgm 1 2 3\n", "list.txt:2: 4 fields" },
        { "a.pgm 1 nan\n", "list.txt:1: label '1 nan' is not two numbers" },
        { "# nothing\n", "no images listed" },
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        f = fopen(path, "w");
        fputs(bad[i].text, f);
        fclose(f);
        assert_int_equal(fv_eyesrc_open_list(&s, path, err, sizeof err), -1);
        if (!strstr(err, bad[i].want))
            fail_msg("list '%s': error '%s' lacks '%s'", bad[i].text, err, bad[i].want);
    }
    f = fopen(path, "w");
    fputs("a.pgm\nmissing.png 1 2\n", f);
    fclose(f);
    assert_int_equal(fv_eyesrc_open_list(&s, path, err, sizeof err), 0);
    assert_int_equal(fv_eyesrc_next(s, &fr, err, sizeof err), 1);
    assert_int_equal(fv_eyesrc_next(s, &fr, err, sizeof err), -1);
    assert_non_null(strstr(err, "list.txt:2: missing.png: No such file"));
    fv_eyesrc_close(s);
}

/* Reads the whole file written at path. */
static size_t slurp(const char *path, char *buf, size_t cap)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    const size_t n = fread(buf, 1, cap, f);
    fclose(f);
    assert_true(n < cap);
    return n;
}

/* The in-memory entries (fv_eyesrc_open_*_mem, what the fuzz harnesses call) against the path
 * ones on the same bytes: the same open result and message, then the same frames (index, size,
 * luma, label) or the same error, to the end. */
static void expect_same(int list, const char *path)
{
    static char bytes[1 << 16];
    const size_t n = slurp(path, bytes, sizeof bytes);
    fv_eyesrc *a = NULL, *b = NULL;
    char ea[256] = "", eb[256] = "";
    const int ra = list ? fv_eyesrc_open_list(&a, path, ea, sizeof ea) : fv_eyesrc_open_y4m(&a, path, ea, sizeof ea);
    const int rb = list ? fv_eyesrc_open_list_mem(&b, bytes, n, path, dir, eb, sizeof eb)
                        : fv_eyesrc_open_y4m_mem(&b, bytes, n, path, eb, sizeof eb);
    assert_int_equal(ra, rb);
    assert_string_equal(ea, eb);
    if (ra) {
        assert_null(a);
        assert_null(b);
        return;
    }
    assert_int_equal(fv_eyesrc_count(a), fv_eyesrc_count(b));
    assert_int_equal(fv_eyesrc_has_labels(a), fv_eyesrc_has_labels(b));
    for (int k = 0;; k++) {
        fv_eye_frame fa, fb;
        const int na = fv_eyesrc_next(a, &fa, ea, sizeof ea), nb = fv_eyesrc_next(b, &fb, eb, sizeof eb);
        assert_int_equal(na, nb);
        if (na < 0)
            assert_string_equal(ea, eb);
        if (na != 1)
            break;
        assert_int_equal(fa.index, fb.index);
        assert_int_equal(fa.w, fb.w);
        assert_int_equal(fa.h, fb.h);
        assert_memory_equal(fa.luma, fb.luma, (size_t)fa.w * fa.h);
        assert_int_equal(fa.has_label, fb.has_label);
        if (fa.has_label) /* unset on frames without one */
            assert_true(fa.label_x == fb.label_x && fa.label_y == fb.label_y);
        if (fa.name)
            assert_string_equal(fa.name, fb.name);
        assert_true(k < 100);
    }
    fv_eyesrc_close(a);
    fv_eyesrc_close(b);
}

static void test_in_memory_matches_file(void **state)
{
    (void)state;
    char path[128];
    path_in(path, sizeof path, "m.y4m");
    write_y4m(path, "YUV4MPEG2 W7 H5 C420jpeg\n", 7, 5, 3, 2 * 4 * 3);
    expect_same(0, path);
    write_y4m(path, "YUV4MPEG2 W7 H5 Cmono\n", 7, 5, 2, 0);
    expect_same(0, path);
    assert_int_equal(truncate(path, 22 + 6 + 35 + 11 + 20), 0); /* the second frame cut short */
    expect_same(0, path);
    static const char *const bad_y4m[] = {
        "", "YUV4MPEG W4 H4\n", "YUV4MPEG2 W4 H4", "YUV4MPEG2 W0 H4\n", "YUV4MPEG2 W4\n", "YUV4MPEG2 W4 H4 C411\n",
        "YUV4MPEG2 W2 H2 Cmono\nFRAME\nabcdFRAMX\nabcd", "YUV4MPEG2 W2 H2 Cmono\nFRAME\nab",
    };
    for (size_t i = 0; i < sizeof bad_y4m / sizeof bad_y4m[0]; i++) {
        FILE *f = fopen(path, "wb");
        fputs(bad_y4m[i], f);
        fclose(f);
        expect_same(0, path);
    }
    /* lists: entries resolve against the list's folder in both */
    char img[128];
    path_in(img, sizeof img, "b.pgm");
    FILE *f = fopen(img, "wb");
    fputs("P5 2 2 255\n", f);
    fwrite("\x09\x08\x07\x06", 1, 4, f);
    fclose(f);
    static const char *const lists[] = {
        "# c\n\nb.pgm 1.5 0.25\n  b.pgm\t2 3  \nb.pgm\n", "b.pgm\nmissing.png 1 2\nb.pgm\n", "b.pgm 1\n",
        "b.pgm 1 nan\n", "# nothing\n", "", "b.pgm", /* no final newline */
    };
    path_in(path, sizeof path, "m.txt");
    for (size_t i = 0; i < sizeof lists / sizeof lists[0]; i++) {
        f = fopen(path, "wb");
        fputs(lists[i], f);
        fclose(f);
        expect_same(1, path);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_y4m_colour_spaces),
        cmocka_unit_test(test_y4m_errors),
        cmocka_unit_test(test_image_list),
        cmocka_unit_test(test_in_memory_matches_file),
    };
    return cmocka_run_group_tests_name("eyesrc", tests, setup, teardown);
}
