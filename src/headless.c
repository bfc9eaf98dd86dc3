#include "headless.h"

#include <stdio.h>

#include "display.h"
#include "glapi.h"
#include "hud.h"

#include <GL/osmesa.h>

/* A heat map's colour bar, drawn over the image by the display before read-back. */
struct bar {
    const struct ao_glapi *gl;
    const struct ao_heatmap_scale *range;
    const char *title;
    bool failed;
};

static void draw_bar(void *user, int width, int height)
{
    struct bar *b = user;
    struct ao_hud *hud = ao_hud_create(b->gl);
    if (!hud) {
        b->failed = true;
        return;
    }
    ao_heatmap_draw_bar(hud, b->range, b->title, width - 8, 8, 1.0f, width, height);
    ao_hud_destroy(hud);
}

/* Writes rgb as ao_headless_write_png does, with bar's colour bar over it unless bar is NULL. */
static bool write_png(const char *path, const float *rgb, int width, int height, struct bar *bar)
{
    /* An OpenGL 3.3 core context, like the window's, so the same shaders run. */
    static const int attribs[] = {
        OSMESA_FORMAT, OSMESA_RGBA,
        OSMESA_PROFILE, OSMESA_CORE_PROFILE,
        OSMESA_CONTEXT_MAJOR_VERSION, 3,
        OSMESA_CONTEXT_MINOR_VERSION, 3,
        0,
    };
    OSMesaContext context = OSMesaCreateContextAttribs(attribs, NULL);
    if (!context) {
        fprintf(stderr, "aoview: %s: no OpenGL 3.3 core context from OSMesa\n", path);
        return false;
    }

    /* The display draws into its own 1:1 offscreen framebuffer, exactly as the window's screenshot
     * does; OSMesa only needs some buffer to make the context current. */
    unsigned char buffer[4];
    bool ok = OSMesaMakeCurrent(context, buffer, GL_UNSIGNED_BYTE, 1, 1);
    if (!ok)
        fprintf(stderr, "aoview: %s: cannot make the OSMesa context current\n", path);

    struct ao_glapi gl;
    struct ao_display *display = NULL;
    ok = ok && ao_glapi_load(&gl, OSMesaGetProcAddress) && (display = ao_display_create(&gl));
    if (bar)
        bar->gl = &gl;
    ok = ok && ao_display_upload(display, rgb, width, height) &&
         ao_display_write_png_with(display, path, bar ? draw_bar : NULL, bar) && !(bar && bar->failed);
    ao_display_destroy(display);
    OSMesaDestroyContext(context);
    return ok;
}

bool ao_headless_write_png(const char *path, const float *rgb, int width, int height)
{
    return write_png(path, rgb, width, height, NULL);
}

bool ao_headless_write_heatmap(const char *path, const float *heat, int width, int height,
                               const struct ao_heatmap_scale *range, const char *title)
{
    struct bar bar = {.range = range, .title = title};
    bool room = width >= AO_HEADLESS_BAR_WIDTH && height >= AO_HEADLESS_BAR_HEIGHT;
    return write_png(path, heat, width, height, room ? &bar : NULL);
}
