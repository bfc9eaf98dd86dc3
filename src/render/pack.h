/* Lossless packing of a run of pixel sums for the wire: the distinct values once (a palette) and
 * each pixel as a 4-, 8- or 16-bit index into them, or the floats as they are when that is not
 * smaller. Bit for bit: -0 and +0 are different values, so the unpacked sums equal the packed. A
 * pass of a few samples a pixel of AO (cosine-weighted sampling: a sample is 0 or the albedo)
 * holds few distinct sums, so the sums of tiles lent between aoview-mpi's ranks shrink 10-20x. */
#ifndef AO_PACK_H
#define AO_PACK_H

#include <stdbool.h>
#include <stddef.h>

#include "vec3.h"

/* The most bytes ao_pack_sums writes for n sums. */
size_t ao_pack_bound(size_t n);

/* Packs sums[0..n) into out (room for ao_pack_bound(n) bytes); returns the bytes written. */
size_t ao_pack_sums(const struct ao_vec3 *sums, size_t n, unsigned char *out);

/* Unpacks `bytes` bytes that ao_pack_sums made into sums[0..n); false, sums unspecified, when they
 * are not the packing of n sums. */
bool ao_unpack_sums(const unsigned char *in, size_t bytes, struct ao_vec3 *sums, size_t n);

#endif
