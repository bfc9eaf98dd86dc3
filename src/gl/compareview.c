/* The comparison's overlay on screen (see compareview.h): the split layout's divider and its
 * handle, and each side's label in its corner. */
#include "compareview.h"

/* The divider: a light line two pixels wide, with a handle half way down to show it can be dragged. */
static const struct ao_hud_colour DIVIDER = {1.0f, 1.0f, 1.0f, 0.9f};
static const struct ao_hud_colour HANDLE = {0.0f, 0.0f, 0.0f, 0.7f};

int ao_compareview_draw(struct ao_hud *hud, enum ao_compare_layout layout, double split, struct ao_display_rect image,
                        const char *const *labels, float scale, int fb_width, int fb_height)
{
    int top = fb_height - (image.y + image.height), margin = (int)(8 * scale);
    if (layout == AO_COMPARE_SPLIT) {
        float x = (float)image.x + (float)(split * image.width), middle = (float)top + 0.5f * (float)image.height;
        float handle = 4.0f * scale;
        ao_hud_begin(hud, fb_width, fb_height);
        ao_hud_fill(hud, x - handle, middle - 3 * handle, x + handle, middle + 3 * handle, HANDLE);
        ao_hud_fill(hud, x - 1.0f, (float)top, x + 1.0f, (float)(top + image.height), DIVIDER);
        ao_hud_end(hud);
    }
    if (!labels)
        return top;
    int bottom = top;
    for (int k = 0; k < 2; k++) {
        int w, h;
        ao_hud_measure(hud, labels[k], scale, &w, &h);
        int pad = (int)(2 * AO_HUD_PADDING * scale), x = image.x + margin;
        if (k == 1)
            x = layout == AO_COMPARE_SPLIT ? image.x + image.width - margin - w - pad : image.x + image.width / 2 + margin;
        ao_hud_draw(hud, labels[k], x, top + margin, scale, fb_width, fb_height);
        bottom = top + margin + h + pad > bottom ? top + margin + h + pad : bottom;
    }
    return bottom;
}
