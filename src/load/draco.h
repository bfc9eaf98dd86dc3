/* KHR_draco_mesh_compression: one Draco-compressed primitive decoded by Debian's libdraco (C++),
 * behind this C interface; src/load/draco.cc is the only C++ in the program and the only file that
 * includes Draco's headers; only the glTF loader's files include this (through gltf_reader.h). */
#ifndef AO_LOAD_DRACO_H
#define AO_LOAD_DRACO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* What a primitive decodes to: positions and (when asked for) normals, three floats per point, and
 * three point indices per triangle, each array malloc'd (ao_draco_free frees them); peak is the most
 * the decoding held at once, these arrays included. */
struct ao_draco_mesh {
    float *positions, *normals;
    uint32_t *indices;
    size_t point_count, face_count;
    uint64_t peak;
};

/* Decodes the Draco mesh in data[0, size): POSITION from the attribute whose unique id is
 * position_id, NORMAL from normal_id (negative: none), each of at least 3 components, the faces as
 * they decode. An attribute is converted to float as Draco dequantizes it, or, where integers[k]
 * (0: POSITION, 1: NORMAL) asks for it (a glTF accessor of integer components, KHR_mesh_quantization),
 * read as the integers Draco stores, each value made a float as it is (an attribute that Draco
 * stores as floats is then refused). Every allocation the decoder makes on this thread is counted,
 * and one that would take more than cap bytes at once fails, and the decoding with it: *over_cap
 * then says so. Every point a face names is checked to exist. False, with the reason in why and out
 * empty, on any failure. Any thread. */
bool ao_draco_decode(const unsigned char *data, size_t size, int64_t position_id, int64_t normal_id,
                     const bool integers[2], uint64_t cap, struct ao_draco_mesh *out, bool *over_cap, char *why,
                     size_t why_size);

/* Frees what ao_draco_decode allocated and empties mesh. */
void ao_draco_free(struct ao_draco_mesh *mesh);

#ifdef __cplusplus
}
#endif

#endif
