/* glTF 2.0: .gltf (JSON, buffers in external files or base64 data URIs) and .glb (binary
 * container). The JSON is parsed by json-c; this file reads what aoview needs from it: the
 * default scene's nodes (or scene 0's, or every root node when there is no scene), their
 * transforms (matrix, or translation/rotation/scale; nested), and their meshes' triangle
 * primitives (mode 4 or absent; indexed by any unsigned type or not indexed) with float VEC3
 * POSITION and NORMAL. Everything else (materials, texture coordinates, animations, cameras, other
 * primitive modes) is ignored; sparse accessors and required extensions are refused.
 *
 * Every range a file gives is checked before it is read: a GLB's chunk lengths against the file,
 * a bufferView against its buffer, an accessor's last element against its bufferView, indices
 * against their vertex count. Integers are read only up to 2^53, so that sums of three of them and
 * products of one with a stride (at most 252) stay far below 2^64. Nodes must form trees: a node
 * with two parents, or a cycle, is refused before anything is traversed. Whatever the load holds
 * is charged to the scene budget before it is allocated: the JSON tree json-c will build and the
 * per-node arrays (both estimated from the text, json_cost), each buffer, and the mesh its nodes
 * instance, counted in a first pass, so that a small file cannot demand gigabytes. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <json.h>

#include "file.h"
#include "load/load.h"

/* Largest integer read from the JSON; see the header comment. */
#define MAX_INTEGER 9007199254740992.0
/* JSON nesting depth accepted (glTF needs 6 or so; deep nesting is an attack on the parser). */
#define MAX_DEPTH 64

/* GLB container constants: magic "glTF", chunk types "JSON" and "BIN\0". */
enum { GLB_MAGIC = 0x46546C67, GLB_JSON = 0x4E4F534A, GLB_BIN = 0x004E4942, GLB_HEADER = 12 };
/* Accessor component types. */
enum { UNSIGNED_BYTE = 5121, UNSIGNED_SHORT = 5123, UNSIGNED_INT = 5125, FLOAT = 5126 };

/* A buffer's bytes: the GLB's BIN chunk, a decoded data URI or an external file's contents. */
struct buffer {
    const unsigned char *data;
    size_t size;          /* the declared byteLength; the data holds at least this many bytes */
    unsigned char *owned; /* what to free, or NULL */
};

/* The elements of one accessor, checked to lie inside their buffer. */
struct elements {
    const unsigned char *first;
    size_t stride, count;
    int component_type;
};

/* A node's place in the tree. */
enum { NODE_UNSEEN, NODE_WALKING, NODE_CHECKED };

/* The file being loaded and the mesh being built. */
struct gltf {
    const char *path;
    json_object *root, *accessors, *views, *meshes, *nodes;
    struct buffer *buffers;
    size_t buffer_count;
    const unsigned char *bin;     /* GLB BIN chunk, or NULL */
    size_t bin_size;
    size_t *parent;               /* per node: its parent, or SIZE_MAX */
    double (*world)[16];          /* per node: its world matrix, column major */
    uint64_t triangles, vertices; /* totals of the instances found so far */
    struct ao_budget *budget;     /* the scene budget */
    uint64_t taken;               /* what this load took from it, given back at its end */
    struct mesh_size {
        uint64_t triangles, vertices;
        bool known;
    } *sizes;                     /* per mesh, once counted: instances need not recount */
    struct ao_load_array positions, normals, lacking, indices; /* ao_vec3, ao_vec3, bool, uint32 */
    size_t lacking_count;
};

/* Reports "path: message" and returns false. */
static bool gltf_error(const struct gltf *g, const char *format, ...)
{
    char message[400];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    ao_load_report(g->path, 0, "%s", message);
    return false;
}

/* Takes bytes from the scene budget for what the load holds until its end; else reports that
 * `what` would need more than is left. */
static bool take(struct gltf *g, uint64_t bytes, const char *what)
{
    if (ao_budget_take(g->budget, bytes)) {
        g->taken += bytes;
        return true;
    }
    char why[200];
    ao_budget_explain(g->budget, bytes, why, sizeof why);
    return gltf_error(g, "%s would %s", what, why);
}

/* ------------------------------------------------------------------ JSON access */

/* The member key of obj, or NULL when absent (or obj is not an object). */
static json_object *member(json_object *obj, const char *key)
{
    json_object *value = NULL;
    return json_object_is_type(obj, json_type_object) && json_object_object_get_ex(obj, key, &value)
               ? value : NULL;
}

/* The length of array, 0 when it is NULL (absent) or not an array. */
static size_t length_of(json_object *array)
{
    return json_object_is_type(array, json_type_array) ? json_object_array_length(array) : 0;
}

/* The length of an array member (0 when absent); false when present but not an array. */
static bool array_member(const struct gltf *g, json_object *obj, const char *key, const char *where,
                         json_object **out, size_t *length)
{
    *out = member(obj, key);
    *length = 0;
    if (!*out)
        return true;
    if (!json_object_is_type(*out, json_type_array))
        return gltf_error(g, "%s: '%s' is not an array", where, key);
    *length = json_object_array_length(*out);
    return true;
}

/* Reads a whole number in [0, limit] from value (a JSON integer, or a double with no fraction). */
static bool whole_number(json_object *value, double limit, uint64_t *out)
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
static bool integer(const struct gltf *g, json_object *obj, const char *key, bool required,
                    uint64_t fallback, double limit, const char *where, uint64_t *out)
{
    json_object *value = member(obj, key);
    *out = fallback;
    if (!value && !required)
        return true;
    if (!value)
        return gltf_error(g, "%s: no '%s'", where, key);
    return whole_number(value, limit, out) ||
           gltf_error(g, "%s: '%s' is not a whole number from 0 to %.0f", where, key, limit);
}

/* An index into an array of count entries. */
static bool index_member(const struct gltf *g, json_object *obj, const char *key, size_t count,
                         const char *where, size_t *out)
{
    uint64_t value;
    *out = 0;
    if (!integer(g, obj, key, true, 0, MAX_INTEGER, where, &value))
        return false;
    if (value >= count)
        return gltf_error(g, "%s: '%s' %llu is out of range (%zu defined)", where, key,
                          (unsigned long long)value, count);
    *out = (size_t)value;
    return true;
}

/* n finite numbers of an array member into out; false (reported) when malformed. */
static bool numbers(const struct gltf *g, json_object *obj, const char *key, size_t n,
                    const char *where, double *out)
{
    json_object *array = member(obj, key);
    if (!json_object_is_type(array, json_type_array) || json_object_array_length(array) != n)
        return gltf_error(g, "%s: '%s' must be an array of %zu numbers", where, key, n);
    for (size_t i = 0; i < n; i++) {
        json_object *item = json_object_array_get_idx(array, i);
        if (!json_object_is_type(item, json_type_int) && !json_object_is_type(item, json_type_double))
            return gltf_error(g, "%s: '%s' must be an array of %zu numbers", where, key, n);
        out[i] = json_object_get_double(item);
        if (!isfinite(out[i]))
            return gltf_error(g, "%s: '%s' holds a non-finite number", where, key);
    }
    return true;
}

/* ------------------------------------------------------------------ containers and buffers */

/* A little-endian 32-bit word. */
static uint32_t le32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

/* A GLB: header, then chunks; the first must be JSON, a BIN chunk may follow. Sets *json. */
static bool parse_glb(struct gltf *g, const unsigned char *data, size_t size,
                      const unsigned char **json, size_t *json_size)
{
    if (size < GLB_HEADER || le32(data) != GLB_MAGIC)
        return gltf_error(g, "not a GLB file (no 'glTF' magic)");
    if (le32(data + 4) != 2)
        return gltf_error(g, "GLB version %u; only version 2 is supported", le32(data + 4));
    if (le32(data + 8) != size)
        return gltf_error(g, "GLB header says %u bytes, the file has %zu", le32(data + 8), size);
    *json = NULL;
    for (size_t offset = GLB_HEADER; offset < size;) {
        if (size - offset < 8)
            return gltf_error(g, "GLB chunk header at byte %zu runs past the end", offset);
        size_t length = le32(data + offset), type = le32(data + offset + 4);
        if (length > size - offset - 8)
            return gltf_error(g, "GLB chunk at byte %zu claims %zu bytes, only %zu remain", offset,
                              length, size - offset - 8);
        const unsigned char *body = data + offset + 8;
        if (!*json && type != GLB_JSON)
            return gltf_error(g, "GLB's first chunk is not JSON");
        if (!*json) {
            *json = body;
            *json_size = length;
        } else if (type == GLB_BIN && !g->bin) {
            g->bin = body;
            g->bin_size = length;
        }
        offset += 8 + length;
    }
    return *json || gltf_error(g, "GLB without a JSON chunk");
}

/* The value of one base64 digit, or -1. */
static int base64_digit(unsigned char c)
{
    if (c >= 'A' && c <= 'Z')
        return c - 'A';
    if (c >= 'a' && c <= 'z')
        return c - 'a' + 26;
    if (c >= '0' && c <= '9')
        return c - '0' + 52;
    return c == '+' ? 62 : c == '/' ? 63 : -1;
}

/* Decodes base64 text (padding optional) into a new buffer; false on a bad digit. */
static bool decode_base64(const char *text, size_t n, unsigned char **out, size_t *size)
{
    while (n > 0 && text[n - 1] == '=')
        n--;
    unsigned char *bytes = malloc(n / 4 * 3 + 3);
    if (!bytes)
        return false;
    size_t count = 0;
    uint32_t bits = 0;
    for (size_t i = 0; i < n; i++) {
        int digit = base64_digit((unsigned char)text[i]);
        if (digit < 0) {
            free(bytes);
            return false;
        }
        bits = bits << 6 | (uint32_t)digit;
        if (i % 4 == 3) {
            bytes[count++] = (unsigned char)(bits >> 16);
            bytes[count++] = (unsigned char)(bits >> 8);
            bytes[count++] = (unsigned char)bits;
        }
    }
    if (n % 4 == 1) {
        free(bytes);
        return false;
    }
    if (n % 4 >= 2)
        bytes[count++] = (unsigned char)(bits >> (n % 4 == 2 ? 4 : 10));
    if (n % 4 == 3)
        bytes[count++] = (unsigned char)(bits >> 2);
    *out = bytes;
    *size = count;
    return true;
}

/* Reads byteLength bytes of the file a buffer's URI names inside the model's folder (uri.c). */
static bool read_buffer_file(struct gltf *g, const char *where, const char *uri, uint64_t length,
                             struct buffer *b)
{
    char path[4096], why[160];
    int fd;
    if (!ao_load_uri_decode(uri, path, sizeof path, why, sizeof why) ||
        !ao_load_uri_open(g->path, path, &fd, why, sizeof why))
        return gltf_error(g, "%s ('%.60s'): %s", where, uri, why);
    char *data = NULL, what[100];
    snprintf(what, sizeof what, "%s ('%.40s'), byteLength %llu,", where, uri, (unsigned long long)length);
    if (length >= SIZE_MAX || !take(g, length + 1, what)) {
        close(fd);
        return length >= SIZE_MAX && gltf_error(g, "%s too large", what);   /* else take reported */
    }
    const char *reason = NULL;
    bool ok = ao_file_read_prefix(fd, (size_t)length, &data, &reason);
    close(fd);
    if (!ok)
        return gltf_error(g, "%s ('%.60s'), byteLength %llu: %s", where, uri,
                          (unsigned long long)length, reason);
    b->data = b->owned = (unsigned char *)data;
    return true;
}

/* Loads buffer i: the GLB's BIN chunk (no uri), a data URI or a file in the glTF's folder. */
static bool load_buffer(struct gltf *g, json_object *json, size_t i)
{
    char where[64];
    snprintf(where, sizeof where, "buffer %zu", i);
    struct buffer *b = &g->buffers[i];
    uint64_t length;
    if (!integer(g, json, "byteLength", true, 0, MAX_INTEGER, where, &length))
        return false;
    json_object *uri_json = member(json, "uri");
    const char *uri = json_object_is_type(uri_json, json_type_string)
                          ? json_object_get_string(uri_json) : NULL;
    size_t size = 0;
    if (uri_json && !uri)
        return gltf_error(g, "%s: 'uri' is not a string", where);
    if (!uri) {
        if (i != 0 || !g->bin)
            return gltf_error(g, "%s has no 'uri' and is not a GLB's BIN chunk", where);
        b->data = g->bin;
        size = g->bin_size;
    } else if (strncmp(uri, "data:", 5) == 0) {
        const char *comma = strchr(uri, ',');
        if (!comma || comma - uri < 12 || memcmp(comma - 7, ";base64", 7) != 0)
            return gltf_error(g, "%s: only base64 data URIs are supported", where);
        size_t digits = strlen(comma + 1);
        char what[96];
        snprintf(what, sizeof what, "%.64s's data URI", where);
        if (!take(g, digits / 4 * 3 + 3, what))
            return false;
        if (!decode_base64(comma + 1, digits, &b->owned, &size))
            return gltf_error(g, "%s: bad base64 data (or out of memory)", where);
        b->data = b->owned;
    } else {
        if (!read_buffer_file(g, where, uri, length, b))
            return false;
        size = (size_t)length;
    }
    if (size < length)
        return gltf_error(g, "%s: byteLength %llu but only %zu bytes of data", where,
                          (unsigned long long)length, size);
    b->size = (size_t)length;
    return true;
}

/* ------------------------------------------------------------------ accessors */

/* Accessor i's elements: type ("SCALAR" or "VEC3") and component types as required, every
 * element inside its bufferView and the view inside its buffer. */
static bool accessor(struct gltf *g, size_t i, const char *type, bool want_float, const char *use,
                     struct elements *out)
{
    char where[96];
    snprintf(where, sizeof where, "accessor %zu (%s)", i, use);
    json_object *a = json_object_array_get_idx(g->accessors, i);
    json_object *type_json = member(a, "type");
    uint64_t component, count, offset;
    size_t view_index;
    if (member(a, "sparse"))
        return gltf_error(g, "%s: sparse accessors are not supported", where);
    if (!member(a, "bufferView"))
        return gltf_error(g, "%s: no bufferView (all-zero accessors are not supported)", where);
    if (!json_object_is_type(type_json, json_type_string) ||
        strcmp(json_object_get_string(type_json), type) != 0)
        return gltf_error(g, "%s: type must be %s", where, type);
    if (!integer(g, a, "componentType", true, 0, MAX_INTEGER, where, &component) ||
        !integer(g, a, "count", true, 0, (double)UINT32_MAX, where, &count) ||
        !integer(g, a, "byteOffset", false, 0, MAX_INTEGER, where, &offset) ||
        !index_member(g, a, "bufferView", length_of(g->views), where, &view_index))
        return false;
    bool is_index = component == UNSIGNED_BYTE || component == UNSIGNED_SHORT ||
                    component == UNSIGNED_INT;
    if (want_float ? component != FLOAT : !is_index)
        return gltf_error(g, "%s: componentType %llu; %s", where, (unsigned long long)component,
                          want_float ? "only float (5126) is supported"
                                     : "indices must be unsigned byte, short or int");
    if (count == 0)
        return gltf_error(g, "%s: count is 0", where);
    size_t element = component == FLOAT ? 12 : component == UNSIGNED_INT ? 4
                   : component == UNSIGNED_SHORT ? 2 : 1;

    /* The bufferView, inside its buffer. */
    char view_where[64];
    snprintf(view_where, sizeof view_where, "bufferView %zu", view_index);
    json_object *v = json_object_array_get_idx(g->views, view_index);
    uint64_t view_offset, view_length, stride;
    size_t buffer_index;
    if (!index_member(g, v, "buffer", g->buffer_count, view_where, &buffer_index) ||
        !integer(g, v, "byteOffset", false, 0, MAX_INTEGER, view_where, &view_offset) ||
        !integer(g, v, "byteLength", true, 0, MAX_INTEGER, view_where, &view_length) ||
        !integer(g, v, "byteStride", false, element, 252, view_where, &stride))
        return false;
    const struct buffer *b = &g->buffers[buffer_index];
    if (view_offset + view_length > b->size)
        return gltf_error(g, "%s: bytes [%llu, %llu) run past buffer %zu (%zu bytes)", view_where,
                          (unsigned long long)view_offset,
                          (unsigned long long)(view_offset + view_length), buffer_index, b->size);
    if (stride < element)
        return gltf_error(g, "%s: byteStride %llu is smaller than an element (%zu bytes)",
                          view_where, (unsigned long long)stride, element);
    /* The last element ends inside the view: offset + stride * (count - 1) + element. */
    uint64_t end = offset + stride * (count - 1) + element;
    if (end > view_length)
        return gltf_error(g, "%s: %llu elements from byte %llu need %llu bytes of bufferView %zu, "
                          "which has %llu", where, (unsigned long long)count,
                          (unsigned long long)offset, (unsigned long long)end, view_index,
                          (unsigned long long)view_length);
    *out = (struct elements){b->data + view_offset + offset, (size_t)stride, (size_t)count,
                             (int)component};
    return true;
}

/* Element i's component k as a float. */
static float float_at(const struct elements *e, size_t i, int k)
{
    uint32_t bits = le32(e->first + i * e->stride + 4 * (size_t)k);
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

/* Index element i. */
static uint32_t index_at(const struct elements *e, size_t i)
{
    const unsigned char *p = e->first + i * e->stride;
    return e->component_type == UNSIGNED_INT ? le32(p)
           : e->component_type == UNSIGNED_SHORT ? (uint32_t)(p[0] | p[1] << 8) : p[0];
}

/* ------------------------------------------------------------------ nodes */

/* Column-major 4x4 product out = a b (out may not alias). */
static void multiply(const double a[16], const double b[16], double out[16])
{
    for (int c = 0; c < 4; c++)
        for (int r = 0; r < 4; r++)
            out[4 * c + r] = a[r] * b[4 * c] + a[4 + r] * b[4 * c + 1] + a[8 + r] * b[4 * c + 2] +
                             a[12 + r] * b[4 * c + 3];
}

/* A node's local matrix: its 'matrix', else translation * rotation * scale. */
static bool local_matrix(const struct gltf *g, json_object *node, const char *where, double m[16])
{
    if (member(node, "matrix"))
        return numbers(g, node, "matrix", 16, where, m);
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
    if ((member(node, "translation") && !numbers(g, node, "translation", 3, where, t)) ||
        (member(node, "rotation") && !numbers(g, node, "rotation", 4, where, q)) ||
        (member(node, "scale") && !numbers(g, node, "scale", 3, where, s)))
        return false;
    /* glTF asks for a unit quaternion; any other nonzero one is normalized, divided first by its
     * largest component so that the squares can neither overflow (1e200 would give an infinite
     * length and a silent identity) nor vanish (1e-200, a zero length). */
    double big = fmax(fmax(fabs(q[0]), fabs(q[1])), fmax(fabs(q[2]), fabs(q[3])));
    if (!(big > 0.0))
        return gltf_error(g, "%s: rotation is a zero quaternion", where);
    for (int k = 0; k < 4; k++)
        q[k] /= big;
    double length = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    double x = q[0] / length, y = q[1] / length, z = q[2] / length, w = q[3] / length;
    double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
                   2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                   2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};
    for (int c = 0; c < 3; c++) {
        for (int k = 0; k < 3; k++)
            m[4 * c + k] = r[3 * c + k] * s[c];
        m[4 * c + 3] = 0.0;
    }
    m[12] = t[0];
    m[13] = t[1];
    m[14] = t[2];
    m[15] = 1.0;
    return true;
}

/* Records every node's parent, refusing bad child indices, a node with two parents and cycles. */
static bool check_tree(struct gltf *g, size_t count)
{
    for (size_t i = 0; i < count; i++)
        g->parent[i] = SIZE_MAX;
    for (size_t i = 0; i < count; i++) {
        char where[64];
        snprintf(where, sizeof where, "node %zu", i);
        json_object *children;
        size_t n;
        if (!array_member(g, json_object_array_get_idx(g->nodes, i), "children", where, &children, &n))
            return false;
        for (size_t k = 0; k < n; k++) {
            uint64_t child;
            if (!whole_number(json_object_array_get_idx(children, k), MAX_INTEGER, &child) ||
                child >= count)
                return gltf_error(g, "%s: child %zu is not a node index", where, k);
            if (g->parent[child] != SIZE_MAX)
                return gltf_error(g, "node %llu is a child of nodes %zu and %zu (nodes must form "
                                  "trees)", (unsigned long long)child, g->parent[child], i);
            g->parent[child] = i;
        }
    }
    /* With one parent each, following parents from any node ends at a root or goes round a
     * cycle; each node is walked once (state: unseen, on the current walk, checked). */
    unsigned char *state = calloc(count ? count : 1, 1);
    if (!state)
        return ao_load_out_of_memory(g->path);
    bool ok = true;
    for (size_t i = 0; ok && i < count; i++) {
        size_t n = i;
        while (n != SIZE_MAX && state[n] == NODE_UNSEEN) {
            state[n] = NODE_WALKING;
            n = g->parent[n];
        }
        if (n != SIZE_MAX && state[n] == NODE_WALKING)
            ok = gltf_error(g, "node %zu is its own ancestor (a cycle in the node graph)", n);
        for (n = i; n != SIZE_MAX && state[n] == NODE_WALKING; n = g->parent[n])
            state[n] = NODE_CHECKED;
    }
    free(state);
    return ok;
}

/* ------------------------------------------------------------------ instances */

/* The cofactor matrix C(r, c) of the 3x3 part of the column-major m (M(r, c) = m[4c + r]) into cof,
 * which maps normals as M's inverse transpose does up to the factor det M, and a number with the
 * sign of det M (negative where M mirrors). Computed from M divided by its largest entry: neither
 * direction nor sign depends on that scale, and no product of two entries can then overflow
 * (a finite but huge matrix would give inf - inf = NaN normals) or vanish together. */
static double normal_matrix(const double m[16], double cof[3][3])
{
    double big = 0.0, a[9];
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++)
            big = fmax(big, fabs(m[4 * c + r]));
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++)
            a[3 * c + r] = big > 0.0 ? m[4 * c + r] / big : 0.0;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
            cof[r][c] = a[3 * c1 + r1] * a[3 * c2 + r2] - a[3 * c2 + r1] * a[3 * c1 + r2];
        }
    return a[0] * cof[0][0] + a[3] * cof[0][1] + a[6] * cof[0][2];
}

/* Appends one primitive under the world matrix m: positions and normals transformed, triangles
 * offset (and turned round where m mirrors). With count_only, adds its size to the totals. */
static bool add_primitive(struct gltf *g, json_object *primitive, const double m[16],
                          const char *where, bool count_only)
{
    json_object *attributes = member(primitive, "attributes");
    size_t count = length_of(g->accessors), position_index, normal_index = 0, index_index = 0;
    struct elements positions, normals = {0}, indices = {0};
    bool has_normals = member(attributes, "NORMAL") != NULL;
    bool indexed = member(primitive, "indices") != NULL;
    if (!member(attributes, "POSITION"))
        return gltf_error(g, "%s: no POSITION attribute", where);
    if (!index_member(g, attributes, "POSITION", count, where, &position_index) ||
        !accessor(g, position_index, "VEC3", true, "POSITION", &positions) ||
        (has_normals && (!index_member(g, attributes, "NORMAL", count, where, &normal_index) ||
                         !accessor(g, normal_index, "VEC3", true, "NORMAL", &normals))) ||
        (indexed && (!index_member(g, primitive, "indices", count, where, &index_index) ||
                     !accessor(g, index_index, "SCALAR", false, "indices", &indices))))
        return false;
    if (has_normals && normals.count != positions.count)
        return gltf_error(g, "%s: %zu normals for %zu positions", where, normals.count,
                          positions.count);
    size_t corners = indexed ? indices.count : positions.count;
    if (corners % 3)
        return gltf_error(g, "%s: %zu %s, not a whole number of triangles", where, corners,
                          indexed ? "indices" : "vertices");
    if (count_only) {
        g->triangles += corners / 3;
        g->vertices += positions.count;
        return true;
    }
    if (g->vertices + positions.count >= AO_LOAD_NO_INDEX)
        return gltf_error(g, "more than %u vertices in all", AO_LOAD_NO_INDEX - 1);
    uint32_t base = (uint32_t)g->positions.count;

    /* Vertices: p' = M (p, 1); n' along M's inverse transpose times n (normal_matrix). */
    struct ao_vec3 *p = ao_load_append(&g->positions, positions.count);
    struct ao_vec3 *n = ao_load_append(&g->normals, positions.count);
    bool *lacking = ao_load_append(&g->lacking, positions.count);
    if (!p || !n || !lacking)
        return ao_load_out_of_memory(g->path);
    double cof[3][3];
    double det = normal_matrix(m, cof), sign = det < 0.0 ? -1.0 : 1.0;
    for (size_t i = 0; i < positions.count; i++) {
        double x = float_at(&positions, i, 0), y = float_at(&positions, i, 1);
        double z = float_at(&positions, i, 2);
        p[i] = ao_vec3_make((float)(m[0] * x + m[4] * y + m[8] * z + m[12]),
                            (float)(m[1] * x + m[5] * y + m[9] * z + m[13]),
                            (float)(m[2] * x + m[6] * y + m[10] * z + m[14]));
        if (!ao_vec3_is_finite(p[i]))
            return gltf_error(g, "%s: vertex %zu is not a finite float once transformed", where, i);
        lacking[i] = !has_normals;
        n[i] = ao_vec3_make(0.0f, 0.0f, 0.0f);
        if (has_normals) {
            double a = float_at(&normals, i, 0), b = float_at(&normals, i, 1);
            double d = float_at(&normals, i, 2);
            if (!isfinite(a) || !isfinite(b) || !isfinite(d))
                return gltf_error(g, "%s: normal %zu is not finite", where, i);
            double t[3];
            for (int r = 0; r < 3; r++)
                t[r] = sign * (cof[r][0] * a + cof[r][1] * b + cof[r][2] * d);
            n[i] = ao_load_unit(t[0], t[1], t[2]);
        }
    }
    g->lacking_count += has_normals ? 0 : positions.count;
    g->vertices += positions.count;

    /* Triangles. */
    uint32_t *t = ao_load_append(&g->indices, corners);
    if (!t)
        return ao_load_out_of_memory(g->path);
    for (size_t i = 0; i < corners; i++) {
        uint32_t v = indexed ? index_at(&indices, i) : (uint32_t)i;
        if (v >= positions.count)
            return gltf_error(g, "%s: index %u at %zu is out of range (%zu vertices)", where, v, i,
                              positions.count);
        t[i] = base + v;
    }
    if (det < 0.0)
        for (size_t i = 0; i < corners; i += 3) {
            uint32_t swap = t[i + 1];
            t[i + 1] = t[i + 2];
            t[i + 2] = swap;
        }
    g->triangles += corners / 3;
    return true;
}

/* The triangle primitives of node's mesh, if any, under the node's world matrix. With count_only,
 * adds their size to the totals, walking each mesh's primitives once however many nodes use it
 * (so that a small file cannot make the count take hours). */
static bool add_node_mesh(struct gltf *g, size_t node, bool count_only)
{
    json_object *node_json = json_object_array_get_idx(g->nodes, node);
    char where[96];
    size_t mesh, primitive_count;
    json_object *primitives;
    snprintf(where, sizeof where, "node %zu", node);
    if (!member(node_json, "mesh"))
        return true;
    if (!index_member(g, node_json, "mesh", length_of(g->meshes), where, &mesh))
        return false;
    struct mesh_size *size = &g->sizes[mesh], before = {g->triangles, g->vertices, true};
    if (count_only && size->known) {
        g->triangles += size->triangles;
        g->vertices += size->vertices;
        return true;
    }
    snprintf(where, sizeof where, "mesh %zu", mesh);
    if (!array_member(g, json_object_array_get_idx(g->meshes, mesh), "primitives", where,
                      &primitives, &primitive_count))
        return false;
    for (size_t k = 0; k < primitive_count; k++) {
        json_object *primitive = json_object_array_get_idx(primitives, k);
        uint64_t mode;
        snprintf(where, sizeof where, "mesh %zu primitive %zu", mesh, k);
        if (!integer(g, primitive, "mode", false, 4, 6, where, &mode))
            return false;
        if (mode == 4 && !add_primitive(g, primitive, g->world[node], where, count_only))
            return false;
    }
    if (count_only)
        *size = (struct mesh_size){g->triangles - before.triangles, g->vertices - before.vertices,
                                   true};
    return true;
}

/* The roots: the default scene's nodes, scene 0's, or every node without a parent. Each root is
 * marked in is_root; a root listed twice or with a parent is refused. */
static bool find_roots(struct gltf *g, size_t node_count, bool *is_root)
{
    json_object *scenes, *list;
    size_t scene_count, n;
    if (!array_member(g, g->root, "scenes", "file", &scenes, &scene_count))
        return false;
    if (scene_count == 0) {
        for (size_t i = 0; i < node_count; i++)
            is_root[i] = g->parent[i] == SIZE_MAX;
        return true;
    }
    size_t scene = 0;
    if (member(g->root, "scene") && !index_member(g, g->root, "scene", scene_count, "file", &scene))
        return false;
    char where[64];
    snprintf(where, sizeof where, "scene %zu", scene);
    if (!array_member(g, json_object_array_get_idx(scenes, scene), "nodes", where, &list, &n))
        return false;
    for (size_t k = 0; k < n; k++) {
        uint64_t node;
        if (!whole_number(json_object_array_get_idx(list, k), MAX_INTEGER, &node) || node >= node_count)
            return gltf_error(g, "%s: entry %zu is not a node index", where, k);
        if (is_root[node] || g->parent[node] != SIZE_MAX)
            return gltf_error(g, "%s: node %llu is listed twice or is not a root", where,
                              (unsigned long long)node);
        is_root[node] = true;
    }
    return true;
}

/* World matrices of the roots and every node under them, parents first (the nodes form trees, so
 * each is pushed once and the stack never holds more than all of them); marks them placed. */
static bool place_nodes(struct gltf *g, size_t node_count, const bool *is_root, bool *placed)
{
    static const double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    size_t *stack = malloc((node_count ? node_count : 1) * sizeof *stack), top = 0;
    if (!stack)
        return ao_load_out_of_memory(g->path);
    for (size_t i = 0; i < node_count; i++)
        if (is_root[i])
            stack[top++] = i;
    bool ok = true;
    while (ok && top > 0) {
        size_t n = stack[--top];
        json_object *node = json_object_array_get_idx(g->nodes, n);
        char where[64];
        double local[16];
        snprintf(where, sizeof where, "node %zu", n);
        ok = local_matrix(g, node, where, local);
        if (ok)
            multiply(is_root[n] ? identity : g->world[g->parent[n]], local, g->world[n]);
        for (int k = 0; ok && k < 16; k++)
            if (!isfinite(g->world[n][k]))
                ok = gltf_error(g, "%s: its transform overflows (an entry of its world matrix is "
                                "not finite)", where);
        placed[n] = true;
        json_object *children = member(node, "children");
        for (size_t k = 0; ok && k < length_of(children); k++) {
            uint64_t child = 0;
            whole_number(json_object_array_get_idx(children, k), MAX_INTEGER, &child);
            stack[top++] = (size_t)child;   /* checked by check_tree */
        }
    }
    free(stack);
    return ok;
}

/* ------------------------------------------------------------------ the file */

/* An upper estimate of json-c's memory for text, and of the loader's per-node arrays: each '{'
 * makes an object with a 16-entry hash table (measured: 780 bytes) and may be a node, for which
 * read_scene keeps AO_BUDGET_NODE bytes more; each '[' an array (150 bytes), and every other
 * value, which follows a ',' or ':', 70 to 110 bytes; a string's bytes are gathered in a buffer
 * grown by doubling (less than twice their length) and then copied into the string (once more):
 * 3 bytes per byte (measured: 1.9 for a 200 MB string). Charged before parsing, it keeps a few
 * megabytes of "{}," from taking gigabytes, a 1 GB string 3 GB, and a million nodes from being
 * parsed only to be refused. */
static uint64_t json_cost(const char *text, size_t size)
{
    uint64_t cost = 0;
    bool in_string = false;
    for (size_t i = 0; i < size; i++) {
        char c = text[i];
        if (in_string) {
            i += c == '\\';   /* an escaped character, '"' too, stays in the string */
            in_string = c != '"';
            cost += 3;
        } else {
            in_string = c == '"';
            cost += c == '{' ? 800 + AO_BUDGET_NODE : c == '[' ? 160 : c == ',' || c == ':' ? 112 : 0;
        }
    }
    return cost;
}

/* Parses the JSON text into g->root; errors name the line. */
static bool parse_json(struct gltf *g, const char *text, size_t size)
{
    if (!take(g, json_cost(text, size), "parsing its JSON"))
        return false;
    struct json_tokener *tokener = json_tokener_new_ex(MAX_DEPTH);
    if (!tokener)
        return ao_load_out_of_memory(g->path);
    g->root = size > INT32_MAX ? NULL : json_tokener_parse_ex(tokener, text, (int)size);
    enum json_tokener_error error = json_tokener_get_error(tokener);
    size_t end = json_tokener_get_parse_end(tokener);
    json_tokener_free(tokener);
    size_t line = 1;
    for (size_t i = 0; i < end && i < size; i++)
        line += text[i] == '\n';
    if (size > INT32_MAX)
        return gltf_error(g, "JSON of %zu bytes is too large", size);
    if (!g->root || error != json_tokener_success) {
        ao_load_report(g->path, line, "JSON: %s", error == json_tokener_continue
                                                      ? "unexpected end of text"
                                                      : json_tokener_error_desc(error));
        return false;
    }
    for (; end < size; end++)
        if (text[end] != ' ' && text[end] != '\t' && text[end] != '\r' && text[end] != '\n') {
            ao_load_report(g->path, line, "JSON: text after the top-level value");
            return false;
        }
    if (!json_object_is_type(g->root, json_type_object))
        return gltf_error(g, "the JSON top level is not an object");
    return true;
}

/* The asset version and required extensions. */
static bool check_asset(struct gltf *g)
{
    json_object *version = member(member(g->root, "asset"), "version"), *required;
    size_t n;
    if (!json_object_is_type(version, json_type_string))
        return gltf_error(g, "no asset.version (not a glTF file?)");
    if (strncmp(json_object_get_string(version), "2.", 2) != 0)
        return gltf_error(g, "glTF version '%.20s'; only 2.x is supported",
                          json_object_get_string(version));
    if (!array_member(g, g->root, "extensionsRequired", "file", &required, &n))
        return false;
    if (n > 0)
        return gltf_error(g, "requires extension '%.60s', which aoview does not support",
                          json_object_get_string(json_object_array_get_idx(required, 0)));
    return true;
}

/* Everything after the JSON is parsed: arrays, buffers, the node tree, the instances. */
static bool read_scene(struct gltf *g)
{
    json_object *buffers;
    size_t node_count, mesh_count, count;
    if (!check_asset(g) || !array_member(g, g->root, "accessors", "file", &g->accessors, &count) ||
        !array_member(g, g->root, "bufferViews", "file", &g->views, &count) ||
        !array_member(g, g->root, "meshes", "file", &g->meshes, &mesh_count) ||
        !array_member(g, g->root, "nodes", "file", &g->nodes, &node_count) ||
        !array_member(g, g->root, "buffers", "file", &buffers, &g->buffer_count))
        return false;
    /* The per-node, per-buffer and per-mesh arrays: each of those is a JSON object, whose charge
     * (json_cost) covers them. */
    g->buffers = calloc(g->buffer_count ? g->buffer_count : 1, sizeof *g->buffers);
    g->parent = malloc((node_count ? node_count : 1) * sizeof *g->parent);
    g->world = malloc((node_count ? node_count : 1) * sizeof *g->world);
    bool *flags = calloc(node_count ? 2 * node_count : 1, sizeof *flags);
    g->sizes = calloc(mesh_count ? mesh_count : 1, sizeof *g->sizes);
    bool ok = (g->buffers && g->parent && g->world && flags && g->sizes) ||
              ao_load_out_of_memory(g->path);
    for (size_t i = 0; ok && i < g->buffer_count; i++)
        ok = load_buffer(g, json_object_array_get_idx(buffers, i), i);
    bool *is_root = flags, *placed = flags + node_count;
    ok = ok && check_tree(g, node_count) && find_roots(g, node_count, is_root) &&
         place_nodes(g, node_count, is_root, placed);

    /* First count (validating every accessor), then refuse a mesh, as its nodes instance it,
     * that does not fit in the budget beside what the load holds already. Then fill. */
    for (size_t i = 0; ok && i < node_count; i++)
        ok = !placed[i] || add_node_mesh(g, i, true);
    ok = ok && ao_load_fits(g->budget, g->triangles, g->vertices, g->path, 0);
    g->triangles = g->vertices = 0;
    for (size_t i = 0; ok && i < node_count; i++)
        ok = !placed[i] || add_node_mesh(g, i, false);
    free(flags);
    return ok;
}

bool ao_load_gltf(struct ao_mesh *mesh, const char *path, const char *text, size_t size,
                  struct ao_budget *budget)
{
    struct gltf g = {
        .path = path,
        .budget = budget,
        .positions = {.size = sizeof(struct ao_vec3)},
        .normals = {.size = sizeof(struct ao_vec3)},
        .lacking = {.size = sizeof(bool)},
        .indices = {.size = sizeof(uint32_t)},
    };
    const unsigned char *json = (const unsigned char *)text;
    size_t json_size = size;
    bool glb = size >= 4 && le32(json) == GLB_MAGIC;
    bool ok = (!glb || parse_glb(&g, (const unsigned char *)text, size, &json, &json_size)) &&
              parse_json(&g, (const char *)json, json_size) && read_scene(&g);
    if (ok) {
        mesh->vertex_count = g.positions.count;
        mesh->positions = ao_load_take(&g.positions);
        mesh->triangle_count = g.indices.count / 3;
        mesh->indices = ao_load_take(&g.indices);
        bool all_lacking = g.lacking_count == mesh->vertex_count;
        mesh->normals = ao_load_take(&g.normals);
        if (all_lacking) {
            free(mesh->normals);
            mesh->normals = NULL;
        }
        const bool *lacking = all_lacking || !g.lacking_count ? NULL : (const bool *)g.lacking.data;
        ok = ao_load_finish(mesh, path, lacking);
    }
    for (size_t i = 0; i < g.buffer_count && g.buffers; i++)
        free(g.buffers[i].owned);
    free(g.buffers);
    free(g.parent);
    free(g.world);
    free(g.sizes);
    json_object_put(g.root);
    ao_load_free(&g.positions);
    ao_load_free(&g.normals);
    ao_load_free(&g.lacking);
    ao_load_free(&g.indices);
    ao_budget_give(budget, g.taken);
    return ok;
}
