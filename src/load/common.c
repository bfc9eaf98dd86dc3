/* What the mesh loaders share (see load.h): growth arrays, line tokens, numbers, error lines. */
/* Linux's madvise and MADV_HUGEPAGE, which POSIX lacks, for ao_load_advise_huge alone. */
#define _DEFAULT_SOURCE
#include "load/load.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "file.h"

/* Makes room for n more elements; false when memory or size_t runs out. */
bool ao_load_reserve(struct ao_load_array *a, size_t n)
{
    if (n <= a->capacity - a->count)
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
    ao_load_advise_huge(data, want * a->size);
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

/* Prints the load's one error line: "path:line: message", or "path: message" when line is 0. */
void ao_load_report(const char *path, size_t line, const char *format, ...)
{
    char message[512];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    if (line)
        ao_file_report("%s:%zu: %s", path, line, message);
    else
        ao_file_report("%s: %s", path, message);
}

bool ao_load_fits(const struct ao_budget *budget, uint64_t triangles, uint64_t vertices, const char *path,
                  size_t line)
{
    uint64_t charge = ao_budget_mesh(triangles, vertices);
    if (ao_budget_fits(budget, charge))
        return true;
    char why[200];
    ao_budget_explain(budget, charge, why, sizeof why);
    ao_load_report(path, line, "%llu triangles and %llu vertices %s", (unsigned long long)triangles,
                   (unsigned long long)vertices, why);
    return false;
}

bool ao_load_fits_model(const struct ao_budget *budget, uint64_t triangles, uint64_t vertices, uint64_t placements,
                        const char *path)
{
    uint64_t charge = ao_budget_model(triangles, vertices, placements);
    if (ao_budget_fits(budget, charge))
        return true;
    char why[200];
    ao_budget_explain(budget, charge, why, sizeof why);
    ao_load_report(path, 0, "%llu triangles and %llu vertices placed %llu times %s", (unsigned long long)triangles,
                   (unsigned long long)vertices, (unsigned long long)placements, why);
    return false;
}

/* Reports an allocation failure; returns false for the caller to pass on. */
bool ao_load_out_of_memory(const char *path)
{
    ao_load_report(path, 0, "out of memory");
    return false;
}

/* Whitespace inside a line ('\r' too, so CRLF files need no special case). */
bool ao_load_is_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

/* Moves to the next whitespace-separated token of the line; false at its end. */
bool ao_load_next_token(struct ao_load_tokens *t, struct ao_load_span *s)
{
    while (t->p < t->end && ao_load_is_blank(*t->p))
        t->p++;
    if (t->p == t->end)
        return false;
    s->begin = t->p;
    while (t->p < t->end && !ao_load_is_blank(*t->p))
        t->p++;
    s->end = t->p;
    return true;
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

/* Parses a whole token as a number (strtod syntax); false when anything is left over. A token
 * always ends at a blank, a newline, '#' or the text's terminating NUL, where strtod stops. */
bool ao_load_parse_number(struct ao_load_span s, double *out)
{
    char *stop;
    *out = strtod(s.begin, &stop);
    return stop == s.end;
}

/* Parses a whole token as a finite single-precision number. */
bool ao_load_parse_float(struct ao_load_span s, float *out)
{
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

/* The unit vector along (x, y, z) in single precision, or zero when it is zero or not finite.
 * Divided first by its largest component, so that squares neither overflow nor vanish. */
struct ao_vec3 ao_load_unit(double x, double y, double z)
{
    double big = fmax(fabs(x), fmax(fabs(y), fabs(z)));
    if (!(big > 0.0) || !isfinite(x) || !isfinite(y) || !isfinite(z))
        return ao_vec3_make(0.0f, 0.0f, 0.0f);
    x /= big, y /= big, z /= big;
    double length = sqrt(x * x + y * y + z * z);
    return ao_vec3_make((float)(x / length), (float)(y / length), (float)(z / length));
}

/* Advises the whole pages inside [data, data + size) into transparent huge pages, where the system
 * has them (Linux's "madvise" mode) and the array is big enough to gain. */
void ao_load_advise_huge(void *data, size_t size)
{
#ifdef MADV_HUGEPAGE
    uintptr_t page = (uintptr_t)sysconf(_SC_PAGESIZE), start = (uintptr_t)data;
    uintptr_t begin = (start + page - 1) / page * page, end = (start + size) / page * page;
    if (size >= AO_LOAD_HUGE_ARRAY && end > begin)
        madvise((void *)begin, end - begin, MADV_HUGEPAGE);
#else
    (void)data, (void)size;
#endif
}
