/* The glTF loader's buffers (see gltf_reader.h): the GLB container, buffers (the BIN chunk, base64
 * and percent-encoded data URIs, files in the model's folder) and bufferViews (plain or
 * EXT_meshopt_compression's), each read on first use and checked against what it lies in. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "file.h"
#include "gltf_reader.h"
#include "meshopt.h"

/* GLB container constants: magic "glTF", chunk types "JSON" and "BIN\0". */
enum { GLB_MAGIC = 0x46546C67, GLB_JSON = 0x4E4F534A, GLB_BIN = 0x004E4942, GLB_HEADER = 12 };

/* A GLB: header, then chunks; the first must be JSON, a BIN chunk may follow. Sets *json. */
bool ao_gltf_parse_glb(struct ao_gltf *g, const unsigned char *data, size_t size,
                      const unsigned char **json, size_t *json_size)
{
    if (size < GLB_HEADER || ao_gltf_le32(data) != GLB_MAGIC)
        return ao_gltf_error(g, "not a GLB file (no 'glTF' magic)");
    if (ao_gltf_le32(data + 4) != 2)
        return ao_gltf_error(g, "GLB version %u; only version 2 is supported", ao_gltf_le32(data + 4));
    /* Bytes after the stated length are ignored (the validator only warns), and said so. */
    size_t stated = ao_gltf_le32(data + 8);
    if (stated > size || stated < GLB_HEADER)
        return ao_gltf_error(g, "GLB header says %zu bytes, the file has %zu", stated, size);
    if (stated < size)
        ao_gltf_note(g, "%zu bytes after the GLB's stated length of %zu are ignored", size - stated, stated);
    size = stated;
    *json = NULL;
    for (size_t offset = GLB_HEADER; offset < size;) {
        if (size - offset < 8)
            return ao_gltf_error(g, "GLB chunk header at byte %zu runs past the end", offset);
        size_t length = ao_gltf_le32(data + offset), type = ao_gltf_le32(data + offset + 4);
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

bool ao_gltf_view(struct ao_gltf *g, size_t index, const struct ao_gltf_view **out)
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

