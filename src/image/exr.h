/* OpenEXR files through the OpenEXR 3 C API (OpenEXRCore). image.c is its only user: callers use
 * ao_image_write_linear and ao_image_read_linear, which pick the format by extension. */
#ifndef AO_EXR_H
#define AO_EXR_H

#include <stdbool.h>
#include <stdio.h>

#include "image_types.h"

/* Writes rgb (3 linear floats per pixel, top row first) to the seekable file f as a ZIP-compressed
 * 32-bit float RGB scanline EXR whose header carries the notes as string attributes; path only
 * names the file in messages. False with errno set on failure (the caller reports). */
bool ao_exr_emit(FILE *f, const char *path, const float *rgb, int width, int height,
                 const struct ao_image_note *notes, size_t note_count);

/* Reads the first part of an EXR file (half or float channels R, G, B and optionally A, which is
 * ignored; scanline or tiled; any compression the library decodes) into a malloc'd top-to-bottom
 * RGB float buffer the caller frees. When want_width is not 0, a file whose header states another
 * size than want_width x want_height is refused before any pixel buffer exists. Refuses images
 * larger than AO_IMAGE_MAX_SIDE/_PIXELS, chunks storing more or fewer bytes than their pixels
 * take (checked for every chunk before the pixels are allocated) and non-finite pixels; on
 * failure prints one line naming path and returns false. Any thread. */
bool ao_exr_read(const char *path, int want_width, int want_height, float **rgb, int *width,
                 int *height);

#endif
