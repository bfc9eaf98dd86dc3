#include "headless.h"

#include <stdio.h>

#include "display.h"
#include "glapi.h"

#include <GL/osmesa.h>

bool ao_headless_write_png(const char *path, const float *rgb, int width, int height)
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
    ok = ok && ao_display_upload(display, rgb, width, height) && ao_display_write_png(display, path);
    ao_display_destroy(display);
    OSMesaDestroyContext(context);
    return ok;
}
