/* Private to the PLY reader's files (ply.c: the elements' rows; ply_header.c: the header): the
 * header's declarations, the reader's state and what the two call of each other. */
#ifndef AO_LOAD_PLY_READER_H
#define AO_LOAD_PLY_READER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "budget.h"
#include "loader.h"

/* PLY scalar types, indexing ao_ply_types. */
enum ply_type { PLY_INT8, PLY_UINT8, PLY_INT16, PLY_UINT16, PLY_INT32, PLY_UINT32, PLY_FLOAT32,
                PLY_FLOAT64, PLY_TYPE_COUNT };

/* Names (classic and sized alias), byte sizes and signedness of the PLY scalar types. */
struct ply_type_info {
    const char *name, *alias;
    unsigned size;
    bool is_signed_int;
};

/* The PLY scalar types, indexed by enum ply_type (ply_header.c). */
extern const struct ply_type_info ao_ply_types[PLY_TYPE_COUNT];

/* What the loader does with a property's values. */
enum ply_role { ROLE_NONE, ROLE_X, ROLE_Y, ROLE_Z, ROLE_NX, ROLE_NY, ROLE_NZ, ROLE_INDICES,
                ROLE_COUNT };

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

/* The element at index i. */
static inline struct ply_element *ao_ply_element(const struct ply_reader *r, size_t i)
{
    return (struct ply_element *)r->elements.data + i;
}

/* The property at index i. */
static inline struct ply_property *ao_ply_property(const struct ply_reader *r, size_t i)
{
    return (struct ply_property *)r->properties.data + i;
}

/* The reader's one error line, located by line (header, ascii) or element row (binary); returns
 * false. */
bool ao_ply_error(const struct ply_reader *r, const char *format, ...);

/* True when so many triangles and vertices fit in the budget; else reports where the reader is. */
bool ao_ply_within_budget(const struct ply_reader *r, uint64_t triangles, uint64_t vertices);

/* The header, from "ply" to "end_header"; leaves r->cur at the first data byte. */
bool ao_ply_parse_header(struct ply_reader *r, const char *text, size_t size);

/* Finds the vertex and face elements and the properties the loader uses. */
bool ao_ply_assign_roles(struct ply_reader *r);

/* Binary files: refuses a header whose rows cannot fit in the bytes after it, before anything
 * is allocated for them (a 100-byte file may claim 4 billion vertices). */
bool ao_ply_check_binary_size(struct ply_reader *r);

#endif
