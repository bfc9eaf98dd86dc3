/* What the mesh loaders share (see loader.h): growth arrays, line tokens, numbers, error lines. */
#include "loader.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "file.h"
#include "text.h"

/* Makes room for n more elements (storage exists after any call, even for n = 0, so that no null
 * pointer meets an offset); false when memory or size_t runs out. */
bool ao_load_reserve(struct ao_load_array *a, size_t n)
{
    if (a->data && n <= a->capacity - a->count)
        return true;
    size_t want = a->capacity ? a->capacity : 64;
    while (want - a->count < n) {
        if (want > SIZE_MAX / 2 / a->size)
            return false;
        want *= 2;
    }
    unsigned char *data = realloc(a->data, want * a->size);
    if (!data)
        return false;
    a->data = data;
    a->capacity = want;
    ao_mesh_advise_huge(data, want * a->size);
    return true;
}

/* Appends n elements and returns the first, or NULL when memory or size_t runs out. */
void *ao_load_append(struct ao_load_array *a, size_t n)
{
    if (!ao_load_reserve(a, n))
        return NULL;
    void *first = a->data + a->count * a->size;
    a->count += n;
    return first;
}

/* Hands the array's storage to the caller (who frees it) and empties the array. */
void *ao_load_take(struct ao_load_array *a)
{
    void *data = a->data;
    a->data = NULL;
    a->count = a->capacity = 0;
    return data;
}

/* Frees the array's storage. */
void ao_load_free(struct ao_load_array *a)
{
    free(ao_load_take(a));
}

bool ao_load_fits_model(const struct ao_budget *budget, uint64_t triangles, uint64_t vertices, uint64_t placements,
                        const char *path)
{
    uint64_t charge = ao_budget_charge(budget, triangles, vertices, placements);
    if (ao_budget_fits(budget, charge))
        return true;
    char why[200], placed[48] = "";
    ao_budget_explain(budget, charge, why, sizeof why);
    if (placements != 1) /* a model placed once is just its triangles */
        snprintf(placed, sizeof placed, " placed %llu times", (unsigned long long)placements);
    ao_text_report_at(path, 0, "%llu triangles and %llu vertices%s %s", (unsigned long long)triangles,
                   (unsigned long long)vertices, placed, why);
    return false;
}

void ao_load_vnote(char *note, const char *format, va_list args)
{
    size_t used = strlen(note);
    if (used + 4 >= AO_MESH_NOTE_SIZE)
        return;
    if (used)
        used += (size_t)snprintf(note + used, AO_MESH_NOTE_SIZE - used, "; ");
    if (vsnprintf(note + used, AO_MESH_NOTE_SIZE - used, format, args) < 0)
        note[used] = '\0';
}

/* Reports an allocation failure; returns false for the caller to pass on. */
bool ao_load_out_of_memory(const char *path)
{
    ao_text_report_at(path, 0, "out of memory");
    return false;
}

/* The blanks of ao_load_is_blank as bits of a mask indexed by character. */
#define BLANKS ((uint64_t)1 << ' ' | 1u << '\t' | 1u << '\r' | 1u << '\f' | 1u << '\v')

/* Whitespace inside a line ('\r' too, so CRLF files need no special case). */
bool ao_load_is_blank(char c)
{
    return (unsigned char)c <= ' ' && (BLANKS >> (unsigned char)c & 1);
}

/* Moves to the next whitespace-separated token of the line; false at its end. */
bool ao_load_next_token(struct ao_load_tokens *t, struct ao_load_span *s)
{
    const char *p = t->p, *end = t->end;
    while (p < end && ao_load_is_blank(*p))
        p++;
    s->begin = p;
    while (p < end && !ao_load_is_blank(*p))
        p++;
    s->end = t->p = p;
    return s->begin < p;
}

/* True when the token is exactly word. */
bool ao_load_span_is(struct ao_load_span s, const char *word)
{
    size_t n = strlen(word);
    return (size_t)(s.end - s.begin) == n && memcmp(s.begin, word, n) == 0;
}

/* Token length for "%.*s" in messages, capped so one bad token cannot flood the line. */
int ao_load_span_length(struct ao_load_span s)
{
    ptrdiff_t n = s.end - s.begin;
    return n < 40 ? (int)n : 40;
}

/* Reads a token of the form [+-]digits[.digits][(e|E)[+-]digits] (digits on at least one side of
 * the point) of at most 19 significant digits as sign, mantissa and power of ten; false for every
 * other token (strtod's other forms, longer mantissas, exponents past 9999, errors), which the
 * callers hand to strtod. */
static bool simple_decimal(struct ao_load_span s, bool *negative, uint64_t *mantissa, int *power)
{
    const char *p = s.begin;
    int digits = 0, scale = 0, exponent = 0;
    bool any = false, point = false, minus = false;
    uint64_t m = 0;
    *negative = p < s.end && *p == '-';
    p += p < s.end && (*p == '-' || *p == '+');
    for (; p < s.end; p++) {
        if (*p == '.' && !point) {
            point = true;
            continue;
        }
        if (*p < '0' || *p > '9')
            break;
        any = true;
        scale -= point;
        if (m == 0 && *p == '0')
            continue;
        if (++digits > 19)
            return false;
        m = m * 10 + (uint64_t)(*p - '0');
    }
    if (!any)
        return false;
    if (p < s.end && (*p == 'e' || *p == 'E')) {
        p++;
        minus = p < s.end && *p == '-';
        p += p < s.end && (*p == '-' || *p == '+');
        if (p == s.end || *p < '0' || *p > '9')
            return false;
        for (; p < s.end && *p >= '0' && *p <= '9'; p++)
            if ((exponent = exponent * 10 + (*p - '0')) > 9999)
                return false;
    }
    *mantissa = m;
    *power = scale + (minus ? -exponent : exponent);
    return p == s.end;
}

/* The value of a simple_decimal token, correctly rounded to double (Clinger 1990: the mantissa
 * below 2^53 and 10^|power| up to 10^22 are exact doubles, so one product or quotient rounds once);
 * false when the token is not one whose value this computes so. */
static bool fast_double(struct ao_load_span s, double *out)
{
    static const double tens[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                     1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    bool negative;
    uint64_t m;
    int power;
    if (!simple_decimal(s, &negative, &m, &power) || m > (uint64_t)1 << 53 || power < -22 || power > 22)
        return false;
    double value = power < 0 ? (double)m / tens[-power] : (double)m * tens[power];
    *out = negative ? -value : value;
    return true;
}

/* Parses a whole token as a number (strtod syntax); false when anything is left over. A token
 * always ends at a blank, a newline, '#' or the text's terminating NUL, where strtod stops. Most
 * tokens a file holds are read by fast_double, as strtod would read them; others by strtod. */
bool ao_load_parse_number(struct ao_load_span s, double *out)
{
    if (fast_double(s, out))
        return true;
    char *stop;
    *out = strtod(s.begin, &stop);
    return stop == s.end;
}

/* Parses a whole token as a finite single-precision number: through fast_double, whose one
 * rounding to double and then to float is the single rounding strtof makes unless the double
 * lies exactly halfway between two floats (the only double the second rounding can get wrong, the
 * nearest double to a value being nearer than any halfway point) or among the subnormal floats;
 * those and other tokens go to strtof. */
bool ao_load_parse_float(struct ao_load_span s, float *out)
{
    double d;
    uint64_t bits;
    if (fast_double(s, &d) && (d == 0.0 || fabs(d) >= FLT_MIN)) {
        memcpy(&bits, &d, sizeof bits);
        if ((bits & 0x1fffffffu) != 0x10000000u) {
            *out = (float)d;
            return isfinite(*out);
        }
    }
    char *stop;
    *out = strtof(s.begin, &stop);
    return stop == s.end && isfinite(*out);
}

/* Appends the fan triangulation (v0, vi, vi+1) of the polygon face (elements of any size, at
 * least 3) to triangles. */
bool ao_load_fan(struct ao_load_array *triangles, const struct ao_load_array *face)
{
    size_t size = face->size;
    unsigned char *out = ao_load_append(triangles, 3 * (face->count - 2));
    if (!out)
        return false;
    for (size_t i = 1; i + 1 < face->count; i++, out += 3 * size) {
        memcpy(out, face->data, size);
        memcpy(out + size, face->data + i * size, 2 * size);
    }
    return true;
}
