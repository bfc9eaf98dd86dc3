/* Exact sums of doubles: every addend kept to the last bit in fixed point (32-bit digits from
 * 2^-1074 up past DBL_MAX), so that a sum is the same whatever the order of its addends and
 * however it was split into partial sums, and its value is the correctly rounded total. The
 * renderer's image error, mean and RMSE are such sums, so that processes sharing an image
 * (aoview-mpi) each add their own tiles and combine the parts into one process's figures. */
#ifndef AO_SUM_H
#define AO_SUM_H

#include <stdint.h>

/* 32-bit digits: the lowest weighs 2^-1074 (the smallest subnormal), the top one holds the sign
 * and carries. */
enum { AO_SUM_DIGITS = 67 };

/* A sum; zero-initialise it. Plain integers throughout, so that parts made elsewhere combine by
 * adding their words (ao_sum_merge, or an integer sum of each word in MPI). */
struct ao_sum {
    int64_t digit[AO_SUM_DIGITS];
    int64_t adds;        /* addends since the digits were last normalized (the carries' headroom) */
    int64_t infinite[2]; /* +inf and -inf addends */
    int64_t nan;         /* NaN addends */
};

/* Adds x exactly. */
void ao_sum_add(struct ao_sum *s, double x);

/* Adds the sum `part` to s exactly (the same as adding part's addends). */
void ao_sum_merge(struct ao_sum *s, const struct ao_sum *part);

/* Propagates carries so that every digit but the top one is in [0, 2^32): after it, the words of
 * up to 2^30 sums may be added as integers without overflow. */
void ao_sum_normalize(struct ao_sum *s);

/* The total rounded to the nearest double (ties to even): +-inf beyond DBL_MAX or with infinite
 * addends, NaN with a NaN addend or both infinities. */
double ao_sum_value(const struct ao_sum *s);

#endif
