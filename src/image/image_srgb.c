/* Linear values encoded as 8-bit sRGB (see image.h): the curve, and a table built once that the
 * PNG writer, screenshots and the window's texture encode whole images with. */
#include "image.h"

#include <assert.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <string.h>

#include "simd.h"

float ao_image_srgb_encode(float linear)
{
    float x = fminf(fmaxf(linear, 0.0f), 1.0f); /* fmaxf maps NaN to 0 */
    return x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
}

/* The 8-bit code of linear value x: round(255 encode(x)), the curve in double precision. */
static int srgb_code(double x)
{
    x = x > 0.0 ? (x < 1.0 ? x : 1.0) : 0.0;
    double s = x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
    return (int)floor(255.0 * s + 0.5);
}

/* The codes by table: the floats in [0, 1) fall into buckets by their bits >> SRGB_SHIFT (7
 * mantissa bits, 0.8 % of a value wide), and a bucket holds at most one step between codes: the
 * curve's slope times a bucket's width stays under 0.9 of a code everywhere (s ~ x^(1/2.4): a
 * relative step of 0.8 %/2.4 of s <= 1, 0.87 of a code at 1; the linear part: 12.92 x 0.8 % of
 * 0.0031, 0.08). srgb_table[b] is the code of the bucket's first float, shifted left 17, or'ed with
 * the offset within the bucket of the first float of the next code (2^16: none); the entry past
 * the last bucket holds 1.0's code, 255. Built once (srgb_init). */
enum { SRGB_SHIFT = 16, SRGB_ONE = 0x3F800000, SRGB_BUCKETS = SRGB_ONE >> SRGB_SHIFT };
static int32_t srgb_table[SRGB_BUCKETS + 1];
static pthread_once_t srgb_once = PTHREAD_ONCE_INIT;

static float float_of(uint32_t bits)
{
    float x;
    memcpy(&x, &bits, sizeof x);
    return x;
}

static void srgb_init(void)
{
    for (uint32_t b = 0; b < SRGB_BUCKETS; b++) {
        uint32_t first = b << SRGB_SHIFT, last = first | ((1u << SRGB_SHIFT) - 1), bucket = first;
        int code = srgb_code(float_of(first));
        if (srgb_code(float_of(last)) != code) {
            assert(srgb_code(float_of(last)) == code + 1);
            while (first + 1 < last) { /* code at first, code + 1 at last */
                uint32_t mid = first + (last - first) / 2;
                if (srgb_code(float_of(mid)) > code)
                    last = mid;
                else
                    first = mid;
            }
        } else {
            last = bucket + (1u << SRGB_SHIFT);
        }
        srgb_table[b] = (int32_t)((uint32_t)code << 17 | (last - bucket));
    }
    srgb_table[SRGB_BUCKETS] = (int32_t)(255u << 17 | (1u << SRGB_SHIFT));
}

/* The codes of count floats by the table (srgb_init done): negative values and NaNs 0, 1 and above
 * 255. A loop the compiler vectorizes (gathers). */
AO_VECTOR_CLONES static void srgb_codes(const float *restrict linear, size_t count, uint8_t *restrict out)
{
    for (size_t i = 0; i < count; i++) {
        int32_t bits;
        memcpy(&bits, &linear[i], sizeof bits);
        int32_t b = bits < 0 || bits > 0x7F800000 ? 0 : bits > SRGB_ONE ? SRGB_ONE : bits;
        int32_t t = srgb_table[b >> SRGB_SHIFT];
        out[i] = (uint8_t)((t >> 17) + ((b & ((1 << SRGB_SHIFT) - 1)) >= (t & 0x1FFFF)));
    }
}

void ao_image_encode_srgb8(const float *linear, size_t count, uint8_t *out)
{
    pthread_once(&srgb_once, srgb_init);
    srgb_codes(linear, count, out);
}

void ao_image_encode_srgb8_bgra(const float *rgb, size_t pixels, uint8_t *out)
{
    enum { CHUNK = 1024 };
    uint8_t codes[3 * CHUNK];
    pthread_once(&srgb_once, srgb_init);
    for (size_t p = 0; p < pixels; p += CHUNK) {
        size_t n = pixels - p < CHUNK ? pixels - p : CHUNK;
        srgb_codes(rgb + 3 * p, 3 * n, codes);
        for (size_t k = 0; k < n; k++, out += 4) {
            out[0] = codes[3 * k + 2];
            out[1] = codes[3 * k + 1];
            out[2] = codes[3 * k];
            out[3] = 255;
        }
    }
}
