/* What the window draws over the image: the status items laid out in a box, or the key help; the
 * comparison's divider and its sides' labels; a heat map's colour bar; the live error chart.
 * Drawn with the overlay's primitives (hud.h) into the framebuffer the image is in; knows no
 * window: window.c says what to draw. */
#ifndef AO_OVERLAY_H
#define AO_OVERLAY_H

#include <stdbool.h>

#include "chart.h"
#include "display.h"
#include "heatmap.h"
#include "hud.h"
#include "modes.h"

/* What the overlay shows over one frame on screen. */
struct ao_overlay {
    int width, height;                   /* the framebuffer's pixels */
    float content_scale;                 /* the window's content scale, 1 unless HiDPI */
    bool hud;                            /* F2: the status, the colour bar and the chart */
    bool help;                           /* F1: the key help, in place of the status */
    const char *items;                   /* the status items, '\n' between them (single view) */
    bool compare;                        /* the comparison is on screen: its divider and labels */
    enum ao_compare_layout layout;
    double split;                        /* the divider, a share of the image's width */
    struct ao_display_rect image;        /* where the image lies (ao_display_fit) */
    const char *labels[2];               /* the sides' labels, lines '\n' apart */
    const struct ao_heatmap_scale *bar;  /* the heat map's scale, or NULL for no colour bar */
    const char *bar_title;
    bool bar_unknown;                    /* a swatch for "not known" under the bar */
    const struct ao_chart *chart;        /* the error chart (drawn when it has a point) */
};

/* Draws the overlay o describes over the image already in the framebuffer. GL thread. */
void ao_overlay_draw(struct ao_hud *hud, const struct ao_overlay *o);

#endif
