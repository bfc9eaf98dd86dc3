/* The PLY reader's header (see ply_reader.h): the format line, the elements and their properties
 * read, the vertex and face elements and the properties aoview uses found, and a binary header's
 * counts checked against the file size before anything is allocated for them; and the reader's
 * error lines. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ply_reader.h"
#include "text.h"

/* Names (classic and sized alias), byte sizes and signedness of the PLY scalar types. */
const struct ply_type_info ao_ply_types[PLY_TYPE_COUNT] = {
    [PLY_INT8] = {"char", "int8", 1, true},
    [PLY_UINT8] = {"uchar", "uint8", 1, false},
    [PLY_INT16] = {"short", "int16", 2, true},
    [PLY_UINT16] = {"ushort", "uint16", 2, false},
    [PLY_INT32] = {"int", "int32", 4, true},
    [PLY_UINT32] = {"uint", "uint32", 4, false},
    [PLY_FLOAT32] = {"float", "float32", 4, false},
    [PLY_FLOAT64] = {"double", "float64", 8, false},
};

bool ao_ply_error(const struct ply_reader *r, const char *format, ...)
{
    /* In a binary body, the element's row where a text one has its line. */
    bool row = r->binary && r->element;
    char place[AO_TEXT_SIZE + 4096];
    if (row)
        snprintf(place, sizeof place, "%s: %.*s %llu", r->path, ao_load_span_length(r->element->name),
                 r->element->name.begin, (unsigned long long)r->row_index);
    va_list args;
    va_start(args, format);
    ao_text_vreport_at(row ? place : r->path, row ? 0 : r->line, format, args);
    va_end(args);
    return false;
}

bool ao_ply_within_budget(const struct ply_reader *r, uint64_t triangles, uint64_t vertices)
{
    uint64_t charge = ao_budget_charge(r->budget, triangles, vertices, 0);
    if (ao_budget_fits(r->budget, charge))
        return true;
    char why[200];
    ao_budget_explain(r->budget, charge, why, sizeof why);
    return ao_ply_error(r, "%llu triangles and %llu vertices %s", (unsigned long long)triangles,
                     (unsigned long long)vertices, why);
}

/* Vertex property names by role. */
static const char *const role_names[ROLE_INDICES] = {NULL, "x", "y", "z", "nx", "ny", "nz"};

/* Takes exactly n more tokens from the line, else reports usage. */
static bool take_tokens(const struct ply_reader *r, struct ao_load_tokens *t,
                        struct ao_load_span *out, size_t n, const char *usage)
{
    struct ao_load_span extra;
    for (size_t i = 0; i < n; i++)
        if (!ao_load_next_token(t, &out[i]))
            return ao_ply_error(r, "expected '%s'", usage);
    return !ao_load_next_token(t, &extra) || ao_ply_error(r, "expected '%s'", usage);
}

/* "format ascii|binary_little_endian 1.0". */
static bool parse_format(struct ply_reader *r, struct ao_load_tokens *t, bool *have_format)
{
    struct ao_load_span s[2];
    if (!take_tokens(r, t, s, 2, "format ascii|binary_little_endian 1.0"))
        return false;
    if (*have_format)
        return ao_ply_error(r, "second format line");
    if (ao_load_span_is(s[0], "binary_big_endian"))
        return ao_ply_error(r, "big-endian binary PLY is not supported; convert it to "
                         "binary_little_endian or ascii");
    if (!ao_load_span_is(s[0], "ascii") && !ao_load_span_is(s[0], "binary_little_endian"))
        return ao_ply_error(r, "unknown PLY format '%.*s'", ao_load_span_length(s[0]), s[0].begin);
    if (!ao_load_span_is(s[1], "1.0"))
        return ao_ply_error(r, "unsupported PLY version '%.*s'", ao_load_span_length(s[1]),
                         s[1].begin);
    r->binary = ao_load_span_is(s[0], "binary_little_endian");
    *have_format = true;
    return true;
}

/* A decimal count without sign, as in "element vertex 8". */
static bool parse_count(struct ao_load_span s, uint64_t *out)
{
    uint64_t value = 0;
    for (const char *p = s.begin; p < s.end; p++) {
        if (*p < '0' || *p > '9' || value > (UINT64_MAX - 9) / 10)
            return false;
        value = value * 10 + (uint64_t)(*p - '0');
    }
    *out = value;
    return s.begin < s.end;
}

/* "element NAME COUNT". */
static bool parse_element(struct ply_reader *r, struct ao_load_tokens *t)
{
    struct ao_load_span s[2];
    if (!take_tokens(r, t, s, 2, "element NAME COUNT"))
        return false;
    struct ply_element *e = ao_load_append(&r->elements, 1);
    if (!e)
        return ao_load_out_of_memory(r->path);
    *e = (struct ply_element){s[0], 0, r->line, r->properties.count, 0};
    return parse_count(s[1], &e->count) ||
           ao_ply_error(r, "bad element count '%.*s'", ao_load_span_length(s[1]), s[1].begin);
}

/* Looks a type name up. */
static bool parse_type(const struct ply_reader *r, struct ao_load_span s, enum ply_type *type)
{
    for (int i = 0; i < PLY_TYPE_COUNT; i++) {
        if (ao_load_span_is(s, ao_ply_types[i].name) || ao_load_span_is(s, ao_ply_types[i].alias)) {
            *type = (enum ply_type)i;
            return true;
        }
    }
    return ao_ply_error(r, "unknown property type '%.*s'", ao_load_span_length(s), s.begin);
}

/* "property TYPE NAME" or "property list COUNT_TYPE ITEM_TYPE NAME". */
static bool parse_property(struct ply_reader *r, struct ao_load_tokens *t)
{
    struct ao_load_span s[4];
    struct ao_load_tokens probe = *t;
    bool is_list = ao_load_next_token(&probe, &s[0]) && ao_load_span_is(s[0], "list");
    if (r->elements.count == 0)
        return ao_ply_error(r, "property before any element");
    if (is_list ? !take_tokens(r, t, s, 4, "property list COUNT_TYPE ITEM_TYPE NAME")
                : !take_tokens(r, t, s + 2, 2, "property TYPE NAME"))
        return false;
    struct ply_property p = {s[3], is_list, PLY_UINT8, PLY_UINT8, ROLE_NONE};
    if ((is_list && !parse_type(r, s[1], &p.count_type)) || !parse_type(r, s[2], &p.type))
        return false;
    struct ply_property *slot = ao_load_append(&r->properties, 1);
    if (!slot)
        return ao_load_out_of_memory(r->path);
    *slot = p;
    ao_ply_element(r, r->elements.count - 1)->property_count++;
    return true;
}

/* One header line after "ply"; sets *done at "end_header". */
static bool parse_header_line(struct ply_reader *r, struct ao_load_tokens *t, bool *have_format,
                              bool *done)
{
    struct ao_load_span keyword;
    if (!ao_load_next_token(t, &keyword) || ao_load_span_is(keyword, "comment") ||
        ao_load_span_is(keyword, "obj_info"))
        return true;
    if (ao_load_span_is(keyword, "format"))
        return parse_format(r, t, have_format);
    if (ao_load_span_is(keyword, "element"))
        return parse_element(r, t);
    if (ao_load_span_is(keyword, "property"))
        return parse_property(r, t);
    if (ao_load_span_is(keyword, "end_header")) {
        *done = true;
        return take_tokens(r, t, NULL, 0, "end_header") &&
               (*have_format || ao_ply_error(r, "no format line before end_header"));
    }
    return ao_ply_error(r, "unknown header keyword '%.*s'", ao_load_span_length(keyword),
                     keyword.begin);
}

/* The header, from "ply" to "end_header"; leaves r->cur at the first data byte. */
bool ao_ply_parse_header(struct ply_reader *r, const char *text, size_t size)
{
    const char *end = text + size, *line = text;
    bool have_format = false, done = false;
    while (!done) {
        if (line == end)
            return ao_ply_error(r, r->line ? "header ends without end_header" : "empty file");
        const char *newline = memchr(line, '\n', (size_t)(end - line));
        struct ao_load_tokens t = {line, newline ? newline : end};
        struct ao_load_span magic;
        line = newline ? newline + 1 : end;
        if (++r->line == 1) {
            if (!ao_load_next_token(&t, &magic) || !ao_load_span_is(magic, "ply") ||
                ao_load_next_token(&t, &magic))
                return ao_ply_error(r, "not a PLY file (no 'ply' first line)");
        } else if (!parse_header_line(r, &t, &have_format, &done)) {
            return false;
        }
    }
    r->cur = line;
    r->end = end;
    r->data_line = r->line;
    return true;
}

/* Finds the element named name; reports a second one. */
static bool find_element(struct ply_reader *r, const char *name, size_t *index)
{
    *index = SIZE_MAX;
    for (size_t i = 0; i < r->elements.count; i++) {
        if (!ao_load_span_is(ao_ply_element(r, i)->name, name))
            continue;
        if (*index != SIZE_MAX) {
            r->line = ao_ply_element(r, i)->line;
            return ao_ply_error(r, "second '%s' element", name);
        }
        *index = i;
    }
    r->line = 0;
    return *index != SIZE_MAX || ao_ply_error(r, "no '%s' element in the header", name);
}

/* Gives the property of element e named name the role, checking it is unique and scalar or list
 * as required; *found counts the roles given. */
static bool assign_role(struct ply_reader *r, const struct ply_element *e, const char *name,
                        enum ply_role role, bool list, int *found)
{
    bool seen = false;
    r->line = e->line;
    for (size_t i = e->first; i < e->first + e->property_count; i++) {
        struct ply_property *p = ao_ply_property(r, i);
        if (!ao_load_span_is(p->name, name))
            continue;
        if (seen)
            return ao_ply_error(r, "element '%.*s' has two '%s' properties",
                             ao_load_span_length(e->name), e->name.begin, name);
        if (p->is_list != list)
            return ao_ply_error(r, "property '%s' must be a %s", name, list ? "list" : "scalar");
        p->role = role;
        seen = true;
    }
    *found += seen;
    return true;
}

/* Finds the vertex and face elements and the properties the loader uses. */
bool ao_ply_assign_roles(struct ply_reader *r)
{
    int positions = 0, normals = 0, indices = 0;
    if (!find_element(r, "vertex", &r->vertex_element) ||
        !find_element(r, "face", &r->face_element))
        return false;
    const struct ply_element *vertex = ao_ply_element(r, r->vertex_element);
    const struct ply_element *face = ao_ply_element(r, r->face_element);
    for (int role = ROLE_X; role < ROLE_INDICES; role++)
        if (!assign_role(r, vertex, role_names[role], role, false,
                         role < ROLE_NX ? &positions : &normals))
            return false;
    if (!assign_role(r, face, "vertex_indices", ROLE_INDICES, true, &indices) ||
        !assign_role(r, face, "vertex_index", ROLE_INDICES, true, &indices))
        return false;
    r->line = vertex->line;
    if (positions != 3)
        return ao_ply_error(r, "vertex element needs x, y and z properties");
    if (normals != 0 && normals != 3)
        return ao_ply_error(r, "vertex normals need all of nx, ny and nz");
    if (vertex->count >= AO_LOAD_NO_INDEX)
        return ao_ply_error(r, "%llu vertices are too many for 32-bit indices",
                         (unsigned long long)vertex->count);
    r->line = face->line;
    if (indices != 1)
        return ao_ply_error(r, "face element needs one list property vertex_indices");
    r->has_normals = normals == 3;
    return true;
}

/* Binary files: refuses a header whose rows cannot fit in the bytes after it, before anything
 * is allocated for them (a 100-byte file may claim 4 billion vertices). */
bool ao_ply_check_binary_size(struct ply_reader *r)
{
    uint64_t left = (uint64_t)(r->end - r->cur);
    for (size_t i = 0; i < r->elements.count; i++) {
        const struct ply_element *e = ao_ply_element(r, i);
        uint64_t row = 0;
        for (size_t j = e->first; j < e->first + e->property_count; j++) {
            const struct ply_property *p = ao_ply_property(r, j);
            row += ao_ply_types[p->is_list ? p->count_type : p->type].size;
        }
        if (row && e->count > left / row) {
            r->line = e->line;
            return ao_ply_error(r, "element '%.*s' declares %llu rows of at least %llu bytes, but "
                             "only %llu bytes of data remain in the file",
                             ao_load_span_length(e->name), e->name.begin,
                             (unsigned long long)e->count, (unsigned long long)row,
                             (unsigned long long)left);
        }
        left -= e->count * row;
    }
    /* The counts are real: they fit in the file. A face is at least one triangle. */
    r->line = 0;
    return ao_ply_within_budget(r, ao_ply_element(r, r->face_element)->count,
                                ao_ply_element(r, r->vertex_element)->count);
}
