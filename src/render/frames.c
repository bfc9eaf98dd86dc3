/* The frames' triple buffer; see frames.h. */
#include "frames.h"

#include <stdlib.h>

#include "buffer.h"
#include "pages.h"
#include "text.h"

/* In `middle`: the frame there is newer than what the consumer has. */
enum { FRESH = 4 };

void ao_frames_init(struct ao_frames *fs)
{
    *fs = (struct ao_frames){.back = 0, .front = 2};
    atomic_init(&fs->middle, 1u);
    atomic_init(&fs->logged, 0);
    atomic_init(&fs->read, 0);
}

void ao_frames_finish(struct ao_frames *fs)
{
    for (int k = 0; k < 3; k++) {
        ao_pages_free(fs->frames[k].rgb, fs->room[k][0] * sizeof *fs->frames[k].rgb);
        free(fs->frames[k].tile_error);
    }
}

struct ao_frame *ao_frames_back(struct ao_frames *fs, int width, int height, int tiles)
{
    uint64_t kept;
    return ao_frames_back_stamped(fs, width, height, tiles, &kept);
}

/* Makes *rgb hold at least `count` floats, *room counting what it holds, as pages.h gives big
 * buffers (a frame is written whole as soon as it grows); what it held is lost when it grows, which
 * only a new size makes it do. False (the buffer untouched) when memory is short. */
static bool grow_pixels(float **rgb, size_t *room, size_t count)
{
    if (count <= *room)
        return true;
    float *more = ao_pages_alloc(count * sizeof *more);
    if (!more)
        return false;
    ao_pages_free(*rgb, *room * sizeof *more);
    *rgb = more;
    *room = count;
    return true;
}

struct ao_frame *ao_frames_back_stamped(struct ao_frames *fs, int width, int height, int tiles, uint64_t *kept)
{
    struct ao_frame *f = &fs->frames[fs->back];
    *kept = f->width == width && f->height == height ? fs->stamp[fs->back] : 0;
    fs->stamp[fs->back] = 0;
    size_t *room = fs->room[fs->back];
    if (!grow_pixels(&f->rgb, &room[0], 3 * (size_t)width * (size_t)height) ||
        !ao_buffer_grow(&f->tile_error, &room[1], (size_t)tiles)) {
        ao_text_report("aoview: out of memory for %dx%d frames", width, height);
        return NULL;
    }
    f->width = width;
    f->height = height;
    return f;
}

void ao_frames_stamp_back(struct ao_frames *fs, uint64_t stamp)
{
    fs->stamp[fs->back] = stamp;
}

void ao_frames_publish(struct ao_frames *fs)
{
    uint_fast64_t logged = atomic_load_explicit(&fs->logged, memory_order_relaxed);
    if (logged - atomic_load_explicit(&fs->read, memory_order_acquire) < AO_FRAMES_LOG) {
        fs->log[logged % AO_FRAMES_LOG] = fs->frames[fs->back].info;
        atomic_store_explicit(&fs->logged, logged + 1, memory_order_release);
    }
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

int ao_frames_take_log(struct ao_frames *fs, struct ao_frame_info *out, int most)
{
    uint_fast64_t read = atomic_load_explicit(&fs->read, memory_order_relaxed);
    uint_fast64_t logged = atomic_load_explicit(&fs->logged, memory_order_acquire);
    int count = 0;
    for (; read < logged && count < most; read++)
        out[count++] = fs->log[read % AO_FRAMES_LOG];
    atomic_store_explicit(&fs->read, read, memory_order_release);
    return count;
}
