/* Accumulation buffer: per-pixel double RGB sums and sample counts, plus the channel sums of the
 * odd passes alone, from which the error of the running average is estimated without a reference
 * (36 bytes a pixel). */
#ifndef AO_ACCUM_H
#define AO_ACCUM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "vec3.h"

/* Running sums; owned by the render thread, workers write disjoint pixels. */
struct ao_accum {
    int width, height;
    double *sum;        /* 3 per pixel, all passes */
    uint32_t *count;    /* samples per pixel, all passes */
    double *odd_sum;    /* per pixel, the three channels' sum over the odd passes' samples */
};

/* Allocates zeroed sums for width x height; false (with a message) when out of memory. */
bool ao_accum_init(struct ao_accum *a, int width, int height);

/* Frees the sums; accepts a zeroed accumulator. */
void ao_accum_finish(struct ao_accum *a);

/* Zeroes the sums and counts of the pixels [x0, x1) x [y0, y1) (a tile's first pass of a run). */
void ao_accum_clear(struct ao_accum *a, int x0, int y0, int x1, int y1);

/* Adds the sum of n samples to pixel p; `odd` says which half of the passes they belong to. */
static inline void ao_accum_add(struct ao_accum *a, size_t p, struct ao_vec3 sum, uint32_t n, bool odd)
{
    a->sum[3 * p + 0] += sum.x;
    a->sum[3 * p + 1] += sum.y;
    a->sum[3 * p + 2] += sum.z;
    a->count[p] += n;
    if (odd)
        a->odd_sum[p] += (double)sum.x + (double)sum.y + (double)sum.z;
}

/* Writes the running average as 3 floats per pixel, top row first (0 where no sample yet). */
void ao_accum_resolve(const struct ao_accum *a, float *rgb);

/* ao_accum_resolve of the pixels [x0, x1) x [y0, y1) alone, into the image rgb of the same size. */
void ao_accum_resolve_rect(const struct ao_accum *a, int x0, int y0, int x1, int y1, float *rgb);

#endif
