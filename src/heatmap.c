/* Heat maps; see heatmap.h. */
#include "heatmap.h"

#include <math.h>
#include <stdio.h>

#include "image.h"

/* The colour ramp's stops in linear RGB, evenly spaced over the scale. */
static const float STOPS[][3] = {
    {0.003f, 0.002f, 0.060f}, {0.010f, 0.080f, 0.600f}, {0.010f, 0.500f, 0.200f},
    {0.850f, 0.750f, 0.010f}, {0.800f, 0.020f, 0.005f},
};
enum { STOP_COUNT = sizeof STOPS / sizeof STOPS[0] };

/* The position of value on the scale, from 0 (low end) to 1 (high end). */
static float position(double value)
{
    if (!(value > 0.0))
        return 0.0f;
    double t = (log10(value) - AO_HEATMAP_LOW) / (AO_HEATMAP_HIGH - AO_HEATMAP_LOW);
    return t < 0.0 ? 0.0f : t > 1.0 ? 1.0f : (float)t;
}

/* The ramp's colour at t in [0, 1]. */
static void ramp(float t, float rgb[3])
{
    float x = t * (STOP_COUNT - 1);
    int k = x >= STOP_COUNT - 1 ? STOP_COUNT - 2 : (int)x;
    float f = x - (float)k;
    for (int c = 0; c < 3; c++)
        rgb[c] = STOPS[k][c] + f * (STOPS[k + 1][c] - STOPS[k][c]);
}

void ao_heatmap_colour(double value, float rgb[3])
{
    ramp(position(value), rgb);
}

void ao_heatmap_tiles(const struct ao_frame *frame, float *heat)
{
    for (int j = 0; j < frame->height; j++)
        for (int i = 0; i < frame->width; i++) {
            int t = j / frame->tile * frame->tiles_x + i / frame->tile;
            ao_heatmap_colour(frame->tile_error[t], heat + 3 * ((size_t)j * (size_t)frame->width + (size_t)i));
        }
}

/* The bar's size in font pixels (times the scale): its ramp, and the room for its labels. */
enum { BAR_WIDTH = 12, BAR_HEIGHT = 120, STEPS = 48 };

void ao_heatmap_draw_bar(struct ao_hud *hud, const char *title, int x, int y, float scale, int fb_width,
                         int fb_height)
{
    int label_width, label_height;
    ao_hud_measure(hud, "0.01 %", scale, &label_width, &label_height);
    int title_width, title_height;
    ao_hud_measure(hud, title, scale, &title_width, &title_height);
    float pad = AO_HUD_PADDING * scale, width = BAR_WIDTH * scale, height = BAR_HEIGHT * scale;
    float inner = width + pad + (float)label_width;
    float box = (float)title_width > inner ? (float)title_width : inner;
    float left = (float)x - box - 2 * pad, top = (float)y, bar_top = top + pad + (float)title_height + pad;
    ao_hud_begin(hud, fb_width, fb_height);
    ao_hud_fill(hud, left, top, (float)x, bar_top + height + pad + (float)label_height / 2,
                (struct ao_hud_colour){0.0f, 0.0f, 0.0f, 0.6f});
    ao_hud_text(hud, title, left + pad, top + pad, scale, (struct ao_hud_colour){1.0f, 1.0f, 1.0f, 1.0f});
    /* The ramp, high end at the top, drawn in sRGB as the display shows the image. */
    for (int s = 0; s < STEPS; s++) {
        float linear[3];
        ramp(1.0f - ((float)s + 0.5f) / STEPS, linear);
        struct ao_hud_colour c = {ao_image_srgb_encode(linear[0]), ao_image_srgb_encode(linear[1]),
                                  ao_image_srgb_encode(linear[2]), 1.0f};
        ao_hud_fill(hud, left + pad, bar_top + height * (float)s / STEPS, left + pad + width,
                    bar_top + height * (float)(s + 1) / STEPS, c);
    }
    /* A label per decade. */
    for (int d = AO_HEATMAP_HIGH; d >= AO_HEATMAP_LOW; d--) {
        char text[16];
        snprintf(text, sizeof text, "%g %%", 100.0 * pow(10.0, d));
        float ty = bar_top + height * (float)(AO_HEATMAP_HIGH - d) / (AO_HEATMAP_HIGH - AO_HEATMAP_LOW);
        ao_hud_text(hud, text, left + 2 * pad + width, ty - (float)label_height / 2, scale,
                    (struct ao_hud_colour){1.0f, 1.0f, 1.0f, 1.0f});
    }
    ao_hud_end(hud);
}
