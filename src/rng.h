/* Counter-based random numbers: every stream is a pure function of (seed, pixel, pass, sample),
 * so results never depend on which thread ran which tile. Header only. */
#ifndef AO_RNG_H
#define AO_RNG_H

#include <stdint.h>

/* One random stream; a plain value, cheap to create per pixel sample. */
struct ao_rng {
    uint64_t state;
};

/* A 64-bit finalizer with full avalanche (the splitmix64 output function). */
static inline uint64_t ao_rng_mix(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* The stream for (seed, pixel, pass, sample); each key is mixed in turn so no two keys collide. */
static inline struct ao_rng ao_rng_make(uint64_t seed, uint64_t pixel, uint64_t pass, uint64_t sample)
{
    uint64_t h = ao_rng_mix(seed + 0x9e3779b97f4a7c15ULL);
    h = ao_rng_mix(h ^ (pixel + 0x632be59bd9b4e019ULL));
    h = ao_rng_mix(h ^ (pass + 0x8cb92ba72f3d8dd7ULL));
    h = ao_rng_mix(h ^ (sample + 0xd6e8feb86659fd93ULL));
    struct ao_rng r = {h};
    return r;
}

/* Next 64 random bits of the stream (splitmix64 step). */
static inline uint64_t ao_rng_next(struct ao_rng *r)
{
    r->state += 0x9e3779b97f4a7c15ULL;
    return ao_rng_mix(r->state);
}

/* Next uniform float in [0, 1): 24 random bits, so 1.0 is never returned. */
static inline float ao_rng_float(struct ao_rng *r)
{
    return (float)(ao_rng_next(r) >> 40) * 0x1.0p-24f;
}

#endif
