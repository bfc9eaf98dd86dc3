/* Counter-based random numbers: every value is a pure function of (seed, pixel, pass, sample), so
 * results never depend on which thread ran which tile. Inline, but for the GFNI path in rng.c. */
#ifndef AO_RNG_H
#define AO_RNG_H

#include <stdbool.h>
#include <stdint.h>

#include "modes.h"
#include "simd.h"

/* A 64-bit finalizer with full avalanche (the splitmix64 output function). */
static inline uint64_t ao_rng_mix(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* The key of the stream for (seed, pixel, pass); each part is mixed in turn so no two collide. */
static inline uint64_t ao_rng_key(uint64_t seed, uint64_t pixel, uint64_t pass)
{
    uint64_t h = ao_rng_mix(seed + 0x632be59bd9b4e019ULL);
    h = ao_rng_mix(h ^ (pixel + 0x8cb92ba72f3d8dd7ULL));
    return ao_rng_mix(h ^ (pass + 0xd6e8feb86659fd93ULL));
}

/* The stream's sample-th pair of uniform floats in [0, 1), 24 bits each (1.0 never occurs): the
 * sample-th output of a splitmix64 generator started at key, one mix per pair. */
static inline void ao_rng_pair(uint64_t key, uint64_t sample, float *u1, float *u2)
{
    uint64_t bits = ao_rng_mix(key + (sample + 1) * 0x9e3779b97f4a7c15ULL);
    *u1 = (float)(bits >> 40) * 0x1.0p-24f;
    *u2 = (float)((bits >> 16) & 0xffffffu) * 0x1.0p-24f;
}


/* The bits of x in reverse order. */
static inline uint32_t ao_rng_reverse(uint32_t x)
{
    x = (x << 16) | (x >> 16);
    x = ((x & 0x00ff00ffu) << 8) | ((x >> 8) & 0x00ff00ffu);
    x = ((x & 0x0f0f0f0fu) << 4) | ((x >> 4) & 0x0f0f0f0fu);
    x = ((x & 0x33333333u) << 2) | ((x >> 2) & 0x33333333u);
    return ((x & 0x55555555u) << 1) | ((x >> 1) & 0x55555555u);
}

/* The multipliers of ao_rng_laine_karras's four rounds. */
static const uint32_t AO_RNG_LAINE_KARRAS[4] = {0x6c50b47cu, 0xb82f1e52u, 0xc7afe638u, 0x8d22f6e6u};

/* The hash of Laine and Karras, a nested uniform (Owen) scramble of bits given in reverse order:
 * each bit is flipped by a hash of the bits below it, since additions and multiplications carry only
 * upwards (Burley, "Practical hash-based Owen scrambling", JCGT 2020). */
static inline uint32_t ao_rng_laine_karras(uint32_t x, uint32_t seed)
{
    x += seed;
    for (int i = 0; i < 4; i++)
        x ^= x * AO_RNG_LAINE_KARRAS[i];
    return x;
}

/* The bits that ao_rng_pascal's step b moves down by 2^b: those with bit b of their index set. */
static const uint32_t AO_RNG_PASCAL_BITS[5] = {0xaaaaaaaau, 0xccccccccu, 0xf0f0f0f0u, 0xff00ff00u, 0xffff0000u};

/* Sobol's second dimension, bit-reversed: bit j of the result is the parity of the bits i >= j of x
 * with binomial(i, j) odd (x times Pascal's matrix mod 2). Reversed, the dimension's direction
 * numbers v_0 = 2^31, v_k = v_(k-1) ^ (v_(k-1) >> 1) are the polynomials (1 + t)^k over GF(2), and
 * (1 + t)^i is the product of (1 + t^(2^b)) over the set bits b of i: step b applies that factor to
 * all bits i with bit b set at once. Five steps, with no branch and no dependence on x. */
static inline uint32_t ao_rng_pascal(uint32_t x)
{
    for (int b = 0; b < 5; b++)
        x ^= (x & AO_RNG_PASCAL_BITS[b]) >> (1 << b);
    return x;
}

/* What drawing from a stream needs of its key, derived once per stream: the key itself (random
 * numbers) and, for Sobol numbers, the seeds of the Owen scrambles of the sample number and of the
 * two dimensions. */
struct ao_rng_stream {
    uint64_t key;
    uint32_t seed_index, seed_x, seed_y;
};

/* The stream of `key`. */
static inline struct ao_rng_stream ao_rng_stream(uint64_t key)
{
    uint64_t seeds = ao_rng_mix(key ^ 0x5851f42d4c957f2dULL);
    struct ao_rng_stream s = {key, (uint32_t)key, (uint32_t)seeds, (uint32_t)(seeds >> 32)};
    return s;
}

/* The sample-th pair (24 bits each, in [0, 1)) of a stream with these seeds (ao_rng_stream) from
 * the first two dimensions of a Sobol sequence, the van der Corput radical inverse and the dimension
 * of ao_rng_pascal, at the sample number's low 32 bits Owen scrambled; each dimension then Owen
 * scrambled with its own seed. Owen scrambling a dimension reverses its bits first, which undoes the
 * reversal of the radical inverse and leaves ao_rng_pascal's result as it is. Free of branches and
 * of 64-bit arithmetic, so that loops over samples or over streams vectorize 16 lanes wide. */
static inline void ao_rng_sobol_seeded(uint32_t seed_index, uint32_t seed_x, uint32_t seed_y, uint32_t sample,
                                       float *u1, float *u2)
{
    uint32_t index = ao_rng_reverse(ao_rng_laine_karras(ao_rng_reverse(sample), seed_index));
    uint32_t d0 = ao_rng_reverse(ao_rng_laine_karras(index, seed_x));
    uint32_t d1 = ao_rng_reverse(ao_rng_laine_karras(ao_rng_pascal(index), seed_y));
    *u1 = (float)(d0 >> 8) * 0x1.0p-24f;
    *u2 = (float)(d1 >> 8) * 0x1.0p-24f;
}

/* The stream key's sample-th Sobol pair (ao_rng_sobol_seeded). */
static inline void ao_rng_sobol_pair(uint64_t key, uint64_t sample, float *u1, float *u2)
{
    struct ao_rng_stream s = ao_rng_stream(key);
    ao_rng_sobol_seeded(s.seed_index, s.seed_x, s.seed_y, (uint32_t)sample, u1, u2);
}

/* Up to AO_RNG_LANES pairs drawn at once, each lane from its own stream: structure of arrays, the
 * lanes set by ao_rng_lanes_set. */
enum { AO_RNG_LANES = 64 };
struct ao_rng_lanes {
    uint64_t key[AO_RNG_LANES], sample[AO_RNG_LANES];                          /* random numbers */
    uint32_t seed_index[AO_RNG_LANES], seed_x[AO_RNG_LANES], seed_y[AO_RNG_LANES], low[AO_RNG_LANES]; /* Sobol */
};

/* Lane k draws pair `sample` of stream s from `sequence`. */
static inline void ao_rng_lanes_set(struct ao_rng_lanes *lanes, enum ao_sequence sequence, int k,
                                    const struct ao_rng_stream *s, uint64_t sample)
{
    if (sequence == AO_SEQUENCE_SOBOL) {
        lanes->seed_index[k] = s->seed_index, lanes->seed_x[k] = s->seed_x, lanes->seed_y[k] = s->seed_y;
        lanes->low[k] = (uint32_t)sample;
    } else {
        lanes->key[k] = s->key, lanes->sample[k] = sample;
    }
}

#if defined(__GNUC__) && defined(__x86_64__)
#define AO_RNG_GFNI 1
/* Whether the CPU runs ao_rng_sobol_pairs_gfni (AVX-512 with byte shuffles, and GFNI). */
bool ao_rng_gfni(void);
/* ao_rng_pairs's Sobol pairs, bit for bit, 16 lanes a vector, each lane's bits reversed by a byte
 * shuffle and one GF(2) affine map (rng.c). */
void ao_rng_sobol_pairs_gfni(const struct ao_rng_lanes *restrict lanes, int n, float *restrict u1,
                             float *restrict u2);
#else
#define AO_RNG_GFNI 0
#endif

/* The pairs of lanes 0..n-1 from `sequence` into u1[k]/u2[k]: loops that vectorize across lanes,
 * whatever their streams and sample numbers. */
AO_VECTOR_CLONES
static inline void ao_rng_pairs_loops(enum ao_sequence sequence, const struct ao_rng_lanes *restrict lanes, int n,
                                      float *restrict u1, float *restrict u2)
{
    if (sequence == AO_SEQUENCE_SOBOL)
        for (int k = 0; k < n; k++)
            ao_rng_sobol_seeded(lanes->seed_index[k], lanes->seed_x[k], lanes->seed_y[k], lanes->low[k], &u1[k],
                                &u2[k]);
    else
        for (int k = 0; k < n; k++)
            ao_rng_pair(lanes->key[k], lanes->sample[k], &u1[k], &u2[k]);
}

/* The pairs of lanes 0..n-1 from `sequence` into u1[k]/u2[k]: Sobol pairs by
 * ao_rng_sobol_pairs_gfni where the CPU has it, else ao_rng_pairs_loops; the same bits either way. */
static inline void ao_rng_pairs(enum ao_sequence sequence, const struct ao_rng_lanes *restrict lanes, int n,
                                float *restrict u1, float *restrict u2)
{
#if AO_RNG_GFNI
    if (sequence == AO_SEQUENCE_SOBOL && ao_rng_gfni()) {
        ao_rng_sobol_pairs_gfni(lanes, n, u1, u2);
        return;
    }
#endif
    ao_rng_pairs_loops(sequence, lanes, n, u1, u2);
}

#endif
