/* Samplers against their pdfs: unit length, finiteness at the edges of [0,1)^2, chi-square tests of
 * the direction histograms, and the weight each sampler hands the estimator. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "rng.h"
#include "sampling.h"

static const double PI = 3.14159265358979323846;

/* Normals to test about: the axes (both signs of z hit the basis' branch), and skewed ones. */
static const struct ao_vec3 NORMALS[] = {
    {0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, -1, 0}, {0.48f, -0.6f, 0.64f}, {-0.36f, 0.48f, -0.8f},
};
enum { NORMAL_COUNT = sizeof NORMALS / sizeof NORMALS[0] };

/* The largest float below 1, the edge of what ao_rng_pair returns. */
static const float ALMOST_ONE = 0x1.fffffep-1f;

static struct ao_vec3 draw(enum ao_sampling mode, struct ao_vec3 n, float u1, float u2, float *weight)
{
    float x, y, z;
    ao_sample_directions(mode, 1, &n.x, &n.y, &n.z, &u1, &u2, &x, &y, &z, weight);
    return ao_vec3_make(x, y, z);
}

static double pdf(enum ao_sampling mode, struct ao_vec3 n, struct ao_vec3 w)
{
    switch (mode) {
    case AO_SAMPLING_UNIFORM:
        return ao_uniform_sphere_pdf();
    case AO_SAMPLING_HEMISPHERE:
        return ao_hemisphere_pdf(n, w);
    case AO_SAMPLING_COSINE:
        return ao_cosine_pdf(n, w);
    }
    return 0;
}

static void test_edges_give_unit_finite_directions(void **state)
{
    (void)state;
    const float edges[] = {0.0f, 0x1p-24f, 0.5f, ALMOST_ONE};
    for (int mode = 0; mode < 3; mode++)
        for (int k = 0; k < NORMAL_COUNT; k++)
            for (int a = 0; a < 4; a++)
                for (int b = 0; b < 4; b++) {
                    float weight;
                    struct ao_vec3 w = draw((enum ao_sampling)mode, NORMALS[k], edges[a], edges[b], &weight);
                    assert_true(ao_vec3_is_finite(w) && isfinite(weight));
                    assert_true(fabsf(ao_vec3_length(w) - 1.0f) < 1e-6f);
                    if (mode != AO_SAMPLING_UNIFORM)
                        assert_true(ao_vec3_dot(w, NORMALS[k]) >= -1e-6f);
                }
}

static void test_cosine_at_minus_n_is_the_horizon(void **state)
{
    (void)state;
    /* u1 = 0 is the uniform-sphere sample s = -n, where normalize(n + s) would be 0/0: the closed
     * form must give the limit of the neighbouring samples, a unit direction on the horizon. */
    for (int k = 0; k < NORMAL_COUNT; k++) {
        float weight;
        struct ao_vec3 w = draw(AO_SAMPLING_COSINE, NORMALS[k], 0.0f, 0.3f, &weight);
        assert_true(fabsf(ao_vec3_dot(w, NORMALS[k])) < 1e-6f);
        assert_true(fabsf(ao_vec3_length(w) - 1.0f) < 1e-6f);
        assert_true(weight == 1.0f);
    }
}

static void test_weight_is_cosine_over_pi_pdf(void **state)
{
    (void)state;
    uint64_t key = ao_rng_key(7, 0, 0);
    uint64_t sample = 0;
    float u1, u2;
    for (int mode = 0; mode < 3; mode++)
        for (int k = 0; k < NORMAL_COUNT; k++)
            for (int i = 0; i < 2000; i++) {
                float weight;
                struct ao_vec3 n = NORMALS[k];
                ao_rng_pair(key, sample++, &u1, &u2);
                struct ao_vec3 w = draw((enum ao_sampling)mode, n, u1, u2, &weight);
                double cosine = fmax(0.0, ao_vec3_dot(n, w));
                double p = pdf((enum ao_sampling)mode, n, w);
                double expected = p > 0 ? cosine / (PI * p) : 0.0;
                assert_true(fabs(weight - expected) < 1e-5 * (1.0 + expected));
            }
    /* Cosine sampling's weight is exactly one: the estimator reduces to rho * V. */
    for (int i = 0; i < 1000; i++) {
        float weight;
        ao_rng_pair(key, sample++, &u1, &u2);
        draw(AO_SAMPLING_COSINE, NORMALS[4], u1, u2, &weight);
        assert_true(weight == 1.0f);
    }
}

static void test_pdfs_integrate_to_one(void **state)
{
    (void)state;
    /* Integral of p over the sphere by uniform Monte Carlo: mean of 4 pi p(w). Per sample the value
     * is at most 4 (cosine: 4 cos), variance at most 16/3 - 1 < 4.5, so over 10^6 samples the
     * standard error is below 0.0022 and 4 sigma below 0.009. */
    enum { N = 1000000 };
    uint64_t key = ao_rng_key(11, 0, 0);
        float u1, u2;
    for (int mode = 0; mode < 3; mode++) {
        double sum = 0;
        for (int i = 0; i < N; i++) {
            ao_rng_pair(key, (uint64_t)i, &u1, &u2);
            struct ao_vec3 w = ao_sample_uniform_sphere(u1, u2);
            sum += 4.0 * PI * pdf((enum ao_sampling)mode, NORMALS[5], w);
        }
        assert_true(fabs(sum / N - 1.0) < 0.009);
    }
}

/* Chi-square of a histogram over (bin of a function of cos(theta), bin of phi) in an independent
 * frame. `stratum` maps cos(theta) to [0,1) so that each of its bins is equally likely under the
 * sampler's pdf; phi bins are equally likely for all three. */
static double chi_square(enum ao_sampling mode, struct ao_vec3 n, double (*stratum)(double))
{
    enum { THETA_BINS = 20, PHI_BINS = 16, N = 320000 };
    static unsigned counts[THETA_BINS][PHI_BINS];
    memset(counts, 0, sizeof counts);
    /* A frame built by Gram-Schmidt, not the sampler's own basis. */
    struct ao_vec3 a = fabsf(n.x) < 0.9f ? ao_vec3_make(1, 0, 0) : ao_vec3_make(0, 1, 0);
    struct ao_vec3 t = ao_vec3_normalize(ao_vec3_sub(a, ao_vec3_scale(n, ao_vec3_dot(a, n))));
    struct ao_vec3 b = ao_vec3_cross(n, t);
    uint64_t key = ao_rng_key(3, (uint64_t)mode, 0);
    for (int i = 0; i < N; i++) {
        float weight;
        float u1, u2;
        ao_rng_pair(key, (uint64_t)i, &u1, &u2);
        struct ao_vec3 w = draw(mode, n, u1, u2, &weight);
        double s = stratum(fmin(1.0, fmax(-1.0, ao_vec3_dot(w, n))));
        double phi = atan2(ao_vec3_dot(w, b), ao_vec3_dot(w, t)) / (2 * PI) + 0.5;
        int i_theta = (int)fmin(THETA_BINS - 1, fmax(0, s * THETA_BINS));
        int i_phi = (int)fmin(PHI_BINS - 1, fmax(0, phi * PHI_BINS));
        counts[i_theta][i_phi]++;
    }
    double expected = (double)N / (THETA_BINS * PHI_BINS), chi2 = 0;
    for (int i = 0; i < THETA_BINS; i++)
        for (int j = 0; j < PHI_BINS; j++)
            chi2 += (counts[i][j] - expected) * (counts[i][j] - expected) / expected;
    return chi2;
}

static double sphere_stratum(double c) { return 0.5 * (c + 1.0); }     /* cos uniform on [-1,1] */
static double hemisphere_stratum(double c) { return c; }               /* cos uniform on [0,1] */
static double cosine_stratum(double c) { return c * c; }               /* cos^2 uniform on [0,1] */

static void test_histograms_match_pdfs(void **state)
{
    (void)state;
    /* 320 equally likely cells, 319 degrees of freedom: the statistic has mean 319 and standard
     * deviation sqrt(2 * 319) = 25.3, so a correct sampler stays below 319 + 5 * 25.3 = 445 (the
     * right tail is a little heavier than normal; 5 sigma keeps the false alarm rate under 1e-4).
     * A wrong pdf (e.g. hemisphere drawn for cosine) gives a statistic in the tens of thousands. */
    const double bound = 319 + 5 * sqrt(2 * 319.0);
    for (int k = 0; k < NORMAL_COUNT; k++) {
        assert_true(chi_square(AO_SAMPLING_UNIFORM, NORMALS[k], sphere_stratum) < bound);
        assert_true(chi_square(AO_SAMPLING_HEMISPHERE, NORMALS[k], hemisphere_stratum) < bound);
        assert_true(chi_square(AO_SAMPLING_COSINE, NORMALS[k], cosine_stratum) < bound);
    }
    /* The test can fail: hemisphere samples binned as if cosine-distributed. */
    assert_true(chi_square(AO_SAMPLING_HEMISPHERE, NORMALS[0], cosine_stratum) > 10 * bound);
}

static void test_sobol_pairs_stratify(void **state)
{
    (void)state;
    /* Any aligned block of 2^m consecutive indices of one stream is a (0, m, 2)-net: each of the
     * 2^m elementary intervals of every shape (2^a x 2^(m-a)) holds exactly one point. Checked
     * for m = 4 and 8, several blocks and keys. Random pairs fail this almost surely. */
    for (uint64_t key = 1; key < 5; key++)
        for (int m = 4; m <= 8; m += 4)
            for (uint64_t block = 0; block < 3; block++)
                for (int a = 0; a <= m; a++) {
                    static unsigned cells[256];
                    memset(cells, 0, sizeof cells);
                    for (uint64_t i = 0; i < (1u << m); i++) {
                        float u1, u2;
                        ao_rng_sobol_pair(ao_rng_key(9, key, 0), (block << m) + i, &u1, &u2);
                        unsigned cx = (unsigned)(u1 * (float)(1u << a)), cy = (unsigned)(u2 * (float)(1u << (m - a)));
                        cells[(cx << (m - a)) + cy]++;
                    }
                    for (unsigned c = 0; c < (1u << m); c++)
                        assert_int_equal(cells[c], 1);
                }
}

/* A nested uniform (Owen) scramble of x keyed by seed: each bit flipped by a hash of the bits above
 * it, the hash of Laine and Karras applied to the reversed bits. */
static uint32_t owen(uint32_t x, uint32_t seed)
{
    return ao_rng_reverse(ao_rng_laine_karras(ao_rng_reverse(x), seed));
}

/* The definition the vectorized Sobol pairs must equal bit for bit, as the textbook states it: the
 * index Owen scrambled, the second dimension as the XOR of the direction numbers (v_0 = 2^31,
 * v_k = v_(k-1) ^ (v_(k-1) >> 1)) of the index's set bits, in a loop as long as the index, and each
 * dimension Owen scrambled as drawn. rng.h reaches the same bits with no branch and no loop. */
static void reference_sobol_pair(uint64_t key, uint64_t sample, float *u1, float *u2)
{
    uint64_t seeds = ao_rng_mix(key ^ 0x5851f42d4c957f2dULL);
    uint32_t index = owen((uint32_t)sample, (uint32_t)key), v = 1u << 31, d1 = 0;
    for (uint32_t i = index; i; i >>= 1, v ^= v >> 1)
        d1 ^= (i & 1) ? v : 0;
    *u1 = (float)(owen(ao_rng_reverse(index), (uint32_t)seeds) >> 8) * 0x1.0p-24f;
    *u2 = (float)(owen(d1, (uint32_t)(seeds >> 32)) >> 8) * 0x1.0p-24f;
}

/* Fails naming the first of the n pairs u1/u2 (pair index[k] of stream key[k]) that differs from the
 * reference in any bit. */
static void assert_reference_pairs(const uint64_t *key, const uint64_t *index, int n, const float *u1, const float *u2)
{
    for (int k = 0; k < n; k++) {
        float r1, r2;
        reference_sobol_pair(key[k], index[k], &r1, &r2);
        if (memcmp(&r1, &u1[k], sizeof r1) != 0 || memcmp(&r2, &u2[k], sizeof r2) != 0)
            fail_msg("key %#llx index %#llx: (%a, %a), the reference gives (%a, %a)", (unsigned long long)key[k],
                     (unsigned long long)index[k], (double)u1[k], (double)u2[k], (double)r1, (double)r2);
    }
}

/* A way of drawing the Sobol pairs of lanes 0..n-1. */
typedef void draw_pairs_fn(const struct ao_rng_lanes *lanes, int n, float *u1, float *u2);

/* Pair index[k] of stream key[k] for k below n, drawn through lanes by draw. */
static void draw_sobol(draw_pairs_fn *draw, const uint64_t *key, const uint64_t *index, int n,
                       struct ao_rng_lanes *lanes, float *u1, float *u2)
{
    for (int k = 0; k < n; k++) {
        struct ao_rng_stream s = ao_rng_stream(key[k]);
        ao_rng_lanes_set(lanes, AO_SEQUENCE_SOBOL, k, &s, index[k]);
    }
    draw(lanes, n, u1, u2);
}

/* Fails unless draw gives the reference's pairs bit for bit. */
static void assert_draws_reference_sobol(draw_pairs_fn *draw)
{
    /* Keys: 0, all ones, and pseudo-random ones (fixed seed); indices from 0, and around 2^31 (the
     * top bit of the scrambled index), 2^32 (where the sample number is truncated), 2^40 and the
     * top of the range. Drawn as the AO samples are (one stream, consecutive indices) and as the
     * eye jitter is (one index, a stream per lane), in calls of every length up to AO_RNG_LANES, so
     * that the vector loops run at every length and leave every remainder. */
    enum { KEYS = 66, SPAN = 4096, LANES = AO_RNG_LANES };
    static const uint64_t STARTS[] = {0, (1ULL << 31) - SPAN / 2, (1ULL << 32) - SPAN / 2, (1ULL << 40) - SPAN / 2,
                                      UINT64_MAX - SPAN + 1};
    enum { START_COUNT = sizeof STARTS / sizeof STARTS[0] };
    uint64_t keys[KEYS] = {0, UINT64_MAX};
    for (int j = 2; j < KEYS; j++)
        keys[j] = ao_rng_mix(0x243f6a8885a308d3ULL + (uint64_t)j);
    uint64_t key[LANES], index[LANES];
    struct ao_rng_lanes lanes;
    float u1[LANES], u2[LANES];
    for (int j = 0; j < KEYS; j++)
        for (int s = 0; s < START_COUNT; s++)
            for (int done = 0, c = j; done < SPAN; c++) {
                int n = 1 + c % LANES < SPAN - done ? 1 + c % LANES : SPAN - done;
                for (int k = 0; k < n; k++)
                    key[k] = keys[j], index[k] = STARTS[s] + (uint64_t)(done + k);
                draw_sobol(draw, key, index, n, &lanes, u1, u2);
                assert_reference_pairs(key, index, n, u1, u2);
                done += n;
            }
    for (int s = 0; s < START_COUNT; s++)
        for (uint64_t i = STARTS[s]; i != STARTS[s] + 64; i++)
            for (int j = 0, c = (int)(i % LANES); j < KEYS; c++) {
                int n = 1 + c % LANES < KEYS - j ? 1 + c % LANES : KEYS - j;
                for (int k = 0; k < n; k++)
                    key[k] = keys[j + k], index[k] = i;
                draw_sobol(draw, key, index, n, &lanes, u1, u2);
                assert_reference_pairs(key, index, n, u1, u2);
                j += n;
            }
}

/* The plain loops, as the vector clones of this CPU run them. */
static void draw_loops(const struct ao_rng_lanes *lanes, int n, float *u1, float *u2)
{
    ao_rng_pairs_loops(AO_SEQUENCE_SOBOL, lanes, n, u1, u2);
}

static void test_vector_sobol_equals_reference(void **state)
{
    (void)state;
    assert_draws_reference_sobol(draw_loops);
}

static void test_gfni_sobol_equals_reference(void **state)
{
    (void)state;
#if AO_RNG_GFNI
    if (ao_rng_gfni()) {
        assert_draws_reference_sobol(ao_rng_sobol_pairs_gfni);
        return;
    }
#endif
    skip();
}

static void test_names_round_trip(void **state)
{
    (void)state;
    for (int mode = 0; mode < 3; mode++) {
        enum ao_sampling parsed;
        assert_true(ao_sampling_parse(ao_sampling_name((enum ao_sampling)mode), &parsed));
        assert_int_equal(parsed, mode);
    }
    enum ao_sampling parsed;
    assert_false(ao_sampling_parse("foo", &parsed));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_edges_give_unit_finite_directions),
        cmocka_unit_test(test_cosine_at_minus_n_is_the_horizon),
        cmocka_unit_test(test_weight_is_cosine_over_pi_pdf),
        cmocka_unit_test(test_pdfs_integrate_to_one),
        cmocka_unit_test(test_histograms_match_pdfs),
        cmocka_unit_test(test_sobol_pairs_stratify),
        cmocka_unit_test(test_vector_sobol_equals_reference),
        cmocka_unit_test(test_gfni_sobol_equals_reference),
        cmocka_unit_test(test_names_round_trip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
