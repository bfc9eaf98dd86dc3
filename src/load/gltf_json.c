/* The glTF loader's JSON access (see gltf_reader.h): members, arrays, whole numbers and indices
 * checked as glTF requires, and the reader's error and note lines. */
#include <math.h>
#include <stdarg.h>

#include "gltf_reader.h"
#include "text.h"

/* Reports "path: message" and returns false. */
bool ao_gltf_error(const struct ao_gltf *g, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    ao_text_vreport_at(g->path, 0, format, args);
    va_end(args);
    return false;
}

/* Takes bytes from the scene budget for what the load holds until its end; else reports that
 * `what` would need more than is left. */
bool ao_gltf_take(struct ao_gltf *g, uint64_t bytes, const char *what)
{
    if (ao_budget_take(g->budget, bytes)) {
        g->taken += bytes;
        return true;
    }
    char why[200];
    ao_budget_explain(g->budget, bytes, why, sizeof why);
    return ao_gltf_error(g, "%s would %s", what, why);
}

/* ------------------------------------------------------------------ JSON access */

/* The member key of obj, or NULL when absent (or obj is not an object). */
json_object *ao_gltf_member(json_object *obj, const char *key)
{
    json_object *value = NULL;
    return json_object_is_type(obj, json_type_object) && json_object_object_get_ex(obj, key, &value)
               ? value : NULL;
}

/* The length of array, 0 when it is NULL (absent) or not an array. */
size_t ao_gltf_length(json_object *array)
{
    return json_object_is_type(array, json_type_array) ? json_object_array_length(array) : 0;
}

/* The length of an array member (0 when absent); false when present but not an array. */
bool ao_gltf_array(const struct ao_gltf *g, json_object *obj, const char *key, const char *where,
                         json_object **out, size_t *length)
{
    *out = ao_gltf_member(obj, key);
    *length = 0;
    if (!*out)
        return true;
    if (!json_object_is_type(*out, json_type_array))
        return ao_gltf_error(g, "%s: '%s' is not an array", where, key);
    *length = json_object_array_length(*out);
    return true;
}

/* Reads a whole number in [0, limit] from value (a JSON integer, or a double with no fraction). */
bool ao_gltf_whole(json_object *value, double limit, uint64_t *out)
{
    if (!value || !(json_object_is_type(value, json_type_int) ||
                    json_object_is_type(value, json_type_double)))
        return false;
    double d = json_object_get_double(value);
    if (!(d >= 0.0 && d <= limit && d == floor(d)))
        return false;
    *out = (uint64_t)d;
    return true;
}

/* A whole-number member: *out gets its value, or fallback when absent and not required. */
bool ao_gltf_integer(const struct ao_gltf *g, json_object *obj, const char *key, bool required,
                    uint64_t fallback, double limit, const char *where, uint64_t *out)
{
    json_object *value = ao_gltf_member(obj, key);
    *out = fallback;
    if (!value && !required)
        return true;
    if (!value)
        return ao_gltf_error(g, "%s: no '%s'", where, key);
    return ao_gltf_whole(value, limit, out) ||
           ao_gltf_error(g, "%s: '%s' is not a whole number from 0 to %.0f", where, key, limit);
}

/* An index into an array of count entries. */
bool ao_gltf_index(const struct ao_gltf *g, json_object *obj, const char *key, size_t count,
                         const char *where, size_t *out)
{
    uint64_t value;
    *out = 0;
    if (!ao_gltf_integer(g, obj, key, true, 0, AO_GLTF_MAX_INTEGER, where, &value))
        return false;
    if (value >= count)
        return ao_gltf_error(g, "%s: '%s' %llu is out of range (%zu defined)", where, key,
                          (unsigned long long)value, count);
    *out = (size_t)value;
    return true;
}

/* ------------------------------------------------------------------ accessors */

void ao_gltf_note(struct ao_gltf *g, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    ao_load_vnote(g->note, format, args);
    va_end(args);
}
