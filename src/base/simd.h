/* Hot loops compiled once per x86 vector width and picked at load time for the CPU at hand, as
 * Embree picks its own kernels: the default build targets SSE2 only. */
#ifndef AO_SIMD_H
#define AO_SIMD_H

/* Put before a function whose loops vectorize: clones for x86-64-v4 (AVX-512 with its 64-bit
 * multiplies, which the random-number hash needs), AVX2 and the baseline (GCC on x86-64; elsewhere
 * nothing; nor under TSan, whose runtime is not up yet when the loader runs the clones' resolvers,
 * so that the program crashes on start). The build turns off FMA contraction (meson.build), so
 * every clone rounds alike and images do not depend on the CPU. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__SANITIZE_THREAD__)
#define AO_VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v4", "avx2", "default")))
#else
#define AO_VECTOR_CLONES
#endif

#endif
