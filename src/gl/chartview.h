/* The viewer's live error chart on screen: chart.h's curves drawn with the overlay's primitives in a
 * translucent panel, log-log axes with labelled ticks, and a legend of the sampling modes charted. */
#ifndef AO_CHARTVIEW_H
#define AO_CHARTVIEW_H

#include "chart.h"
#include "hud.h"

/* Draws chart in the panel of width x height pixels whose top left is (x, y) in a fb_width x
 * fb_height framebuffer, text at scale; draws nothing when the chart has no point. Each run is a
 * line in its mode's colour, faded when a newer run has the same mode. GL thread. */
void ao_chartview_draw(struct ao_hud *hud, const struct ao_chart *chart, int x, int y, int width,
                       int height, float scale, int fb_width, int fb_height);

#endif
