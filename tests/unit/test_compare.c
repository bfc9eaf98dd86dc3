/* The live comparison (compare.c): equal render time by turns, restarts of both sides, pausing,
 * and the pure pieces: composing the layouts, the partner configuration, labels, the chart. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdatomic.h>
#include <string.h>
#include <time.h>

#include "compare.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

static const char SCENE[] = "camera eye 0 1.5 4 target 0 0.5 0 fov 40\n"
                            "quad corner -5 0 -5 edge1 0 0 10 edge2 10 0 0 albedo 0.6\n"
                            "sphere center 0 0.5 0 radius 0.5 albedo 0.9 0.5 0.2\n";

/* The split layout takes columns left of the divider from A, the rest from B, the divider clamped
 * to the image; side by side puts A's row, then B's. */
static void test_compose(void **state)
{
    (void)state;
    enum { W = 3, H = 2, N = 3 * W * H };
    float a[N], b[N], out[2 * N];
    for (int i = 0; i < N; i++)
        a[i] = (float)i, b[i] = (float)(100 + i);
    int splits[] = {-1, 0, 1, 3, 9};
    for (size_t s = 0; s < sizeof splits / sizeof splits[0]; s++) {
        ao_compare_compose(AO_COMPARE_SPLIT, splits[s], a, b, W, H, out);
        int column = splits[s] < 0 ? 0 : splits[s] > W ? W : splits[s];
        for (int i = 0; i < N; i++)
            assert_true(out[i] == (i / 3 % W < column ? a[i] : b[i]));
    }
    ao_compare_compose(AO_COMPARE_SIDE_BY_SIDE, 0, a, b, W, H, out);
    for (int y = 0; y < H; y++)
        for (int k = 0; k < 3 * W; k++) {
            assert_true(out[6 * W * y + k] == a[3 * W * y + k]);
            assert_true(out[6 * W * y + 3 * W + k] == b[3 * W * y + k]);
        }
    assert_int_equal(ao_compare_width(AO_COMPARE_SPLIT, 7), 7);
    assert_int_equal(ao_compare_width(AO_COMPARE_SIDE_BY_SIDE, 7), 14);
}

/* V's second configuration: cosine against uniform, anything else against cosine, the sampler
 * and AA kept; labels with and without a reference. */
static void test_partner_and_label(void **state)
{
    (void)state;
    struct ao_compare_side cosine = {AO_SAMPLING_COSINE, AO_SEQUENCE_RANDOM, false};
    struct ao_compare_side p = ao_compare_partner(cosine);
    assert_int_equal(p.sampling, AO_SAMPLING_UNIFORM);
    assert_int_equal(p.sequence, AO_SEQUENCE_RANDOM);
    assert_false(p.aa);
    struct ao_compare_side hemisphere = {AO_SAMPLING_HEMISPHERE, AO_SEQUENCE_SOBOL, true};
    assert_int_equal(ao_compare_partner(hemisphere).sampling, AO_SAMPLING_COSINE);
    assert_int_equal(ao_compare_partner(p).sampling, AO_SAMPLING_COSINE);

    char text[160];
    struct ao_frame_info info = {.spp = 42, .seconds = 1.23456, .rmse = NAN};
    ao_compare_label("A", &cosine, &info, "\n", text, sizeof text);
    assert_string_equal(text, "A: cosine+random+noaa\n42 spp  1.23 s");
    info.rmse = 0.012345;
    ao_compare_label("B", &hemisphere, &info, "  ", text, sizeof text);
    assert_string_equal(text, "B: hemisphere+sobol+aa  42 spp  1.23 s  RMSE 0.01235");
}

/* Sleeps a millisecond. */
static void nap(void)
{
    struct timespec ms = {0, 1000000};
    nanosleep(&ms, NULL);
}

/* What each side's on_pass saw; `inside` catches two calls at once. */
struct seen {
    atomic_int calls;
    atomic_int *inside;
    atomic_bool overlapped;
};

static void count_pass(const struct ao_frame_info *info, void *user)
{
    (void)info;
    struct seen *s = user;
    if (atomic_fetch_add(s->inside, 1) != 0)
        atomic_store(&s->overlapped, true);
    atomic_fetch_add(&s->calls, 1);
    atomic_fetch_sub(s->inside, 1);
}

/* The scene, tracer and comparison of one test. */
struct fixture {
    struct ao_scene scene;
    struct ao_tracer *tracer;
    struct ao_compare *compare;
    atomic_int inside;
    struct seen seen[2];
};

/* Starts A = uniform+random against B = cosine+sobol on SCENE at 48x32 with two threads, one
 * sample a pass, target spp, time limit and reference (or NULL) as given. */
static void start(struct fixture *f, uint32_t spp, double time_limit, const float *reference)
{
    assert_true(ao_scene_parse(&f->scene, SCENE, "compare.scene", NULL));
    assert_non_null(f->tracer = ao_tracer_create(&f->scene));
    atomic_init(&f->inside, 0);
    for (int k = 0; k < 2; k++) {
        atomic_init(&f->seen[k].calls, 0);
        atomic_init(&f->seen[k].overlapped, false);
        f->seen[k].inside = &f->inside;
    }
    struct ao_render_config config = {.scene = &f->scene, .tracer = f->tracer,
                                      .threads = 2, .seed = 3, .target_spp = spp, .time_limit = time_limit,
                                      .ao_distance = INFINITY, .reference = reference, .reference_width = 48,
                                      .reference_height = 32,
                                      .on_pass = count_pass};
    struct ao_settings settings = {.width = 48, .height = 32, .spppp = 1, .camera = f->scene.camera};
    struct ao_compare_side sides[2] = {{AO_SAMPLING_UNIFORM, AO_SEQUENCE_RANDOM, true},
                                       {AO_SAMPLING_COSINE, AO_SEQUENCE_SOBOL, true}};
    void *users[2] = {&f->seen[0], &f->seen[1]};
    assert_non_null(f->compare = ao_compare_create(&config, &settings, sides, users));
}

static void finish(struct fixture *f)
{
    ao_compare_destroy(f->compare);
    ao_tracer_destroy(f->tracer);
    ao_scene_finish(&f->scene);
    for (int k = 0; k < 2; k++)
        assert_false(atomic_load(&f->seen[k].overlapped));
}

/* Takes frames until both sides have one from a run after `restarts` (per side) with at least spp
 * samples, for at most 20 s. */
static void wait_for(struct fixture *f, const uint64_t restarts[2], uint32_t spp)
{
    for (int ms = 0; ms < 20000; ms++) {
        ao_compare_take_frames(f->compare);
        const struct ao_frame *a = ao_compare_frame(f->compare, 0), *b = ao_compare_frame(f->compare, 1);
        if (a && b && a->info.restarts > restarts[0] && b->info.restarts > restarts[1] && a->info.spp >= spp &&
            b->info.spp >= spp)
            return;
        nap();
    }
    fail_msg("the sides did not reach %u spp in a new run", spp);
}

/* Equal time: under a 1 s limit both sides finish, each within 5 % of the other's render seconds
 * (the turns keep them within one pass, well under a millisecond here, and the limit ends each at
 * its first pass past 1 s; 50 ms leave room for a pass preempted by other work on the machine),
 * having taken turns: never two passes reported at once. Then the comparison idles. */
static void test_equal_time(void **state)
{
    (void)state;
    struct fixture f;
    start(&f, 1u << 30, 1.0, NULL);
    for (int ms = 0; ms < 20000 && ao_compare_running(f.compare); ms++)
        nap();
    assert_false(ao_compare_running(f.compare));
    ao_compare_take_frames(f.compare);
    const struct ao_frame *a = ao_compare_frame(f.compare, 0), *b = ao_compare_frame(f.compare, 1);
    assert_non_null(a);
    assert_non_null(b);
    print_message("A %u spp %.4f s, B %u spp %.4f s\n", a->info.spp, a->info.seconds, b->info.spp, b->info.seconds);
    /* One side ends at its first pass past 1 s; the other there too, or at its pass end nearest
     * the first's seconds when it was behind. */
    assert_true(a->info.done || b->info.done);
    assert_true(fmax(a->info.seconds, b->info.seconds) >= 1.0);
    assert_true(fabs(a->info.seconds - b->info.seconds) <= 0.05 * fmax(a->info.seconds, b->info.seconds));
    assert_int_equal(a->info.sampling, AO_SAMPLING_UNIFORM);
    assert_int_equal(b->info.sampling, AO_SAMPLING_COSINE);
    assert_true(atomic_load(&f.seen[0].calls) > 1 && atomic_load(&f.seen[1].calls) > 1);

    /* Finished, a camera move starts both sides over, and they finish again, as fairly; so does a
     * restart. */
    for (int again = 0; again < 2; again++) {
        uint64_t runs[2] = {a->info.restarts, b->info.restarts};
        if (again) {
            ao_compare_restart(f.compare);
        } else {
            struct ao_settings s;
            ao_compare_get_settings(f.compare, &s);
            ao_camera_orbit(&s.camera, 0.2f, 0.0f);
            ao_compare_set_settings(f.compare, &s);
        }
        assert_true(ao_compare_running(f.compare));
        wait_for(&f, runs, 1);
        for (int ms = 0; ms < 20000 && ao_compare_running(f.compare); ms++)
            nap();
        ao_compare_take_frames(f.compare);
        a = ao_compare_frame(f.compare, 0);
        b = ao_compare_frame(f.compare, 1);
        assert_true(a->info.restarts > runs[0] && b->info.restarts > runs[1]);
        assert_true(!ao_compare_running(f.compare) && (a->info.done || b->info.done));
        assert_true(fabs(a->info.seconds - b->info.seconds) <= 0.05 * fmax(a->info.seconds, b->info.seconds));
    }
    finish(&f);
}

/* A camera move and A's sampling each restart both sides; samples per pass restart neither; the
 * user's pause stops both, and the settings read back as set (A's sampling, the user's pause). */
static void test_restarts_and_pause(void **state)
{
    (void)state;
    struct fixture f;
    start(&f, 1u << 30, 0.0, NULL);
    /* The first run is run 0 on both sides. */
    uint64_t before[2];
    for (int ms = 0; ms < 20000; ms++) {
        ao_compare_take_frames(f.compare);
        const struct ao_frame *a = ao_compare_frame(f.compare, 0), *b = ao_compare_frame(f.compare, 1);
        if (a && b && a->info.spp >= 8 && b->info.spp >= 8)
            break;
        nap();
    }
    before[0] = ao_compare_frame(f.compare, 0)->info.restarts;
    before[1] = ao_compare_frame(f.compare, 1)->info.restarts;
    assert_true(before[0] == 0 && before[1] == 0);

    struct ao_settings s;
    ao_compare_get_settings(f.compare, &s);
    assert_int_equal(s.sampling, AO_SAMPLING_UNIFORM);
    ao_camera_orbit(&s.camera, 0.3f, 0.0f);
    ao_compare_set_settings(f.compare, &s);
    wait_for(&f, before, 4);

    /* More samples a pass: no restart, the runs go on. */
    for (int k = 0; k < 2; k++)
        before[k] = ao_compare_frame(f.compare, k)->info.restarts;
    s.spppp = 2;
    ao_compare_set_settings(f.compare, &s);
    uint32_t spp = ao_compare_frame(f.compare, 0)->info.spp;
    for (int ms = 0; ms < 20000 && ao_compare_frame(f.compare, 0)->info.spp < spp + 16; ms++) {
        ao_compare_take_frames(f.compare);
        nap();
    }
    for (int k = 0; k < 2; k++)
        assert_true(ao_compare_frame(f.compare, k)->info.restarts == before[k]);

    /* A's sampling: both restart, B in its own configuration. */
    s.sampling = AO_SAMPLING_HEMISPHERE;
    ao_compare_set_settings(f.compare, &s);
    uint64_t last[2] = {before[0], before[1]};
    wait_for(&f, last, 4);
    assert_int_equal(ao_compare_frame(f.compare, 0)->info.sampling, AO_SAMPLING_HEMISPHERE);
    assert_int_equal(ao_compare_frame(f.compare, 1)->info.sampling, AO_SAMPLING_COSINE);
    char labels[2][AO_COMPARE_LABEL];
    ao_compare_labels(f.compare, " ", labels);
    assert_non_null(strstr(labels[0], "A: hemisphere+random+aa "));
    assert_non_null(strstr(labels[1], "B: cosine+sobol+aa "));

    /* Paused: nothing runs, no frame comes; the settings say paused. */
    s.paused = true;
    ao_compare_set_settings(f.compare, &s);
    assert_false(ao_compare_running(f.compare));
    struct timespec settle = {0, 100000000};
    nanosleep(&settle, NULL);   /* a pass in flight ends */
    ao_compare_take_frames(f.compare);
    assert_false(ao_compare_take_frames(f.compare));
    nanosleep(&settle, NULL);
    assert_false(ao_compare_take_frames(f.compare));
    ao_compare_get_settings(f.compare, &s);
    assert_true(s.paused);
    finish(&f);
}

/* The merged chart holds each side's curves, A's first: one each, then after a restart two each,
 * each in its side's sampling mode. */
static void test_chart(void **state)
{
    (void)state;
    static float black[3 * 48 * 32];
    struct fixture f;
    start(&f, 1u << 30, 0.0, black);
    struct ao_chart chart;
    ao_compare_chart(f.compare, &chart);
    assert_int_equal(chart.count, 0);
    for (int ms = 0; ms < 20000; ms++) {
        ao_compare_take_frames(f.compare);
        ao_compare_chart(f.compare, &chart);
        if (chart.count == 2 && chart.curves[0].count >= 2 && chart.curves[1].count >= 2)
            break;
        nap();
    }
    assert_int_equal(chart.count, 2);
    assert_int_equal(chart.curves[0].sampling, AO_SAMPLING_UNIFORM);
    assert_int_equal(chart.curves[1].sampling, AO_SAMPLING_COSINE);
    uint64_t runs[2] = {0, 0};
    ao_compare_restart(f.compare);
    for (int ms = 0; ms < 20000; ms++) {
        ao_compare_take_frames(f.compare);
        const struct ao_frame *a = ao_compare_frame(f.compare, 0), *b = ao_compare_frame(f.compare, 1);
        ao_compare_chart(f.compare, &chart);
        if (a->info.restarts > runs[0] && b->info.restarts > runs[1] && chart.count == 4 &&
            chart.curves[1].count >= 2 && chart.curves[3].count >= 2)
            break;
        nap();
    }
    assert_int_equal(chart.count, 4);
    int modes[4] = {AO_SAMPLING_UNIFORM, AO_SAMPLING_UNIFORM, AO_SAMPLING_COSINE, AO_SAMPLING_COSINE};
    for (int k = 0; k < 4; k++)
        assert_int_equal(chart.curves[k].sampling, modes[k]);
    finish(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_compose),
        cmocka_unit_test(test_partner_and_label),
        cmocka_unit_test(test_equal_time),
        cmocka_unit_test(test_restarts_and_pause),
        cmocka_unit_test(test_chart),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
