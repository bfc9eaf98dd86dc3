/* EXT_meshopt_compression: a bufferView's data decoded by Debian's libmeshoptimizer (0.18, through
 * its C API). Only the glTF loader (src/load/gltf_data.c) includes this. */
#ifndef AO_LOAD_MESHOPT_H
#define AO_LOAD_MESHOPT_H

#include <stdbool.h>
#include <stddef.h>

/* The extension's modes: vertex attributes, triangle lists of indices, other index sequences. */
enum ao_meshopt_mode { AO_MESHOPT_ATTRIBUTES, AO_MESHOPT_TRIANGLES, AO_MESHOPT_INDICES };

/* The filters applied to attributes after decoding. */
enum ao_meshopt_filter { AO_MESHOPT_NONE, AO_MESHOPT_OCTAHEDRAL, AO_MESHOPT_QUATERNION, AO_MESHOPT_EXPONENTIAL };

/* The mode and filter named by the extension's strings; false for other names. */
bool ao_meshopt_parse(const char *mode_name, const char *filter_name, enum ao_meshopt_mode *mode,
                      enum ao_meshopt_filter *filter);

/* True when count elements of stride bytes fit the mode and filter as the extension requires (and
 * as the library asserts: attributes' stride a multiple of 4 up to 256, indices' 2 or 4, triangles'
 * count a multiple of 3, each filter's strides); else false with the reason in why. Any thread. */
bool ao_meshopt_check(enum ao_meshopt_mode mode, enum ao_meshopt_filter filter, size_t count, size_t stride,
                      char *why, size_t why_size);

/* Decodes size bytes of data into the count * stride bytes at out and applies the filter, for a
 * mode, filter, count and stride that ao_meshopt_check accepted; false with the reason in why for
 * data the library refuses or a codec version it cannot decode. Indices are not checked against
 * anything: the caller does. Any thread. */
bool ao_meshopt_decode(enum ao_meshopt_mode mode, enum ao_meshopt_filter filter, size_t count, size_t stride,
                       const unsigned char *data, size_t size, unsigned char *out, char *why, size_t why_size);

#endif
