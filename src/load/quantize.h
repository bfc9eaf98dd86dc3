/* Accessor components as numbers: float, and the signed and unsigned 8- and 16-bit integers that
 * KHR_mesh_quantization allows for positions and normals (normalized or not), and the unsigned
 * integers of indices. Only the glTF loader (src/load/gltf_data.c) includes this. */
#ifndef AO_LOAD_QUANTIZE_H
#define AO_LOAD_QUANTIZE_H

#include <stdbool.h>
#include <stddef.h>

/* glTF's accessor component types. */
enum ao_quantize_type {
    AO_QUANTIZE_BYTE = 5120,
    AO_QUANTIZE_UNSIGNED_BYTE = 5121,
    AO_QUANTIZE_SHORT = 5122,
    AO_QUANTIZE_UNSIGNED_SHORT = 5123,
    AO_QUANTIZE_UNSIGNED_INT = 5125,
    AO_QUANTIZE_FLOAT = 5126,
};

/* The bytes of one component of type, or 0 when type is none of the above. */
size_t ao_quantize_size(int type);

/* The component at p (little endian) as a number: a float as it is; an integer as its value, or,
 * when normalized, as glTF maps it to [-1, 1] or [0, 1] (c / 127 and c / 32767 at least -1 for
 * signed bytes and shorts, c / 255 and c / 65535 for unsigned ones; unsigned ints as they are).
 * Any thread. */
double ao_quantize_value(const unsigned char *p, int type, bool normalized);

#endif
