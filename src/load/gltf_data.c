/* The glTF loader's data layer (see gltf.h): JSON access, the GLB container, buffers (the BIN
 * chunk, base64 data URIs, files in the model's folder) and accessors, every range checked before
 * anything is read through it. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "draco.h"
#include "file.h"
#include "gltf.h"
#include "meshopt.h"
#include "quantize.h"

/* GLB container constants: magic "glTF", chunk types "JSON" and "BIN\0". */
enum { GLB_MAGIC = 0x46546C67, GLB_JSON = 0x4E4F534A, GLB_BIN = 0x004E4942, GLB_HEADER = 12 };

/* Reports "path: message" and returns false. */
bool ao_gltf_error(const struct ao_gltf *g, const char *format, ...)
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

/* ------------------------------------------------------------------ containers and buffers */

/* A little-endian 32-bit word. */
static uint32_t le32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

/* A GLB: header, then chunks; the first must be JSON, a BIN chunk may follow. Sets *json. */
bool ao_gltf_parse_glb(struct ao_gltf *g, const unsigned char *data, size_t size,
                      const unsigned char **json, size_t *json_size)
{
    if (size < GLB_HEADER || le32(data) != GLB_MAGIC)
        return ao_gltf_error(g, "not a GLB file (no 'glTF' magic)");
    if (le32(data + 4) != 2)
        return ao_gltf_error(g, "GLB version %u; only version 2 is supported", le32(data + 4));
    /* Bytes after the stated length are ignored (the validator only warns), and said so. */
    size_t stated = le32(data + 8);
    if (stated > size || stated < GLB_HEADER)
        return ao_gltf_error(g, "GLB header says %zu bytes, the file has %zu", stated, size);
    if (stated < size)
        ao_gltf_note(g, "%zu bytes after the GLB's stated length of %zu are ignored", size - stated, stated);
    size = stated;
    *json = NULL;
    for (size_t offset = GLB_HEADER; offset < size;) {
        if (size - offset < 8)
            return ao_gltf_error(g, "GLB chunk header at byte %zu runs past the end", offset);
        size_t length = le32(data + offset), type = le32(data + offset + 4);
        if (length > size - offset - 8)
            return ao_gltf_error(g, "GLB chunk at byte %zu claims %zu bytes, only %zu remain", offset,
                              length, size - offset - 8);
        const unsigned char *body = data + offset + 8;
        if (!*json && type != GLB_JSON)
            return ao_gltf_error(g, "GLB's first chunk is not JSON");
        if (!*json) {
            *json = body;
            *json_size = length;
        } else if (type == GLB_BIN && !g->bin) {
            g->bin = body;
            g->bin_size = length;
        }
        offset += 8 + length;
    }
    return *json || ao_gltf_error(g, "GLB without a JSON chunk");
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

/* The value of a hexadecimal digit, or -1. */
static int hex_digit(unsigned char c)
{
    return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
}

/* Decodes the percent-encoded text of a data URI that is not base64 (RFC 2397: bytes as they are,
 * or %XX) into a new buffer; false at a bad escape, with its offset in *bad. */
static bool decode_percent(const char *text, size_t n, unsigned char **out, size_t *size, size_t *bad)
{
    unsigned char *bytes = malloc(n ? n : 1);
    size_t count = 0;
    *bad = SIZE_MAX;
    for (size_t i = 0; bytes && i < n; i++) {
        int high = 0, low = 0;
        if (text[i] == '%' && (i + 2 >= n || (high = hex_digit((unsigned char)text[i + 1])) < 0 ||
                               (low = hex_digit((unsigned char)text[i + 2])) < 0)) {
            *bad = i;
            break;
        }
        bytes[count++] = text[i] == '%' ? (unsigned char)(high << 4 | low) : (unsigned char)text[i];
        i += text[i] == '%' ? 2 : 0;
    }
    if (!bytes || *bad != SIZE_MAX) {
        free(bytes);
        return false;
    }
    *out = bytes;
    *size = count;
    return true;
}

/* Reads byteLength bytes of the file a buffer's URI names inside the model's folder (uri.c). */
static bool read_buffer_file(struct ao_gltf *g, const char *where, const char *uri, uint64_t length,
                             struct ao_gltf_buffer *b)
{
    char path[4096], why[160];
    int fd;
    if (!ao_load_uri_decode(uri, path, sizeof path, why, sizeof why) ||
        !ao_load_uri_open(g->path, path, &fd, why, sizeof why))
        return ao_gltf_error(g, "%s ('%.60s'): %s", where, uri, why);
    char *data = NULL, what[100];
    snprintf(what, sizeof what, "%s ('%.40s'), byteLength %llu,", where, uri, (unsigned long long)length);
    if (length >= SIZE_MAX || !ao_gltf_take(g, length + 1, what)) {
        close(fd);
        return length >= SIZE_MAX && ao_gltf_error(g, "%s too large", what);   /* else take reported */
    }
    const char *reason = NULL;
    bool ok = ao_file_read_prefix(fd, (size_t)length, &data, &reason);
    if (ok)
        ao_file_note_input(fd, path);
    close(fd);
    if (!ok)
        return ao_gltf_error(g, "%s ('%.60s'), byteLength %llu: %s", where, uri,
                          (unsigned long long)length, reason);
    b->data = b->owned = (unsigned char *)data;
    return true;
}

/* Loads buffer i's bytes: the GLB's BIN chunk (no uri), a data URI or a file in the glTF's
 * folder. Buffers load when a bufferView is first read from them: one that is never read (an
 * unused buffer, a fallback without data) may have none. */
static bool load_buffer(struct ao_gltf *g, size_t i)
{
    char where[64];
    snprintf(where, sizeof where, "buffer %zu", i);
    struct ao_gltf_buffer *b = &g->buffers[i];
    json_object *json = json_object_array_get_idx(g->buffer_json, i);
    uint64_t length = b->size;
    b->loaded = true;
    json_object *uri_json = ao_gltf_member(json, "uri");
    const char *uri = json_object_is_type(uri_json, json_type_string)
                          ? json_object_get_string(uri_json) : NULL;
    size_t size = 0;
    if (uri_json && !uri)
        return ao_gltf_error(g, "%s: 'uri' is not a string", where);
    if (!uri) {
        if (i != 0 || !g->bin)
            return ao_gltf_error(g, "%s has no 'uri' and is not a GLB's BIN chunk: it has no data", where);
        b->data = g->bin;
        size = g->bin_size;
    } else if (strncmp(uri, "data:", 5) == 0) {
        /* data:[<media type>][;base64],<data>; without ;base64 the data is percent-encoded. */
        const char *comma = strchr(uri, ',');
        if (!comma)
            return ao_gltf_error(g, "%s: a data URI without a comma", where);
        bool base64 = comma - uri >= 12 && strncasecmp(comma - 7, ";base64", 7) == 0;
        size_t digits = strlen(comma + 1), bad;
        char what[96];
        snprintf(what, sizeof what, "%.64s's data URI", where);
        if (!ao_gltf_take(g, base64 ? digits / 4 * 3 + 3 : digits + 1, what))
            return false;
        if (base64 && !decode_base64(comma + 1, digits, &b->owned, &size))
            return ao_gltf_error(g, "%s: bad base64 data (or out of memory)", where);
        if (!base64 && !decode_percent(comma + 1, digits, &b->owned, &size, &bad))
            return bad == SIZE_MAX ? ao_load_out_of_memory(g->path)
                                   : ao_gltf_error(g, "%s: bad percent-encoding at byte %zu of its data URI's data",
                                                   where, bad);
        b->data = b->owned;
    } else {
        if (!read_buffer_file(g, where, uri, length, b))
            return false;
        size = (size_t)length;
    }
    if (size < length)
        return ao_gltf_error(g, "%s: byteLength %llu but only %zu bytes of data", where,
                          (unsigned long long)length, size);
    return true;
}

/* Buffer i, its byteLength read (and with need_data its bytes loaded) on first use. */
static bool buffer(struct ao_gltf *g, size_t i, bool need_data, const struct ao_gltf_buffer **out)
{
    struct ao_gltf_buffer *b = &g->buffers[i];
    *out = b;
    if (!b->known) {
        char where[64];
        uint64_t length;
        snprintf(where, sizeof where, "buffer %zu", i);
        if (!ao_gltf_integer(g, json_object_array_get_idx(g->buffer_json, i), "byteLength", true, 0,
                             AO_GLTF_MAX_INTEGER, where, &length))
            return false;
        if (length > SIZE_MAX / 2)
            return ao_gltf_error(g, "%s: byteLength %llu is too large", where, (unsigned long long)length);
        b->size = (size_t)length;
        b->known = true;
    }
    return !need_data || b->loaded || load_buffer(g, i);
}

/* The bufferView json (index) whose EXT_meshopt_compression extension ext holds its data
 * compressed: the compressed bytes checked against their buffer, the mode, filter, count and
 * stride against what the library accepts and the view's byteLength against count * stride; the
 * decoded data, charged to the budget first, becomes the view's own. The view's own buffer (a
 * fallback, often without data) is not read. */
static bool meshopt_view(struct ao_gltf *g, size_t index, json_object *json, json_object *ext,
                         struct ao_gltf_view *v)
{
    char where[96], why[200];
    snprintf(where, sizeof where, "bufferView %zu (EXT_meshopt_compression)", index);
    uint64_t offset, length, stride, count, view_length, view_stride;
    size_t source, fallback;
    json_object *mode_json = ao_gltf_member(ext, "mode"), *filter_json = ao_gltf_member(ext, "filter");
    enum ao_meshopt_mode mode;
    enum ao_meshopt_filter filter;
    const struct ao_gltf_buffer *b;
    if (!ao_gltf_index(g, json, "buffer", g->buffer_count, where, &fallback) ||
        !ao_gltf_integer(g, json, "byteLength", true, 0, AO_GLTF_MAX_INTEGER, where, &view_length) ||
        !ao_gltf_integer(g, json, "byteStride", false, 0, 252, where, &view_stride) ||
        !ao_gltf_index(g, ext, "buffer", g->buffer_count, where, &source) ||
        !ao_gltf_integer(g, ext, "byteOffset", false, 0, AO_GLTF_MAX_INTEGER, where, &offset) ||
        !ao_gltf_integer(g, ext, "byteLength", true, 0, AO_GLTF_MAX_INTEGER, where, &length) ||
        !ao_gltf_integer(g, ext, "byteStride", true, 0, 256, where, &stride) ||
        !ao_gltf_integer(g, ext, "count", true, 0, (double)UINT32_MAX, where, &count))
        return false;
    if (!json_object_is_type(mode_json, json_type_string) ||
        (filter_json && !json_object_is_type(filter_json, json_type_string)) ||
        !ao_meshopt_parse(json_object_get_string(mode_json), filter_json ? json_object_get_string(filter_json) : NULL,
                          &mode, &filter))
        return ao_gltf_error(g, "%s: 'mode' must be ATTRIBUTES, TRIANGLES or INDICES and 'filter' NONE, OCTAHEDRAL, "
                             "QUATERNION or EXPONENTIAL", where);
    if (!ao_meshopt_check(mode, filter, (size_t)count, (size_t)stride, why, sizeof why))
        return ao_gltf_error(g, "%s: %s", where, why);
    if (view_length != stride * count)
        return ao_gltf_error(g, "%s: the view's byteLength %llu is not byteStride %llu times count %llu", where,
                             (unsigned long long)view_length, (unsigned long long)stride, (unsigned long long)count);
    if (view_stride && view_stride != stride)
        return ao_gltf_error(g, "%s: the view's byteStride %llu differs from the extension's %llu", where,
                             (unsigned long long)view_stride, (unsigned long long)stride);
    if (!buffer(g, source, false, &b))
        return false;
    if (offset + length > b->size)
        return ao_gltf_error(g, "%s: bytes [%llu, %llu) run past buffer %zu (%zu bytes)", where,
                             (unsigned long long)offset, (unsigned long long)(offset + length), source, b->size);
    char what[160];
    snprintf(what, sizeof what, "%s: decoding %llu elements of %llu bytes", where, (unsigned long long)count,
             (unsigned long long)stride);
    if (!buffer(g, source, true, &b) || !ao_gltf_take(g, view_length, what))
        return false;
    if (!(v->owned = malloc(view_length ? (size_t)view_length : 1)))
        return ao_load_out_of_memory(g->path);
    if (!ao_meshopt_decode(mode, filter, (size_t)count, (size_t)stride, b->data + offset, (size_t)length, v->owned,
                           why, sizeof why))
        return ao_gltf_error(g, "%s: %s", where, why);
    v->data = v->owned;
    v->length = (size_t)view_length;
    v->stride = (size_t)view_stride;
    v->ready = true;
    return true;
}

/* bufferView index, read and checked against its buffer on first use: its bytes and stride. */
static bool view(struct ao_gltf *g, size_t index, const struct ao_gltf_view **out)
{
    struct ao_gltf_view *v = &g->view_cache[index];
    *out = v;
    if (v->ready)
        return true;
    char where[64];
    snprintf(where, sizeof where, "bufferView %zu", index);
    json_object *json = json_object_array_get_idx(g->views, index);
    json_object *ext = ao_gltf_member(ao_gltf_member(json, "extensions"), "EXT_meshopt_compression");
    if (ext)
        return meshopt_view(g, index, json, ext, v);
    uint64_t offset, length, stride;
    size_t buffer_index;
    const struct ao_gltf_buffer *b;
    if (!ao_gltf_index(g, json, "buffer", g->buffer_count, where, &buffer_index) ||
        !ao_gltf_integer(g, json, "byteOffset", false, 0, AO_GLTF_MAX_INTEGER, where, &offset) ||
        !ao_gltf_integer(g, json, "byteLength", true, 0, AO_GLTF_MAX_INTEGER, where, &length) ||
        !ao_gltf_integer(g, json, "byteStride", false, 0, 252, where, &stride) ||
        !buffer(g, buffer_index, false, &b))
        return false;
    if (offset + length > b->size)
        return ao_gltf_error(g, "%s: bytes [%llu, %llu) run past buffer %zu (%zu bytes)", where,
                          (unsigned long long)offset, (unsigned long long)(offset + length), buffer_index,
                          b->size);
    if (!buffer(g, buffer_index, true, &b))
        return false;
    v->data = b->data + offset;
    v->offset = (size_t)offset;
    v->length = (size_t)length;
    v->stride = (size_t)stride;
    v->ready = true;
    return true;
}

/* ------------------------------------------------------------------ accessors */

/* Whether an accessor's componentType may be an attribute's (positions and normals: float, or
 * (KHR_mesh_quantization) 8- or 16-bit integers, normalized or not) or indices' (unsigned integers,
 * never normalized), and its 'normalized' (NULL: absent) true or false; false after reporting at
 * where. Plain and Draco-compressed accessors alike. */
static bool check_component(const struct ao_gltf *g, uint64_t component, json_object *normalized, bool attribute,
                            const char *where)
{
    bool is_index = component == AO_QUANTIZE_UNSIGNED_BYTE || component == AO_QUANTIZE_UNSIGNED_SHORT ||
                    component == AO_QUANTIZE_UNSIGNED_INT;
    bool is_attribute = component != AO_QUANTIZE_UNSIGNED_INT && ao_quantize_size((int)component) > 0;
    if (attribute ? !is_attribute : !is_index)
        return ao_gltf_error(g, "%s: componentType %llu; %s", where, (unsigned long long)component,
                             attribute ? "positions and normals must be float (5126), or byte, unsigned byte, short "
                                         "or unsigned short (5120 to 5123, KHR_mesh_quantization)"
                                       : "indices must be unsigned byte, short or int");
    if (normalized && !json_object_is_type(normalized, json_type_boolean))
        return ao_gltf_error(g, "%s: 'normalized' is not true or false", where);
    if (normalized && json_object_get_boolean(normalized) && (component == AO_QUANTIZE_FLOAT || !attribute))
        return ao_gltf_error(g, "%s: 'normalized' on %s (glTF normalizes 8- and 16-bit integer attributes only)",
                             where, attribute ? "float components" : "indices");
    return true;
}

/* How elements must be aligned in their bufferView, as glTF requires (its validator reports each
 * as an error): to their component's size from the start of the buffer; vertex attributes to 4
 * bytes, byteOffset and byteStride alike. Indices and sparse entries off their alignment are
 * refused; vertex attributes are read as they lie, with a note (ALIGN_VERTEX: the readers users
 * have read them, as cesium-native reads its own cubeQuantized.glb's shorts 6 bytes apart), since
 * every component is read byte by byte. */
enum alignment { ALIGN_COMPONENT, ALIGN_VERTEX };

/* Notes, once, that the vertex attribute `where` (at byte `start` of its buffer, step bytes apart)
 * lies off glTF's alignment. */
static void note_unaligned(struct ao_gltf *g, const char *where, uint64_t start, uint64_t step)
{
    char what[sizeof g->unaligned];
    snprintf(what, sizeof what, "%s at byte %llu of its buffer, %llu bytes apart", where, (unsigned long long)start,
             (unsigned long long)step);
    if (!g->unaligned[0])
        snprintf(g->unaligned, sizeof g->unaligned, "%s", what);
    else if (strcmp(g->unaligned, what) != 0)
        g->unaligned_more = true;
}

/* count elements of element bytes (components of component bytes) from byte offset of bufferView
 * index, stride bytes apart (0: packed), checked to lie inside the view and to be aligned as
 * `alignment` says (vertex attributes off it noted); where and what name them in messages. */
static bool view_elements(struct ao_gltf *g, size_t index, uint64_t offset, uint64_t count, size_t element,
                          size_t component, enum alignment alignment, bool strided, const char *where,
                          const unsigned char **first, size_t *stride)
{
    const struct ao_gltf_view *v;
    if (!view(g, index, &v))
        return false;
    uint64_t step = strided && v->stride ? v->stride : element;
    if (step < element)
        return ao_gltf_error(g, "bufferView %zu: byteStride %llu is smaller than an element (%zu bytes)", index,
                             (unsigned long long)step, element);
    if (alignment == ALIGN_COMPONENT && (v->offset + offset) % component)
        return ao_gltf_error(g, "%s: byte %llu of its buffer (byteOffset %llu in bufferView %zu) is not a multiple of "
                             "its %zu-byte components, as glTF requires", where,
                             (unsigned long long)(v->offset + offset), (unsigned long long)offset, index, component);
    /* The last element ends inside the view: offset + step * (count - 1) + element. */
    uint64_t end = offset + step * (count - 1) + element;
    if (end > v->length)
        return ao_gltf_error(g, "%s: %llu elements from byte %llu need %llu bytes of bufferView %zu, which has %zu",
                             where, (unsigned long long)count, (unsigned long long)offset, (unsigned long long)end,
                             index, v->length);
    if (alignment == ALIGN_VERTEX && ((v->offset + offset) % component || offset % 4 || (count > 1 && step % 4)))
        note_unaligned(g, where, v->offset + offset, step);
    *first = v->data + offset;
    *stride = (size_t)step;
    return true;
}

/* The accessor's elements gathered into memory of their own (packed, element bytes each), charged
 * to the budget: a copy of those of its bufferView, or zeros without one, with the sparse entries,
 * if any, written over them (of component bytes each, aligned to them). Each sparse index is checked
 * against the count and must follow the one before, as glTF requires. */
static bool gather(struct ao_gltf *g, size_t i, json_object *a, const char *where, uint64_t count, size_t element,
                   size_t component, const struct ao_gltf_elements *base)
{
    char what[128];
    snprintf(what, sizeof what, "%s: its %llu values", where, (unsigned long long)count);
    if (!ao_gltf_take(g, count * element, what))
        return false;
    unsigned char *dense = calloc((size_t)count, element);
    if (!dense)
        return ao_load_out_of_memory(g->path);
    g->gathered[i] = dense;
    for (size_t k = 0; base && k < count; k++)
        memcpy(dense + k * element, base->first + k * base->stride, element);
    json_object *sparse = ao_gltf_member(a, "sparse");
    if (!sparse)
        return true;

    /* sparse: count entries; indices (unsigned integers) and values, each in a bufferView. */
    char sparse_where[128];
    snprintf(sparse_where, sizeof sparse_where, "%s sparse", where);
    json_object *indices = ao_gltf_member(sparse, "indices"), *values = ao_gltf_member(sparse, "values");
    uint64_t entries, index_type, index_offset, value_offset;
    if (!json_object_is_type(indices, json_type_object) || !json_object_is_type(values, json_type_object))
        return ao_gltf_error(g, "%s: no 'indices' and 'values' objects", sparse_where);
    size_t index_view, value_view, index_stride, value_stride;
    const unsigned char *index_first, *value_first;
    if (!ao_gltf_integer(g, sparse, "count", true, 0, (double)UINT32_MAX, sparse_where, &entries) ||
        !ao_gltf_integer(g, indices, "componentType", true, 0, AO_GLTF_MAX_INTEGER, sparse_where, &index_type) ||
        !ao_gltf_integer(g, indices, "byteOffset", false, 0, AO_GLTF_MAX_INTEGER, sparse_where, &index_offset) ||
        !ao_gltf_index(g, indices, "bufferView", ao_gltf_length(g->views), sparse_where, &index_view) ||
        !ao_gltf_integer(g, values, "byteOffset", false, 0, AO_GLTF_MAX_INTEGER, sparse_where, &value_offset) ||
        !ao_gltf_index(g, values, "bufferView", ao_gltf_length(g->views), sparse_where, &value_view))
        return false;
    if (entries == 0)
        return ao_gltf_error(g, "%s: count is 0", sparse_where);
    if (index_type != AO_QUANTIZE_UNSIGNED_BYTE && index_type != AO_QUANTIZE_UNSIGNED_SHORT &&
        index_type != AO_QUANTIZE_UNSIGNED_INT)
        return ao_gltf_error(g, "%s: indices' componentType %llu; they must be unsigned byte, short or int",
                             sparse_where, (unsigned long long)index_type);
    struct ao_gltf_elements at_list = {.component_type = (int)index_type};
    snprintf(what, sizeof what, "%s sparse indices", where);
    if (!view_elements(g, index_view, index_offset, entries, ao_quantize_size((int)index_type),
                       ao_quantize_size((int)index_type), ALIGN_COMPONENT, false, what, &index_first, &index_stride))
        return false;
    snprintf(what, sizeof what, "%s sparse values", where);
    if (!view_elements(g, value_view, value_offset, entries, element, component, ALIGN_COMPONENT, false, what,
                       &value_first, &value_stride))
        return false;
    at_list.first = index_first;
    at_list.stride = index_stride;
    for (size_t k = 0; k < entries; k++) {
        uint32_t at = ao_gltf_index_at(&at_list, k);
        if (at >= count)
            return ao_gltf_error(g, "%s: index %u at %zu is out of range (%llu elements)", sparse_where, at, k,
                                 (unsigned long long)count);
        if (k > 0 && at <= ao_gltf_index_at(&at_list, k - 1))
            return ao_gltf_error(g, "%s: index %u at %zu does not follow %u: glTF's sparse indices strictly increase",
                                 sparse_where, at, k, ao_gltf_index_at(&at_list, k - 1));
        memcpy(dense + (size_t)at * element, value_first + k * value_stride, element);
    }
    return true;
}

bool ao_gltf_accessor(struct ao_gltf *g, size_t i, bool attribute, const char *use, struct ao_gltf_elements *out)
{
    const char *type = attribute ? "VEC3" : "SCALAR";
    char where[96];
    snprintf(where, sizeof where, "accessor %zu (%s)", i, use);
    json_object *a = json_object_array_get_idx(g->accessors, i);
    json_object *type_json = ao_gltf_member(a, "type");
    json_object *normalized = ao_gltf_member(a, "normalized");
    bool has_view = ao_gltf_member(a, "bufferView") != NULL, sparse = ao_gltf_member(a, "sparse") != NULL;
    uint64_t component, count, offset;
    size_t view_index = 0;
    if (!json_object_is_type(type_json, json_type_string) ||
        strcmp(json_object_get_string(type_json), type) != 0)
        return ao_gltf_error(g, "%s: type must be %s", where, type);
    if (!ao_gltf_integer(g, a, "componentType", true, 0, AO_GLTF_MAX_INTEGER, where, &component) ||
        !ao_gltf_integer(g, a, "count", true, 0, (double)UINT32_MAX, where, &count) ||
        !ao_gltf_integer(g, a, "byteOffset", false, 0, AO_GLTF_MAX_INTEGER, where, &offset) ||
        (has_view && !ao_gltf_index(g, a, "bufferView", ao_gltf_length(g->views), where, &view_index)))
        return false;
    if (!check_component(g, component, normalized, attribute, where))
        return false;
    if (count == 0)
        return ao_gltf_error(g, "%s: count is 0", where);
    size_t size = ao_quantize_size((int)component), element = (attribute ? 3 : 1) * size;
    *out = (struct ao_gltf_elements){NULL, element, (size_t)count, (int)component, size,
                                     normalized && json_object_get_boolean(normalized)};
    if (has_view && !view_elements(g, view_index, offset, count, element, size,
                                   attribute ? ALIGN_VERTEX : ALIGN_COMPONENT, true, where, &out->first, &out->stride))
        return false;

    /* Without a bufferView (zeros) or with sparse entries: gathered once into memory of its own. */
    if (has_view && !sparse)
        return true;
    if (!g->gathered[i] && !gather(g, i, a, where, count, element, size, has_view ? out : NULL))
        return false;
    out->first = g->gathered[i];
    out->stride = element;
    return true;
}

/* The attribute or indices accessor of a Draco-compressed primitive (name in attributes, or
 * "indices" of the primitive): its index, count and, for an attribute, how it reads its values
 * (VEC3 of float, or of 8- and 16-bit integers, KHR_mesh_quantization; normalized only those); its
 * componentType checked as a plain accessor's. The extension forbids 'sparse' on these accessors,
 * which read decoded data only. */
static bool draco_accessor(struct ao_gltf *g, json_object *holder, const char *name, bool attribute, const char *where,
                           size_t *index, uint64_t *count, struct ao_gltf_reading *reading)
{
    uint64_t component;
    char what[128];
    if (!ao_gltf_index(g, holder, name, ao_gltf_length(g->accessors), where, index))
        return false;
    snprintf(what, sizeof what, "accessor %zu (%s)", *index, name);
    json_object *a = json_object_array_get_idx(g->accessors, *index), *type = ao_gltf_member(a, "type");
    json_object *normalized = ao_gltf_member(a, "normalized");
    if (!json_object_is_type(type, json_type_string) || strcmp(json_object_get_string(type), attribute ? "VEC3" : "SCALAR"))
        return ao_gltf_error(g, "%s: type must be %s", what, attribute ? "VEC3" : "SCALAR");
    if (!ao_gltf_integer(g, a, "count", true, 0, AO_GLTF_MAX_INTEGER, what, count) ||
        !ao_gltf_integer(g, a, "componentType", true, 0, AO_GLTF_MAX_INTEGER, what, &component) ||
        !check_component(g, component, normalized, attribute, what))
        return false;
    if (ao_gltf_member(a, "sparse"))
        return ao_gltf_error(g, "%s: 'sparse' on an accessor of KHR_draco_mesh_compression data, which the extension "
                             "forbids", what);
    if (attribute)
        *reading = (struct ao_gltf_reading){(int)component, normalized && json_object_get_boolean(normalized)};
    return true;
}

/* Dequantizes the count VEC3 values decoded as integers in place, as their accessor reads them
 * (ao_quantize_value, from the little-endian bytes of the component type); false (reported) at a
 * value outside that type. */
static bool dequantize(struct ao_gltf *g, float *values, size_t count, struct ao_gltf_reading reading,
                       const char *what)
{
    if (reading.component_type == AO_QUANTIZE_FLOAT)
        return true;
    bool is_signed = reading.component_type == AO_QUANTIZE_BYTE || reading.component_type == AO_QUANTIZE_SHORT;
    size_t size = ao_quantize_size(reading.component_type);
    double bits = 8.0 * (double)size, lo = is_signed ? -ldexp(1.0, (int)bits - 1) : 0.0;
    double hi = is_signed ? ldexp(1.0, (int)bits - 1) - 1.0 : ldexp(1.0, (int)bits) - 1.0;
    for (size_t i = 0; i < 3 * count; i++) {
        double v = values[i];
        if (!(v >= lo && v <= hi))
            return ao_gltf_error(g, "%s: point %zu's value %.0f lies outside componentType %d", what, i / 3, v,
                                 reading.component_type);
        uint32_t word = (uint32_t)(int32_t)v;
        unsigned char le[2] = {(unsigned char)word, (unsigned char)(word >> 8)};
        values[i] = (float)ao_quantize_value(le, reading.component_type, reading.normalized);
    }
    return true;
}

/* Notes a Draco primitive whose accessor counts otherwise than its data decode (the first named). */
static void recounted(struct ao_gltf *g, const char *where, size_t accessor, uint64_t count, size_t decoded,
                      const char *what)
{
    if (g->recounted++ == 0)
        snprintf(g->recount, sizeof g->recount, "%s (KHR_draco_mesh_compression): accessor %zu counts %llu %s where "
                 "its data decode to %zu", where, accessor, (unsigned long long)count, what, decoded);
}

bool ao_gltf_draco(struct ao_gltf *g, json_object *primitive, json_object *ext, bool normals, const char *where,
                   struct ao_gltf_elements out[3])
{
    char at[128], why[256];
    snprintf(at, sizeof at, "%s (KHR_draco_mesh_compression)", where);
    json_object *attributes = ao_gltf_member(ext, "attributes"), *accessors = ao_gltf_member(primitive, "attributes");
    size_t index, accessor[3] = {0, 0, 0};
    uint64_t position_id, normal_id = 0, counts[3] = {0, 0, 0};
    struct ao_gltf_reading readings[2] = {{AO_QUANTIZE_FLOAT, false}, {AO_QUANTIZE_FLOAT, false}};
    bool indexed = ao_gltf_member(primitive, "indices") != NULL;
    if (!ao_gltf_index(g, ext, "bufferView", ao_gltf_length(g->views), at, &index) ||
        !ao_gltf_integer(g, attributes, "POSITION", true, 0, UINT32_MAX, at, &position_id) ||
        (normals && !ao_gltf_integer(g, attributes, "NORMAL", true, 0, UINT32_MAX, at, &normal_id)) ||
        !draco_accessor(g, accessors, "POSITION", true, at, &accessor[0], &counts[0], &readings[0]) ||
        (normals && !draco_accessor(g, accessors, "NORMAL", true, at, &accessor[1], &counts[1], &readings[1])) ||
        (indexed && !draco_accessor(g, primitive, "indices", false, at, &accessor[2], &counts[2], NULL)))
        return false;

    /* Decoded once per bufferView, within what the budget has left; then the arrays are charged. */
    struct ao_gltf_draco *d = &g->draco[index];
    int64_t want_normal = normals ? (int64_t)normal_id : -1;
    if (d->done && (d->position_id != (int64_t)position_id || d->normal_id != want_normal ||
                    memcmp(d->readings, readings, sizeof readings) != 0))
        return ao_gltf_error(g, "%s: bufferView %zu is decoded for other attribute ids or types by another primitive",
                             at, index);
    if (!d->done) {
        const struct ao_gltf_view *v;
        bool over = false, integers[2] = {readings[0].component_type != AO_QUANTIZE_FLOAT,
                                          readings[1].component_type != AO_QUANTIZE_FLOAT};
        if (!view(g, index, &v))
            return false;
        uint64_t left = g->budget->limit - g->budget->used;
        if (!ao_draco_decode(v->data, v->length, (int64_t)position_id, want_normal, integers, left, &d->mesh, &over,
                             why, sizeof why))
            return over ? ao_gltf_error(g, "%s: decoding it would take more than the %llu bytes left of the scene "
                                        "budget (raise it with --scene-budget)", at, (unsigned long long)left)
                        : ao_gltf_error(g, "%s: %s", at, why);
        d->done = true;
        d->position_id = (int64_t)position_id;
        d->normal_id = want_normal;
        memcpy(d->readings, readings, sizeof readings);
        snprintf(why, sizeof why, "%s: its %zu points and %zu triangles", at, d->mesh.point_count,
                 d->mesh.face_count);
        uint64_t bytes = (uint64_t)d->mesh.point_count * (normals ? 24 : 12) + (uint64_t)d->mesh.face_count * 12;
        if (!ao_gltf_take(g, bytes, why) ||
            !dequantize(g, d->mesh.positions, d->mesh.point_count, readings[0], at) ||
            (normals && !dequantize(g, d->mesh.normals, d->mesh.point_count, readings[1], at)))
            return false;
        /* An accessor that counts otherwise than what decoded (Draco may add points at seams; the
         * Khronos CesiumMilkTruck sample counts 1856 for 1886) is read as decoded, as cesium-native
         * reads it: the triangles name decoded points only (draco.cc checks each). */
        if (counts[0] != d->mesh.point_count)
            recounted(g, where, accessor[0], counts[0], d->mesh.point_count, "points");
        else if (normals && counts[1] != d->mesh.point_count)
            recounted(g, where, accessor[1], counts[1], d->mesh.point_count, "normals");
        else if (indexed && counts[2] != 3 * (uint64_t)d->mesh.face_count)
            recounted(g, where, accessor[2], counts[2], 3 * d->mesh.face_count, "indices");
    }
    out[0] = (struct ao_gltf_elements){(const unsigned char *)d->mesh.positions, 12, d->mesh.point_count,
                                       AO_QUANTIZE_FLOAT, 4, false};
    out[1] = (struct ao_gltf_elements){(const unsigned char *)d->mesh.normals, 12, normals ? d->mesh.point_count : 0,
                                       AO_QUANTIZE_FLOAT, 4, false};
    out[2] = (struct ao_gltf_elements){(const unsigned char *)d->mesh.indices, 4, 3 * d->mesh.face_count,
                                       AO_QUANTIZE_UNSIGNED_INT, 4, false};
    return true;
}

double ao_gltf_value(const struct ao_gltf_elements *e, size_t i, int k)
{
    return ao_quantize_value(e->first + i * e->stride + (size_t)k * e->component_size, e->component_type,
                             e->normalized);
}

uint32_t ao_gltf_index_at(const struct ao_gltf_elements *e, size_t i)
{
    const unsigned char *p = e->first + i * e->stride;
    return e->component_type == AO_QUANTIZE_UNSIGNED_INT ? le32(p)
           : e->component_type == AO_QUANTIZE_UNSIGNED_SHORT ? (uint32_t)(p[0] | p[1] << 8) : p[0];
}

struct ao_vec3 ao_gltf_position(const struct ao_gltf_elements *e, size_t i)
{
    const unsigned char *p = e->first + i * e->stride;
    if (e->component_type != AO_QUANTIZE_FLOAT)
        return ao_vec3_make((float)ao_gltf_value(e, i, 0), (float)ao_gltf_value(e, i, 1),
                            (float)ao_gltf_value(e, i, 2));
    uint32_t bits[3] = {le32(p), le32(p + 4), le32(p + 8)};
    float f[3];
    memcpy(f, bits, sizeof f);
    return ao_vec3_make(f[0], f[1], f[2]);
}

bool ao_gltf_list_indices(const struct ao_gltf_elements *e, uint32_t base, size_t limit, uint32_t *out, size_t *bad)
{
    for (size_t i = 0; i < e->count; i++) {
        uint32_t v = ao_gltf_index_at(e, i);
        if (v >= limit) {
            *bad = i;
            return false;
        }
        out[i] = base + v;
    }
    return true;
}

/* ------------------------------------------------------------------ loading and freeing */

bool ao_gltf_begin_data(struct ao_gltf *g)
{
    size_t views = ao_gltf_length(g->views);
    g->buffers = calloc(g->buffer_count ? g->buffer_count : 1, sizeof *g->buffers);
    g->view_cache = calloc(views ? views : 1, sizeof *g->view_cache);
    g->gathered = calloc(ao_gltf_length(g->accessors) + 1, sizeof *g->gathered);
    g->draco = calloc(views ? views : 1, sizeof *g->draco);
    return (g->buffers && g->view_cache && g->gathered && g->draco) || ao_load_out_of_memory(g->path);
}

void ao_gltf_note(struct ao_gltf *g, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    ao_load_vnote(g->note, format, args);
    va_end(args);
}

void ao_gltf_free_data(struct ao_gltf *g)
{
    for (size_t i = 0; i < g->buffer_count && g->buffers; i++)
        free(g->buffers[i].owned);
    free(g->buffers);
    for (size_t i = 0; i < ao_gltf_length(g->views) && g->view_cache; i++)
        free(g->view_cache[i].owned);
    free(g->view_cache);
    for (size_t i = 0; i < ao_gltf_length(g->accessors) && g->gathered; i++)
        free(g->gathered[i]);
    free(g->gathered);
    for (size_t i = 0; i < ao_gltf_length(g->views) && g->draco; i++)
        ao_draco_free(&g->draco[i].mesh);
    free(g->draco);
}
