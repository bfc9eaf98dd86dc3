/* Screenshots without a display server: an OSMesa core-profile context running the window's own
 * display code. */
#ifndef AO_HEADLESS_H
#define AO_HEADLESS_H

#include <stdbool.h>

#include "heatmap.h"

/* Under a limit on the address space (ulimit -v), whether drawing a width x height PNG through
 * OSMesa fits in what is left of it (its needs measured with Mesa 22.3, rounded up; Mesa does not
 * survive running out); false after one line naming path. Each write checks it first; a front end
 * asks before rendering, its renderer allocated. Any thread. */
bool ao_headless_check_room(const char *path, int width, int height);

/* Renders rgb (linear, width x height, top row first) through the display shader in an OSMesa
 * core-profile context, reads it back and writes path as PNG; false with one message on failure,
 * libOSMesa not loading included (it is opened at the first call and kept). Any one thread at a
 * time; uses no window system. */
bool ao_headless_write_png(const char *path, const float *rgb, int width, int height);

/* As ao_headless_write_png for a heat map (heatmap.h's colours on range), with its colour bar,
 * titled, in the top right corner where the image is at least AO_HEADLESS_BAR_WIDTH x
 * AO_HEADLESS_BAR_HEIGHT pixels (smaller images would be hidden under it). */
bool ao_headless_write_heatmap(const char *path, const float *heat, int width, int height,
                               const struct ao_heatmap_scale *range, const char *title);

/* Text burnt into a headless PNG in the overlay's box, its top left x, y pixels from the image's. */
struct ao_headless_label {
    const char *text;
    int x, y;
};

/* As ao_headless_write_png, with count labels drawn over the image by the window's overlay text. */
bool ao_headless_write_labelled(const char *path, const float *rgb, int width, int height,
                                const struct ao_headless_label *labels, int count);

/* The smallest image that ao_headless_write_heatmap draws the colour bar on. */
#define AO_HEADLESS_BAR_WIDTH 320
#define AO_HEADLESS_BAR_HEIGHT 200

#endif
