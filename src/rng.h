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

#endif
