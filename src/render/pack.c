/* Pixel sums packed as a palette and indices (see pack.h). The layout: a uint32 count p of
 * palette entries, 0 for raw; then either the n sums as they are, or the p distinct sums followed
 * by n indices of index_bits(p) bits each (4 bits: two a byte, the first in the low half; 16 bits:
 * low byte first). The sums' bytes in native order: the ranks of a job run one binary. */
#include "pack.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Past this many distinct sums the indices would not fit 16 bits: the sums go raw. */
enum { MOST_DISTINCT = 65536 };

static const size_t SUM_BYTES = sizeof(struct ao_vec3);

static int index_bits(size_t distinct)
{
    return distinct <= 16 ? 4 : distinct <= 256 ? 8 : 16;
}

static size_t packed_size(size_t distinct, size_t n)
{
    return sizeof(uint32_t) + distinct * SUM_BYTES + (n * (size_t)index_bits(distinct) + 7) / 8;
}

size_t ao_pack_bound(size_t n)
{
    return sizeof(uint32_t) + n * SUM_BYTES;
}

/* A slot of the table of distinct sums, by their bits. */
static size_t slot_of(const unsigned char *bits, size_t mask)
{
    uint32_t w[3];
    memcpy(w, bits, sizeof w);
    uint32_t h = w[0] * 0x9e3779b1u ^ w[1] * 0x85ebca77u ^ w[2] * 0xc2b2ae3du;
    return (h ^ h >> 15) & mask;
}

static size_t pack_raw(const struct ao_vec3 *sums, size_t n, unsigned char *out)
{
    uint32_t raw = 0;
    memcpy(out, &raw, sizeof raw);
    memcpy(out + sizeof raw, sums, n * SUM_BYTES);
    return ao_pack_bound(n);
}

size_t ao_pack_sums(const struct ao_vec3 *sums, size_t n, unsigned char *out)
{
    size_t most = n < MOST_DISTINCT ? n : MOST_DISTINCT, slots = 16;
    while (slots < 2 * most)
        slots *= 2;
    uint32_t *table = n ? calloc(slots, sizeof *table) : NULL; /* palette index + 1; 0: empty */
    uint16_t *index = n ? malloc(n * sizeof *index) : NULL;
    unsigned char *palette = out + sizeof(uint32_t); /* at most n sums: within the bound */
    size_t distinct = 0;
    bool fits = table && index;
    for (size_t k = 0; k < n && fits; k++) {
        const unsigned char *bits = (const unsigned char *)&sums[k];
        size_t s = slot_of(bits, slots - 1);
        while (table[s] && memcmp(palette + (table[s] - 1) * SUM_BYTES, bits, SUM_BYTES) != 0)
            s = (s + 1) & (slots - 1);
        if (!table[s]) {
            if (distinct == most) {
                fits = false;
                break;
            }
            memcpy(palette + distinct * SUM_BYTES, bits, SUM_BYTES);
            table[s] = (uint32_t)++distinct;
        }
        index[k] = (uint16_t)(table[s] - 1);
    }
    size_t bytes = fits && n ? packed_size(distinct, n) : 0;
    if (!bytes || bytes >= ao_pack_bound(n)) {
        free(table);
        free(index);
        return pack_raw(sums, n, out);
    }
    uint32_t count = (uint32_t)distinct;
    memcpy(out, &count, sizeof count);
    unsigned char *at = palette + distinct * SUM_BYTES;
    int bits = index_bits(distinct);
    if (bits == 4)
        memset(at, 0, (n + 1) / 2);
    for (size_t k = 0; k < n; k++) {
        if (bits == 4)
            at[k / 2] |= (unsigned char)(index[k] << (k % 2 * 4));
        else if (bits == 8)
            at[k] = (unsigned char)index[k];
        else
            at[2 * k] = (unsigned char)(index[k] & 0xff), at[2 * k + 1] = (unsigned char)(index[k] >> 8);
    }
    free(table);
    free(index);
    return bytes;
}

bool ao_unpack_sums(const unsigned char *in, size_t bytes, struct ao_vec3 *sums, size_t n)
{
    uint32_t distinct;
    if (bytes < sizeof distinct)
        return false;
    memcpy(&distinct, in, sizeof distinct);
    if (distinct == 0) {
        if (bytes != ao_pack_bound(n))
            return false;
        memcpy(sums, in + sizeof distinct, n * SUM_BYTES);
        return true;
    }
    if (distinct > n || distinct > MOST_DISTINCT || bytes != packed_size(distinct, n))
        return false;
    const unsigned char *palette = in + sizeof distinct, *at = palette + (size_t)distinct * SUM_BYTES;
    int bits = index_bits(distinct);
    for (size_t k = 0; k < n; k++) {
        size_t i = bits == 4 ? (size_t)(at[k / 2] >> (k % 2 * 4) & 15)
                   : bits == 8 ? (size_t)at[k]
                               : (size_t)at[2 * k] | (size_t)at[2 * k + 1] << 8;
        if (i >= distinct)
            return false;
        memcpy(&sums[k], palette + i * SUM_BYTES, SUM_BYTES);
    }
    return true;
}
