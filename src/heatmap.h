/* Heat maps of per-pixel quantities on a log scale (the estimated-error view), and their colour
 * bar drawn with the overlay. */
#ifndef AO_HEATMAP_H
#define AO_HEATMAP_H

#include "hud.h"
#include "render.h"

/* The decades the scale spans: relative errors from 10^AO_HEATMAP_LOW to 10^AO_HEATMAP_HIGH. */
#define AO_HEATMAP_LOW (-4)
#define AO_HEATMAP_HIGH (-1)

/* The colour of value on the log scale, as linear RGB for the display's sRGB shader: dark blue at
 * or below the low end (0 included), through green and yellow, to red at or above the high end. */
void ao_heatmap_colour(double value, float rgb[3]);

/* Paints frame's tile errors as a heat map into heat (3 linear floats per pixel, top row first,
 * the frame's size). Pure. */
void ao_heatmap_tiles(const struct ao_frame *frame, float *heat);

/* Draws the labelled colour bar (top at y, right edge at x) at text scale into a fb_width x
 * fb_height framebuffer. GL thread. */
void ao_heatmap_draw_bar(struct ao_hud *hud, const char *title, int x, int y, float scale, int fb_width,
                         int fb_height);

#endif
