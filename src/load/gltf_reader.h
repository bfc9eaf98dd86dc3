/* The glTF reader: the state of one file being read, and what the glTF loader's files share over it
 * (gltf.c: the file, its meshes and their placements; gltf_nodes.c: the node tree; gltf_data.c:
 * JSON access and accessors; gltf_buffers.c: the GLB container, buffers and bufferViews). Only
 * src/load/gltf*.c include this. */
#ifndef AO_LOAD_GLTF_READER_H
#define AO_LOAD_GLTF_READER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <json.h>

#include "draco.h"
#include "loader.h"

/* The deepest node tree aoview reads: a node under more ancestors than this is refused (real files
 * nest a few dozen deep; the tree is walked without recursion, so this bounds nothing but trust). */
#define AO_GLTF_MAX_NODE_DEPTH 1024

/* Largest integer read from the JSON: sums of three of them and products of one with a stride (at
 * most 252) stay far below 2^64. */
#define AO_GLTF_MAX_INTEGER 9007199254740992.0

/* A buffer: its declared byteLength, read at its first use, and its bytes (the GLB's BIN chunk, a
 * decoded data URI or an external file's contents), loaded when a bufferView is first read. */
struct ao_gltf_buffer {
    const unsigned char *data;
    size_t size;          /* the declared byteLength; the data holds at least this many bytes */
    unsigned char *owned; /* what to free, or NULL */
    bool known, loaded;   /* size read; data loaded */
};

/* A bufferView's bytes, checked against its buffer at its first use. */
struct ao_gltf_view {
    const unsigned char *data;
    size_t offset;           /* its byteOffset in its buffer (0 for decoded data of its own) */
    size_t length, stride;   /* stride 0: not given (the elements are packed) */
    unsigned char *owned;    /* decoded data of its own (EXT_meshopt_compression), or NULL */
    bool ready;
};

/* The elements of one accessor, checked to lie inside their buffer. */
struct ao_gltf_elements {
    const unsigned char *first;
    size_t stride, count;
    int component_type;          /* quantize.h's types */
    size_t component_size;       /* bytes */
    bool normalized;
};

/* How the accessor of a Draco-compressed attribute reads its values: float as Draco dequantizes
 * them, or (KHR_mesh_quantization) the integers Draco stores, of a component type, normalized or
 * not. */
struct ao_gltf_reading {
    int component_type;
    bool normalized;
};

/* A bufferView's KHR_draco_mesh_compression data, once decoded, and the attribute ids and readings
 * (POSITION, NORMAL) it was decoded for. */
struct ao_gltf_draco {
    struct ao_draco_mesh mesh;
    int64_t position_id, normal_id;
    struct ao_gltf_reading readings[2];
    bool done;
};

/* The file being loaded and the mesh being built. */
struct ao_gltf {
    const char *path;
    json_object *root, *accessors, *views, *meshes, *nodes;
    json_object *buffer_json;     /* the buffers array */
    struct ao_gltf_buffer *buffers;
    size_t buffer_count;
    struct ao_gltf_view *view_cache;   /* per bufferView */
    unsigned char **gathered;     /* per accessor: its elements in memory of their own (sparse, or
                                     without a bufferView), or NULL */
    struct ao_gltf_draco *draco;  /* per bufferView */
    const unsigned char *bin;     /* GLB BIN chunk, or NULL */
    size_t bin_size;
    size_t *parent;               /* per node: its parent, or SIZE_MAX */
    double (*world)[16];          /* per node: its world matrix, column major */
    uint64_t triangles, vertices; /* totals of the meshes counted so far */
    struct ao_budget *budget;     /* the scene budget */
    uint64_t taken;               /* what this load took from it, given back at its end */
    struct mesh_size {
        uint64_t triangles, vertices;
        size_t points, lines;     /* primitives of points and of lines skipped */
        size_t model;             /* its index in the model once built; SIZE_MAX before, DROPPED
                                     when it had no triangle that is not degenerate */
        bool known;
    } *sizes;                     /* per mesh, once counted: its placements need not recount */
    struct shared {
        uint64_t instance;        /* the mesh walk that last added this POSITION accessor */
        size_t normals;           /* with this NORMAL accessor (SIZE_MAX: none) */
        uint32_t base;            /* at this first vertex */
    } *shared;                    /* per accessor */
    uint64_t instance;            /* mesh walks so far (both passes) */
    uint32_t *depth;              /* per node: how many nodes deep it lies (a root is 1) */
    struct ao_load_array positions, normals, indices; /* the mesh being built: ao_vec3, ao_vec3
                                                          (missing where not given), uint32 */
    size_t invalid_normals;       /* its normals given as zero or not finite */
    size_t degenerate_count;      /* zero-area triangles dropped, all meshes */
    size_t recounted;             /* Draco primitives decoding to other counts than their accessors say */
    char recount[160];            /* the first of them, for the note */
    bool unaligned_more;          /* vertex attributes read off glTF's alignment: more than the first */
    char unaligned[160];          /* the first of them, for the note ("" when none) */
    unsigned modes_found;         /* bit m: a primitive of mode m was found */
    size_t point_primitives, line_primitives;   /* skipped, each time a node placed them */
    char note[AO_MESH_NOTE_SIZE]; /* what was ignored that the user should hear of (mesh.h) */
};

/* Reports "path: message" and returns false. */
bool ao_gltf_error(const struct ao_gltf *g, const char *format, ...);

/* Takes bytes from the scene budget for what the load holds until its end; else reports that
 * `what` would need more than is left. */
bool ao_gltf_take(struct ao_gltf *g, uint64_t bytes, const char *what);

/* The member key of obj, or NULL when absent (or obj is not an object). */
json_object *ao_gltf_member(json_object *obj, const char *key);

/* The length of array, 0 when it is NULL (absent) or not an array. */
size_t ao_gltf_length(json_object *array);

/* The length of an array member (0 when absent); false when present but not an array. */
bool ao_gltf_array(const struct ao_gltf *g, json_object *obj, const char *key, const char *where,
                   json_object **out, size_t *length);

/* Reads a whole number in [0, limit] from value (a JSON integer, or a double with no fraction). */
bool ao_gltf_whole(json_object *value, double limit, uint64_t *out);

/* A whole-number member: *out gets its value, or fallback when absent and not required. */
bool ao_gltf_integer(const struct ao_gltf *g, json_object *obj, const char *key, bool required,
                     uint64_t fallback, double limit, const char *where, uint64_t *out);

/* An index into an array of count entries. */
bool ao_gltf_index(const struct ao_gltf *g, json_object *obj, const char *key, size_t count,
                   const char *where, size_t *out);

/* A little-endian 32-bit word. */
static inline uint32_t ao_gltf_le32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

/* bufferView index, read and checked against its buffer on first use: its bytes and stride
 * (gltf_buffers.c). */
bool ao_gltf_view(struct ao_gltf *g, size_t index, const struct ao_gltf_view **out);

/* A GLB: header, then chunks; the first must be JSON, a BIN chunk may follow. Sets *json. */
bool ao_gltf_parse_glb(struct ao_gltf *g, const unsigned char *data, size_t size,
                       const unsigned char **json, size_t *json_size);

/* Allocates the per-buffer and per-bufferView state once g->buffer_json, g->buffer_count and
 * g->views are set; buffers and views are read at their first use. */
bool ao_gltf_begin_data(struct ao_gltf *g);

/* Appends a printf-formatted note (what was ignored) to g->note, after a "; " when there are others;
 * what does not fit is left out. */
void ao_gltf_note(struct ao_gltf *g, const char *format, ...);

/* Accessor i's elements, for use (named in messages): with attribute, VEC3 positions or normals,
 * float or (KHR_mesh_quantization) 8- and 16-bit integers, normalized or not; else SCALAR indices
 * of unsigned byte, short or int. Every element lies inside its bufferView and the view inside its
 * buffer; an accessor without a bufferView is zeros; sparse entries are written over a copy (each
 * index checked against the count), made once and charged to the budget. */
bool ao_gltf_accessor(struct ao_gltf *g, size_t i, bool attribute, const char *use, struct ao_gltf_elements *out);

/* The positions, normals (when asked for) and triangle indices, out[0] to out[2], of a primitive
 * whose KHR_draco_mesh_compression extension is ext: its bufferView decoded once (draco.h) within
 * what the scene budget has left, the result charged to it; the attributes read as their accessors
 * say (VEC3 of floats, or of 8- and 16-bit integers dequantized as KHR_mesh_quantization does),
 * which may not be sparse; an accessor counting other than what decoded is recounted (noted), as
 * the decoded triangles name decoded points only. */
bool ao_gltf_draco(struct ao_gltf *g, json_object *primitive, json_object *ext, bool normals, const char *where,
                   struct ao_gltf_elements out[3]);

/* Element i's component k as a number (quantize.h: integers as glTF maps them when normalized). */
double ao_gltf_value(const struct ao_gltf_elements *e, size_t i, int k);

/* Index element i. */
uint32_t ao_gltf_index_at(const struct ao_gltf_elements *e, size_t i);

/* Element i of VEC3 positions as floats: ao_gltf_value's numbers narrowed, floats read as they lie. */
struct ao_vec3 ao_gltf_position(const struct ao_gltf_elements *e, size_t i);

/* A triangle list's indices plus base into out (e->count of them); false at the first index at or
 * above limit, its place in *bad. */
bool ao_gltf_list_indices(const struct ao_gltf_elements *e, uint32_t base, size_t limit, uint32_t *out, size_t *bad);

/* The node tree of g->nodes (node_count of them): each node's parent into g->parent, refusing bad
 * child indices, a node with two parents and cycles; the roots (the default scene's nodes, scene
 * 0's, or every node without a parent) marked in is_root; the world matrix of each node under
 * them into g->world and its depth into g->depth, marked in placed, refusing a node deeper than
 * AO_GLTF_MAX_NODE_DEPTH or whose matrix overflows. False after one report (gltf_nodes.c). */
bool ao_gltf_place_nodes(struct ao_gltf *g, size_t node_count, bool *is_root, bool *placed);

/* Frees what the data layer holds (buffers, decoded views). */
void ao_gltf_free_data(struct ao_gltf *g);

#endif
