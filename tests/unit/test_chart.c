/* chart.c: runs become curves, the newest six kept; a long run thins to log-spaced points within
 * its fixed capacity; axes hold every point with ticks at 1, 2, 5 or powers of ten. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>

#include "chart.h"

/* A frame of run `restarts` at `seconds` with error `rmse`. */
static struct ao_frame_info frame(uint64_t restarts, enum ao_sampling sampling, double seconds, double rmse)
{
    return (struct ao_frame_info){.restarts = restarts, .sampling = sampling, .seconds = seconds, .rmse = rmse};
}

/* Adds `frames` frames of one run, 0.1 s apart, with the error falling as 1/sqrt(t). */
static void add_run(struct ao_chart *chart, uint64_t restarts, enum ao_sampling sampling, int frames)
{
    for (int i = 1; i <= frames; i++) {
        struct ao_frame_info f = frame(restarts, sampling, 0.1 * i, 0.05 / sqrt(0.1 * i));
        ao_chart_add(chart, &f);
    }
}

static void test_frames_without_error_or_time_are_ignored(void **state)
{
    (void)state;
    static struct ao_chart chart;
    const double bad[][2] = {{1, NAN}, {1, 0}, {1, -0.1}, {1, INFINITY}, {0, 0.1}, {-1, 0.1},
                             {NAN, 0.1}, {INFINITY, 0.1}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        struct ao_frame_info f = frame(0, AO_SAMPLING_COSINE, bad[i][0], bad[i][1]);
        ao_chart_add(&chart, &f);
    }
    /* The normals view's RMSE against an AO reference means nothing. */
    struct ao_frame_info normals = frame(0, AO_SAMPLING_COSINE, 1.0, 0.1);
    normals.output = AO_OUTPUT_NORMALS;
    ao_chart_add(&chart, &normals);
    assert_int_equal(chart.count, 0);
    struct ao_chart_axis x, y;
    assert_false(ao_chart_axes(&chart, &x, &y));
}

/* Each restart opens a curve with its sampling mode; points are log10 of seconds and RMSE. */
static void test_each_run_is_a_curve(void **state)
{
    (void)state;
    static struct ao_chart chart;
    add_run(&chart, 0, AO_SAMPLING_UNIFORM, 3);
    add_run(&chart, 1, AO_SAMPLING_COSINE, 4);
    assert_int_equal(chart.count, 2);
    assert_int_equal(chart.curves[0].sampling, AO_SAMPLING_UNIFORM);
    assert_int_equal(chart.curves[0].count, 3);
    assert_int_equal(chart.curves[1].sampling, AO_SAMPLING_COSINE);
    assert_int_equal(chart.curves[1].restarts, 1);
    assert_int_equal(chart.curves[1].count, 4);
    struct ao_chart_point p = chart.curves[1].points[3];
    assert_float_equal(p.x, log10(0.4), 1e-6);
    assert_float_equal(p.y, log10(0.05 / sqrt(0.4)), 1e-6);
}

/* A run that showed a single frame (a drag restarts at every step) gives way to the next run. */
static void test_one_frame_runs_are_replaced(void **state)
{
    (void)state;
    static struct ao_chart chart;
    add_run(&chart, 0, AO_SAMPLING_UNIFORM, 5);
    for (uint64_t r = 1; r <= 20; r++)
        add_run(&chart, r, AO_SAMPLING_HEMISPHERE, 1);
    add_run(&chart, 21, AO_SAMPLING_COSINE, 5);
    assert_int_equal(chart.count, 2);
    assert_int_equal(chart.curves[0].restarts, 0);
    assert_int_equal(chart.curves[1].restarts, 21);
}

/* Past AO_CHART_CURVES runs the oldest go, and the rest keep their points and order. */
static void test_newest_runs_are_kept(void **state)
{
    (void)state;
    static struct ao_chart chart;
    for (uint64_t r = 0; r < AO_CHART_CURVES + 3; r++)
        add_run(&chart, r, (enum ao_sampling)(r % 3), 2 + (int)r);
    assert_int_equal(chart.count, AO_CHART_CURVES);
    for (int k = 0; k < AO_CHART_CURVES; k++) {
        assert_int_equal(chart.curves[k].restarts, 3 + k);
        assert_int_equal(chart.curves[k].sampling, (3 + k) % 3);
        assert_int_equal(chart.curves[k].count, 5 + k);
    }
}

/* A run of 10^5 frames at 60 per second (28 minutes, 4.8 decades of time): the curve stays within
 * its capacity, starts at the first frame and ends at the newest, keeps its points at least its
 * gap apart, and spreads them evenly over log time. Keeping every other point instead would put
 * 90 % of them in the last decade. */
static void test_long_run_thins_to_log_spacing(void **state)
{
    (void)state;
    static struct ao_chart chart;
    int per_decade[8] = {0};
    for (int i = 1; i <= 100000; i++) {
        struct ao_frame_info f = frame(0, AO_SAMPLING_COSINE, i / 60.0, 0.1 / sqrt(i));
        ao_chart_add(&chart, &f);
        const struct ao_chart_curve *c = &chart.curves[0];
        assert_in_range(c->count, 1, AO_CHART_POINTS);
        assert_float_equal(c->points[c->count - 1].x, log10(i / 60.0), 1e-6);
    }
    const struct ao_chart_curve *c = &chart.curves[0];
    assert_int_equal(chart.count, 1);
    assert_float_equal(c->points[0].x, log10(1 / 60.0), 1e-6);
    for (int i = 1; i < c->count - 1; i++)
        assert_true(c->points[i].x - c->points[i - 1].x >= c->gap);
    for (int i = 0; i < c->count; i++)
        per_decade[(int)floorf(c->points[i].x) + 2]++;
    /* Decades 0.1-1 s, 1-10 s, 10-100 s and 100-1000 s are all fully covered by frames: each
     * holds between half and twice the mean of the four. */
    int sum = per_decade[1] + per_decade[2] + per_decade[3] + per_decade[4];
    for (int d = 1; d <= 4; d++)
        assert_in_range(per_decade[d] * 8, sum, 4 * sum);
    /* Thinning halves at most: more than a third of the capacity stays in use. */
    assert_true(c->count > AO_CHART_POINTS / 3);
    printf("%d points, gap %.4f decades, per decade from 0.01 s: %d %d %d %d %d %d\n", c->count,
           (double)c->gap, per_decade[0], per_decade[1], per_decade[2], per_decade[3], per_decade[4],
           per_decade[5]);
}

/* Checks an axis's ends and ticks against expected powers-of-ten values. */
static void check_axis(const struct ao_chart_axis *axis, const double *values, int count)
{
    assert_int_equal(axis->ticks, count);
    for (int k = 0; k < count; k++)
        assert_float_equal(axis->tick[k], log10(values[k]), 1e-4);
    assert_float_equal(axis->lo, axis->tick[0], 0);
    assert_float_equal(axis->hi, axis->tick[count - 1], 0);
}

static void test_axis_ticks(void **state)
{
    (void)state;
    struct ao_chart_axis a;
    /* Within two decades: 1, 2, 5; ends on the ticks around the values. */
    ao_chart_axis(log10f(0.06f), log10f(3.0f), &a);
    check_axis(&a, (const double[]){0.05, 0.1, 0.2, 0.5, 1, 2, 5}, 7);
    ao_chart_axis(log10f(0.0021f), log10f(0.013f), &a);
    check_axis(&a, (const double[]){0.002, 0.005, 0.01, 0.02}, 4);
    /* Values on ticks (through float rounding) are their own ends. */
    ao_chart_axis(log10f(0.1f), log10f(0.5f), &a);
    check_axis(&a, (const double[]){0.1, 0.2, 0.5}, 3);
    /* One value: one step wide. */
    ao_chart_axis(0.0f, 0.0f, &a);
    check_axis(&a, (const double[]){1, 2}, 2);
    ao_chart_axis(log10f(0.03f), log10f(0.03f), &a);
    check_axis(&a, (const double[]){0.02, 0.05}, 2);
    /* Wider: decades. */
    ao_chart_axis(log10f(0.0015f), log10f(150.0f), &a);
    check_axis(&a, (const double[]){0.001, 0.01, 0.1, 1, 10, 100, 1000}, 7);
    /* Far wider: every third decade, within AO_CHART_TICKS. */
    ao_chart_axis(-20.0f, 20.0f, &a);
    assert_int_equal(a.ticks, 15);
    assert_float_equal(a.lo, -21, 0);
    assert_float_equal(a.hi, 21, 0);
}

/* The axes hold the points of every kept curve, old runs included. */
static void test_axes_span_all_curves(void **state)
{
    (void)state;
    static struct ao_chart chart;
    struct ao_frame_info frames[] = {
        frame(0, AO_SAMPLING_UNIFORM, 0.02, 0.3), frame(0, AO_SAMPLING_UNIFORM, 4.0, 0.02),
        frame(1, AO_SAMPLING_COSINE, 0.03, 0.04), frame(1, AO_SAMPLING_COSINE, 1.0, 0.007),
    };
    for (size_t i = 0; i < sizeof frames / sizeof frames[0]; i++)
        ao_chart_add(&chart, &frames[i]);
    struct ao_chart_axis x, y;
    assert_true(ao_chart_axes(&chart, &x, &y));
    check_axis(&x, (const double[]){0.01, 0.1, 1, 10}, 4);   /* 1-2-5 would take 8 ticks */
    check_axis(&y, (const double[]){0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5}, 7);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frames_without_error_or_time_are_ignored),
        cmocka_unit_test(test_each_run_is_a_curve),
        cmocka_unit_test(test_one_frame_runs_are_replaced),
        cmocka_unit_test(test_newest_runs_are_kept),
        cmocka_unit_test(test_long_run_thins_to_log_spacing),
        cmocka_unit_test(test_axis_ticks),
        cmocka_unit_test(test_axes_span_all_curves),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
