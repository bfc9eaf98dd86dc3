/* Counter-based random numbers (see rng.h): the Sobol pairs on AVX-512 with GFNI. The four bit
 * reversals of a pair are most of ao_rng_sobol_seeded's work in plain vector code (five rounds of
 * shifts and masks each); here each is a byte shuffle and one affine map, and the result is the
 * same bit for bit (test_gfni_sobol_equals_reference). */
#include "rng.h"

#if AO_RNG_GFNI
#include <immintrin.h>

#define GFNI_TARGET __attribute__((target("avx512f,avx512bw,gfni")))

/* ao_rng_reverse on 16 lanes: the bytes swapped, then each byte's bits reversed by the affine map
 * whose matrix is the anti-diagonal. */
GFNI_TARGET static inline __m512i reverse(__m512i x)
{
    const __m512i swap = _mm512_set4_epi32(0x0c0d0e0f, 0x08090a0b, 0x04050607, 0x00010203);
    return _mm512_gf2p8affine_epi64_epi8(_mm512_shuffle_epi8(x, swap), _mm512_set1_epi64(0x8040201008040201LL),
                                         0);
}

/* ao_rng_laine_karras on 16 lanes. */
GFNI_TARGET static inline __m512i laine_karras(__m512i x, __m512i seed)
{
    x = _mm512_add_epi32(x, seed);
    for (int i = 0; i < 4; i++)
        x = _mm512_xor_si512(x, _mm512_mullo_epi32(x, _mm512_set1_epi32((int)AO_RNG_LAINE_KARRAS[i])));
    return x;
}

/* ao_rng_pascal on 16 lanes. */
GFNI_TARGET static inline __m512i pascal(__m512i x)
{
    for (unsigned b = 0; b < 5; b++)
        x = _mm512_xor_si512(
            x, _mm512_srli_epi32(_mm512_and_si512(x, _mm512_set1_epi32((int)AO_RNG_PASCAL_BITS[b])), 1u << b));
    return x;
}

/* One dimension's 24 bits as a float in [0, 1). */
GFNI_TARGET static inline __m512 unit(__m512i bits)
{
    return _mm512_mul_ps(_mm512_cvtepi32_ps(_mm512_srli_epi32(bits, 8)), _mm512_set1_ps(0x1.0p-24f));
}

GFNI_TARGET void ao_rng_sobol_pairs_gfni(const struct ao_rng_lanes *restrict lanes, int n, float *restrict u1,
                                          float *restrict u2)
{
    for (int k = 0; k < n; k += 16) {
        __mmask16 m = n - k >= 16 ? (__mmask16)0xffff : (__mmask16)((1u << (n - k)) - 1u);
        __m512i sample = _mm512_maskz_loadu_epi32(m, lanes->low + k);
        __m512i index = reverse(laine_karras(reverse(sample), _mm512_maskz_loadu_epi32(m, lanes->seed_index + k)));
        __m512i d0 = reverse(laine_karras(index, _mm512_maskz_loadu_epi32(m, lanes->seed_x + k)));
        __m512i d1 = reverse(laine_karras(pascal(index), _mm512_maskz_loadu_epi32(m, lanes->seed_y + k)));
        _mm512_mask_storeu_ps(u1 + k, m, unit(d0));
        _mm512_mask_storeu_ps(u2 + k, m, unit(d1));
    }
}

bool ao_rng_gfni(void)
{
    return __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("gfni");
}
#endif
