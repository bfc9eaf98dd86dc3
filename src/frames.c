/* The frames' triple buffer; see frames.h. */
#include "frames.h"

#include <stdio.h>
#include <stdlib.h>

#include "buffer.h"

/* In `middle`: the frame there is newer than what the consumer has. */
enum { FRESH = 4 };

void ao_frames_init(struct ao_frames *fs)
{
    *fs = (struct ao_frames){.back = 0, .front = 2};
    atomic_init(&fs->middle, 1u);
}

void ao_frames_finish(struct ao_frames *fs)
{
    for (int k = 0; k < 3; k++) {
        free(fs->frames[k].rgb);
        free(fs->frames[k].tile_error);
    }
}

struct ao_frame *ao_frames_back(struct ao_frames *fs, int width, int height, int tiles)
{
    struct ao_frame *f = &fs->frames[fs->back];
    size_t *room = fs->room[fs->back];
    if (!ao_buffer_grow(&f->rgb, &room[0], 3 * (size_t)width * (size_t)height) ||
        !ao_buffer_grow(&f->tile_error, &room[1], (size_t)tiles)) {
        fprintf(stderr, "aoview: out of memory for %dx%d frames\n", width, height);
        return NULL;
    }
    f->width = width;
    f->height = height;
    return f;
}

void ao_frames_publish(struct ao_frames *fs)
{
    unsigned previous = atomic_exchange(&fs->middle, (unsigned)fs->back | FRESH);
    fs->back = (int)(previous & ~(unsigned)FRESH);
}

const struct ao_frame *ao_frames_take(struct ao_frames *fs)
{
    if (!(atomic_load(&fs->middle) & FRESH))
        return NULL;
    unsigned previous = atomic_exchange(&fs->middle, (unsigned)fs->front);
    fs->front = (int)(previous & ~(unsigned)FRESH);
    return &fs->frames[fs->front];
}
