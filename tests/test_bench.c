/* The bench's and the replay's bookkeeping (core/bench.c, core/quality.c) and their report lines
 * (platform/benchio.c), against hand-computed values: medians, stage means, counter deltas through
 * the stage hook, the roofline, sweep specs (good and bad, with their messages), the turning head,
 * the replay's quality measures, and the stats.csv / table lines. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"
#include "bench.h"
#include "benchio.h"
#include "quality.h"
#include "vsyncpred.h"

#define assert_near(a, b, eps) assert_true(fabs((double)(a) - (double)(b)) <= (eps))

static void test_median(void **state)
{
    (void)state;
    double odd[] = {3.0, 1.0, 2.0}, even[] = {4.0, 1.0, 3.0, 2.0}, one[] = {7.5};
    assert_near(fv_median(odd, 3), 2.0, 0);
    assert_near(fv_median(even, 4), 2.5, 0);
    assert_near(fv_median(one, 1), 7.5, 0);
    assert_true(isnan(fv_median(NULL, 0)));
    assert_near(even[0], 1.0, 0); /* sorted in place */
    assert_near(even[3], 4.0, 0);
}

static fv_frame_stats frame(double trace, double recon, double total, long samples)
{
    fv_frame_stats st;
    memset(&st, 0, sizeof st);
    for (int s = 0; s < FV_STAGE_COUNT; s++)
        st.stage_ms[s] = NAN; /* not built */
    st.stage_ms[FV_STAGE_TRACE] = trace;
    st.stage_ms[FV_STAGE_RECONSTRUCT] = recon;
    st.total_ms = total;
    st.samples = samples;
    return st;
}

static void test_stage_means(void **state)
{
    (void)state;
    fv_bench_run r;
    fv_bench_acc a;
    assert_int_equal(fv_bench_acc_init(&a, &r, "foveated", 4), 0);
    const fv_frame_stats f[5] = {frame(2, 1, 4, 1000), frame(4, 1, 9, 1000), frame(6, 2, 5, 1000),
                                 frame(4, 4, 6, 2000), frame(100, 100, 100, 5)}; /* the 5th is past `frames` */
    for (int i = 0; i < 5; i++)
        fv_bench_acc_add(&a, &f[i]);
    fv_bench_acc_finish(&a);
    assert_string_equal(r.mode, "foveated");
    assert_near(r.stage_mean[FV_STAGE_TRACE], 4.0, 1e-12);      /* (2 + 4 + 6 + 4) / 4 */
    assert_near(r.stage_mean[FV_STAGE_RECONSTRUCT], 2.0, 1e-12); /* (1 + 1 + 2 + 4) / 4 */
    assert_true(isnan(r.stage_mean[FV_STAGE_COC]));             /* not built: stays NAN */
    assert_near(r.total_mean, 6.0, 1e-12);                      /* (4 + 9 + 5 + 6) / 4 */
    assert_near(r.total_median, 5.5, 1e-12);                    /* 4 5 | 6 9 */
    assert_int_equal(r.samples, 2000);                          /* the last timed frame's */
    assert_near(r.mrays, 2000.0 / (4.0 * 1e3), 1e-12);          /* rays per microsecond = Mrays/s */
    assert_null(a.total);
}

/* The shading share: the mean of the timed frames' shading times over the stage's mean time;
 * NAN until a frame's shading is added. */
static void test_shade_share(void **state)
{
    (void)state;
    fv_bench_run r;
    fv_bench_acc a;
    assert_int_equal(fv_bench_acc_init(&a, &r, "full", 3), 0);
    const fv_frame_stats f = frame(10, 1, 20, 100);
    for (int i = 0; i < 3; i++)
        fv_bench_acc_add(&a, &f);
    fv_bench_acc_finish(&a);
    assert_true(isnan(r.shade_ms) && isnan(fv_bench_shade_share(&r)));
    assert_int_equal(fv_bench_acc_init(&a, &r, "full", 3), 0);
    static const double shade[4] = {2, 3, 7, 50}; /* the 4th is past `frames` */
    for (int i = 0; i < 4; i++) {
        fv_bench_acc_add(&a, &f);
        fv_bench_acc_add_shade(&a, shade[i]);
    }
    fv_bench_acc_finish(&a);
    assert_near(r.shade_ms, 4.0, 1e-12);                     /* (2 + 3 + 7) / 3 */
    assert_near(fv_bench_shade_share(&r), 0.4, 1e-12);       /* of the 10 ms stage */
}

static void test_stats_sum(void **state)
{
    (void)state;
    fv_frame_stats sum, l = frame(2, 1, 4, 100), r = frame(3, 0.5, 5, 50);
    l.shade_ms = 0.75, r.shade_ms = 1.5;
    fv_frame_stats_sum(&sum, &l, 1);
    fv_frame_stats_sum(&sum, &r, 0);
    assert_near(sum.shade_ms, 2.25, 0);
    assert_near(sum.stage_ms[FV_STAGE_TRACE], 5.0, 0);
    assert_near(sum.stage_ms[FV_STAGE_RECONSTRUCT], 1.5, 0);
    assert_true(isnan(sum.stage_ms[FV_STAGE_COMBINE]));
    assert_near(sum.total_ms, 9.0, 0);
    assert_int_equal(sum.samples, 150);
}

/* A fake counter: each read returns the next scripted totals, or fails at `fail_at`. */
typedef struct {
    uint64_t v[8][2];
    int next, fail_at;
} script;
static int script_read(void *ctx, uint64_t *v)
{
    script *s = ctx;
    if (s->next == s->fail_at)
        return -1;
    v[0] = s->v[s->next][0];
    v[1] = s->v[s->next][1];
    s->next++;
    return 0;
}

static void test_counter_hook(void **state)
{
    (void)state;
    script s = {.v = {{100, 10}, {150, 13}, {200, 20}, {260, 30}, {300, 31}, {400, 41}}, .fail_at = -1};
    fv_bench_ctrs c;
    fv_bench_ctrs_init(&c, script_read, &s, 2);
    c.on = 0; /* warm-up: read, not summed */
    fv_bench_ctrs_hook(&c, FV_STAGE_TRACE, 0);
    fv_bench_ctrs_hook(&c, FV_STAGE_TRACE, 1);
    c.on = 1;
    fv_bench_ctrs_hook(&c, FV_STAGE_TRACE, 0);   /* 200, 20 */
    fv_bench_ctrs_hook(&c, FV_STAGE_TRACE, 1);   /* 260, 30: +60, +10 */
    fv_bench_ctrs_hook(&c, FV_PROF_FRAME, 0);    /* 300, 31 */
    fv_bench_ctrs_hook(&c, FV_PROF_FRAME, 1);    /* 400, 41: +100, +10 */
    fv_bench_ctrs_hook(&c, FV_PROF_STAGES, 0);   /* out of range: no read */
    fv_bench_ctrs_hook(&c, -1, 1);
    assert_int_equal(s.next, 6);
    assert_false(c.failed);
    fv_bench_run r;
    memset(&r, 0, sizeof r);
    fv_bench_ctrs_mean(&c, 2, &r);
    assert_true(r.counters);
    assert_near(r.ctr[FV_STAGE_TRACE][0], 30.0, 0); /* 60 over 2 frames */
    assert_near(r.ctr[FV_STAGE_TRACE][1], 5.0, 0);
    assert_near(r.ctr[FV_PROF_FRAME][0], 50.0, 0);
    assert_near(r.ctr[FV_STAGE_COC][0], 0.0, 0);

    /* a failed read stops the accumulator for good */
    script f = {.v = {{1, 1}, {2, 2}, {3, 3}}, .fail_at = 1};
    fv_bench_ctrs_init(&c, script_read, &f, 2);
    c.on = 1;
    fv_bench_ctrs_hook(&c, FV_STAGE_COC, 0);
    fv_bench_ctrs_hook(&c, FV_STAGE_COC, 1);
    assert_true(c.failed);
    fv_bench_ctrs_hook(&c, FV_STAGE_COC, 0);
    assert_int_equal(f.next, 1);
}

static void test_roofline(void **state)
{
    (void)state;
    fv_bench_run r;
    memset(&r, 0, sizeof r);
    for (int s = 0; s < FV_STAGE_COUNT; s++)
        r.stage_mean[s] = NAN;
    r.samples = 1250; /* of 100 x 50: holes 0.75 */
    assert_near(fv_bench_holes(r.samples, 100, 50), 0.75, 1e-12);
    assert_near(fv_bench_holes(6000, 100, 50), 0.0, 0); /* more rays than pixels: no holes */
    fv_roof rf;
    /* CoC: level 0 colour + depth read (16 B a pixel), the CoC plane written (4 B): 100 kB in 0.1 ms */
    r.stage_mean[FV_STAGE_COC] = 0.1;
    assert_int_equal(fv_bench_roofline(&r, FV_STAGE_COC, 100, 50, 4.0, &rf), 0);
    assert_near(rf.read_bytes, 80000, 0);
    assert_near(rf.written_bytes, 20000, 0);
    assert_near(rf.gbps, 1.0, 1e-12);
    assert_near(rf.fraction, 0.25, 1e-12);
    assert_int_equal(fv_bench_roofline(&r, FV_STAGE_COC, 100, 50, 0.0, &rf), 0);
    assert_true(isnan(rf.fraction)); /* no bandwidth measured */
    assert_int_equal(fv_bench_roofline(&r, FV_STAGE_COMBINE, 100, 50, 4.0, &rf), -1); /* not built */
    r.stage_mean[FV_STAGE_TRACE] = 1.0;
    assert_int_equal(fv_bench_roofline(&r, FV_STAGE_TRACE, 100, 50, 4.0, &rf), -1); /* no byte model */
    r.stage_mean[FV_STAGE_DOF_FILTER] = 0.0;
    assert_int_equal(fv_bench_roofline(&r, FV_STAGE_DOF_FILTER, 100, 50, 4.0, &rf), -1); /* no time */
    r.samples = 5000; /* full sampling: no reprojection bytes */
    r.stage_mean[FV_STAGE_REPROJECT] = 0.5;
    assert_int_equal(fv_bench_roofline(&r, FV_STAGE_REPROJECT, 100, 50, 4.0, &rf), -1);
    assert_near(fv_bench_scaling(10.0, 1, 6.0, 2), 10.0 / 12.0, 1e-12);
}

static void test_sweep_parse(void **state)
{
    (void)state;
    static fv_sweep sw;
    char err[256];
    assert_int_equal(fv_sweep_parse("threads=2..4", &sw, err, sizeof err), 0);
    assert_int_equal(sw.param, FV_SWEEP_THREADS);
    assert_int_equal(sw.n, 3);
    assert_int_equal(sw.iv[0], 2);
    assert_int_equal(sw.iv[2], 4);
    assert_string_equal(sw.label[1], "3");
    assert_int_equal(fv_sweep_parse("size=640x720,960x1080", &sw, err, sizeof err), 0);
    assert_int_equal(sw.n, 2);
    assert_int_equal(sw.w[1], 960);
    assert_int_equal(sw.h[1], 1080);
    assert_string_equal(sw.label[0], "640x720");
    assert_int_equal(fv_sweep_parse("pmin=0.1,0.3", &sw, err, sizeof err), 0);
    assert_near(sw.fv[1], 0.3f, 1e-7);

    fv_pipeline_config base;
    fv_pipeline_config_default(&base);
    base.samp.r1_deg = 20.0f;
    fv_pipeline_config c = fv_sweep_config(&sw, 1, &base);
    assert_near(c.samp.p_min, 0.3f, 1e-7);
    assert_int_equal(c.cam.width, base.cam.width);
    assert_int_equal(fv_sweep_parse("r0=5,30", &sw, err, sizeof err), 0);
    assert_int_equal(fv_sweep_check(&sw, &base, err, sizeof err), -1);
    assert_string_equal(err, "--sweep r0: r0 30 must not exceed r1 20");
    assert_int_equal(fv_sweep_parse("r1=25,30", &sw, err, sizeof err), 0);
    assert_int_equal(fv_sweep_check(&sw, &base, err, sizeof err), 0);

    static fv_sweep two[2];
    assert_int_equal(fv_sweep_parse("threads=1,6", &two[0], err, sizeof err), 0);
    assert_int_equal(fv_sweep_parse("pmin=0.5", &two[1], err, sizeof err), 0);
    assert_int_equal(fv_sweep_max_threads(two, 2, 4), 6);
    assert_int_equal(fv_sweep_max_threads(two, 2, 8), 8);
    c = fv_sweep_config(&two[0], 1, &base);
    assert_int_equal(c.threads, 6);

    /* bad specs, with the messages the command line shows */
    const struct {
        const char *spec, *msg;
    } bad[] = {
        {"speed=1", "--sweep: 'speed=1' is not P=VALUES with P one of threads, size, pmin, r0, r1"},
        {"threads", "--sweep: 'threads' is not P=VALUES with P one of threads, size, pmin, r0, r1"},
        {"r0=", "--sweep: 'r0=' is not P=VALUES with P one of threads, size, pmin, r0, r1"},
        {"threads=0..2", "--sweep threads: 0 is out of range [1, 256]"},
        {"threads=4..40", "--sweep threads: 40 is out of range [4, 35]"},
        {"threads=2,x", "--sweep threads: 'x' is not a whole number"},
        {"size=64", "--sweep size: '64' is not WxH (for example 1280x1440)"},
        {"pmin=2", "--sweep pmin: 2 is out of range [0.001, 1]"},
        {"r1=,", "--sweep: 'r1=,' has no values"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        err[0] = 0;
        assert_int_equal(fv_sweep_parse(bad[i].spec, &sw, err, sizeof err), -1);
        assert_string_equal(err, bad[i].msg);
    }
    char many[256] = "pmin=";
    for (int i = 0; i < 33; i++)
        strcat(many, i ? ",0.5" : "0.5");
    assert_int_equal(fv_sweep_parse(many, &sw, err, sizeof err), -1);
    assert_string_equal(err, "--sweep: more than 32 values");
}

static void test_head_at(void **state)
{
    (void)state;
    fv_pose view = {{1.0f, 2.0f, 3.0f}, {0.0f, 0.0f, 0.0f, 1.0f}};
    fv_pose p = fv_bench_head_at(&view, 45.0f, 0);
    assert_near(p.quat[3], 1.0f, 1e-7);
    /* 45 deg/s for 180 frames at 90 Hz: 90 deg about y; the position stays */
    p = fv_bench_head_at(&view, 45.0f, 180);
    assert_near(p.quat[0], 0.0f, 1e-6);
    assert_near(p.quat[1], sqrt(0.5), 1e-6);
    assert_near(p.quat[2], 0.0f, 1e-6);
    assert_near(p.quat[3], sqrt(0.5), 1e-6);
    assert_near(p.pos[2], 3.0f, 0);
}

static void test_copy_gbps(void **state)
{
    (void)state;
    assert_true(fv_bench_copy_gbps(1) > 0.0);
    assert_true(fv_bench_copy_gbps(2) > 0.0);
}

static void test_mean_acc(void **state)
{
    (void)state;
    fv_mean_acc m = {0};
    assert_true(isnan(fv_mean_get(&m)));
    fv_mean_add(&m, INFINITY);
    assert_true(isinf(fv_mean_get(&m))); /* only identical images */
    fv_mean_add(&m, 1.0);
    fv_mean_add(&m, NAN);
    fv_mean_add(&m, 4.0);
    assert_near(fv_mean_get(&m), 2.5, 0); /* the infinity and the NAN left out */
    assert_near(fv_gaze_px(0.5f, 10), 5.5f, 0);
    assert_near(fv_gaze_px(0.26f, 10), 2.5f, 0);
}

/* Grey images: luma is the value, so the differences are exact. */
static void test_quality(void **state)
{
    (void)state;
    enum { W = 8, H = 4 };
    uint8_t a[2 * W * H * 3], full[W * H * 3];
    fv_quality q;
    assert_int_equal(fv_quality_init(&q, W, H, 1), 0);
    fv_quality_row row;
    /* frame 0: 100 everywhere (side by side with a 0 right eye, stride 2W), full sampling 110 */
    memset(a, 0, sizeof a);
    for (int y = 0; y < H; y++)
        memset(a + (size_t)y * 2 * W * 3, 100, W * 3);
    memset(full, 110, sizeof full);
    fv_quality_frame(&q, a, 2 * W * 3, full, 4.0f, 2.0f, 1.0f, 1.5f, &row);
    assert_true(isnan(row.dluma_periph)); /* no previous frame */
    assert_true(isnan(row.flicker_periph));
    const double p10 = 10.0 * log10(255.0 * 255.0 / 100.0);
    assert_near(row.psnr_all, p10, 1e-3);
    assert_near(row.psnr_fovea, p10, 1e-3);
    assert_near(row.psnr_periph, p10, 1e-3);
    /* frame 1: 104, full still 110: luma change 4, error -10 -> -6, flicker 4 */
    for (int y = 0; y < H; y++)
        memset(a + (size_t)y * 2 * W * 3, 104, W * 3);
    fv_quality_frame(&q, a, 2 * W * 3, full, 4.0f, 2.0f, 1.0f, 1.5f, &row);
    assert_near(row.dluma_periph, 4.0, 1e-3);
    assert_near(row.flicker_periph, 4.0, 1e-3);
    assert_near(row.psnr_all, 10.0 * log10(255.0 * 255.0 / 36.0), 1e-3);
    assert_int_equal(q.frames, 2);
    assert_near(fv_mean_get(&q.dluma), 4.0, 1e-3);
    assert_near(fv_mean_get(&q.psnr_all), 0.5 * (p10 + 10.0 * log10(255.0 * 255.0 / 36.0)), 1e-3);
    fv_quality_free(&q);

    /* without --vs-full: only the luma change */
    assert_int_equal(fv_quality_init(&q, W, H, 0), 0);
    fv_quality_frame(&q, a, 2 * W * 3, NULL, 4.0f, 2.0f, 1.0f, 1.5f, &row);
    assert_true(isnan(row.psnr_all));
    fv_quality_free(&q);
}

/* The stats.csv line and the table, as the replay and the bench print them. */
static void test_report_lines(void **state)
{
    (void)state;
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_non_null(f);
    fv_frame_stats st = frame(1.25, 0.5, 3.0, 42);
    fv_quality_row q = {NAN, INFINITY, 30.1234, NAN, 0.5};
    fv_stats_csv_row(f, 7, 77.7777, 0.25f, 0.75f, &st, &q, NAN);
    fclose(f);
    assert_string_equal(buf, "7,77.778,0.25000,0.75000,42,1.250,,0.500,,,,,3.000,,inf,30.123,,0.5000,\n");
    free(buf);

    f = open_memstream(&buf, &len);
    fv_stats_csv_header(f);
    fclose(f);
    assert_string_equal(buf, "frame,t_ms,gaze_x,gaze_y,samples,trace_ms,reproject_ms,reconstruct_ms,coc_ms,"
                             "dof_filter_ms,combine_ms,output_ms,total_ms,dluma_periph,psnr_all,psnr_fovea,psnr_periph,"
                             "flicker_periph,focus_m\n");
    free(buf);

    fv_bench_run r;
    memset(&r, 0, sizeof r);
    for (int s = 0; s < FV_STAGE_COUNT; s++)
        r.stage_mean[s] = NAN;
    r.mode = "full";
    r.stage_mean[FV_STAGE_TRACE] = 12.345;
    r.total_mean = 20.0;
    r.samples = 1000;
    r.mrays = 81.0;
    f = open_memstream(&buf, &len);
    fv_bench_print_table(f, &r, 1, 5);
    fclose(f);
    assert_non_null(strstr(buf, "\nfull             12.35             -               -        -        -        -"
                                "        -     20.00       1000      81.0\n"));
    assert_non_null(strstr(buf, "(ms per frame, means over 5 frames; one eye)\n"));
    free(buf);
}

/* --latency-csv: times in ms from t0; the gaze fields empty for a frame without a gaze sample */
static void test_latency_csv(void **state)
{
    (void)state;
    char dir[] = "/tmp/fv_latXXXXXX", path[64], line[2][256];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/lat.csv", dir);
    const int64_t t0 = 1000000000;
    fv_frame_record r[2];
    memset(r, 0, sizeof r);
    r[0].frame = 0, r[0].has_gaze = 1, r[0].gaze_t_ns = t0 + 1000000, r[0].ray_start_ns = t0 + 2000000;
    r[0].done_ns = t0 + 9500000, r[0].target_ns = t0 + 11111111, r[0].photon_ns = t0 + 11111111;
    r[0].late = 0, r[0].photon_edge = 1, r[0].budget_ns = 8000000, r[0].gaze_x = 0.25f, r[0].gaze_y = 0.5f;
    r[0].head_t_ns = t0 + 2000000, r[0].pose_err_deg = 0.125; /* motion-to-photon 9.111 ms */
    r[1] = r[0];
    r[1].frame = 1, r[1].has_gaze = 0, r[1].late = 1, r[1].head_t_ns = 0; /* no head sample: empty */
    char err[256];
    assert_int_equal(fv_latency_csv_write(path, r, 2, t0, err, sizeof err), 0);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(line[0], sizeof line[0], f));
    assert_string_equal(line[0], "frame,gaze_t_ms,ray_start_ms,done_ms,target_ms,photon_ms,gaze_to_photon_ms,"
                                 "render_ms,late,photon_edge,vsync_state,budget_ms,gaze_x,gaze_y,head_t_ms,"
                                 "motion_to_photon_ms,pose_err_deg\n");
    assert_non_null(fgets(line[0], sizeof line[0], f));
    assert_non_null(fgets(line[1], sizeof line[1], f));
    fclose(f);
    char want[2][256];
    snprintf(want[0], sizeof want[0], "0,1.000,2.000,9.500,11.111,11.111,10.111,7.500,0,1,%s,8.000,0.2500,0.5000,2.000,9.111,0.1250\n",
             fv_vsync_state_name(0));
    snprintf(want[1], sizeof want[1], "1,,2.000,9.500,11.111,11.111,,7.500,1,1,%s,8.000,,,,,\n", fv_vsync_state_name(0));
    assert_string_equal(line[0], want[0]);
    assert_string_equal(line[1], want[1]);
    remove(path);
    snprintf(path, sizeof path, "%s/no/such/dir/lat.csv", dir);
    assert_int_equal(fv_latency_csv_write(path, r, 2, t0, err, sizeof err), -1);
    assert_non_null(strstr(err, "lat.csv"));
    rmdir(dir);
}

/* --timewarp on's --latency-csv: one row per refresh; fields of a refresh without a frame empty */
static void test_refresh_csv(void **state)
{
    (void)state;
    char dir[] = "/tmp/fv_rfsXXXXXX", path[64], line[3][320];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/r.csv", dir);
    const int64_t t0 = 1000000000;
    fv_refresh_record r[2];
    memset(r, 0, sizeof r);
    r[0].refresh = 0, r[0].frame = -1, r[0].pose_err_deg = NAN;
    r[0].wake_ns = t0 + 1000000, r[0].done_ns = t0 + 1500000, r[0].target_ns = r[0].photon_ns = t0 + 11111111;
    r[0].margin_ns = 3000000;
    r[1] = r[0];
    r[1].refresh = 1, r[1].frame = 7, r[1].reused = 1, r[1].head_t_ns = t0 + 12000000, r[1].has_gaze = 1;
    r[1].gaze_t_ns = t0 + 2000000, r[1].frame_start_ns = t0 + 3000000, r[1].frame_done_ns = t0 + 9000000;
    r[1].wake_ns = t0 + 12500000, r[1].done_ns = t0 + 15000000, r[1].target_ns = r[1].photon_ns = t0 + 22222222;
    r[1].photon_edge = 1, r[1].disoccluded = 42, r[1].pose_err_deg = 0.25, r[1].gaze_x = 0.5f, r[1].gaze_y = 0.75f;
    char err[256];
    assert_int_equal(fv_refresh_csv_write(path, r, 2, t0, err, sizeof err), 0);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    for (int i = 0; i < 3; i++)
        assert_non_null(fgets(line[i], sizeof line[i], f));
    fclose(f);
    assert_string_equal(line[0], "refresh,frame,reused,late,head_t_ms,gaze_t_ms,frame_start_ms,frame_done_ms,"
                                 "compose_start_ms,compose_done_ms,target_ms,photon_ms,motion_to_photon_ms,"
                                 "gaze_to_photon_ms,photon_edge,vsync_state,margin_ms,disoccluded,pose_err_deg,"
                                 "gaze_x,gaze_y\n");
    char want[2][320];
    snprintf(want[0], sizeof want[0], "0,-1,0,0,,,,,1.000,1.500,11.111,11.111,,,0,%s,3.000,0,,,\n",
             fv_vsync_state_name(0));
    snprintf(want[1], sizeof want[1],
             "1,7,1,0,12.000,2.000,3.000,9.000,12.500,15.000,22.222,22.222,10.222,20.222,1,%s,3.000,42,0.2500,"
             "0.5000,0.7500\n",
             fv_vsync_state_name(0));
    assert_string_equal(line[1], want[0]);
    assert_string_equal(line[2], want[1]);
    remove(path);
    rmdir(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_median),       cmocka_unit_test(test_stage_means), cmocka_unit_test(test_stats_sum),
        cmocka_unit_test(test_shade_share),
        cmocka_unit_test(test_counter_hook), cmocka_unit_test(test_roofline),    cmocka_unit_test(test_sweep_parse),
        cmocka_unit_test(test_head_at),      cmocka_unit_test(test_copy_gbps),   cmocka_unit_test(test_mean_acc),
        cmocka_unit_test(test_quality),      cmocka_unit_test(test_report_lines), cmocka_unit_test(test_latency_csv),
        cmocka_unit_test(test_refresh_csv),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
