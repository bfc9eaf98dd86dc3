/* The on-screen overlay (see hud.h): stb_easy_font's text drawn as quads, boxes and lines in GL
 * core through the hud shader, and the status text the overlay and the window title share. */
#include "hud.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ao_shaders.h"
#include "progress.h"
#include "sampling.h"

/* stb_easy_font is a header of static functions, not all used here, written in an older style. */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-braces"
#include <stb_easy_font.h>
#pragma GCC diagnostic pop

/* stb_easy_font's vertex: position, unused z, colour; four per quad. */
struct glyph_vertex {
    float x, y, z;
    unsigned char rgba[4];
};

struct ao_hud {
    const struct ao_glapi *gl;
    GLuint program, vao, vbo;
    GLint screen, tint;
    char *text;                  /* sanitised copy of the text being drawn */
    size_t text_size;
    struct glyph_vertex *quads;  /* stb_easy_font output */
    float *triangles;            /* x, y pairs: two triangles per glyph quad */
    size_t quad_capacity;
};

/* Appends one status item, preceded by the separator unless it is the first. */
static void item(char *out, size_t size, size_t *used, const char *separator, const char *format, ...)
{
    if (*used >= size)
        return;
    if (*used > 0)
        *used += (size_t)snprintf(out + *used, size - *used, "%s", separator);
    if (*used >= size)
        return;
    va_list args;
    va_start(args, format);
    *used += (size_t)vsnprintf(out + *used, size - *used, format, args);
    va_end(args);
}

void ao_hud_format(const struct ao_hud_status *s, const char *separator, const char *unknown, char *out,
                   size_t size)
{
    const struct ao_frame_info *f = &s->info;
    /* The normals view has no AO error, rate or time left to show (it ends when its picture does). */
    bool measured = f->pass > 0, preview = s->block > 1, ao = f->output != AO_OUTPUT_NORMALS;
    size_t used = 0;
    out[0] = '\0';
    item(out, size, &used, separator, "%s", s->scene);
    if (preview)
        item(out, size, &used, separator, "%dx%d preview, %d px cells", s->width, s->height, s->block);
    else
        item(out, size, &used, separator, "%dx%d", s->width, s->height);
    item(out, size, &used, separator, "%s", ao_sampling_name(f->sampling));
    item(out, size, &used, separator, "AA %s", f->aa ? "on" : "off");
    if (f->output == AO_OUTPUT_NORMALS)
        item(out, size, &used, separator, "normals");
    if (f->shading == AO_SHADING_FLAT)
        item(out, size, &used, separator, "flat");
    char text[64];
    ao_progress_format_spp(f, text, sizeof text);
    if (text[0] && !preview)
        item(out, size, &used, separator, "%s", text);
    if (measured && !preview && ao) {
        if (isnan(f->error))
            item(out, size, &used, separator, "error %s", unknown);
        else
            item(out, size, &used, separator, "error %.2f %%", 100.0 * f->error);
    }
    if (measured) {
        item(out, size, &used, separator, "%.1fs", s->seconds);
        ao_progress_format(f->done || !ao ? NAN : s->seconds_left, text, sizeof text);
        if (f->done)
            item(out, size, &used, separator, "finished");
        else if (text[0])
            item(out, size, &used, separator, "%s", text);
        if (f->seconds > 0.0 && ao)
            item(out, size, &used, separator, "%.1f Mrays/s",
                 (double)(f->eye_rays + f->shadow_rays) / f->seconds / 1e6);
    }
    item(out, size, &used, separator, "pass %u", (unsigned)f->pass);
    if (s->spppp)
        item(out, size, &used, separator, "%d spp/pass", s->spppp);
    else if (f->spppp)
        item(out, size, &used, separator, "auto %u spp/pass", (unsigned)f->spppp);
    else
        item(out, size, &used, separator, "auto spp/pass");
    if (s->adaptive && measured && !preview)
        item(out, size, &used, separator, "adaptive: %.0f %% converged", 100.0 * f->converged);
    if (measured && !preview && ao && !isnan(f->rmse))
        item(out, size, &used, separator, "RMSE %.4g", f->rmse);
    else if (s->reference_differs)
        item(out, size, &used, separator, "no RMSE: reference of another size");
    if (s->paused)
        item(out, size, &used, separator, "paused");
}

struct ao_hud *ao_hud_create(const struct ao_glapi *gl)
{
    struct ao_hud *hud = calloc(1, sizeof *hud);
    if (!hud) {
        fprintf(stderr, "aoview: out of memory for the overlay\n");
        return NULL;
    }
    hud->gl = gl;
    hud->program = ao_glapi_program(gl, "hud", ao_shader_hud_vert, ao_shader_hud_frag);
    if (!hud->program) {
        free(hud);
        return NULL;
    }
    hud->screen = gl->GetUniformLocation(hud->program, "screen");
    hud->tint = gl->GetUniformLocation(hud->program, "tint");
    gl->GenVertexArrays(1, &hud->vao);
    gl->GenBuffers(1, &hud->vbo);
    gl->BindVertexArray(hud->vao);
    gl->BindBuffer(GL_ARRAY_BUFFER, hud->vbo);
    gl->VertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), NULL);
    gl->EnableVertexAttribArray(0);
    gl->BindVertexArray(0);
    return hud;
}

void ao_hud_destroy(struct ao_hud *hud)
{
    if (!hud)
        return;
    hud->gl->DeleteBuffers(1, &hud->vbo);
    hud->gl->DeleteVertexArrays(1, &hud->vao);
    hud->gl->DeleteProgram(hud->program);
    free(hud->text);
    free(hud->quads);
    free(hud->triangles);
    free(hud);
}

/* Copies text into the scratch buffer with every byte stb_easy_font has no glyph for (it indexes
 * its table by byte - 32) replaced by '?'; false when memory is short. */
static bool sanitise(struct ao_hud *hud, const char *text)
{
    size_t n = strlen(text) + 1;
    if (n > hud->text_size) {
        char *grown = realloc(hud->text, n);
        if (!grown)
            return false;
        hud->text = grown;
        hud->text_size = n;
    }
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)text[i];
        hud->text[i] = c == '\n' || c == '\0' || (c >= 32 && c < 127) ? (char)c : '?';
    }
    return true;
}

void ao_hud_measure(struct ao_hud *hud, const char *text, float scale, int *width, int *height)
{
    *width = *height = 0;
    if (!sanitise(hud, text))
        return;
    *width = (int)ceilf((float)stb_easy_font_width(hud->text) * scale);
    *height = (int)ceilf((float)stb_easy_font_height(hud->text) * scale);
}

/* Writes the two triangles of the rectangle (x0, y0)-(x1, y1) at t; returns the next slot. */
static float *rectangle(float *t, float x0, float y0, float x1, float y1)
{
    const float v[12] = {x0, y0, x1, y0, x1, y1, x0, y0, x1, y1, x0, y1};
    memcpy(t, v, sizeof v);
    return t + 12;
}

/* Makes room for quads glyph quads in the scratch buffers. */
static bool reserve(struct ao_hud *hud, size_t quads)
{
    if (quads <= hud->quad_capacity)
        return true;
    struct glyph_vertex *q = realloc(hud->quads, quads * 4 * sizeof *q);
    if (!q)
        return false;
    hud->quads = q;
    float *t = realloc(hud->triangles, quads * 12 * sizeof *t);
    if (!t)
        return false;
    hud->triangles = t;
    hud->quad_capacity = quads;
    return true;
}

/* Draws count x, y pairs from xy as mode in the colour. */
static void draw_points(struct ao_hud *hud, GLenum mode, const float *xy, int count, struct ao_hud_colour c)
{
    const struct ao_glapi *gl = hud->gl;
    gl->BufferData(GL_ARRAY_BUFFER, (GLsizeiptr)((size_t)count * 2 * sizeof(float)), xy, GL_STREAM_DRAW);
    gl->Uniform4f(hud->tint, c.r, c.g, c.b, c.a);
    gl->DrawArrays(mode, 0, count);
}

void ao_hud_begin(struct ao_hud *hud, int fb_width, int fb_height)
{
    const struct ao_glapi *gl = hud->gl;
    gl->Viewport(0, 0, fb_width, fb_height);
    gl->Enable(GL_BLEND);
    gl->BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    gl->UseProgram(hud->program);
    gl->Uniform2f(hud->screen, (float)fb_width, (float)fb_height);
    gl->BindVertexArray(hud->vao);
    gl->BindBuffer(GL_ARRAY_BUFFER, hud->vbo);
}

void ao_hud_end(struct ao_hud *hud)
{
    hud->gl->BindVertexArray(0);
    hud->gl->Disable(GL_BLEND);
}

void ao_hud_fill(struct ao_hud *hud, float x0, float y0, float x1, float y1, struct ao_hud_colour colour)
{
    float t[12];
    rectangle(t, x0, y0, x1, y1);
    draw_points(hud, GL_TRIANGLES, t, 6, colour);
}

void ao_hud_lines(struct ao_hud *hud, const float *xy, int count, bool strip, struct ao_hud_colour colour)
{
    draw_points(hud, strip ? GL_LINE_STRIP : GL_LINES, xy, count, colour);
}

void ao_hud_text(struct ao_hud *hud, const char *text, float x, float y, float scale,
                 struct ao_hud_colour colour)
{
    /* No glyph has more than 16 segments, each one quad of 64 bytes. */
    if (!sanitise(hud, text) || !reserve(hud, 16 * strlen(hud->text) + 1))
        return;
    int quads = stb_easy_font_print(0, 0, hud->text, NULL, hud->quads,
                                    (int)(hud->quad_capacity * 4 * sizeof *hud->quads));
    /* Each glyph quad as two triangles, scaled and moved into place. */
    float *t = hud->triangles;
    for (int i = 0; i < quads; i++) {
        const struct glyph_vertex *q = hud->quads + 4 * i;
        t = rectangle(t, x + q[0].x * scale, y + q[0].y * scale, x + q[2].x * scale, y + q[2].y * scale);
    }
    draw_points(hud, GL_TRIANGLES, hud->triangles, 6 * quads, colour);
}

void ao_hud_draw(struct ao_hud *hud, const char *text, int x, int y, float scale, int fb_width,
                 int fb_height)
{
    int width, height;
    ao_hud_measure(hud, text, scale, &width, &height);
    float pad = AO_HUD_PADDING * scale;
    ao_hud_begin(hud, fb_width, fb_height);
    ao_hud_fill(hud, (float)x, (float)y, (float)x + (float)width + 2 * pad, (float)y + (float)height + 2 * pad,
                (struct ao_hud_colour){0.0f, 0.0f, 0.0f, 0.7f});
    ao_hud_text(hud, text, (float)x + pad, (float)y + pad, scale, (struct ao_hud_colour){1.0f, 1.0f, 0.85f, 1.0f});
    ao_hud_end(hud);
}
