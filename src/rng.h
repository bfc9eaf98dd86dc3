/* Counter-based random numbers: every value is a pure function of (seed, pixel, pass, sample), so
 * results never depend on which thread ran which tile. Header only. */
#ifndef AO_RNG_H
#define AO_RNG_H

#include <stdint.h>

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

/* How a stream's numbers are drawn: independent random pairs, or an Owen-scrambled Sobol sequence
 * whose first 2^k points (of any pixel, from index 0) stratify the unit square. */
enum ao_sequence {
    AO_SEQUENCE_RANDOM,
    AO_SEQUENCE_SOBOL,
};

/* The bits of x in reverse order. */
static inline uint32_t ao_rng_reverse(uint32_t x)
{
    x = (x << 16) | (x >> 16);
    x = ((x & 0x00ff00ffu) << 8) | ((x >> 8) & 0x00ff00ffu);
    x = ((x & 0x0f0f0f0fu) << 4) | ((x >> 4) & 0x0f0f0f0fu);
    x = ((x & 0x33333333u) << 2) | ((x >> 2) & 0x33333333u);
    return ((x & 0x55555555u) << 1) | ((x >> 1) & 0x55555555u);
}

/* A nested uniform (Owen) scramble of x keyed by seed: each bit is flipped by a hash of the bits
 * above it. On reversed bits, additions and multiplications carry only upwards, so the hash of
 * Laine and Karras has that property (Burley, "Practical hash-based Owen scrambling", JCGT 2020). */
static inline uint32_t ao_rng_owen(uint32_t x, uint32_t seed)
{
    x = ao_rng_reverse(x);
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return ao_rng_reverse(x);
}

/* The first two dimensions of the Sobol sequence at index: the van der Corput radical inverse,
 * and the dimension whose direction numbers are v_0 = 2^31, v_k = v_(k-1) ^ (v_(k-1) >> 1). */
static inline void ao_rng_sobol(uint32_t index, uint32_t *d0, uint32_t *d1)
{
    uint32_t v = 1u << 31, y = 0;
    for (uint32_t i = index; i; i >>= 1, v ^= v >> 1)
        y ^= (i & 1) ? v : 0;
    *d0 = ao_rng_reverse(index);
    *d1 = y;
}

/* The stream's sample-th pair from a Sobol sequence whose order and both dimensions are Owen
 * scrambled with seeds derived from key (24 bits each, in [0, 1)). */
static inline void ao_rng_sobol_pair(uint64_t key, uint64_t sample, float *u1, float *u2)
{
    uint64_t seeds = ao_rng_mix(key ^ 0x5851f42d4c957f2dULL);
    uint32_t d0, d1;
    ao_rng_sobol(ao_rng_owen((uint32_t)sample, (uint32_t)key), &d0, &d1);
    *u1 = (float)(ao_rng_owen(d0, (uint32_t)seeds) >> 8) * 0x1.0p-24f;
    *u2 = (float)(ao_rng_owen(d1, (uint32_t)(seeds >> 32)) >> 8) * 0x1.0p-24f;
}

#endif
