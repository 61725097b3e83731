/* fovea: the trace recorder (core/prof.c). */
#include <math.h>
#include <string.h>

#include "base/clock.h"
#include "testutil.h"

#include "pipeline.h"
#include "pool.h"
#include "bench.h"
#include "prof.h"
#include "testscene.h"

static void test_ring(void **state)
{
    (void)state;
    fv_prof *p = fv_prof_create(2, 5); /* rounded up to 8 */
    assert_non_null(p);
    assert_int_equal(fv_prof_slots(p), 2);
    for (int i = 0; i < 20; i++)
        fv_prof_span(p, 1, 1, "s", 100 * i, 100 * i + 50, i);
    fv_prof_instant(p, 0, FV_PROF_TRACK_MARKERS, "vsync", 7, -1);
    fv_prof_span(p, 2, 2, "ignored", 0, 1, 0); /* slot out of range */
    fv_prof_span(NULL, 0, 0, "ignored", 0, 1, 0);
    assert_int_equal(fv_prof_count(p, 1), 8);
    assert_int_equal(fv_prof_dropped(p, 1), 12);
    for (size_t i = 0; i < 8; i++) { /* the newest 8, oldest first */
        const fv_prof_event *e = fv_prof_event_at(p, 1, i);
        assert_non_null(e);
        assert_int_equal(e->arg, 12 + (int)i);
        assert_true(e->t1_ns - e->t0_ns == 50 && e->kind == 'X');
    }
    assert_null(fv_prof_event_at(p, 1, 8));
    assert_int_equal(fv_prof_count(p, 0), 1);
    assert_true(fv_prof_event_at(p, 0, 0)->kind == 'i');
    assert_int_equal(fv_prof_count(p, 2), 0);
    fv_prof_frame_markers(p, 41, 1000, 2000, 1); /* the headset's markers: latch, late, vsync */
    fv_prof_frame_markers(NULL, 41, 1000, 2000, 1);
    assert_int_equal(fv_prof_count(p, 0), 4);
    assert_string_equal(fv_prof_event_at(p, 0, 1)->name, "gaze latch");
    assert_string_equal(fv_prof_event_at(p, 0, 3)->name, "vsync");
    assert_true(fv_prof_event_at(p, 0, 3)->t0_ns == 2000 && fv_prof_event_at(p, 0, 3)->arg == 41);
    assert_int_equal(fv_prof_event_at(p, 0, 2)->track, FV_PROF_TRACK_MARKERS);
    fv_prof_destroy(p);
}

/* every worker records its tiles on its own slot while the others do (race-free under TSan) */
static void task(void *ctx, int i, int tid)
{
    fv_prof *p = ctx;
    const int64_t t = fv_time_ns();
    fv_prof_span(p, tid, tid, "item", t, fv_time_ns(), i);
}
static void test_pool_threads(void **state)
{
    (void)state;
    fv_pool *pool = fv_pool_create(3);
    assert_non_null(pool);
    fv_prof *p = fv_prof_create(3, 1 << 12);
    assert_non_null(p);
    fv_pool_set_prof(pool, p);
    for (int r = 0; r < 5; r++)
        fv_pool_run(pool, 200, task, p);
    fv_pool_set_prof(pool, NULL);
    size_t items = 0, jobs = 0;
    for (int s = 0; s < 3; s++)
        for (size_t i = 0; i < fv_prof_count(p, s); i++) {
            const fv_prof_event *e = fv_prof_event_at(p, s, i);
            assert_int_equal(e->track, s);
            items += !strcmp(e->name, "item");
            jobs += !strcmp(e->name, "pool job");
        }
    assert_int_equal(items, 1000);
    assert_true(jobs >= 5 && jobs <= 15); /* one per worker per job at most */
    fv_prof_destroy(p);
    fv_pool_destroy(pool);
}

static int hook_calls[FV_PROF_STAGES][2];
static void hook(void *ctx, int stage, int end)
{
    (void)ctx;
    hook_calls[stage][end]++;
}
/* a grey quad 2 m in front of the eye */
static fv_scene *quad_scene(void)
{
    fv_scene *scene = fv_scene_create();
    assert_non_null(scene);
    static const float grey[3] = {0.5f, 0.5f, 0.5f};
    fv_test_add_quad(scene, -2.0f, -2.0f, 2.0f, 2.0f, -2.0f, grey, -1);
    char cerr[256];
    assert_int_equal(fv_scene_commit(scene, cerr, sizeof cerr), 0);
    return scene;
}

/* a 64x48, 2-thread pipeline (depth of field: preset, model) recording into a new recorder
 * whose stage hook counts calls into hook_calls (cleared) */
static fv_pipeline *recorded_pipeline(const fv_scene *scene, fv_dof_preset preset, fv_dof_model model, fv_prof **prof)
{
    fv_pipeline_config cfg;
    fv_pipeline_config_default(&cfg);
    cfg.cam.width = 64, cfg.cam.height = 48, cfg.threads = 2;
    cfg.dof.preset = preset;
    cfg.dof.model = model;
    char err[256];
    fv_pipeline *pl = fv_pipeline_create(scene, &cfg, err, sizeof err);
    assert_non_null(pl);
    *prof = fv_prof_create(2, 1 << 14);
    assert_non_null(*prof);
    memset(hook_calls, 0, sizeof hook_calls);
    fv_prof_set_stage_hook(*prof, hook, NULL);
    fv_pipeline_set_prof(pl, *prof);
    return pl;
}

/* a pipeline with a recorder: stage spans on the stage tracks, tiles on the workers', the hook
 * at each stage boundary; without one nothing is recorded */
static void test_pipeline_spans(void **state)
{
    (void)state;
    fv_scene *scene = quad_scene();
    fv_prof *p;
    fv_pipeline *pl = recorded_pipeline(scene, FV_DOF_NONE, FV_DOF_MODEL_WEIER, &p);
    static const fv_pose origin = {{0, 0, 0}, {0, 0, 0, 1}};
    fv_frame_stats st;
    for (int f = 0; f < 3; f++)
        assert_int_equal(fv_pipeline_render(pl, FV_EYE_CENTER, &origin, 0.5f, 0.5f, &st), 0);
    fv_pipeline_set_prof(pl, NULL);
    fv_pipeline_render(pl, FV_EYE_CENTER, &origin, 0.5f, 0.5f, &st); /* not recorded */
    int frames = 0, casts = 0, tiles = 0;
    for (int s = 0; s < 2; s++)
        for (size_t i = 0; i < fv_prof_count(p, s); i++) {
            const fv_prof_event *e = fv_prof_event_at(p, s, i);
            frames += e->track == FV_PROF_TRACK_STAGE + FV_PROF_FRAME;
            casts += e->track == FV_PROF_TRACK_STAGE + FV_STAGE_TRACE;
            tiles += !strcmp(e->name, "tile");
            assert_true(e->t1_ns >= e->t0_ns);
        }
    assert_int_equal(frames, 3);
    assert_int_equal(casts, 3);
    assert_int_equal(tiles, 3 * 4 * 3); /* 64x48: 4x3 tiles of 16 */
    assert_int_equal(hook_calls[FV_STAGE_TRACE][0], 3);
    assert_int_equal(hook_calls[FV_STAGE_TRACE][1], 3);
    assert_int_equal(hook_calls[FV_STAGE_RECONSTRUCT][1], 3);
    assert_int_equal(hook_calls[FV_STAGE_COC][0], 0); /* no depth of field */
    fv_prof_destroy(p);
    fv_pipeline_destroy(pl);
    fv_scene_free(scene);
}

/* with depth of field the models time their stages through the recorder too: every stage of
 * the pipeline's enum that has a pass of its own gets a span on its track inside the frame's,
 * with the eye as its argument, and the hook is called in begin/end pairs */
static void test_pipeline_dof_spans(void **state)
{
    (void)state;
    fv_scene *scene = quad_scene();
    for (int model = 0; model < FV_DOF_MODEL_COUNT; model++) {
        fv_prof *p;
        fv_pipeline *pl = recorded_pipeline(scene, FV_DOF_MEDIUM, (fv_dof_model)model, &p);
        static const fv_pose origin = {{0, 0, 0}, {0, 0, 0, 1}};
        fv_frame_stats st;
        assert_int_equal(fv_pipeline_render(pl, FV_EYE_RIGHT, &origin, 0.5f, 0.5f, &st), 0);
        int64_t f0 = 0, f1 = 0;
        int spans[FV_PROF_STAGES] = {0};
        for (size_t i = 0; i < fv_prof_count(p, 0); i++) {
            const fv_prof_event *e = fv_prof_event_at(p, 0, i);
            if (e->track < FV_PROF_TRACK_STAGE || e->track >= FV_PROF_TRACK_STAGE + FV_PROF_STAGES)
                continue;
            const int sid = e->track - FV_PROF_TRACK_STAGE;
            spans[sid]++;
            assert_string_equal(e->name, fv_prof_stage_name(sid));
            assert_int_equal(e->arg, (int)FV_EYE_RIGHT);
            if (sid == FV_PROF_FRAME)
                f0 = e->t0_ns, f1 = e->t1_ns;
        }
        assert_int_equal(spans[FV_PROF_FRAME], 1);
        for (size_t i = 0; i < fv_prof_count(p, 0); i++) { /* every stage span inside the frame */
            const fv_prof_event *e = fv_prof_event_at(p, 0, i);
            if (e->track >= FV_PROF_TRACK_STAGE && e->track < FV_PROF_TRACK_STAGE + FV_STAGE_COUNT)
                assert_true(e->t0_ns >= f0 && e->t1_ns <= f1);
        }
        assert_int_equal(spans[FV_STAGE_TRACE], 1);
        assert_int_equal(spans[FV_STAGE_RECONSTRUCT], 1);
        assert_int_equal(spans[FV_STAGE_REPROJECT], 0); /* inside the tiles: worker tracks */
        assert_int_equal(spans[FV_STAGE_COC], 2);      /* the focus estimate, then the CoC pass */
        assert_int_equal(spans[FV_STAGE_DOF_FILTER], 1);
        /* a separate combine pass: hussain's; weier's runs inside its filter, the gathers have none */
        assert_int_equal(spans[FV_STAGE_COMBINE], model == FV_DOF_MODEL_HUSSAIN);
        for (int s = 0; s < FV_PROF_STAGES; s++) {
            assert_int_equal(hook_calls[s][0], hook_calls[s][1]);
            assert_int_equal(hook_calls[s][1], spans[s]);
        }
        assert_false(isnan(st.stage_ms[FV_STAGE_COC]));
        assert_false(isnan(st.stage_ms[FV_STAGE_DOF_FILTER]));
        fv_prof_destroy(p);
        fv_pipeline_destroy(pl);
    }
    fv_scene_free(scene);
}

static void test_stage_bytes(void **state)
{
    (void)state;
    double rd, wr;
    assert_int_equal(fv_bench_stage_bytes(FV_STAGE_TRACE, 1280, 1440, 0.7, &rd, &wr), -1);
    assert_int_equal(fv_bench_stage_bytes(FV_STAGE_COC, 1280, 1440, 0.7, &rd, &wr), 0);
    assert_true(rd == 16.0 * 1280 * 1440 && wr == 4.0 * 1280 * 1440);
    assert_int_equal(fv_bench_stage_bytes(FV_STAGE_REPROJECT, 1280, 1440, 0.0, &rd, &wr), 0);
    assert_true(rd == 0.0 && wr == 0.0); /* full sampling: no reprojection */
    double r0, w0, r1, w1;
    fv_bench_stage_bytes(FV_STAGE_RECONSTRUCT, 1280, 1440, 0.0, &r0, &w0);
    fv_bench_stage_bytes(FV_STAGE_RECONSTRUCT, 1280, 1440, 0.76, &r1, &w1);
    /* full: the weights of every level (4/3 of level 0's) and the small levels' pulls */
    assert_true(r0 > 4.0 * 1280 * 1440 && r0 < 4.0 * 1280 * 1440 * 1.4 && w0 < 0.01 * r0);
    assert_true(r1 > 2.0 * r0 && w1 > 0.76 * 16.0 * 1280 * 1440);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ring),
        cmocka_unit_test(test_pool_threads),
        cmocka_unit_test(test_pipeline_spans),
        cmocka_unit_test(test_pipeline_dof_spans),
        cmocka_unit_test(test_stage_bytes),
    };
    return cmocka_run_group_tests_name("prof", tests, NULL, NULL);
}
