/* Buffers that grow and never shrink: what a frame or a view of a changing size keeps. */
#ifndef AO_BUFFER_H
#define AO_BUFFER_H

#include <stdbool.h>
#include <stdlib.h>

/* Makes *buffer hold at least `count` floats, *room counting what it holds, keeping its contents;
 * false (the buffer untouched) when memory is short. */
static inline bool ao_buffer_grow(float **buffer, size_t *room, size_t count)
{
    if (count <= *room)
        return true;
    float *more = realloc(*buffer, count * sizeof *more);
    if (!more)
        return false;
    *buffer = more;
    *room = count;
    return true;
}

#endif
