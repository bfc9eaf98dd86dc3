/* Accumulation buffer; see accum.h. */
#include "accum.h"

#include <string.h>

#include "pages.h"
#include "text.h"

/* The bytes of a width x height accumulation: its sums, odd sums and counts in one mapping. */
static size_t accum_bytes(int width, int height)
{
    return (size_t)width * (size_t)height * (4 * sizeof(double) + sizeof(uint32_t));
}

bool ao_accum_init(struct ao_accum *a, int width, int height)
{
    size_t pixels = (size_t)width * (size_t)height;
    a->width = width;
    a->height = height;
    a->sum = ao_pages_alloc(accum_bytes(width, height));
    if (!a->sum) {
        ao_text_report("aoview: out of memory for a %dx%d accumulation buffer", width, height);
        ao_accum_finish(a);
        return false;
    }
    a->odd_sum = a->sum + 3 * pixels;
    a->count = (uint32_t *)(a->odd_sum + pixels);
    return true;
}

void ao_accum_finish(struct ao_accum *a)
{
    ao_pages_free(a->sum, accum_bytes(a->width, a->height));
    memset(a, 0, sizeof *a);
}

void ao_accum_clear(struct ao_accum *a, int x0, int y0, int x1, int y1)
{
    for (int j = y0; j < y1; j++) {
        size_t p = (size_t)j * (size_t)a->width + (size_t)x0, n = (size_t)(x1 - x0);
        memset(a->sum + 3 * p, 0, 3 * n * sizeof *a->sum);
        memset(a->count + p, 0, n * sizeof *a->count);
        memset(a->odd_sum + p, 0, n * sizeof *a->odd_sum);
    }
}

void ao_accum_resolve(const struct ao_accum *a, float *rgb)
{
    ao_accum_resolve_rect(a, 0, 0, a->width, a->height, rgb);
}

void ao_accum_resolve_rect(const struct ao_accum *a, int x0, int y0, int x1, int y1, float *rgb)
{
    /* Neighbouring pixels mostly have the same count: its reciprocal is kept, not divided again. */
    uint32_t count = 0;
    double inv = 0.0;
    for (int j = y0; j < y1; j++)
        for (size_t p = (size_t)j * (size_t)a->width + (size_t)x0, end = p + (size_t)(x1 - x0); p < end; p++) {
            if (a->count[p] != count) {
                count = a->count[p];
                inv = 1.0 / count;
            }
            for (int c = 0; c < 3; c++)
                rgb[3 * p + c] = (float)(a->sum[3 * p + c] * inv);
        }
}
