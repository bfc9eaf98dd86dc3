/* Coarse preview frames; see preview.h. */
#include "preview.h"

/* Previews start with about PREVIEW_CELLS cells on the image's long side and double from there
 * while the cells are at least LAST_BLOCK pixels wide: with AO_PREVIEW_SAMPLES samples a cell,
 * those cost about a third of the first full pass (1 eye ray and 1 AO sample a pixel), and a
 * finer one would cost as much as that pass (docs/performance.md). */
enum { PREVIEW_CELLS = 64, LAST_BLOCK = 4, TILE = 16 };

int ao_preview_first_block(int width, int height)
{
    int longest = width > height ? width : height, block = 1;
    /* the nearest power of two in log scale: longest / block within [64 / sqrt 2, 64 sqrt 2) */
    while ((double)longest / (2.0 * block) >= PREVIEW_CELLS / 1.4142135623730951)
        block *= 2;
    return block >= LAST_BLOCK ? block : 1;
}

int ao_preview_next_block(int block)
{
    return block / 2 >= LAST_BLOCK ? block / 2 : 1;
}

bool ao_preview_begin(struct ao_preview *p, const struct ao_context *ctx, const struct ao_camera *camera, int width,
                      int height, int block)
{
    p->ctx = *ctx;
    p->ctx.aa = false;
    if (!ao_camera_view_coarse(camera, width, height, block, &p->ctx.view))
        return false;
    p->block = block;
    p->width = p->ctx.view.width;
    p->height = p->ctx.view.height;
    p->tiles_x = (p->width + TILE - 1) / TILE;
    p->tiles = p->tiles_x * ((p->height + TILE - 1) / TILE);
    atomic_store(&p->next, 0);
    return true;
}

void ao_preview_trace(struct ao_preview *p, bool (*stop)(void *user), void *user)
{
    const struct ao_tile_work work = {.rounds = 1, .count = AO_PREVIEW_SAMPLES};
    uint64_t rays = 0; /* not counted: previews are not part of the run */
    for (int t; !stop(user) && (t = atomic_fetch_add_explicit(&p->next, 1, memory_order_relaxed)) < p->tiles;) {
        struct ao_tile rect = {.x0 = t % p->tiles_x * TILE, .y0 = t / p->tiles_x * TILE};
        rect.x1 = rect.x0 + TILE < p->width ? rect.x0 + TILE : p->width;
        rect.y1 = rect.y0 + TILE < p->height ? rect.y0 + TILE : p->height;
        struct ao_vec3 sums[TILE * TILE];
        if (!ao_estimate_tile(&p->ctx, &rect, &work, sums, &rays, &rays))
            return;
        const struct ao_vec3 *s = sums;
        for (int j = rect.y0; j < rect.y1; j++)
            for (int i = rect.x0; i < rect.x1; i++, s++) {
                float *out = p->rgb + 3 * ((size_t)j * (size_t)p->width + (size_t)i);
                out[0] = s->x / AO_PREVIEW_SAMPLES;
                out[1] = s->y / AO_PREVIEW_SAMPLES;
                out[2] = s->z / AO_PREVIEW_SAMPLES;
            }
    }
}
