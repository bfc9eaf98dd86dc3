// KHR_draco_mesh_compression through Debian's libdraco; see draco.h. The one C++ file of aoview.
//
// Memory. A Draco stream of a few bytes can claim billions of faces (the Edgebreaker decoder
// sizes its tables from the header's counts before reading any symbol) or decode many attributes
// of millions of points from almost nothing (entropy-coded constants), and libdraco takes what it
// asks for. Its allocations go through C++'s operator new, which this file replaces for the whole
// program: the replacement is malloc and free, as the default is, except on a thread inside
// ao_draco_decode, where each allocation is counted and one that would hold more than the cap at
// once fails (std::bad_alloc, or NULL for the nothrow forms, which libdraco checks). So the scene
// budget bounds what decoding takes, before it is allocated, whatever the stream claims.
#include "draco.h"

#include <malloc.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <new>

#include <draco/compression/decode.h>
#include <draco/mesh/mesh.h>

namespace {

// The count of what a thread inside ao_draco_decode holds; off elsewhere.
struct Guard {
    bool on, over;
    uint64_t cap, used, peak;
};
thread_local Guard guard;

// malloc, counted against the cap while the guard is on; NULL when it would pass it.
void *counted(std::size_t size) noexcept
{
    if (guard.on && (size > guard.cap || guard.used > guard.cap - size)) {
        guard.over = true;
        return nullptr;
    }
    void *p = std::malloc(size ? size : 1);
    if (p && guard.on) {
        guard.used += malloc_usable_size(p);
        guard.peak = guard.used > guard.peak ? guard.used : guard.peak;
    }
    return p;
}

// free, uncounting while the guard is on.
void uncounted(void *p) noexcept
{
    if (p && guard.on) {
        uint64_t size = malloc_usable_size(p);
        guard.used -= size < guard.used ? size : guard.used;
    }
    std::free(p);
}

// A counted array of n elements of T; NULL when n is 0 or it does not fit.
template <typename T> T *counted_array(std::size_t n)
{
    return n && n <= SIZE_MAX / sizeof(T) ? static_cast<T *>(counted(n * sizeof(T))) : nullptr;
}

// True when the attribute stores integers.
bool stores_integers(const draco::PointAttribute *a)
{
    switch (a->data_type()) {
    case draco::DT_INT8: case draco::DT_UINT8: case draco::DT_INT16: case draco::DT_UINT16:
    case draco::DT_INT32: case draco::DT_UINT32:
        return true;
    default:
        return false;
    }
}

// Reads point p of attribute a as 3 floats into out: as Draco dequantizes it, or with integer the
// integers it stores, each made a float as it is; false when its value is missing or out of range.
bool read_point(const draco::PointAttribute *a, uint32_t p, bool integer, float *out)
{
    draco::PointIndex point(p);
    if (!a->is_mapping_identity() && p >= a->indices_map_size())
        return false;
    draco::AttributeValueIndex value = a->mapped_index(point);
    if (value.value() >= a->size())
        return false;
    if (!integer)
        return a->ConvertValue<float>(value, 3, out);
    int32_t v[3];
    if (!a->ConvertValue<int32_t>(value, 3, v))
        return false;
    for (int k = 0; k < 3; k++)
        out[k] = static_cast<float>(v[k]);
    return true;
}

// The decoding itself, with the guard on.
bool decode(const unsigned char *data, std::size_t size, int64_t position_id, int64_t normal_id,
            const bool integers[2], ao_draco_mesh *out, char *why, std::size_t why_size)
{
    draco::DecoderBuffer buffer;
    buffer.Init(reinterpret_cast<const char *>(data), size);
    auto type = draco::Decoder::GetEncodedGeometryType(&buffer);
    if (!type.ok() || type.value() != draco::TRIANGULAR_MESH) {
        std::snprintf(why, why_size, "not a Draco triangle mesh (%s)",
                      type.ok() ? "a point cloud" : type.status().error_msg());
        return false;
    }
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
    if (!decoded.ok()) {
        std::snprintf(why, why_size, "libdraco cannot decode it (%s)", decoded.status().error_msg());
        return false;
    }
    std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
    const draco::PointAttribute *attributes[2] = {nullptr, nullptr};
    const int64_t ids[2] = {position_id, normal_id};
    for (int k = 0; k < 2; k++) {
        if (ids[k] < 0)
            continue;
        attributes[k] = ids[k] <= UINT32_MAX ? mesh->GetAttributeByUniqueId(static_cast<uint32_t>(ids[k])) : nullptr;
        if (!attributes[k] || attributes[k]->num_components() < 3) {
            std::snprintf(why, why_size, "it has no %s attribute of id %lld with 3 components",
                          k ? "NORMAL" : "POSITION", static_cast<long long>(ids[k]));
            return false;
        }
        if (integers[k] && !stores_integers(attributes[k])) {
            std::snprintf(why, why_size, "its %s attribute stores floats where the accessor says integers",
                          k ? "NORMAL" : "POSITION");
            return false;
        }
    }
    std::size_t points = mesh->num_points(), faces = mesh->num_faces();
    out->positions = counted_array<float>(3 * points);
    out->normals = attributes[1] ? counted_array<float>(3 * points) : nullptr;
    out->indices = counted_array<uint32_t>(3 * faces);
    if (!out->positions || (attributes[1] && !out->normals) || !out->indices) {
        std::snprintf(why, why_size, "%zu points and %zu triangles%s", points, faces,
                      guard.over ? "" : ": none, or out of memory");
        return false;
    }
    out->point_count = points;
    out->face_count = faces;
    for (uint32_t p = 0; p < points; p++)
        for (int k = 0; k < 2; k++)
            if (attributes[k] && !read_point(attributes[k], p, integers[k], (k ? out->normals : out->positions) + 3 * p)) {
                std::snprintf(why, why_size, "point %u has no %s value", p, k ? "NORMAL" : "POSITION");
                return false;
            }
    for (uint32_t f = 0; f < faces; f++) {
        const draco::Mesh::Face &face = mesh->face(draco::FaceIndex(f));
        for (int k = 0; k < 3; k++) {
            uint32_t p = face[k].value();
            if (p >= points) {
                std::snprintf(why, why_size, "triangle %u names point %u of %zu", f, p, points);
                return false;
            }
            out->indices[3 * f + k] = p;
        }
    }
    return true;
}

} // namespace

void *operator new(std::size_t size)
{
    void *p = counted(size);
    if (!p)
        throw std::bad_alloc();
    return p;
}

void *operator new[](std::size_t size)
{
    return operator new(size);
}

void *operator new(std::size_t size, const std::nothrow_t &) noexcept
{
    return counted(size);
}

void *operator new[](std::size_t size, const std::nothrow_t &) noexcept
{
    return counted(size);
}

void operator delete(void *p) noexcept
{
    uncounted(p);
}

void operator delete[](void *p) noexcept
{
    uncounted(p);
}

void operator delete(void *p, std::size_t) noexcept
{
    uncounted(p);
}

void operator delete[](void *p, std::size_t) noexcept
{
    uncounted(p);
}

void operator delete(void *p, const std::nothrow_t &) noexcept
{
    uncounted(p);
}

void operator delete[](void *p, const std::nothrow_t &) noexcept
{
    uncounted(p);
}

extern "C" bool ao_draco_decode(const unsigned char *data, size_t size, int64_t position_id, int64_t normal_id,
                                const bool integers[2], uint64_t cap, struct ao_draco_mesh *out, bool *over_cap,
                                char *why, size_t why_size)
{
    *out = ao_draco_mesh{};
    guard = Guard{true, false, cap, 0, 0};
    bool ok = false;
    try {
        ok = decode(data, size, position_id, normal_id, integers, out, why, why_size);
    } catch (const std::bad_alloc &) {
        std::snprintf(why, why_size, "libdraco ran out of memory");
    } catch (...) {
        std::snprintf(why, why_size, "libdraco failed");
    }
    out->peak = guard.peak;
    *over_cap = guard.over;
    guard.on = false;
    if (!ok)
        ao_draco_free(out);
    return ok;
}

extern "C" void ao_draco_free(struct ao_draco_mesh *mesh)
{
    std::free(mesh->positions);
    std::free(mesh->normals);
    std::free(mesh->indices);
    *mesh = ao_draco_mesh{};
}
