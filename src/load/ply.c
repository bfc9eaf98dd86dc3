/* PLY: ascii and binary little endian; x y z and optional nx ny nz vertex properties, face
 * vertex_indices lists (polygons fanned). A binary header's counts are checked against the file
 * size before anything is allocated for them. Errors name the line (header, ascii) or the
 * element row (binary). */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loader.h"
#include "ply_reader.h"

/* Decodes the little-endian bytes of one value of a PLY type. */
static double decode(enum ply_type type, const unsigned char *bytes)
{
    unsigned size = ao_ply_types[type].size;
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
    if (ao_ply_types[type].is_signed_int && bits >> (8 * size - 1))
        value -= ldexp(1.0, (int)(8 * size));
    return value;
}

/* Reads one value of the given type (binary), or the row's next number (ascii). */
static bool read_value(struct ply_reader *r, enum ply_type type, double *out)
{
    struct ao_load_span s;
    if (r->binary) {
        if ((size_t)(r->end - r->cur) < ao_ply_types[type].size)
            return ao_ply_error(r, "unexpected end of file");
        *out = decode(type, (const unsigned char *)r->cur);
        r->cur += ao_ply_types[type].size;
        return true;
    }
    if (!ao_load_next_token(&r->row, &s))
        return ao_ply_error(r, "too few values for a '%.*s' row", ao_load_span_length(r->element->name),
                         r->element->name.begin);
    return ao_load_parse_number(s, out) ||
           ao_ply_error(r, "bad number '%.*s'", ao_load_span_length(s), s.begin);
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
            return ao_ply_error(r, "unexpected end of file: '%.*s' declares %llu rows, found %llu",
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
           ao_ply_error(r, "more values than the header declares for a '%.*s' row",
                     ao_load_span_length(r->element->name), r->element->name.begin);
}

/* A vertex index from a face list: integral and below the declared vertex count. */
static bool add_index(struct ply_reader *r, double value)
{
    uint64_t vertices = ao_ply_element(r, r->vertex_element)->count;
    if (!(value >= 0.0 && value < (double)vertices && value == floor(value)))
        return ao_ply_error(r, "vertex index %.17g is not an integer in [0, %llu)", value,
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
        return ao_ply_error(r, "bad list count %.17g", count);
    if (r->binary && count > (double)((size_t)(r->end - r->cur) / ao_ply_types[p->type].size))
        return ao_ply_error(r, "list of %.0f items runs past the end of the file", count);
    if (p->role == ROLE_INDICES && count > AO_LOAD_MAX_FACE_VERTICES)
        return ao_ply_error(r, "face with %.0f vertices (more than %d)", count,
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
        const struct ply_property *p = ao_ply_property(r, i);
        if (p->is_list ? !read_list(r, p) : !read_value(r, p->type, &values[p->role]))
            return false;
    }
    return end_row(r);
}

/* Stores a vertex row: a finite position and, when present, a normal (normalized; a zero or
 * non-finite one stored missing and counted). */
static bool add_vertex(struct ply_reader *r, const double v[ROLE_COUNT])
{
    if (!ao_ply_within_budget(r, r->indices.count / 3, r->positions.count + 1))
        return false;
    struct ao_vec3 p = ao_vec3_make((float)v[ROLE_X], (float)v[ROLE_Y], (float)v[ROLE_Z]);
    if (!ao_vec3_is_finite(p))
        return ao_ply_error(r, "vertex position is not a finite float");
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
        return ao_ply_error(r, "face with %zu vertices; at least 3 needed", r->face.count);
    if (!ao_ply_within_budget(r, r->indices.count / 3 + r->face.count - 2, r->positions.count))
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
        const struct ply_property *p = ao_ply_property(r, i);
        if (p->is_list || (p->role != ROLE_NONE && p->type != PLY_FLOAT32))
            return false;
        offset[p->role] = *row;
        *row += ao_ply_types[p->type].size;
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
    if (!ao_ply_within_budget(r, r->indices.count / 3, count))
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
            return ao_ply_error(r, "unexpected end of file");
        for (int role = ROLE_X; role <= (r->has_normals ? ROLE_NZ : ROLE_Z); role++)
            memcpy(&f[role], bytes + offset[role], sizeof f[role]);
        p[i] = ao_vec3_make(f[ROLE_X], f[ROLE_Y], f[ROLE_Z]);
        if (!ao_vec3_is_finite(p[i]))
            return ao_ply_error(r, "vertex position is not a finite float");
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
    const struct ply_property *p = ao_ply_property(r, e->first);
    return r->binary && host_is_little_endian() && e->property_count == 1 && p->count_type == PLY_UINT8 &&
           (p->type == PLY_INT32 || p->type == PLY_UINT32);
}

/* The face element's rows as plain_face_rows describes them, straight from the bytes into
 * triangle fans, with read_list, add_index and add_face's checks and messages. */
static bool read_face_rows(struct ply_reader *r)
{
    bool is_signed = ao_ply_property(r, r->element->first)->type == PLY_INT32;
    uint64_t vertices = ao_ply_element(r, r->vertex_element)->count, checked = r->element->count;
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
            return ao_ply_error(r, "unexpected end of file");
        uint32_t corners = *bytes++, index[255];
        if (corners > (size_t)(end - bytes) / 4)
            return ao_ply_error(r, "list of %u items runs past the end of the file", (unsigned)corners);
        memcpy(index, bytes, 4 * (size_t)corners);
        bytes += 4 * (size_t)corners;
        for (uint32_t i = 0; i < corners; i++) {
            double value = is_signed ? (double)(int32_t)index[i] : (double)index[i];
            if (!(value >= 0.0 && value < (double)vertices))
                return ao_ply_error(r, "vertex index %.17g is not an integer in [0, %llu)", value,
                                 (unsigned long long)vertices);
        }
        if (corners < 3)
            return ao_ply_error(r, "face with %u vertices; at least 3 needed", (unsigned)corners);
        /* The header's face count was checked against the budget as triangles; a polygon's fan
         * may go further. */
        uint64_t triangles = r->indices.count / 3 + corners - 2;
        if (triangles > checked && !ao_ply_within_budget(r, triangles, r->positions.count))
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
        r->element = ao_ply_element(r, i);
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
               ao_ply_error(r, "%zu bytes after the last element; the header's counts are wrong",
                         (size_t)(r->end - r->cur));
    }
    for (const char *p = r->cur; p < r->end; p++) {
        if (*p != '\n' && !ao_load_is_blank(*p)) {
            r->line++;
            return ao_ply_error(r, "data after the last element; the header's counts are wrong");
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
    bool ok = ao_ply_parse_header(&r, text, size) && ao_ply_assign_roles(&r) &&
              (!r.binary || ao_ply_check_binary_size(&r)) && read_elements(&r) &&
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
