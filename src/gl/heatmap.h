/* Heat maps of per-pixel quantities on a log scale (the estimated-error and difference views), and
 * their colour bar drawn with the overlay. */
#ifndef AO_HEATMAP_H
#define AO_HEATMAP_H

#include <stdbool.h>

#include "frame.h"
#include "hud.h"

/* A log scale from 10^low to 10^high, labelled per decade as percentages or as plain numbers. */
struct ao_heatmap_scale {
    int low, high;
    bool percent;
};

/* The estimated-error view's scale: relative errors from 0.01 % to 10 %. */
extern const struct ao_heatmap_scale ao_heatmap_error;

/* The difference view's scale: absolute differences of linear values from 0.0001 to 1. */
extern const struct ao_heatmap_scale ao_heatmap_difference;

/* The colour of value on the log scale, as linear RGB for the display's sRGB shader: dark blue at
 * or below the low end (0 included), through green and yellow, to red at or above the high end. */
void ao_heatmap_colour(const struct ao_heatmap_scale *scale, double value, float rgb[3]);

/* The colour of a value not known yet (a tile without an error estimate), as linear RGB: a mid
 * grey, apart from every colour of the ramp. */
extern const float ao_heatmap_unknown[3];

/* Paints frame's tile errors on the error scale into heat (3 linear floats per pixel, top row
 * first, the frame's size), a tile not estimated yet (NAN), and all of a preview (no tiles), in
 * ao_heatmap_unknown. Pure. */
void ao_heatmap_tiles(const struct ao_frame *frame, float *heat);

/* Paints |rgb - reference| per pixel (the mean over its three channels) on the difference scale
 * into heat; all three are 3 linear floats per pixel of a width x height image. Pure. */
void ao_heatmap_pixels(const float *rgb, const float *reference, int width, int height, float *heat);

/* Draws the colour bar of range, titled and labelled per decade (top at y, right edge at x), with a
 * swatch of ao_heatmap_unknown labelled "not known" below it when `unknown`, at text scale into a
 * fb_width x fb_height framebuffer. GL thread. */
void ao_heatmap_draw_bar(struct ao_hud *hud, const struct ao_heatmap_scale *range, const char *title, bool unknown,
                         int x, int y, float scale, int fb_width, int fb_height);

#endif
