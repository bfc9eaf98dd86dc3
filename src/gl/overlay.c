/* What the window draws over the image; see overlay.h. */
#include "overlay.h"

#include <math.h>
#include <string.h>

#include "chartview.h"
#include "compareview.h"
#include "keys.h"

/* The error chart's panel in the bottom right corner, in font pixels at its text scale. */
#define CHART_WIDTH 200
#define CHART_HEIGHT 130

/* Draws the error chart, when there is one, in the bottom right corner: its text at twice the
 * content scale where the panel then fits into a quarter of the window, else at the content scale
 * with the panel at most half the window wide and tall. */
static void draw_chart(struct ao_hud *hud, const struct ao_chart *chart, const struct ao_overlay *o,
                       float content_scale)
{
    float scale = content_scale;
    if (2 * CHART_WIDTH * scale <= 0.5f * (float)o->width && 2 * CHART_HEIGHT * scale <= 0.5f * (float)o->height)
        scale *= 2;
    int margin = (int)(8 * content_scale);
    int width = (int)fminf(CHART_WIDTH * scale, 0.5f * (float)o->width);
    int height = (int)fminf(CHART_HEIGHT * scale, 0.5f * (float)o->height);
    ao_chartview_draw(hud, chart, o->width - margin - width, o->height - margin - height, width, height, scale,
                      o->width, o->height);
}

/* Lays the status items ('\n' between them) out for the overlay into out, items two spaces apart
 * in lines no wider than 45 % of the framebuffer, and returns their text scale: twice the content
 * scale, or less (down to 1) while the box would cover more than a sixth of the framebuffer. */
static float status_layout(struct ao_hud *hud, const char *items, const struct ao_overlay *o, float content_scale,
                           char *out, size_t size)
{
    float scale = 2.0f * content_scale;
    for (;; scale -= 0.5f * content_scale) {
        float pad = 2.0f * AO_HUD_PADDING * scale;
        size_t used = 0, line = 0; /* where the current line starts in out */
        out[0] = '\0';
        for (const char *item = items; *item;) {
            size_t length = strcspn(item, "\n");
            if (used + length + 3 >= size)
                break;
            if (used == 0) {
                memcpy(out, item, length);
                used = length;
            } else { /* on this line if it fits, else on the next */
                int w, h;
                memcpy(out + used, "  ", 2);
                memcpy(out + used + 2, item, length);
                out[used + 2 + length] = '\0';
                ao_hud_measure(hud, out + line, scale, &w, &h);
                if ((float)w + pad > 0.45f * (float)o->width) {
                    out[used] = '\n';
                    memcpy(out + used + 1, item, length);
                    line = used + 1;
                    used += 1 + length;
                } else {
                    used += 2 + length;
                }
            }
            out[used] = '\0';
            item += length + (item[length] == '\n');
        }
        int w, h;
        ao_hud_measure(hud, out, scale, &w, &h);
        if (((float)w + pad) * ((float)h + pad) <= (float)o->width * (float)o->height / 6.0f ||
            scale - 0.5f * content_scale < 1.0f)
            return scale;
    }
}

void ao_overlay_draw(struct ao_hud *hud, const struct ao_overlay *o)
{
    float content_scale = o->content_scale;
    float scale = content_scale * (o->height >= 360 ? 2.0f : 1.0f);
    int bar_top = (int)(8 * scale);
    if (o->compare)
        bar_top = ao_compareview_draw(hud, o->layout, o->split, o->image, o->hud && !o->help ? o->labels : NULL,
                                      scale, o->width, o->height) + (int)(8 * scale);
    if (o->help) {
        /* At the overlay's scale, or at the content scale where that does not fit the height. */
        float help_scale = scale;
        int w, h;
        for (;;) {
            ao_hud_measure(hud, ao_keys_help(), help_scale, &w, &h);
            w += (int)(2 * AO_HUD_PADDING * help_scale);
            h += (int)(2 * AO_HUD_PADDING * help_scale);
            if (h <= o->height || help_scale <= content_scale)
                break;
            help_scale = content_scale;
        }
        ao_hud_draw(hud, ao_keys_help(), (o->width - w) / 2, (o->height - h) / 2, help_scale, o->width, o->height);
    } else if (o->hud) {
        if (!o->compare) {
            char lines[512];
            float text_scale = status_layout(hud, o->items, o, content_scale, lines, sizeof lines);
            ao_hud_draw(hud, lines, (int)(8 * content_scale), (int)(8 * content_scale), text_scale, o->width,
                        o->height);
            bar_top = (int)(8 * content_scale);
        }
        if (o->bar)
            ao_heatmap_draw_bar(hud, o->bar, o->bar_title, o->bar_unknown, o->width - (int)(8 * scale), bar_top,
                                scale, o->width, o->height);
        draw_chart(hud, o->chart, o, content_scale);
    }
}
