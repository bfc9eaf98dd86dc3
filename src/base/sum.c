/* Exact sums of doubles; see sum.h. A finite double is m 2^e with an integer m < 2^53 and
 * e >= -1074: its bits land at position p = e + 1074 of a fixed-point number whose lowest bit
 * weighs 2^-1074, spread over up to three 32-bit digits. Digits are int64_t, so that carries
 * wait: each addend moves a digit by less than 2^33, and the digits are normalized every
 * NORMALIZE_EVERY addends, long before 2^63. */
#include "sum.h"

#include <math.h>
#include <stdbool.h>
#include <string.h>

enum { TOP = AO_SUM_DIGITS - 1 };
static const int64_t NORMALIZE_EVERY = (int64_t)1 << 28;
static const uint64_t LOW = 0xffffffffu;

void ao_sum_add(struct ao_sum *s, double x)
{
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    unsigned exponent = (unsigned)(bits >> 52) & 0x7ffu;
    uint64_t m = bits & ((UINT64_C(1) << 52) - 1);
    if (exponent == 0x7ffu) { /* inf or NaN */
        if (m)
            s->nan++;
        else
            s->infinite[bits >> 63]++;
        return;
    }
    if (exponent == 0 && m == 0)
        return;
    /* normal: m 2^52 + mantissa at p = exponent - 1; subnormal: the mantissa at p = 0 */
    int p = exponent ? (int)exponent - 1 : 0;
    if (exponent)
        m |= UINT64_C(1) << 52;
    int d = p / 32, shift = p % 32;
    uint64_t lo = (m & LOW) << shift, hi = (m >> 32) << shift;
    int64_t c0 = (int64_t)(lo & LOW), c1 = (int64_t)((lo >> 32) + (hi & LOW)), c2 = (int64_t)(hi >> 32);
    if (bits >> 63) {
        s->digit[d] -= c0;
        s->digit[d + 1] -= c1;
        s->digit[d + 2] -= c2;
    } else {
        s->digit[d] += c0;
        s->digit[d + 1] += c1;
        s->digit[d + 2] += c2;
    }
    if (++s->adds >= NORMALIZE_EVERY)
        ao_sum_normalize(s);
}

void ao_sum_merge(struct ao_sum *s, const struct ao_sum *part)
{
    for (int k = 0; k < AO_SUM_DIGITS; k++)
        s->digit[k] += part->digit[k];
    s->infinite[0] += part->infinite[0];
    s->infinite[1] += part->infinite[1];
    s->nan += part->nan;
    /* each digit now holds up to both parts' headroom, and one normalized digit more */
    s->adds += part->adds + 1;
    if (s->adds >= NORMALIZE_EVERY)
        ao_sum_normalize(s);
}

void ao_sum_normalize(struct ao_sum *s)
{
    for (int k = 0; k < TOP; k++) {
        int64_t v = s->digit[k], low = (int64_t)((uint64_t)v & LOW);
        s->digit[k] = low;
        s->digit[k + 1] += (v - low) / ((int64_t)1 << 32); /* exact: v - low is a multiple */
    }
    s->adds = 1; /* the digits below the top are now worth one addend each */
}

/* Bit `p` of a normalized, non-negative sum below its top digit. */
static unsigned bit(const struct ao_sum *s, int p)
{
    return (unsigned)((uint64_t)s->digit[p / 32] >> (p % 32)) & 1u;
}

double ao_sum_value(const struct ao_sum *s)
{
    if (s->nan || (s->infinite[0] && s->infinite[1]))
        return NAN;
    if (s->infinite[0] || s->infinite[1])
        return s->infinite[0] ? INFINITY : -INFINITY;
    struct ao_sum t = *s;
    ao_sum_normalize(&t);
    bool negative = t.digit[TOP] < 0;
    if (negative) { /* the magnitude: negate every digit, normalize again */
        for (int k = 0; k < AO_SUM_DIGITS; k++)
            t.digit[k] = -t.digit[k];
        ao_sum_normalize(&t);
    }
    double sign = negative ? -1.0 : 1.0;
    if (t.digit[TOP] != 0) /* 2^(32 TOP - 1074) = 2^1038 and more */
        return sign * INFINITY;
    int k = TOP - 1;
    while (k >= 0 && t.digit[k] == 0)
        k--;
    if (k < 0)
        return 0.0;
    int top = 32 * k + 31;
    while (!bit(&t, top))
        top--;
    /* The result's lowest bit: 53 bits below the top one, or 2^-1074 (subnormal results). */
    int low = top >= 52 ? top - 52 : 0;
    uint64_t m = 0;
    for (int p = top; p >= low; p--)
        m = m << 1 | bit(&t, p);
    if (low > 0 && bit(&t, low - 1)) { /* round to nearest, ties to even */
        int r = low - 1;
        bool sticky = ((uint64_t)t.digit[r / 32] & ((UINT64_C(1) << (r % 32)) - 1)) != 0;
        for (int j = r / 32 - 1; j >= 0 && !sticky; j--)
            sticky = t.digit[j] != 0;
        if (sticky || (m & 1u))
            m++;
    }
    return sign * ldexp((double)m, low - 1074);
}
