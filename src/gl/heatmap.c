/* Heat maps; see heatmap.h. */
#include "heatmap.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "image.h"

/* The colour ramp's stops in linear RGB, evenly spaced over the scale. */
static const float STOPS[][3] = {
    {0.003f, 0.002f, 0.060f}, {0.010f, 0.080f, 0.600f}, {0.010f, 0.500f, 0.200f},
    {0.850f, 0.750f, 0.010f}, {0.800f, 0.020f, 0.005f},
};
enum { STOP_COUNT = sizeof STOPS / sizeof STOPS[0] };

const struct ao_heatmap_scale ao_heatmap_error = {.low = -4, .high = -1, .percent = true};
const float ao_heatmap_unknown[3] = {0.2f, 0.2f, 0.2f};
const struct ao_heatmap_scale ao_heatmap_difference = {.low = -4, .high = 0, .percent = false};

/* The position of value on the scale, from 0 (low end) to 1 (high end). */
static float position(const struct ao_heatmap_scale *scale, double value)
{
    if (!(value > 0.0))
        return 0.0f;
    double t = (log10(value) - scale->low) / (scale->high - scale->low);
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

void ao_heatmap_colour(const struct ao_heatmap_scale *scale, double value, float rgb[3])
{
    ramp(position(scale, value), rgb);
}

void ao_heatmap_tiles(const struct ao_frame *frame, float *heat)
{
    for (int j = 0; j < frame->height; j++)
        for (int i = 0; i < frame->width; i++) {
            int t = j / frame->tile * frame->tiles_x + i / frame->tile;
            float *out = heat + 3 * ((size_t)j * (size_t)frame->width + (size_t)i);
            if (frame->tiles_x == 0 || isnan(frame->tile_error[t]))
                memcpy(out, ao_heatmap_unknown, sizeof ao_heatmap_unknown);
            else
                ao_heatmap_colour(&ao_heatmap_error, frame->tile_error[t], out);
        }
}

void ao_heatmap_pixels(const float *rgb, const float *reference, int width, int height, float *heat)
{
    size_t pixels = (size_t)width * (size_t)height;
    for (size_t p = 0; p < pixels; p++) {
        const float *a = rgb + 3 * p, *b = reference + 3 * p;
        double d = (fabs((double)a[0] - b[0]) + fabs((double)a[1] - b[1]) + fabs((double)a[2] - b[2])) / 3.0;
        ao_heatmap_colour(&ao_heatmap_difference, d, heat + 3 * p);
    }
}

/* A decade's label: 10^d as a percentage or a plain number. */
static void label(const struct ao_heatmap_scale *scale, int d, char *text, size_t size)
{
    if (scale->percent)
        snprintf(text, size, "%g %%", 100.0 * pow(10.0, d));
    else
        snprintf(text, size, "%g", pow(10.0, d));
}

/* The bar's size in font pixels (times the scale): its ramp, and the room for its labels. */
enum { BAR_WIDTH = 12, BAR_HEIGHT = 120, STEPS = 48 };

void ao_heatmap_draw_bar(struct ao_hud *hud, const struct ao_heatmap_scale *range, const char *title, bool unknown,
                         int x, int y, float scale, int fb_width, int fb_height)
{
    /* The widest label is the low end's, or "not known". */
    char text[16];
    label(range, range->low, text, sizeof text);
    int label_width, label_height, unknown_width, unknown_height;
    ao_hud_measure(hud, text, scale, &label_width, &label_height);
    ao_hud_measure(hud, "not known", scale, &unknown_width, &unknown_height);
    if (unknown && unknown_width > label_width)
        label_width = unknown_width;
    int title_width, title_height;
    ao_hud_measure(hud, title, scale, &title_width, &title_height);
    float pad = AO_HUD_PADDING * scale, width = BAR_WIDTH * scale, height = BAR_HEIGHT * scale;
    float inner = width + pad + (float)label_width;
    float box = (float)title_width > inner ? (float)title_width : inner;
    float left = (float)x - box - 2 * pad, top = (float)y, bar_top = top + pad + (float)title_height + pad;
    float bottom = bar_top + height + pad + (float)label_height / 2;
    float swatch = bottom + pad; /* the "not known" swatch's top, a label's height */
    ao_hud_begin(hud, fb_width, fb_height);
    ao_hud_fill(hud, left, top, (float)x, unknown ? swatch + (float)label_height + pad : bottom,
                (struct ao_hud_colour){0.0f, 0.0f, 0.0f, 0.6f});
    if (unknown) {
        struct ao_hud_colour c = {ao_image_srgb_encode(ao_heatmap_unknown[0]), ao_image_srgb_encode(ao_heatmap_unknown[1]),
                                  ao_image_srgb_encode(ao_heatmap_unknown[2]), 1.0f};
        ao_hud_fill(hud, left + pad, swatch, left + pad + width, swatch + (float)label_height, c);
        ao_hud_text(hud, "not known", left + 2 * pad + width, swatch, scale, (struct ao_hud_colour){1.0f, 1.0f, 1.0f, 1.0f});
    }
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
    for (int d = range->high; d >= range->low; d--) {
        label(range, d, text, sizeof text);
        float ty = bar_top + height * (float)(range->high - d) / (float)(range->high - range->low);
        ao_hud_text(hud, text, left + 2 * pad + width, ty - (float)label_height / 2, scale,
                    (struct ao_hud_colour){1.0f, 1.0f, 1.0f, 1.0f});
    }
    ao_hud_end(hud);
}
