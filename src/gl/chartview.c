/* The live error chart on screen (see chartview.h): the panel, the log-log axes with their
 * labelled ticks, a line per run in its sampling mode's colour, and the legend. */
#include "chartview.h"

#include <math.h>
#include <stdio.h>

#include "sampling.h"

/* Saturated colours that no AO image (grey times an albedo) shows, one per sampling mode, in the
 * order of enum ao_sampling; the window test looks for them on screen. */
static const struct ao_hud_colour MODE_COLOUR[3] = {
    {1.0f, 0.5f, 0.0f, 1.0f},    /* uniform: orange */
    {0.0f, 1.0f, 0.25f, 1.0f},   /* hemisphere: green */
    {0.0f, 0.75f, 1.0f, 1.0f},   /* cosine: sky blue */
};

static const struct ao_hud_colour PANEL = {0.0f, 0.0f, 0.0f, 0.7f};
static const struct ao_hud_colour TEXT = {1.0f, 1.0f, 0.85f, 1.0f};
static const struct ao_hud_colour GRID = {1.0f, 1.0f, 1.0f, 0.18f};
static const struct ao_hud_colour FRAME = {1.0f, 1.0f, 1.0f, 0.6f};

/* Where the plot area lies in the framebuffer, and the axes it shows. */
struct plot {
    float x0, y0, x1, y1;        /* pixels; y0 at the top */
    struct ao_chart_axis x, y;
};

/* Pixel centre of a one-pixel line at v, so that lines stay crisp. */
static float crisp(float v)
{
    return floorf(v) + 0.5f;
}

static float plot_x(const struct plot *p, float log_seconds)
{
    return p->x0 + (p->x1 - p->x0) * (log_seconds - p->x.lo) / (p->x.hi - p->x.lo);
}

static float plot_y(const struct plot *p, float log_rmse)
{
    return p->y1 - (p->y1 - p->y0) * (log_rmse - p->y.lo) / (p->y.hi - p->y.lo);
}

/* A tick's label: its value (10^tick) in the shortest form, with a unit suffix. */
static void label(char *out, size_t size, float tick, const char *unit)
{
    snprintf(out, size, "%g%s", pow(10.0, (double)tick), unit);
}

/* The widest y tick label, in pixels. */
static int y_label_width(struct ao_hud *hud, const struct ao_chart_axis *y, float scale)
{
    int widest = 0;
    for (int k = 0; k < y->ticks; k++) {
        char text[32];
        int w, h;
        label(text, sizeof text, y->tick[k], "");
        ao_hud_measure(hud, text, scale, &w, &h);
        widest = w > widest ? w : widest;
    }
    return widest;
}

/* Grid lines and labels at every tick; x labels start right of the y labels, and those that would
 * run into the previous one are left out. */
static void draw_axes(struct ao_hud *hud, const struct plot *p, float scale, float gap)
{
    float grid[4 * 2 * AO_CHART_TICKS];
    int n = 0;
    for (int k = 0; k < p->y.ticks; k++) {
        float py = crisp(plot_y(p, p->y.tick[k]));
        float line[4] = {p->x0, py, p->x1, py};
        for (int i = 0; i < 4; i++)
            grid[n++] = line[i];
        char text[32];
        int w, h;
        label(text, sizeof text, p->y.tick[k], "");
        ao_hud_measure(hud, text, scale, &w, &h);
        ao_hud_text(hud, text, p->x0 - gap - (float)w, py - 3.5f * scale, scale, TEXT);
    }
    float free_from = p->x0 - gap;
    for (int k = 0; k < p->x.ticks; k++) {
        float px = crisp(plot_x(p, p->x.tick[k]));
        float line[4] = {px, p->y0, px, p->y1};
        for (int i = 0; i < 4; i++)
            grid[n++] = line[i];
        char text[32];
        int w, h;
        label(text, sizeof text, p->x.tick[k], "s");
        ao_hud_measure(hud, text, scale, &w, &h);
        float left = fmaxf(px - 0.5f * (float)w, p->x0 - gap);
        if (left >= free_from) {
            ao_hud_text(hud, text, left, p->y1 + gap, scale, TEXT);
            free_from = left + (float)w + 2.0f * gap;
        }
    }
    ao_hud_lines(hud, grid, n / 2, false, GRID);
    float x0 = crisp(p->x0), y0 = crisp(p->y0), x1 = crisp(p->x1), y1 = crisp(p->y1);
    float frame[10] = {x0, y0, x1, y0, x1, y1, x0, y1, x0, y0};
    ao_hud_lines(hud, frame, 5, true, FRAME);
}

/* One run's line; a single point shows as a short tick so that it is visible at all. */
static void draw_curve(struct ao_hud *hud, const struct plot *p, const struct ao_chart_curve *c,
                       struct ao_hud_colour colour)
{
    float xy[2 * AO_CHART_POINTS + 2];
    int n = 0;
    for (int i = 0; i < c->count; i++) {
        xy[n++] = plot_x(p, c->points[i].x);
        xy[n++] = plot_y(p, c->points[i].y);
    }
    if (c->count == 1) {
        xy[n++] = xy[0] + 2.0f;
        xy[n++] = xy[1];
    }
    ao_hud_lines(hud, xy, n / 2, true, colour);
}

/* How many points of the chart fall into the rectangle (x0, y0)-(x1, y1). */
static int points_in(const struct ao_chart *chart, const struct plot *p, float x0, float y0, float x1,
                     float y1)
{
    int inside = 0;
    for (int k = 0; k < chart->count; k++)
        for (int i = 0; i < chart->curves[k].count; i++) {
            float px = plot_x(p, chart->curves[k].points[i].x), py = plot_y(p, chart->curves[k].points[i].y);
            inside += px >= x0 && px <= x1 && py >= y0 && py <= y1;
        }
    return inside;
}

/* The names of the modes of the runs charted, in their colours, one a line, in the plot's bottom
 * left corner (which falling curves leave empty), or its top right corner when that one covers
 * fewer points. */
static void draw_legend(struct ao_hud *hud, const struct ao_chart *chart, const struct plot *p,
                        float scale, float gap)
{
    bool charted[3] = {false, false, false};
    for (int k = 0; k < chart->count; k++)
        charted[chart->curves[k].sampling] = true;
    int width = 0, height = 0, lines = 0;
    for (int m = 0; m < 3; m++) {
        int w, h;
        ao_hud_measure(hud, ao_sampling_name((enum ao_sampling)m), scale, &w, &h);
        width = charted[m] && w > width ? w : width;
        height = h;
        lines += charted[m];
    }
    float w = (float)width, h = (float)(lines * height);
    float x = p->x0 + gap, y = p->y1 - gap - h;
    if (points_in(chart, p, p->x1 - gap - w, p->y0 + gap, p->x1 - gap, p->y0 + gap + h) <
        points_in(chart, p, x, y, x + w, y + h)) {
        x = p->x1 - gap - w;
        y = p->y0 + gap;
    }
    for (int m = 0, line = 0; m < 3; m++)
        if (charted[m])
            ao_hud_text(hud, ao_sampling_name((enum ao_sampling)m), x, y + (float)(line++ * height), scale,
                        MODE_COLOUR[m]);
}

void ao_chartview_draw(struct ao_hud *hud, const struct ao_chart *chart, int x, int y, int width,
                       int height, float scale, int fb_width, int fb_height)
{
    struct plot p;
    if (!ao_chart_axes(chart, &p.x, &p.y))
        return;

    /* Layout: the title on top, y labels left of the plot, x labels below it. */
    float gap = 4.0f * scale, line = 8.0f * scale;
    float left = (float)x, top = (float)y, right = (float)(x + width), bottom = (float)(y + height);
    p.x0 = left + gap + (float)y_label_width(hud, &p.y, scale) + gap;
    p.x1 = right - 3.0f * gap;
    p.y0 = top + gap + line + gap;
    p.y1 = bottom - gap - line - gap;

    ao_hud_begin(hud, fb_width, fb_height);
    ao_hud_fill(hud, left, top, right, bottom, PANEL);
    ao_hud_text(hud, "RMSE against time", left + gap, top + gap, scale, TEXT);
    draw_axes(hud, &p, scale, gap);
    draw_legend(hud, chart, &p, scale, gap);
    for (int k = 0; k < chart->count; k++) {
        const struct ao_chart_curve *c = &chart->curves[k];
        struct ao_hud_colour colour = MODE_COLOUR[c->sampling];
        for (int later = k + 1; later < chart->count; later++)
            if (chart->curves[later].sampling == c->sampling)
                colour.a = 0.45f;
        draw_curve(hud, &p, c, colour);
    }
    ao_hud_end(hud);
}
