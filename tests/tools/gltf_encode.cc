// Writes the triangles of an OBJ file (v and f lines, polygons fanned) as a GLB whose geometry is
// compressed by the libraries aoview decodes with, through their own encoders, for the format and
// hostile tests (tests/sh/test_formats.sh, tests/sh/test_hostile.sh):
//
//   gltf_encode MODE IN.obj OUT.glb
//
//   meshopt            EXT_meshopt_compression: float positions (ATTRIBUTES) and indices as an
//                      index sequence (INDICES): decodes to exactly the OBJ's arrays
//   meshopt-quantized  positions as normalized shorts under a node transform (KHR_mesh_quantization),
//                      indices as a triangle list (TRIANGLES, which may rotate corners)
//   draco              KHR_draco_mesh_compression, Edgebreaker, positions quantized to 14 bits
//   draco-sequential   KHR_draco_mesh_compression, sequential, positions not quantized
//   draco-quantized    KHR_draco_mesh_compression over KHR_mesh_quantization: positions as
//                      normalized shorts (as meshopt-quantized's) that Draco stores as integers,
//                      the accessor of componentType 5122 saying how to read them
//   draco-fewer        as draco, the POSITION accessor counting 30 points fewer than decode (1 for a
//                      mesh of 60 points or fewer; as the
//                      Khronos CesiumMilkTruck glTF-Draco sample: 1856 for 1886)
//
// and, for tests/sh/test_hostile.sh, streams that lie:
//
//   meshopt-range      as meshopt, the last index one past the vertices
//   draco-claims       as draco, its header claiming 1431655765 triangles (~34 GB of tables)
//   draco-range        as draco-sequential, the first corner naming point 65535 of fewer
//   draco-count        as draco, the POSITION accessor counting one point more than decode (read as
//                      decoded, noted, like draco-fewer)
//
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>
#include <meshoptimizer.h>

namespace {

struct Obj {
    std::vector<float> positions;       // 3 per vertex
    std::vector<uint32_t> indices;      // 3 per triangle
};

[[noreturn]] void die(const std::string &message)
{
    std::fprintf(stderr, "gltf_encode: %s\n", message.c_str());
    std::exit(1);
}

Obj read_obj(const char *path)
{
    std::ifstream in(path);
    if (!in)
        die(std::string("cannot read ") + path);
    Obj obj;
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream words(line);
        std::string key;
        words >> key;
        if (key == "v") {
            float x, y, z;
            words >> x >> y >> z;
            obj.positions.insert(obj.positions.end(), {x, y, z});
        } else if (key == "f") {
            std::vector<uint32_t> corners;
            std::string corner;
            while (words >> corner) {
                long v = std::strtol(corner.c_str(), nullptr, 10);
                corners.push_back(static_cast<uint32_t>(v > 0 ? v - 1 : static_cast<long>(obj.positions.size() / 3) + v));
            }
            for (size_t i = 1; i + 1 < corners.size(); i++)
                obj.indices.insert(obj.indices.end(), {corners[0], corners[i], corners[i + 1]});
        }
    }
    return obj;
}

// The binary chunk being built, padded to 4 bytes per piece.
struct Bin {
    std::vector<unsigned char> bytes;
    size_t add(const void *data, size_t size)
    {
        size_t offset = bytes.size();
        bytes.insert(bytes.end(), static_cast<const unsigned char *>(data), static_cast<const unsigned char *>(data) + size);
        bytes.resize((bytes.size() + 3) / 4 * 4, 0);
        return offset;
    }
};

void write_glb(const char *path, const std::string &json_text, const Bin &bin)
{
    std::string json = json_text;
    json.resize((json.size() + 3) / 4 * 4, ' ');
    uint32_t total = static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.bytes.size());
    uint32_t header[5] = {0x46546C67, 2, total, static_cast<uint32_t>(json.size()), 0x4E4F534A};
    uint32_t bin_header[2] = {static_cast<uint32_t>(bin.bytes.size()), 0x004E4942};
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char *>(header), sizeof header);
    out.write(json.data(), static_cast<std::streamsize>(json.size()));
    out.write(reinterpret_cast<const char *>(bin_header), sizeof bin_header);
    out.write(reinterpret_cast<const char *>(bin.bytes.data()), static_cast<std::streamsize>(bin.bytes.size()));
    if (!out)
        die(std::string("cannot write ") + path);
}

// EXT_meshopt_compression's bufferView JSON for count elements of stride bytes at offset/size of
// buffer 0, its uncompressed view in the fallback buffer 1 at fallback_offset.
std::string meshopt_view(size_t fallback_offset, size_t count, size_t stride, bool strided, size_t offset,
                         size_t size, const char *mode)
{
    char text[512];
    std::snprintf(text, sizeof text,
                  "{\"buffer\": 1, \"byteOffset\": %zu, \"byteLength\": %zu%s, \"extensions\": {\"EXT_meshopt_compression\": "
                  "{\"buffer\": 0, \"byteOffset\": %zu, \"byteLength\": %zu, \"byteStride\": %zu, \"count\": %zu, "
                  "\"mode\": \"%s\"}}}",
                  fallback_offset, count * stride, strided ? (", \"byteStride\": " + std::to_string(stride)).c_str() : "",
                  offset, size, stride, count, mode);
    return text;
}

// Positions quantized as KHR_mesh_quantization allows: q = round((p - lo) / size * 32767), as
// normalized shorts, `stride` of them a vertex (the rest zero), and the node that places them back
// (translation lo, scale size).
std::vector<int16_t> quantize(const Obj &obj, size_t stride, std::string *node)
{
    size_t n = obj.positions.size() / 3;
    float lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = hi[k] = obj.positions[k];
        for (size_t i = 0; i < n; i++) {
            lo[k] = std::fmin(lo[k], obj.positions[3 * i + k]);
            hi[k] = std::fmax(hi[k], obj.positions[3 * i + k]);
        }
    }
    double size = std::fmax(hi[0] - lo[0], std::fmax(hi[1] - lo[1], hi[2] - lo[2]));
    std::vector<int16_t> q(stride * n, 0);
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            q[stride * i + k] = static_cast<int16_t>(std::lround((obj.positions[3 * i + k] - lo[k]) / size * 32767.0));
    char text[256];
    std::snprintf(text, sizeof text, "{\"mesh\": 0, \"translation\": [%.9g, %.9g, %.9g], \"scale\": [%.17g, %.17g, %.17g]}",
                  lo[0], lo[1], lo[2], size, size, size);
    *node = text;
    return q;
}

void meshopt_file(const Obj &obj, const char *path, bool quantized, bool out_of_range)
{
    size_t n = obj.positions.size() / 3, m = obj.indices.size();
    Bin bin;
    std::vector<unsigned char> encoded;
    std::vector<uint32_t> indices = obj.indices;
    if (out_of_range)
        indices.back() = static_cast<uint32_t>(n);
    std::string node = "{\"mesh\": 0}", position_accessor, extensions = "\"EXT_meshopt_compression\"";
    size_t position_stride = 12, position_offset, position_size, index_offset, index_size;
    if (!quantized) {
        encoded.resize(meshopt_encodeVertexBufferBound(n, 12));
        position_size = meshopt_encodeVertexBuffer(encoded.data(), encoded.size(), obj.positions.data(), n, 12);
        position_accessor = "{\"bufferView\": 0, \"componentType\": 5126, \"count\": " + std::to_string(n) +
                            ", \"type\": \"VEC3\"}";
    } else {
        std::vector<int16_t> q = quantize(obj, 4, &node);
        position_stride = 8;
        encoded.resize(meshopt_encodeVertexBufferBound(n, 8));
        position_size = meshopt_encodeVertexBuffer(encoded.data(), encoded.size(), q.data(), n, 8);
        position_accessor = "{\"bufferView\": 0, \"componentType\": 5122, \"normalized\": true, \"count\": " +
                            std::to_string(n) + ", \"type\": \"VEC3\"}";
        extensions += ", \"KHR_mesh_quantization\"";
    }
    if (position_size == 0)
        die("meshopt_encodeVertexBuffer failed");
    position_offset = bin.add(encoded.data(), position_size);
    meshopt_encodeIndexVersion(1);
    encoded.resize(quantized ? meshopt_encodeIndexBufferBound(m, n) : meshopt_encodeIndexSequenceBound(m, n));
    index_size = quantized ? meshopt_encodeIndexBuffer(encoded.data(), encoded.size(), indices.data(), m)
                           : meshopt_encodeIndexSequence(encoded.data(), encoded.size(), indices.data(), m);
    if (index_size == 0)
        die("meshopt index encoding failed");
    index_offset = bin.add(encoded.data(), index_size);
    std::string json =
        "{\"asset\": {\"version\": \"2.0\", \"generator\": \"aoview tests/gltf_encode\"}, \"extensionsUsed\": [" +
        extensions + "], \"extensionsRequired\": [" + extensions + "], \"scene\": 0, \"scenes\": [{\"nodes\": [0]}], " +
        "\"nodes\": [" + node + "], \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1}]}], " +
        "\"accessors\": [" + position_accessor + ", {\"bufferView\": 1, \"componentType\": 5125, \"count\": " +
        std::to_string(m) + ", \"type\": \"SCALAR\"}], \"bufferViews\": [" +
        meshopt_view(0, n, position_stride, true, position_offset, position_size, "ATTRIBUTES") + ", " +
        meshopt_view(n * position_stride, m, 4, false, index_offset, index_size, quantized ? "TRIANGLES" : "INDICES") +
        "], \"buffers\": [{\"byteLength\": " + std::to_string(bin.bytes.size()) + "}, {\"byteLength\": " +
        std::to_string(n * position_stride + 4 * m) +
        ", \"extensions\": {\"EXT_meshopt_compression\": {\"fallback\": true}}}]}";
    write_glb(path, json, bin);
}

// A LEB128 varint as Draco writes them.
void put_varint(std::vector<unsigned char> &out, uint64_t v)
{
    do {
        unsigned char byte = v & 0x7f;
        v >>= 7;
        out.push_back(byte | (v ? 0x80 : 0));
    } while (v);
}

// Reads a varint at data[*at], advancing *at.
uint64_t get_varint(const std::vector<unsigned char> &data, size_t *at)
{
    uint64_t v = 0;
    for (int shift = 0; *at < data.size(); shift += 7) {
        unsigned char byte = data[(*at)++];
        v |= static_cast<uint64_t>(byte & 0x7f) << shift;
        if (!(byte & 0x80))
            break;
    }
    return v;
}

void draco_file(const Obj &obj, const char *path, bool sequential, const std::string &lie)
{
    size_t n = obj.positions.size() / 3;
    draco::Mesh mesh;
    mesh.set_num_points(static_cast<uint32_t>(n));
    draco::GeometryAttribute position;
    bool quantized = lie == "quantized";
    std::string node = "{\"mesh\": 0}";
    std::vector<int16_t> q = quantized ? quantize(obj, 3, &node) : std::vector<int16_t>();
    if (quantized)
        position.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_INT16, false, 6, 0);
    else
        position.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false, 12, 0);
    int id = mesh.AddAttribute(position, true, static_cast<uint32_t>(n));
    for (size_t i = 0; i < n; i++)
        mesh.attribute(id)->SetAttributeValue(draco::AttributeValueIndex(static_cast<uint32_t>(i)),
                                              quantized ? static_cast<const void *>(&q[3 * i]) : &obj.positions[3 * i]);
    for (size_t t = 0; t < obj.indices.size(); t += 3)
        mesh.AddFace({draco::PointIndex(obj.indices[t]), draco::PointIndex(obj.indices[t + 1]),
                      draco::PointIndex(obj.indices[t + 2])});
    draco::Encoder encoder;
    if (sequential)
        encoder.SetEncodingMethod(draco::MESH_SEQUENTIAL_ENCODING);
    else if (!quantized)
        encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, 14);
    draco::EncoderBuffer buffer;
    if (!encoder.EncodeMeshToBuffer(mesh, &buffer).ok())
        die("Draco's encoder failed");
    std::vector<unsigned char> stream(buffer.data(), buffer.data() + buffer.size());

    // The decoded counts, which the accessors must state.
    draco::DecoderBuffer in;
    in.Init(buffer.data(), buffer.size());
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&in);
    if (!decoded.ok())
        die("Draco's decoder refused its encoder's stream");
    size_t points = decoded.value()->num_points(), faces = decoded.value()->num_faces();
    uint32_t unique_id = mesh.attribute(id)->unique_id();

    // Header: "DRACO", major, minor, geometry type, method, flags (2 bytes).
    size_t at = 11;
    if (lie == "claims") {          // Edgebreaker: traversal type, then vertices and faces as varints
        at++;
        get_varint(stream, &at);
        size_t faces_at = at;
        get_varint(stream, &at);
        std::vector<unsigned char> patched(stream.begin(), stream.begin() + static_cast<long>(faces_at));
        put_varint(patched, 1431655765);
        patched.insert(patched.end(), stream.begin() + static_cast<long>(at), stream.end());
        stream = patched;
    } else if (lie == "range") {    // sequential: faces, points, method 1 (raw), then 16-bit indices
        get_varint(stream, &at);
        uint64_t stream_points = get_varint(stream, &at);
        if (stream_points < 256 || stream_points >= 65536 || stream[at] != 1)
            die("unexpected sequential connectivity");
        stream[at + 1] = 0xff, stream[at + 2] = 0xff;
    }
    Bin bin;
    size_t offset = bin.add(stream.data(), stream.size());
    size_t position_count = points + (lie == "count" ? 1 : 0) - (lie == "fewer" ? (points > 60 ? 30 : 1) : 0);
    std::string extensions = quantized ? "\"KHR_draco_mesh_compression\", \"KHR_mesh_quantization\"" : "\"KHR_draco_mesh_compression\"";
    std::string json =
        "{\"asset\": {\"version\": \"2.0\", \"generator\": \"aoview tests/gltf_encode\"}, "
        "\"extensionsUsed\": [" + extensions + "], \"extensionsRequired\": [" + extensions + "], "
        "\"scene\": 0, \"scenes\": [{\"nodes\": [0]}], \"nodes\": [" + node + "], "
        "\"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1, \"mode\": 4, "
        "\"extensions\": {\"KHR_draco_mesh_compression\": {\"bufferView\": 0, \"attributes\": {\"POSITION\": " +
        std::to_string(unique_id) + "}}}}]}], \"accessors\": [{\"componentType\": " +
        (quantized ? "5122, \"normalized\": true" : "5126") + ", \"count\": " +
        std::to_string(position_count) + ", \"type\": \"VEC3\"}, {\"componentType\": 5125, \"count\": " +
        std::to_string(3 * faces) + ", \"type\": \"SCALAR\"}], \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": " +
        std::to_string(offset) + ", \"byteLength\": " + std::to_string(stream.size()) + "}], \"buffers\": [{\"byteLength\": " +
        std::to_string(bin.bytes.size()) + "}]}";
    write_glb(path, json, bin);
}

} // namespace

int main(int argc, char **argv)
{
    if (argc != 4)
        die("usage: gltf_encode MODE IN.obj OUT.glb (see the source for the modes)");
    std::string mode = argv[1];
    Obj obj = read_obj(argv[2]);
    if (obj.indices.empty() || obj.positions.size() / 3 > UINT32_MAX)
        die("the OBJ needs triangles");
    if (mode == "meshopt" || mode == "meshopt-quantized" || mode == "meshopt-range")
        meshopt_file(obj, argv[3], mode == "meshopt-quantized", mode == "meshopt-range");
    else if (mode == "draco" || mode == "draco-claims" || mode == "draco-count" || mode == "draco-quantized" ||
             mode == "draco-fewer")
        draco_file(obj, argv[3], false, mode == "draco" ? "" : mode.substr(6));
    else if (mode == "draco-sequential" || mode == "draco-range")
        draco_file(obj, argv[3], true, mode == "draco-range" ? "range" : "");
    else
        die("unknown mode '" + mode + "'");
    return 0;
}
