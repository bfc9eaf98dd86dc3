/* pack.c: pixel sums as a palette and indices, unpacked bit for bit, raw when that is smaller. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pack.h"
#include "rng.h"

/* n sums, sum k the `distinct` values' (k * 7919) mod distinct-th: value v is (v, v / 2, -v) / 8,
 * so that distinct values differ in every channel. */
static struct ao_vec3 *sums_of(size_t n, size_t distinct)
{
    struct ao_vec3 *s = malloc(n * sizeof *s);
    for (size_t k = 0; k < n; k++) {
        float v = (float)((k * 7919) % distinct) / 8.0f;
        s[k] = (struct ao_vec3){v, v / 2.0f, -v};
    }
    return s;
}

/* Packs and unpacks n sums; returns the packed bytes after checking the sums come back bit for bit. */
static size_t round_trip(const struct ao_vec3 *sums, size_t n)
{
    unsigned char *packed = malloc(ao_pack_bound(n));
    struct ao_vec3 *back = malloc((n ? n : 1) * sizeof *back);
    size_t bytes = ao_pack_sums(sums, n, packed);
    assert_true(bytes <= ao_pack_bound(n));
    assert_true(ao_unpack_sums(packed, bytes, back, n));
    assert_memory_equal(back, sums, n * sizeof *sums);
    free(packed);
    free(back);
    return bytes;
}

/* The size by the layout: a 4-byte count, the distinct sums, then 4-, 8- or 16-bit indices. */
static void test_indices_take_the_fewest_bits(void **state)
{
    (void)state;
    const size_t n = 256 * 16; /* the sums of 16 lent 16x16 tiles */
    const struct { size_t distinct, bytes; } cases[] = {
        {1, 4 + 12 + n / 2}, {16, 4 + 16 * 12 + n / 2}, {17, 4 + 17 * 12 + n},
        {256, 4 + 256 * 12 + n}, {257, 4 + 257 * 12 + 2 * n}, {1000, 4 + 1000 * 12 + 2 * n}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        struct ao_vec3 *s = sums_of(n, cases[c].distinct);
        assert_int_equal(round_trip(s, n), cases[c].bytes);
        free(s);
    }
}

/* Where a palette would not be smaller (every sum distinct, or more than 16-bit indices can name,
 * or nothing at all), the sums go raw: the bound, exactly. */
static void test_raw_when_not_smaller(void **state)
{
    (void)state;
    size_t sizes[] = {0, 1, 5, 4096, 70000};
    for (size_t c = 0; c < sizeof sizes / sizeof sizes[0]; c++) {
        size_t n = sizes[c];
        struct ao_vec3 *s = malloc((n ? n : 1) * sizeof *s);
        for (size_t k = 0; k < n; k++)
            s[k] = (struct ao_vec3){(float)k, 1.0f, 2.0f};
        assert_int_equal(round_trip(s, n), ao_pack_bound(n));
        free(s);
    }
    /* 70,000 sums of 3 values: more than 65,536 sums, few distinct: packed */
    struct ao_vec3 *s = sums_of(70000, 3);
    assert_int_equal(round_trip(s, 70000), 4 + 3 * 12 + 35000);
    free(s);
}

/* Bits, not values: -0 and +0, NaNs of different payloads and subnormals stay what they were. */
static void test_bits_not_values(void **state)
{
    (void)state;
    enum { N = 128 };
    uint32_t patterns[] = {0x00000000u, 0x80000000u, 0x7fc00000u, 0x7fc00001u, 0xffc00000u, 0x00000001u,
                           0x7f800000u, 0x3f800000u};
    struct ao_vec3 s[N];
    for (int k = 0; k < N; k++) {
        uint32_t w[3] = {patterns[k % 8], patterns[(k / 8) % 8], patterns[3]};
        memcpy(&s[k], w, sizeof w);
    }
    /* 64 distinct triples of bit patterns (8 x 8), each twice: 8-bit indices */
    assert_int_equal(round_trip(s, N), 4 + 64 * 12 + N);
}

/* Random sums of a few values, as a pass of 1 to 4 samples a pixel makes them, at random lengths. */
static void test_random_round_trips(void **state)
{
    (void)state;
    for (uint64_t trial = 0; trial < 200; trial++) {
        uint64_t h = ao_rng_mix(trial + 1);
        size_t n = (size_t)(h % 20000), values = 1 + (size_t)(h >> 20) % 5;
        struct ao_vec3 *s = malloc((n ? n : 1) * sizeof *s);
        for (size_t k = 0; k < n; k++) {
            float v = 0.8f * (float)(ao_rng_mix(h ^ k) % values);
            s[k] = (struct ao_vec3){v, v, v};
        }
        round_trip(s, n);
        free(s);
    }
}

/* What was not made by ao_pack_sums for n sums is refused, never read past its length. */
static void test_refuses_what_is_not_a_packing(void **state)
{
    (void)state;
    enum { N = 100 };
    struct ao_vec3 *s = sums_of(N, 3), back[N];
    unsigned char packed[4 + 12 * N];
    size_t bytes = ao_pack_sums(s, N, packed);
    assert_false(ao_unpack_sums(packed, bytes - 1, back, N));     /* short */
    assert_false(ao_unpack_sums(packed, bytes, back, N + 1));     /* for other n */
    assert_false(ao_unpack_sums(packed, 3, back, N));             /* no count */
    unsigned char bad[sizeof packed];
    memcpy(bad, packed, bytes);
    bad[4 + 3 * 12] = 0x03;                                      /* an index past the palette */
    assert_false(ao_unpack_sums(bad, bytes, back, N));
    uint32_t many = N + 1;                                        /* more distinct sums than sums */
    memcpy(bad, &many, sizeof many);
    assert_false(ao_unpack_sums(bad, bytes, back, N));
    uint32_t raw = 0;                                             /* raw, but not n sums long */
    memcpy(bad, &raw, sizeof raw);
    assert_false(ao_unpack_sums(bad, bytes, back, N));
    free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_indices_take_the_fewest_bits),
        cmocka_unit_test(test_raw_when_not_smaller),
        cmocka_unit_test(test_bits_not_values),
        cmocka_unit_test(test_random_round_trips),
        cmocka_unit_test(test_refuses_what_is_not_a_packing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
