/* EXT_meshopt_compression through libmeshoptimizer; see meshopt.h. The library's decoders are safe
 * for untrusted data (their documentation's word, and the fuzz targets replay such data), but
 * they assert their size arguments, and Debian builds them with assertions on: ao_meshopt_check
 * refuses what they would assert before any call. */
#include "meshopt.h"

#include <stdio.h>
#include <string.h>

#include <meshoptimizer.h>

/* The headers' high nibbles of the three codecs; the low nibble is the codec's version. */
enum { VERTEX_HEADER = 0xa0, INDEX_HEADER = 0xe0, SEQUENCE_HEADER = 0xd0 };
/* The newest version of each codec that libmeshoptimizer 0.18 decodes. */
enum { VERTEX_VERSION = 0, INDEX_VERSION = 1, SEQUENCE_VERSION = 1 };

bool ao_meshopt_parse(const char *mode_name, const char *filter_name, enum ao_meshopt_mode *mode,
                      enum ao_meshopt_filter *filter)
{
    static const char *const modes[] = {"ATTRIBUTES", "TRIANGLES", "INDICES"};
    static const char *const filters[] = {"NONE", "OCTAHEDRAL", "QUATERNION", "EXPONENTIAL"};
    int m = -1, f = filter_name ? -1 : 0;
    for (int k = 0; k < 3; k++)
        m = strcmp(mode_name, modes[k]) == 0 ? k : m;
    for (int k = 0; filter_name && k < 4; k++)
        f = strcmp(filter_name, filters[k]) == 0 ? k : f;
    *mode = (enum ao_meshopt_mode)(m < 0 ? 0 : m);
    *filter = (enum ao_meshopt_filter)(f < 0 ? 0 : f);
    return m >= 0 && f >= 0;
}

bool ao_meshopt_check(enum ao_meshopt_mode mode, enum ao_meshopt_filter filter, size_t count, size_t stride,
                      char *why, size_t why_size)
{
    const char *problem = NULL;
    if (mode == AO_MESHOPT_ATTRIBUTES && !(stride > 0 && stride <= 256 && stride % 4 == 0))
        problem = "attributes need a byteStride that is a multiple of 4 from 4 to 256";
    else if (mode != AO_MESHOPT_ATTRIBUTES && stride != 2 && stride != 4)
        problem = "indices need a byteStride of 2 or 4";
    else if (mode == AO_MESHOPT_TRIANGLES && count % 3)
        problem = "triangles need a count that is a multiple of 3";
    else if (mode != AO_MESHOPT_ATTRIBUTES && filter != AO_MESHOPT_NONE)
        problem = "indices take no filter";
    else if (filter == AO_MESHOPT_OCTAHEDRAL && stride != 4 && stride != 8)
        problem = "the OCTAHEDRAL filter needs a byteStride of 4 or 8";
    else if (filter == AO_MESHOPT_QUATERNION && stride != 8)
        problem = "the QUATERNION filter needs a byteStride of 8";
    if (problem)
        snprintf(why, why_size, "%s (byteStride %zu, count %zu)", problem, stride, count);
    return !problem;
}

bool ao_meshopt_decode(enum ao_meshopt_mode mode, enum ao_meshopt_filter filter, size_t count, size_t stride,
                       const unsigned char *data, size_t size, unsigned char *out, char *why, size_t why_size)
{
    static const int headers[] = {VERTEX_HEADER, INDEX_HEADER, SEQUENCE_HEADER};
    static const int versions[] = {VERTEX_VERSION, INDEX_VERSION, SEQUENCE_VERSION};
    static const char *const names[] = {"meshopt_decodeVertexBuffer", "meshopt_decodeIndexBuffer",
                                        "meshopt_decodeIndexSequence"};
    /* The header byte first, for a message naming the version when it is one 0.18 cannot read. */
    if (size < 1 || (data[0] & 0xf0) != headers[mode]) {
        snprintf(why, why_size, "its data does not begin with the %s header (0x%02x)",
                 mode == AO_MESHOPT_ATTRIBUTES ? "attribute" : mode == AO_MESHOPT_TRIANGLES ? "triangle" : "index",
                 headers[mode]);
        return false;
    }
    if ((data[0] & 0x0f) > versions[mode]) {
        snprintf(why, why_size, "its data is of codec version %d, and libmeshoptimizer %d.%d decodes up to version %d",
                 data[0] & 0x0f, MESHOPTIMIZER_VERSION / 1000, MESHOPTIMIZER_VERSION % 1000 / 10, versions[mode]);
        return false;
    }
    int status = mode == AO_MESHOPT_ATTRIBUTES ? meshopt_decodeVertexBuffer(out, count, stride, data, size)
                 : mode == AO_MESHOPT_TRIANGLES ? meshopt_decodeIndexBuffer(out, count, stride, data, size)
                                                : meshopt_decodeIndexSequence(out, count, stride, data, size);
    if (status != 0) {
        snprintf(why, why_size, "its %zu bytes do not decode to %zu elements of %zu bytes (%s: error %d)", size,
                 count, stride, names[mode], status);
        return false;
    }
    if (filter == AO_MESHOPT_OCTAHEDRAL)
        meshopt_decodeFilterOct(out, count, stride);
    else if (filter == AO_MESHOPT_QUATERNION)
        meshopt_decodeFilterQuat(out, count, stride);
    else if (filter == AO_MESHOPT_EXPONENTIAL)
        meshopt_decodeFilterExp(out, count, stride);
    return true;
}
