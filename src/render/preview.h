/* Coarse frames for the eye after a restart: the image traced on a grid of block x block pixel
 * cells, one eye ray through each cell's centre and a few AO samples, shown until the first full
 * pass is. They never enter the accumulation. */
#ifndef AO_PREVIEW_H
#define AO_PREVIEW_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "ao.h"
#include "camera.h"

/* AO samples per preview cell: enough to read as a shaded picture (docs/performance.md). */
enum { AO_PREVIEW_SAMPLES = 8 };

/* One preview frame being traced: the grid, its context, and the tiles handed out so far. */
struct ao_preview {
    struct ao_context ctx;       /* the pass's, with the grid's view and no jitter */
    int block;                   /* image pixels per cell, each way */
    int width, height;           /* cells */
    int tiles_x, tiles;          /* 16 x 16 cell tiles */
    atomic_int next;
    float *rgb;                  /* width x height x 3 floats, top row first: set before tracing */
};

/* The block size of the first preview of a width x height image (the power of two that brings its
 * long side nearest to 64 cells), or 1 when the image is too small for previews to pay. Pure. */
int ao_preview_first_block(int width, int height);

/* The block size of the preview after one of `block`, or 1 when the full pass comes next. Pure. */
int ao_preview_next_block(int block);

/* Prepares p to trace the preview of a width x height image with camera and the rest of ctx at
 * `block` (its cells in p->width x p->height); false when the camera cannot form an image. Render
 * thread, between jobs. */
bool ao_preview_begin(struct ao_preview *p, const struct ao_context *ctx, const struct ao_camera *camera, int width,
                      int height, int block);

/* Traces tiles of the preview until none is left or stop(user) says so. Any thread of the job. */
void ao_preview_trace(struct ao_preview *p, bool (*stop)(void *user), void *user);

#endif
