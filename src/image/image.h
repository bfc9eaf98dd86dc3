/* Image files: PNG (8-bit sRGB), PFM and OpenEXR (linear float RGB) writing, reading for tests
 * and references, and the sRGB transfer curve shared with the display shader. Writes go to a
 * temporary file "<name>.tmp.<pid>.<n>" beside the target (the name part cut to fit the file
 * system's longest name) that is renamed into place. */
#ifndef AO_IMAGE_H
#define AO_IMAGE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "image_types.h"

/* The sRGB encoding of one linear value, clamped to [0, 1]. */
float ao_image_srgb_encode(float linear);

/* Encodes count linear floats to 8-bit sRGB, rounding to nearest (the display shader's curve):
 * correctly rounded (the curve taken in double precision), by a table. The display shader rounds
 * alike but for a value within its float rounding of a step between two codes (none of the
 * bunny's 921,600 values at 640x480). Any thread. */
void ao_image_encode_srgb8(const float *linear, size_t count, uint8_t *out);

/* As ao_image_encode_srgb8 for `pixels` pixels of 3 floats, written as 4 bytes each: blue, green,
 * red, 255 (GL_BGRA's order). Any thread. */
void ao_image_encode_srgb8_bgra(const float *rgb, size_t pixels, uint8_t *out);

/* Checks that an image can be written to path before it is made: its name fits the file system,
 * it is not a directory, and a temporary file can be created beside it (and is removed again);
 * false after one line naming path. Any thread. */
bool ao_image_check_output(const char *path);

/* How many images this process has renamed into place so far (writes finished). Any thread. */
unsigned ao_image_written(void);

/* Removes the temporary files of the writes in progress (in any thread); for a process about to
 * _exit: no write can begin or end afterwards (they wait for ever), so ao_image_written stays as
 * it is from then on. */
void ao_image_discard_temporaries(void);

/* Writes an RGB8 PNG, rows top to bottom, via a temporary file renamed into place; on failure
 * prints one line naming path and returns false. */
bool ao_image_write_png(const char *path, const uint8_t *rgb, int width, int height);

/* Writes a little-endian PFM (rows stored bottom to top as the format says) from rows given top to
 * bottom, via a temporary file renamed into place; on failure prints one line and returns false. */
bool ao_image_write_pfm(const char *path, const float *rgb, int width, int height);

/* Reads a colour PFM (either endianness) into a malloc'd top-to-bottom RGB float buffer the
 * caller frees; on failure prints one line naming path and returns false. */
bool ao_image_read_pfm(const char *path, float **rgb, int *width, int *height);

/* Writes a linear image chosen by path's extension: .exr (32-bit float RGB, the notes as header
 * attributes) or else PFM; via a temporary file renamed into place; on failure prints one line
 * naming path and returns false. */
bool ao_image_write_linear(const char *path, const float *rgb, int width, int height,
                           const struct ao_image_note *notes, size_t note_count);

/* Reads a linear image chosen by path's extension, .exr (see exr.h) or else PFM, into a malloc'd
 * top-to-bottom RGB float buffer the caller frees; on failure prints one line and returns false. */
bool ao_image_read_linear(const char *path, float **rgb, int *width, int *height);

/* Reads a linear image as ao_image_read_linear does, which must be width x height pixels (both
 * above 0): a file whose header states another size is refused, in one line naming it and both
 * sizes, before its pixels are read or any buffer for them exists. For --reference. */
bool ao_image_read_linear_sized(const char *path, int width, int height, float **rgb);

/* True when path ends in ext, ignoring case. */
bool ao_image_has_extension(const char *path, const char *ext);

/* Reads a PNG into a malloc'd top-to-bottom RGB8 buffer the caller frees; false on failure. */
bool ao_image_read_png(const char *path, uint8_t **rgb, int *width, int *height);

#endif
