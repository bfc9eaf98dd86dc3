/* The glTF loader's accessors (see gltf_reader.h): plain, sparse, meshopt- or Draco-compressed,
 * every range checked before anything is read through it; the buffers and bufferViews under them
 * are gltf_buffers.c's, the JSON access gltf_json.c's. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "draco.h"
#include "gltf_reader.h"
#include "quantize.h"

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
    if (!ao_gltf_view(g, index, &v))
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
        if (!ao_gltf_view(g, index, &v))
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
    return e->component_type == AO_QUANTIZE_UNSIGNED_INT ? ao_gltf_le32(p)
           : e->component_type == AO_QUANTIZE_UNSIGNED_SHORT ? (uint32_t)(p[0] | p[1] << 8) : p[0];
}

struct ao_vec3 ao_gltf_position(const struct ao_gltf_elements *e, size_t i)
{
    const unsigned char *p = e->first + i * e->stride;
    if (e->component_type != AO_QUANTIZE_FLOAT)
        return ao_vec3_make((float)ao_gltf_value(e, i, 0), (float)ao_gltf_value(e, i, 1),
                            (float)ao_gltf_value(e, i, 2));
    uint32_t bits[3] = {ao_gltf_le32(p), ao_gltf_le32(p + 4), ao_gltf_le32(p + 8)};
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
