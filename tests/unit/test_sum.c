/* sum.c: exact sums of doubles, the same whatever the order and split, correctly rounded. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <string.h>

#include "rng.h"
#include "sum.h"
#include "unit_main.h"

/* A random 64-bit word from (stream, counter). */
static uint64_t hash(uint64_t stream, uint64_t counter)
{
    return ao_rng_mix(ao_rng_mix(stream) ^ counter);
}

static double sum_of(const double *x, int n)
{
    struct ao_sum s = {0};
    for (int k = 0; k < n; k++)
        ao_sum_add(&s, x[k]);
    return ao_sum_value(&s);
}

/* Cases a naive double sum gets wrong, each with its correctly rounded total. */
static void test_known_totals(void **state)
{
    (void)state;
    double tenth[10];
    for (int k = 0; k < 10; k++)
        tenth[k] = 0.1;
    /* ten doubles 0.1 add up to 1 + 5.55e-17, nearest 1 (naively 0.9999999999999999) */
    assert_true(sum_of(tenth, 10) == 1.0);
    double small[] = {1.0, 0x1p-53, 0x1p-53};
    assert_true(sum_of(small, 3) == 1.0 + 0x1p-52);
    double tie[] = {0x1p53, 1.0};                  /* half way: to the even 2^53 */
    assert_true(sum_of(tie, 2) == 0x1p53);
    double above[] = {0x1p53, 1.0, 0x1p-60};       /* just above half way: up */
    assert_true(sum_of(above, 3) == 0x1p53 + 2.0);
    double odd[] = {0x1p53 + 2.0, 1.0};            /* half way from an odd mantissa: up */
    assert_true(sum_of(odd, 2) == 0x1p53 + 4.0);
    double big[] = {DBL_MAX, DBL_MAX, -DBL_MAX};   /* naively inf */
    assert_true(sum_of(big, 3) == DBL_MAX);
    double over[] = {DBL_MAX, DBL_MAX};
    assert_true(sum_of(over, 2) == INFINITY);
    double tiny[] = {DBL_TRUE_MIN, DBL_TRUE_MIN, -DBL_MIN, DBL_MIN};
    assert_true(sum_of(tiny, 4) == 2.0 * DBL_TRUE_MIN);
    double cancel[] = {1e300, 1.0, -1e300, -0.25};
    assert_true(sum_of(cancel, 4) == 0.75);
    double negative[] = {-1.0, -0x1p-53, -0x1p-53};
    assert_true(sum_of(negative, 3) == -1.0 - 0x1p-52);
    double zero[] = {0.0, -0.0, 3.0, -3.0};
    assert_true(sum_of(zero, 4) == 0.0);
    assert_true(sum_of(zero, 0) == 0.0);
    double special[] = {1.0, INFINITY};
    assert_true(sum_of(special, 2) == INFINITY);
    double both[] = {INFINITY, -INFINITY};
    assert_true(isnan(sum_of(both, 2)));
    double nan[] = {1.0, NAN};
    assert_true(isnan(sum_of(nan, 2)));
}

/* Integers times 2^-20 below 2^40 add up exactly in int64_t: that total, rounded once, is the
 * reference for random sums of mixed signs; and the sum is the same in reverse order. */
static void test_random_sums_round_once(void **state)
{
    (void)state;
    uint64_t counter = 0;
    for (int round = 0; round < 200; round++) {
        struct ao_sum forward = {0}, backward = {0};
        double x[1000];
        int64_t exact = 0;
        for (int k = 0; k < 1000; k++) {
            uint64_t r = hash(7, counter++);
            int64_t v = (int64_t)(r >> 24) - ((int64_t)1 << 39); /* in [-2^39, 2^39) */
            exact += v;
            x[k] = ldexp((double)v, -20);
            ao_sum_add(&forward, x[k]);
        }
        for (int k = 999; k >= 0; k--)
            ao_sum_add(&backward, x[k]);
        double want = ldexp((double)exact, -20); /* one rounding, to nearest even */
        assert_true(ao_sum_value(&forward) == want);
        assert_true(ao_sum_value(&backward) == want);
    }
}

/* Parts made apart (processes), normalized and added word by word as integers (what an MPI
 * integer sum of the words does), or merged, give the whole sum's value: values of every
 * magnitude and sign, split at random. */
static void test_parts_combine_as_integers(void **state)
{
    (void)state;
    uint64_t counter = 0;
    for (int round = 0; round < 50; round++) {
        enum { PARTS = 5, COUNT = 500 };
        struct ao_sum whole = {0}, part[PARTS], merged = {0};
        memset(part, 0, sizeof part);
        for (int k = 0; k < COUNT; k++) {
            uint64_t r = hash(11, counter++);
            double x = ldexp((double)(r >> 11), (int)(hash(12, counter) % 600) - 350);
            x = (r & 1) ? -x : x;
            ao_sum_add(&whole, x);
            ao_sum_add(&part[hash(13, counter) % PARTS], x);
        }
        int64_t words[PARTS][sizeof(struct ao_sum) / sizeof(int64_t)];
        struct ao_sum added;
        memset(&added, 0, sizeof added);
        for (int p = 0; p < PARTS; p++) {
            ao_sum_normalize(&part[p]);
            memcpy(words[p], &part[p], sizeof part[p]);
            ao_sum_merge(&merged, &part[p]);
        }
        int64_t total[sizeof(struct ao_sum) / sizeof(int64_t)] = {0};
        for (int p = 0; p < PARTS; p++)
            for (size_t w = 0; w < sizeof total / sizeof total[0]; w++)
                total[w] += words[p][w];
        memcpy(&added, total, sizeof added);
        double want = ao_sum_value(&whole);
        assert_true(ao_sum_value(&merged) == want);
        assert_true(ao_sum_value(&added) == want);
    }
}

/* Four million addends into one digit, each filling it: the carries stay exact. */
static void test_many_addends(void **state)
{
    (void)state;
    struct ao_sum s = {0};
    double x = 4294967295.0; /* 2^32 - 1: fills a whole digit on every add */
    for (int k = 0; k < (1 << 22); k++)
        ao_sum_add(&s, x);
    assert_true(ao_sum_value(&s) == x * (double)(1 << 22));
}

UNIT_TEST_MAIN(cmocka_unit_test(test_known_totals), cmocka_unit_test(test_random_sums_round_once),
               cmocka_unit_test(test_parts_combine_as_integers), cmocka_unit_test(test_many_addends))
