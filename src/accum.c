/* Accumulation buffer; see accum.h. */
#include "accum.h"

#include <stdlib.h>
#include <string.h>

#include "text.h"

bool ao_accum_init(struct ao_accum *a, int width, int height)
{
    size_t pixels = (size_t)width * (size_t)height;
    a->width = width;
    a->height = height;
    a->sum = calloc(3 * pixels, sizeof *a->sum);
    a->count = calloc(pixels, sizeof *a->count);
    a->odd_sum = calloc(pixels, sizeof *a->odd_sum);
    if (!a->sum || !a->count || !a->odd_sum) {
        ao_text_report("aoview: out of memory for a %dx%d accumulation buffer", width, height);
        ao_accum_finish(a);
        return false;
    }
    return true;
}

void ao_accum_finish(struct ao_accum *a)
{
    free(a->sum);
    free(a->count);
    free(a->odd_sum);
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
