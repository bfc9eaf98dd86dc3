/* PLY: ascii and binary little endian; x y z and optional nx ny nz vertex properties, face
 * vertex_indices lists (polygons fanned). A binary header's counts are checked against the file
 * size before anything is allocated for them. Errors name the line (header, ascii) or the
 * element row (binary). */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loader.h"

/* PLY scalar types, indexing ply_types. */
enum ply_type { PLY_INT8, PLY_UINT8, PLY_INT16, PLY_UINT16, PLY_INT32, PLY_UINT32, PLY_FLOAT32,
                PLY_FLOAT64, PLY_TYPE_COUNT };

/* Names (classic and sized alias), byte sizes and signedness of the PLY scalar types. */
static const struct {
    const char *name, *alias;
    unsigned size;
    bool is_signed_int;
} ply_types[PLY_TYPE_COUNT] = {
    [PLY_INT8] = {"char", "int8", 1, true},
    [PLY_UINT8] = {"uchar", "uint8", 1, false},
    [PLY_INT16] = {"short", "int16", 2, true},
    [PLY_UINT16] = {"ushort", "uint16", 2, false},
    [PLY_INT32] = {"int", "int32", 4, true},
    [PLY_UINT32] = {"uint", "uint32", 4, false},
    [PLY_FLOAT32] = {"float", "float32", 4, false},
    [PLY_FLOAT64] = {"double", "float64", 8, false},
};

/* What the loader does with a property's values. */
enum ply_role { ROLE_NONE, ROLE_X, ROLE_Y, ROLE_Z, ROLE_NX, ROLE_NY, ROLE_NZ, ROLE_INDICES,
                ROLE_COUNT };

/* Vertex property names by role. */
static const char *const role_names[ROLE_INDICES] = {NULL, "x", "y", "z", "nx", "ny", "nz"};

/* One "property" header line. */
struct ply_property {
    struct ao_load_span name;
    bool is_list;
    enum ply_type count_type;   /* lists only */
    enum ply_type type;         /* of the value, or of each list item */
    enum ply_role role;
};

/* One "element" header line and its properties properties[first, first + property_count). */
struct ply_element {
    struct ao_load_span name;
    uint64_t count;
    size_t line;
    size_t first, property_count;
};

/* A PLY file being read: the header's declarations and the cursor in the data. */
struct ply_reader {
    const char *path;
    bool binary;
    struct ao_load_array elements;     /* struct ply_element */
    struct ao_load_array properties;   /* struct ply_property */
    size_t vertex_element, face_element;  /* indices into elements, SIZE_MAX when absent */
    bool has_normals;
    size_t invalid_normals;       /* vertices whose normal is zero or not finite */
    const char *cur, *end;     /* unread data */
    size_t line;               /* header or ascii data line */
    size_t data_line;          /* the end_header line */
    struct ao_load_tokens row;         /* ascii: the rest of the current row's line */
    const struct ply_element *element;  /* element being read, NULL in the header */
    uint64_t row_index;
    struct ao_load_array positions, normals;    /* struct ao_vec3 */
    struct ao_load_array face, indices;         /* uint32_t */
    const struct ao_budget *budget;
};

/* The reader's one error line, located by line (header, ascii) or element row (binary). */
static bool ply_error(const struct ply_reader *r, const char *format, ...)
{
    char message[400];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    if (r->binary && r->element)
        ao_load_report(r->path, 0, "%.*s %llu: %s", ao_load_span_length(r->element->name),
                       r->element->name.begin, (unsigned long long)r->row_index, message);
    else
        ao_load_report(r->path, r->line, "%s", message);
    return false;
}

/* True when so many triangles and vertices fit in the budget; else reports where the reader is. */
static bool within_budget(const struct ply_reader *r, uint64_t triangles, uint64_t vertices)
{
    uint64_t charge = ao_budget_charge(r->budget, triangles, vertices, 0);
    if (ao_budget_fits(r->budget, charge))
        return true;
    char why[200];
    ao_budget_explain(r->budget, charge, why, sizeof why);
    return ply_error(r, "%llu triangles and %llu vertices %s", (unsigned long long)triangles,
                     (unsigned long long)vertices, why);
}

/* The element at index i. */
static struct ply_element *element_at(const struct ply_reader *r, size_t i)
{
    return (struct ply_element *)r->elements.data + i;
}

/* The property at index i. */
static struct ply_property *property_at(const struct ply_reader *r, size_t i)
{
    return (struct ply_property *)r->properties.data + i;
}

/* Takes exactly n more tokens from the line, else reports usage. */
static bool take_tokens(const struct ply_reader *r, struct ao_load_tokens *t,
                        struct ao_load_span *out, size_t n, const char *usage)
{
    struct ao_load_span extra;
    for (size_t i = 0; i < n; i++)
        if (!ao_load_next_token(t, &out[i]))
            return ply_error(r, "expected '%s'", usage);
    return !ao_load_next_token(t, &extra) || ply_error(r, "expected '%s'", usage);
}

/* "format ascii|binary_little_endian 1.0". */
static bool parse_format(struct ply_reader *r, struct ao_load_tokens *t, bool *have_format)
{
    struct ao_load_span s[2];
    if (!take_tokens(r, t, s, 2, "format ascii|binary_little_endian 1.0"))
        return false;
    if (*have_format)
        return ply_error(r, "second format line");
    if (ao_load_span_is(s[0], "binary_big_endian"))
        return ply_error(r, "big-endian binary PLY is not supported; convert it to "
                         "binary_little_endian or ascii");
    if (!ao_load_span_is(s[0], "ascii") && !ao_load_span_is(s[0], "binary_little_endian"))
        return ply_error(r, "unknown PLY format '%.*s'", ao_load_span_length(s[0]), s[0].begin);
    if (!ao_load_span_is(s[1], "1.0"))
        return ply_error(r, "unsupported PLY version '%.*s'", ao_load_span_length(s[1]),
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
           ply_error(r, "bad element count '%.*s'", ao_load_span_length(s[1]), s[1].begin);
}

/* Looks a type name up. */
static bool parse_type(const struct ply_reader *r, struct ao_load_span s, enum ply_type *type)
{
    for (int i = 0; i < PLY_TYPE_COUNT; i++) {
        if (ao_load_span_is(s, ply_types[i].name) || ao_load_span_is(s, ply_types[i].alias)) {
            *type = (enum ply_type)i;
            return true;
        }
    }
    return ply_error(r, "unknown property type '%.*s'", ao_load_span_length(s), s.begin);
}

/* "property TYPE NAME" or "property list COUNT_TYPE ITEM_TYPE NAME". */
static bool parse_property(struct ply_reader *r, struct ao_load_tokens *t)
{
    struct ao_load_span s[4];
    struct ao_load_tokens probe = *t;
    bool is_list = ao_load_next_token(&probe, &s[0]) && ao_load_span_is(s[0], "list");
    if (r->elements.count == 0)
        return ply_error(r, "property before any element");
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
    element_at(r, r->elements.count - 1)->property_count++;
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
               (*have_format || ply_error(r, "no format line before end_header"));
    }
    return ply_error(r, "unknown header keyword '%.*s'", ao_load_span_length(keyword),
                     keyword.begin);
}

/* The header, from "ply" to "end_header"; leaves r->cur at the first data byte. */
static bool parse_ply_header(struct ply_reader *r, const char *text, size_t size)
{
    const char *end = text + size, *line = text;
    bool have_format = false, done = false;
    while (!done) {
        if (line == end)
            return ply_error(r, r->line ? "header ends without end_header" : "empty file");
        const char *newline = memchr(line, '\n', (size_t)(end - line));
        struct ao_load_tokens t = {line, newline ? newline : end};
        struct ao_load_span magic;
        line = newline ? newline + 1 : end;
        if (++r->line == 1) {
            if (!ao_load_next_token(&t, &magic) || !ao_load_span_is(magic, "ply") ||
                ao_load_next_token(&t, &magic))
                return ply_error(r, "not a PLY file (no 'ply' first line)");
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
        if (!ao_load_span_is(element_at(r, i)->name, name))
            continue;
        if (*index != SIZE_MAX) {
            r->line = element_at(r, i)->line;
            return ply_error(r, "second '%s' element", name);
        }
        *index = i;
    }
    r->line = 0;
    return *index != SIZE_MAX || ply_error(r, "no '%s' element in the header", name);
}

/* Gives the property of element e named name the role, checking it is unique and scalar or list
 * as required; *found counts the roles given. */
static bool assign_role(struct ply_reader *r, const struct ply_element *e, const char *name,
                        enum ply_role role, bool list, int *found)
{
    bool seen = false;
    r->line = e->line;
    for (size_t i = e->first; i < e->first + e->property_count; i++) {
        struct ply_property *p = property_at(r, i);
        if (!ao_load_span_is(p->name, name))
            continue;
        if (seen)
            return ply_error(r, "element '%.*s' has two '%s' properties",
                             ao_load_span_length(e->name), e->name.begin, name);
        if (p->is_list != list)
            return ply_error(r, "property '%s' must be a %s", name, list ? "list" : "scalar");
        p->role = role;
        seen = true;
    }
    *found += seen;
    return true;
}

/* Finds the vertex and face elements and the properties the loader uses. */
static bool assign_roles(struct ply_reader *r)
{
    int positions = 0, normals = 0, indices = 0;
    if (!find_element(r, "vertex", &r->vertex_element) ||
        !find_element(r, "face", &r->face_element))
        return false;
    const struct ply_element *vertex = element_at(r, r->vertex_element);
    const struct ply_element *face = element_at(r, r->face_element);
    for (int role = ROLE_X; role < ROLE_INDICES; role++)
        if (!assign_role(r, vertex, role_names[role], role, false,
                         role < ROLE_NX ? &positions : &normals))
            return false;
    if (!assign_role(r, face, "vertex_indices", ROLE_INDICES, true, &indices) ||
        !assign_role(r, face, "vertex_index", ROLE_INDICES, true, &indices))
        return false;
    r->line = vertex->line;
    if (positions != 3)
        return ply_error(r, "vertex element needs x, y and z properties");
    if (normals != 0 && normals != 3)
        return ply_error(r, "vertex normals need all of nx, ny and nz");
    if (vertex->count >= AO_LOAD_NO_INDEX)
        return ply_error(r, "%llu vertices are too many for 32-bit indices",
                         (unsigned long long)vertex->count);
    r->line = face->line;
    if (indices != 1)
        return ply_error(r, "face element needs one list property vertex_indices");
    r->has_normals = normals == 3;
    return true;
}

/* Binary files: refuses a header whose rows cannot fit in the bytes after it, before anything
 * is allocated for them (a 100-byte file may claim 4 billion vertices). */
static bool check_binary_size(struct ply_reader *r)
{
    uint64_t left = (uint64_t)(r->end - r->cur);
    for (size_t i = 0; i < r->elements.count; i++) {
        const struct ply_element *e = element_at(r, i);
        uint64_t row = 0;
        for (size_t j = e->first; j < e->first + e->property_count; j++) {
            const struct ply_property *p = property_at(r, j);
            row += ply_types[p->is_list ? p->count_type : p->type].size;
        }
        if (row && e->count > left / row) {
            r->line = e->line;
            return ply_error(r, "element '%.*s' declares %llu rows of at least %llu bytes, but "
                             "only %llu bytes of data remain in the file",
                             ao_load_span_length(e->name), e->name.begin,
                             (unsigned long long)e->count, (unsigned long long)row,
                             (unsigned long long)left);
        }
        left -= e->count * row;
    }
    /* The counts are real: they fit in the file. A face is at least one triangle. */
    r->line = 0;
    return within_budget(r, element_at(r, r->face_element)->count, element_at(r, r->vertex_element)->count);
}

/* Decodes the little-endian bytes of one value of a PLY type. */
static double decode(enum ply_type type, const unsigned char *bytes)
{
    unsigned size = ply_types[type].size;
    uint64_t bits = 0;
    for (unsigned i = size; i-- > 0;)
        bits = bits << 8 | bytes[i];
    if (type == PLY_FLOAT32) {
        uint32_t word = (uint32_t)bits;
        float f;
        memcpy(&f, &word, sizeof f);
        return f;
    }
    if (type == PLY_FLOAT64) {
        double d;
        memcpy(&d, &bits, sizeof d);
        return d;
    }
    double value = (double)bits;
    if (ply_types[type].is_signed_int && bits >> (8 * size - 1))
        value -= ldexp(1.0, (int)(8 * size));
    return value;
}

/* Reads one value of the given type (binary), or the row's next number (ascii). */
static bool read_value(struct ply_reader *r, enum ply_type type, double *out)
{
    struct ao_load_span s;
    if (r->binary) {
        if ((size_t)(r->end - r->cur) < ply_types[type].size)
            return ply_error(r, "unexpected end of file");
        *out = decode(type, (const unsigned char *)r->cur);
        r->cur += ply_types[type].size;
        return true;
    }
    if (!ao_load_next_token(&r->row, &s))
        return ply_error(r, "too few values for a '%.*s' row", ao_load_span_length(r->element->name),
                         r->element->name.begin);
    return ao_load_parse_number(s, out) ||
           ply_error(r, "bad number '%.*s'", ao_load_span_length(s), s.begin);
}

/* Ascii: moves to the next non-blank line, which holds one row. */
static bool begin_row(struct ply_reader *r)
{
    struct ao_load_span s;
    struct ao_load_tokens probe;
    if (r->binary)
        return true;
    do {
        if (r->cur == r->end)
            return ply_error(r, "unexpected end of file: '%.*s' declares %llu rows, found %llu",
                             ao_load_span_length(r->element->name), r->element->name.begin,
                             (unsigned long long)r->element->count,
                             (unsigned long long)r->row_index);
        const char *newline = memchr(r->cur, '\n', (size_t)(r->end - r->cur));
        r->row = (struct ao_load_tokens){r->cur, newline ? newline : r->end};
        r->cur = newline ? newline + 1 : r->end;
        r->line++;
        probe = r->row;
    } while (!ao_load_next_token(&probe, &s));
    return true;
}

/* Ascii: the row's line must hold nothing more. */
static bool end_row(struct ply_reader *r)
{
    struct ao_load_span s;
    return r->binary || !ao_load_next_token(&r->row, &s) ||
           ply_error(r, "more values than the header declares for a '%.*s' row",
                     ao_load_span_length(r->element->name), r->element->name.begin);
}

/* A vertex index from a face list: integral and below the declared vertex count. */
static bool add_index(struct ply_reader *r, double value)
{
    uint64_t vertices = element_at(r, r->vertex_element)->count;
    if (!(value >= 0.0 && value < (double)vertices && value == floor(value)))
        return ply_error(r, "vertex index %.17g is not an integer in [0, %llu)", value,
                         (unsigned long long)vertices);
    uint32_t *slot = ao_load_append(&r->face, 1);
    if (!slot)
        return ao_load_out_of_memory(r->path);
    *slot = (uint32_t)value;
    return true;
}

/* A list property: its count, then the items (vertex indices kept, others skipped). */
static bool read_list(struct ply_reader *r, const struct ply_property *p)
{
    double count, item;
    if (!read_value(r, p->count_type, &count))
        return false;
    if (!(count >= 0.0 && count <= UINT32_MAX && count == floor(count)))
        return ply_error(r, "bad list count %.17g", count);
    if (r->binary && count > (double)((size_t)(r->end - r->cur) / ply_types[p->type].size))
        return ply_error(r, "list of %.0f items runs past the end of the file", count);
    if (p->role == ROLE_INDICES && count > AO_LOAD_MAX_FACE_VERTICES)
        return ply_error(r, "face with %.0f vertices (more than %d)", count,
                         AO_LOAD_MAX_FACE_VERTICES);
    for (uint32_t i = 0; i < (uint32_t)count; i++)
        if (!read_value(r, p->type, &item) || (p->role == ROLE_INDICES && !add_index(r, item)))
            return false;
    return true;
}

/* One row of element e: scalar values by role into values, face indices into r->face. */
static bool read_row(struct ply_reader *r, const struct ply_element *e, double values[ROLE_COUNT])
{
    if (!begin_row(r))
        return false;
    for (size_t i = e->first; i < e->first + e->property_count; i++) {
        const struct ply_property *p = property_at(r, i);
        if (p->is_list ? !read_list(r, p) : !read_value(r, p->type, &values[p->role]))
            return false;
    }
    return end_row(r);
}

/* Stores a vertex row: a finite position and, when present, a normal (normalized; a zero or
 * non-finite one stored missing and counted). */
static bool add_vertex(struct ply_reader *r, const double v[ROLE_COUNT])
{
    if (!within_budget(r, r->indices.count / 3, r->positions.count + 1))
        return false;
    struct ao_vec3 p = ao_vec3_make((float)v[ROLE_X], (float)v[ROLE_Y], (float)v[ROLE_Z]);
    if (!ao_vec3_is_finite(p))
        return ply_error(r, "vertex position is not a finite float");
    struct ao_vec3 *slot = ao_load_append(&r->positions, 1);
    if (!slot)
        return ao_load_out_of_memory(r->path);
    *slot = p;
    if (!r->has_normals)
        return true;
    if (!(slot = ao_load_append(&r->normals, 1)))
        return ao_load_out_of_memory(r->path);
    *slot = ao_mesh_given_normal(v[ROLE_NX], v[ROLE_NY], v[ROLE_NZ], &r->invalid_normals);
    return true;
}

/* Stores a face row's polygon as a triangle fan. */
static bool add_face(struct ply_reader *r)
{
    if (r->face.count < 3)
        return ply_error(r, "face with %zu vertices; at least 3 needed", r->face.count);
    if (!within_budget(r, r->indices.count / 3 + r->face.count - 2, r->positions.count))
        return false;
    return ao_load_fan(&r->indices, &r->face) || ao_load_out_of_memory(r->path);
}

/* True on a little-endian host, where a binary PLY's values can be copied as they lie. */
static bool host_is_little_endian(void)
{
    const uint16_t one = 1;
    unsigned char first;
    memcpy(&first, &one, 1);
    return first == 1;
}

/* Binary vertex rows of fixed size (every property a scalar) whose position and normal
 * properties are floats: their byte offsets by role and the row size, for read_vertex_rows;
 * false for other rows, which read_row reads. */
static bool fixed_vertex_rows(const struct ply_reader *r, const struct ply_element *e,
                              size_t offset[ROLE_COUNT], size_t *row)
{
    *row = 0;
    for (size_t i = e->first; i < e->first + e->property_count; i++) {
        const struct ply_property *p = property_at(r, i);
        if (p->is_list || (p->role != ROLE_NONE && p->type != PLY_FLOAT32))
            return false;
        offset[p->role] = *row;
        *row += ply_types[p->type].size;
    }
    return r->binary && host_is_little_endian();
}

/* The vertex element's rows as fixed_vertex_rows describes them, straight from the bytes into
 * the positions and normals, with read_row and add_vertex's checks and messages. */
static bool read_vertex_rows(struct ply_reader *r, const size_t offset[ROLE_COUNT], size_t row)
{
    size_t count = (size_t)r->element->count, fit = (size_t)(r->end - r->cur) / row;
    /* The header's counts were checked; faces read before the vertices may have fanned further. */
    r->row_index = 0;
    if (!within_budget(r, r->indices.count / 3, count))
        return false;
    struct ao_vec3 *p = ao_load_append(&r->positions, count);
    struct ao_vec3 *n = r->has_normals ? ao_load_append(&r->normals, count) : NULL;
    if ((count && !p) || (r->has_normals && count && !n))
        return ao_load_out_of_memory(r->path);
    const unsigned char *bytes = (const unsigned char *)r->cur;
    for (size_t i = 0; i < count; i++, bytes += row) {
        float f[ROLE_COUNT];
        r->row_index = i;
        if (i == fit)
            return ply_error(r, "unexpected end of file");
        for (int role = ROLE_X; role <= (r->has_normals ? ROLE_NZ : ROLE_Z); role++)
            memcpy(&f[role], bytes + offset[role], sizeof f[role]);
        p[i] = ao_vec3_make(f[ROLE_X], f[ROLE_Y], f[ROLE_Z]);
        if (!ao_vec3_is_finite(p[i]))
            return ply_error(r, "vertex position is not a finite float");
        if (!n)
            continue;
        n[i] = ao_mesh_given_normal(f[ROLE_NX], f[ROLE_NY], f[ROLE_NZ], &r->invalid_normals);
    }
    r->cur = (const char *)bytes;
    return true;
}

/* Binary face rows of the common form: the one property a list of uchar count and int or uint
 * indices; for read_face_rows. */
static bool plain_face_rows(const struct ply_reader *r, const struct ply_element *e)
{
    const struct ply_property *p = property_at(r, e->first);
    return r->binary && host_is_little_endian() && e->property_count == 1 && p->count_type == PLY_UINT8 &&
           (p->type == PLY_INT32 || p->type == PLY_UINT32);
}

/* The face element's rows as plain_face_rows describes them, straight from the bytes into
 * triangle fans, with read_list, add_index and add_face's checks and messages. */
static bool read_face_rows(struct ply_reader *r)
{
    bool is_signed = property_at(r, r->element->first)->type == PLY_INT32;
    uint64_t vertices = element_at(r, r->vertex_element)->count, checked = r->element->count;
    const unsigned char *bytes = (const unsigned char *)r->cur, *end = (const unsigned char *)r->end;
    if (!ao_load_reserve(&r->indices, 3 * (size_t)r->element->count))
        return ao_load_out_of_memory(r->path);
    /* Indices below this are in range as either type (a negative int32 reads as 2^31 or more);
     * a triangle's row is its count and three indices. */
    uint64_t limit = is_signed && vertices > (uint64_t)INT32_MAX ? (uint64_t)INT32_MAX + 1 : vertices;
    const ptrdiff_t triangle_row = 1 + 3 * (ptrdiff_t)sizeof(uint32_t);
    for (r->row_index = 0; r->row_index < r->element->count; r->row_index++) {
        /* The usual row, a triangle in range within the checked count and the room reserved, goes
         * straight in; any other row takes the checks below. */
        if (end - bytes >= triangle_row && bytes[0] == 3 && r->indices.count / 3 < checked &&
            r->indices.capacity - r->indices.count >= 3) {
            uint32_t corner[3];
            memcpy(corner, bytes + 1, sizeof corner);
            if (corner[0] < limit && corner[1] < limit && corner[2] < limit) {
                memcpy((uint32_t *)r->indices.data + r->indices.count, corner, sizeof corner);
                r->indices.count += 3;
                bytes += triangle_row;
                continue;
            }
        }
        if (bytes == end)
            return ply_error(r, "unexpected end of file");
        uint32_t corners = *bytes++, index[255];
        if (corners > (size_t)(end - bytes) / 4)
            return ply_error(r, "list of %u items runs past the end of the file", (unsigned)corners);
        memcpy(index, bytes, 4 * (size_t)corners);
        bytes += 4 * (size_t)corners;
        for (uint32_t i = 0; i < corners; i++) {
            double value = is_signed ? (double)(int32_t)index[i] : (double)index[i];
            if (!(value >= 0.0 && value < (double)vertices))
                return ply_error(r, "vertex index %.17g is not an integer in [0, %llu)", value,
                                 (unsigned long long)vertices);
        }
        if (corners < 3)
            return ply_error(r, "face with %u vertices; at least 3 needed", (unsigned)corners);
        /* The header's face count was checked against the budget as triangles; a polygon's fan
         * may go further. */
        uint64_t triangles = r->indices.count / 3 + corners - 2;
        if (triangles > checked && !within_budget(r, triangles, r->positions.count))
            return false;
        checked = triangles > checked ? triangles : checked;
        uint32_t *t = ao_load_append(&r->indices, 3 * ((size_t)corners - 2));
        if (!t)
            return ao_load_out_of_memory(r->path);
        for (uint32_t i = 1; i + 1 < corners; i++, t += 3)
            t[0] = index[0], t[1] = index[i], t[2] = index[i + 1];
    }
    r->cur = (const char *)bytes;
    return true;
}

/* Every row of every element, in header order: binary vertex and face rows of the usual forms
 * straight from their bytes, the others value by value. */
static bool read_elements(struct ply_reader *r)
{
    r->line = r->data_line;
    for (size_t i = 0; i < r->elements.count; i++) {
        r->element = element_at(r, i);
        /* An element without properties has no bytes, whatever its count. */
        if (r->element->property_count == 0)
            continue;
        size_t offset[ROLE_COUNT], row;
        if (i == r->vertex_element && fixed_vertex_rows(r, r->element, offset, &row)) {
            if (!read_vertex_rows(r, offset, row))
                return false;
            continue;
        }
        if (i == r->face_element && plain_face_rows(r, r->element)) {
            if (!read_face_rows(r))
                return false;
            continue;
        }
        for (r->row_index = 0; r->row_index < r->element->count; r->row_index++) {
            double values[ROLE_COUNT] = {0};
            r->face.count = 0;
            if (!read_row(r, r->element, values) ||
                (i == r->vertex_element && !add_vertex(r, values)) ||
                (i == r->face_element && !add_face(r)))
                return false;
        }
    }
    return true;
}

/* After the last element only blank lines (ascii) or nothing (binary) may follow, else the
 * header's counts are wrong. */
static bool check_trailing_data(struct ply_reader *r)
{
    r->element = NULL;
    if (r->binary) {
        r->line = 0;
        return r->cur == r->end ||
               ply_error(r, "%zu bytes after the last element; the header's counts are wrong",
                         (size_t)(r->end - r->cur));
    }
    for (const char *p = r->cur; p < r->end; p++) {
        if (*p != '\n' && !ao_load_is_blank(*p)) {
            r->line++;
            return ply_error(r, "data after the last element; the header's counts are wrong");
        }
        r->line += *p == '\n';
    }
    return true;
}

/* Parses a PLY header and its ascii or binary little-endian data into mesh. */
bool ao_load_ply(struct ao_mesh *mesh, const char *path, const char *text, size_t size,
                 struct ao_budget *budget)
{
    struct ply_reader r = {
        .path = path,
        .budget = budget,
        .elements = {.size = sizeof(struct ply_element)},
        .properties = {.size = sizeof(struct ply_property)},
        .positions = {.size = sizeof(struct ao_vec3)},
        .normals = {.size = sizeof(struct ao_vec3)},
        .face = {.size = sizeof(uint32_t)},
        .indices = {.size = sizeof(uint32_t)},
    };
    bool ok = parse_ply_header(&r, text, size) && assign_roles(&r) &&
              (!r.binary || check_binary_size(&r)) && read_elements(&r) &&
              check_trailing_data(&r);
    if (ok) {
        mesh->vertex_count = r.positions.count;
        mesh->positions = ao_load_take(&r.positions);
        mesh->normals = ao_load_take(&r.normals);
        mesh->triangle_count = r.indices.count / 3;
        mesh->indices = ao_load_take(&r.indices);
        mesh->invalid_normals = r.invalid_normals;
        ok = ao_load_finish(mesh, path);
    }
    ao_load_free(&r.elements);
    ao_load_free(&r.properties);
    ao_load_free(&r.positions);
    ao_load_free(&r.normals);
    ao_load_free(&r.face);
    ao_load_free(&r.indices);
    return ok;
}
