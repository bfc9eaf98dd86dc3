/* Screenshots without a display server: an OSMesa core-profile context running the window's own
 * display code. */
#ifndef AO_HEADLESS_H
#define AO_HEADLESS_H

#include <stdbool.h>

/* Renders rgb (linear, width x height, top row first) through the display shader in an OSMesa
 * core-profile context, reads it back and writes path as PNG; false with one message on failure,
 * libOSMesa not loading included (it is opened at the first call and kept). Any one thread at a
 * time; uses no window system. */
bool ao_headless_write_png(const char *path, const float *rgb, int width, int height);

#endif
