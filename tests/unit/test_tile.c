/* tile.c: a tile's rectangle, its auto-pass schedule, its error estimate and adaptive sampling's rule. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "rng.h"
#include "tile.h"
#include "unit_main.h"

static void rect_clips_to_the_image(void **state)
{
    (void)state;
    struct ao_tile r = ao_tile_rect(40, 20, 2); /* 3 tiles a row: the third of the first row */
    assert_int_equal(r.x0, 32);
    assert_int_equal(r.x1, 40);
    assert_int_equal(r.y0, 0);
    assert_int_equal(r.y1, 16);
    r = ao_tile_rect(40, 20, 4);
    assert_int_equal(r.x0, 16);
    assert_int_equal(r.x1, 32);
    assert_int_equal(r.y0, 16);
    assert_int_equal(r.y1, 20);
}

/* One pass of tile 0 of a 16x16 accumulation, each sample worth `value` in every channel; returns
 * the samples a pixel it took. */
static uint32_t constant_pass(struct ao_tile_state *ts, struct ao_accum *a, const struct ao_tile_pass *p, float value)
{
    struct ao_tile_work w = ao_tile_work_of(ts, p);
    uint32_t samples = (uint32_t)(w.rounds * w.count);
    struct ao_vec3 sums[AO_TILE * AO_TILE];
    for (int k = 0; k < AO_TILE * AO_TILE; k++)
        sums[k] = (struct ao_vec3){value * samples, value * samples, value * samples};
    ao_tile_add(ts, a, AO_TILE, ao_tile_rect(AO_TILE, AO_TILE, 0), &w, sums);
    return samples;
}

/* Auto passes: per_ray in each half, then doubling what each half has given, capped by the pass's
 * samples and the target; with Sobol numbers each pass an aligned block of its half's sequence. */
static void auto_passes_double(void **state)
{
    (void)state;
    struct ao_accum a;
    assert_true(ao_accum_init(&a, AO_TILE, AO_TILE));
    struct ao_tile_state ts;
    memset(&ts, 0, sizeof ts);
    struct ao_tile_pass p = {.target_spp = 1000, .samples = 64, .per_ray = 8, .sobol = true};
    const uint32_t expected[] = {8, 8, 8, 8, 16, 16, 32, 32, 64, 64, 64};
    for (size_t k = 0; k < sizeof expected / sizeof *expected; k++) {
        struct ao_tile_work w = ao_tile_work_of(&ts, &p);
        assert_int_equal(w.half, (int)(k & 1));
        assert_int_equal(w.count, 8); /* whole rounds of per_ray on one eye ray */
        assert_int_equal(w.first_sample % (uint64_t)(w.rounds * w.count), 0);
        assert_int_equal(w.first_sample, ts.spp[k & 1]);
        assert_int_equal(w.first_ray, ts.rays[k & 1]);
        assert_int_equal(constant_pass(&ts, &a, &p, 0.5f), expected[k]);
    }
    /* A pass of a large image (2 samples a pixel, as at 1920x1080) still gives each tile a whole
     * eye ray's samples: 8 a pass, never more. */
    memset(&ts, 0, sizeof ts);
    p.samples = 2;
    for (int k = 0; k < 8; k++) {
        struct ao_tile_work w = ao_tile_work_of(&ts, &p);
        assert_int_equal(w.rounds, 1);
        assert_int_equal(constant_pass(&ts, &a, &p, 0.5f), 8);
    }
    p.samples = 64;
    /* A target of 20: 8, 8, then the 4 left. */
    memset(&ts, 0, sizeof ts);
    p.target_spp = 20;
    uint32_t total = 0;
    for (int k = 0; k < 3; k++)
        total += constant_pass(&ts, &a, &p, 0.5f);
    assert_int_equal(total, 20);
    assert_int_equal(ao_tile_spp(&ts), 20);
    /* A tile whose every sample is the same has no error, and the mean of its pixels. */
    assert_true(ts.variance == 0.0);
    assert_true(fabs(ts.mean - 0.5 * AO_TILE * AO_TILE) < 1e-9);
    ao_accum_finish(&a);
}

/* The error estimate is unbiased: pixels whose samples are 0 or 1 with probability 1/2 (in every
 * channel) have a per-sample variance of 1/4, so after n samples a pixel's average has variance
 * 1/(4n), and a tile's sum of estimates 256/(4n). Each pixel's estimate is (A - B)^2 scaled, A and B
 * its halves' means, a scaled chi-square of about one degree of freedom: its relative standard
 * deviation is at most sqrt(2) (the binomial's kurtosis is below the normal's). Over TRIALS tiles
 * of 256 pixels the mean of the estimates has relative deviation sqrt(2 / (256 TRIALS)) = 1.6 % for
 * 32 trials; the bound is 5 of those, 7.8 %. Fixed seed. */
static void error_estimate_is_unbiased(void **state)
{
    (void)state;
    enum { TRIALS = 32, PASSES = 8 };
    struct ao_accum a;
    assert_true(ao_accum_init(&a, AO_TILE, AO_TILE));
    struct ao_tile_pass p = {.target_spp = 1000, .samples = 4, .per_ray = 0, .sobol = false};
    double estimated = 0.0;
    uint32_t n = 0;
    for (int trial = 0; trial < TRIALS; trial++) {
        struct ao_tile_state ts;
        memset(&ts, 0, sizeof ts);
        for (int pass = 0; pass < PASSES; pass++) {
            struct ao_tile_work w = ao_tile_work_of(&ts, &p);
            struct ao_vec3 sums[AO_TILE * AO_TILE];
            for (int k = 0; k < AO_TILE * AO_TILE; k++) {
                uint64_t key = ao_rng_key(7, (uint64_t)(trial * AO_TILE * AO_TILE + k), (uint64_t)pass);
                float ones = 0.0f;
                for (int s = 0; s < w.count; s++) {
                    float u1, u2;
                    ao_rng_pair(key, (uint64_t)s, &u1, &u2);
                    ones += u1 < 0.5f ? 1.0f : 0.0f;
                }
                sums[k] = (struct ao_vec3){ones, ones, ones};
            }
            ao_tile_add(&ts, &a, AO_TILE, ao_tile_rect(AO_TILE, AO_TILE, 0), &w, sums);
        }
        estimated += ts.variance;
        n = ao_tile_spp(&ts);
    }
    assert_int_equal(n, PASSES * 4);
    double expected = TRIALS * AO_TILE * AO_TILE / (4.0 * n);
    assert_true(fabs(estimated / expected - 1.0) < 0.078);
    ao_accum_finish(&a);
}

/* Short of the target and unsettled: always; settled: by the gain against the fastest tile's, or
 * when the busiest tile has RECHECK (8) times its samples; at the target: never. */
static void adaptive_rule(void **state)
{
    (void)state;
    struct ao_tile_state ts = {.passes = 4, .spp = {8, 8}, .variance = 256.0 * 16.0}; /* gain 1 */
    assert_true(ao_tile_settled(&ts));
    assert_true(ao_tile_gain(&ts, 256) == 1.0);
    assert_true(ao_tile_wanted(&ts, 256, 100, true, 16, 4.0));   /* a quarter of the fastest */
    assert_false(ao_tile_wanted(&ts, 256, 100, true, 16, 4.01));
    assert_true(ao_tile_wanted(&ts, 256, 100, false, 16, 4.01)); /* adaptive sampling off */
    assert_false(ao_tile_wanted(&ts, 256, 16, false, 16, 0.0));  /* at the target */
    ts.variance = 0.0;
    assert_false(ao_tile_wanted(&ts, 256, 100, true, 128, 1.0));
    assert_true(ao_tile_wanted(&ts, 256, 100, true, 129, 1.0));  /* rechecked */
    ts.passes = 3;
    assert_false(ao_tile_settled(&ts));
    assert_true(ao_tile_wanted(&ts, 256, 100, true, 16, 1.0));
}

UNIT_TEST_MAIN(cmocka_unit_test(rect_clips_to_the_image), cmocka_unit_test(auto_passes_double),
               cmocka_unit_test(error_estimate_is_unbiased), cmocka_unit_test(adaptive_rule))
