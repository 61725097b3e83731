/* Vsync sources: the timer ticks on its grid with absolute sleeps and queues like the kernel,
 * replay files are parsed and played back, GPIO and spec errors name the failing call. */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "base/clock.h"
#include "testutil.h"
#include "vsync.h"

static void test_timer(void **st)
{
    (void)st;
    fv_vsync *v;
    char err[256];
    assert_int_equal(fv_vsync_open(&v, "timer:100", err, sizeof err), 0);
    assert_string_equal(fv_vsync_kind(v), "timer");
    assert_int_equal(fv_vsync_nominal_period_ns(v), 10000000);
    int64_t t[6];
    for (int i = 0; i < 6; i++) {
        assert_int_equal(fv_vsync_wait(v, 100000000, &t[i], err, sizeof err), 1);
        assert_true(fv_time_ns() >= t[i]); /* never reported before it happened */
    }
    for (int i = 1; i < 6; i++)
        assert_int_equal(t[i] - t[i - 1], 10000000); /* exact grid, whatever the wake-up jitter */
    int64_t x;
    /* read late: the ticks meanwhile are still there, in order (up to 16) */
    fv_clock_sleep_until_ns(t[5] + 5 * 10000000 + 2000000);
    for (int i = 1; i <= 5; i++) {
        assert_int_equal(fv_vsync_wait(v, 0, &x, err, sizeof err), 1);
        assert_int_equal(x, t[5] + i * 10000000);
    }
    fv_vsync_close(v);
    /* a timeout before the next tick: 0, after about the timeout */
    assert_int_equal(fv_vsync_open(&v, "timer:1", err, sizeof err), 0);
    const int64_t a = fv_time_ns();
    assert_int_equal(fv_vsync_wait(v, 0, &x, err, sizeof err), 0);
    assert_int_equal(fv_vsync_wait(v, 20000000, &x, err, sizeof err), 0);
    assert_true(fv_time_ns() - a >= 20000000);
    fv_vsync_close(v);
}

static void test_replay(void **st)
{
    (void)st;
    char path[] = "/tmp/fovea_vsync_XXXXXX";
    fv_test_temp_file(path, "# recorded edges\n7000000000\n7003000000\n\n7006000000\n");
    fv_vsync *v;
    char err[256];
    char spec[64];
    snprintf(spec, sizeof spec, "replay:%s", path);
    const int64_t t0 = fv_time_ns();
    assert_int_equal(fv_vsync_open(&v, spec, err, sizeof err), 0);
    int64_t t[3];
    for (int i = 0; i < 3; i++)
        assert_int_equal(fv_vsync_wait(v, 100000000, &t[i], err, sizeof err), 1);
    assert_true(t[0] >= t0);
    assert_int_equal(t[1] - t[0], 3000000);
    assert_int_equal(t[2] - t[0], 6000000);
    /* after the recording: silent */
    assert_int_equal(fv_vsync_wait(v, 10000000, &t[0], err, sizeof err), 0);
    fv_vsync_close(v);

    fv_test_write_file(path, "100\n50\n");
    assert_int_equal(fv_vsync_open(&v, spec, err, sizeof err), -1);
    assert_non_null(strstr(err, ":2: times go backwards"));
    fv_test_write_file(path, "100\n1.5e3\n");
    assert_int_equal(fv_vsync_open(&v, spec, err, sizeof err), -1);
    assert_non_null(strstr(err, ":2: not an integer time in ns"));
    unlink(path);
}

static void test_errors(void **st)
{
    (void)st;
    fv_vsync *v;
    char err[256];
    static const struct {
        const char *spec, *why;
    } bad[] = {
        {"gpio:nochip:3", "gpiod_chip_open_lookup(nochip)"},
        {"gpio::3", "want gpio:CHIP:LINE"},
        {"gpio:chip0", "want gpio:CHIP:LINE"},
        {"gpio:chip0:-1", "LINE must be"},
        {"gpio:chip0:2:up", "LINE must be"},
        {"timer:abc", "HZ must be"},
        {"timer:5000", "HZ must be"},
        {"replay:/nonexistent/e.txt", "No such file"},
        {"vblank", "want gpio:CHIP:LINE, timer:HZ or replay:FILE"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        err[0] = 0;
        assert_int_equal(fv_vsync_open(&v, bad[i].spec, err, sizeof err), -1);
        /* a build without libgpiod (the cross leg) says so instead */
        if (!strstr(err, bad[i].why) && !strstr(err, "built without libgpiod"))
            fail_msg("%s: got '%s', want '%s'", bad[i].spec, err, bad[i].why);
    }
    fv_vsync_gpio *g;
    assert_int_equal(fv_vsync_gpio_open(&g, "/nonexistent/gpiochip7", 0, 0, err, sizeof err), -1);
    assert_true(strstr(err, "gpiod_chip_open_lookup(/nonexistent/gpiochip7)") || strstr(err, "built without libgpiod"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_timer),
        cmocka_unit_test(test_replay),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
