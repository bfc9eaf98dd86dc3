/* The live comparison's overlay on screen: the divider of the split layout and each side's label,
 * drawn with the overlay's primitives over the image. */
#ifndef AO_COMPAREVIEW_H
#define AO_COMPAREVIEW_H

#include "display.h"
#include "hud.h"
#include "modes.h"

/* Draws, over the image drawn into the rectangle image (as ao_display_fit gives it) of a fb_width x
 * fb_height framebuffer: in the split layout the divider at the share split of its width; then,
 * unless labels is NULL, labels[0] in A's top left corner and labels[1] in B's (the image's top
 * right corner when split), text at scale. Returns the framebuffer row below the labels. GL thread. */
int ao_compareview_draw(struct ao_hud *hud, enum ao_compare_layout layout, double split, struct ao_display_rect image,
                        const char *const *labels, float scale, int fb_width, int fb_height);

#endif
