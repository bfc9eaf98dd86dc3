/* Accessor components as numbers (KHR_mesh_quantization); see quantize.h. */
#include "quantize.h"

#include <stdint.h>
#include <string.h>

size_t ao_quantize_size(int type)
{
    switch (type) {
    case AO_QUANTIZE_BYTE:
    case AO_QUANTIZE_UNSIGNED_BYTE: return 1;
    case AO_QUANTIZE_SHORT:
    case AO_QUANTIZE_UNSIGNED_SHORT: return 2;
    case AO_QUANTIZE_UNSIGNED_INT:
    case AO_QUANTIZE_FLOAT: return 4;
    }
    return 0;
}

double ao_quantize_value(const unsigned char *p, int type, bool normalized)
{
    uint32_t bits = (uint32_t)p[0];
    if (ao_quantize_size(type) >= 2)
        bits |= (uint32_t)p[1] << 8;
    if (ao_quantize_size(type) == 4)
        bits |= (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    switch (type) {
    case AO_QUANTIZE_FLOAT: {
        float f;
        memcpy(&f, &bits, sizeof f);
        return f;
    }
    case AO_QUANTIZE_BYTE: {
        double c = bits >= 0x80 ? (double)bits - 0x100 : (double)bits;
        return normalized ? (c / 127.0 < -1.0 ? -1.0 : c / 127.0) : c;
    }
    case AO_QUANTIZE_SHORT: {
        double c = bits >= 0x8000 ? (double)bits - 0x10000 : (double)bits;
        return normalized ? (c / 32767.0 < -1.0 ? -1.0 : c / 32767.0) : c;
    }
    case AO_QUANTIZE_UNSIGNED_BYTE: return normalized ? bits / 255.0 : bits;
    case AO_QUANTIZE_UNSIGNED_SHORT: return normalized ? bits / 65535.0 : bits;
    }
    return bits;   /* unsigned int */
}
