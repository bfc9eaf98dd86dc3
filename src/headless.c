#include "headless.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "display.h"
#include "glapi.h"
#include "hud.h"

#include <GL/osmesa.h>

/* libOSMesa pulls in LLVM, whose loading takes longer than starting all the rest of aoview, so it
 * is opened at the first PNG instead of being linked: --version, PFM output and the window never
 * map it. Its soname first, then the development symlink for a system with another soname. */
static const char *const library_names[] = {"libOSMesa.so.8", "libOSMesa.so"};

/* The OSMesa functions used, typed as GL/osmesa.h declares them (checked just below). */
typedef OSMesaContext (GLAPIENTRY *create_context_attribs_fn)(const int *attribs, OSMesaContext share);
typedef GLboolean (GLAPIENTRY *make_current_fn)(OSMesaContext context, void *buffer, GLenum type,
                                                GLsizei width, GLsizei height);
typedef OSMESAproc (GLAPIENTRY *get_proc_address_fn)(const char *name);
typedef void (GLAPIENTRY *destroy_context_fn)(OSMesaContext context);

/* _Generic leaves its operand unevaluated: the header's declarations are checked, not linked to. */
#define SAME_TYPE(function, type) _Static_assert(_Generic(&function, type : 1, default : 0), #function)
SAME_TYPE(OSMesaCreateContextAttribs, create_context_attribs_fn);
SAME_TYPE(OSMesaMakeCurrent, make_current_fn);
SAME_TYPE(OSMesaGetProcAddress, get_proc_address_fn);
SAME_TYPE(OSMesaDestroyContext, destroy_context_fn);

/* The library, opened once per process and kept: unloading LLVM is not safe. */
static struct {
    create_context_attribs_fn create_context_attribs;
    make_current_fn make_current;
    get_proc_address_fn get_proc_address;
    destroy_context_fn destroy_context;
    char error[512];     /* why loading failed; empty once loaded */
} osmesa;
static pthread_once_t osmesa_once = PTHREAD_ONCE_INIT;

/* Adds text to the reasons in osmesa.error, separated by "; " and cut at its size. */
static void add_error(const char *text)
{
    size_t used = strlen(osmesa.error);
    snprintf(osmesa.error + used, sizeof osmesa.error - used, "%s%s", used ? "; " : "", text);
}

/* Looks name up in library into *function, a function pointer (the size of a void *, as POSIX has
 * it); false with dlerror's reason in osmesa.error. */
static bool find(void *library, const char *name, void *function)
{
    void *symbol = dlsym(library, name);
    if (!symbol) {
        add_error(dlerror());
        return false;
    }
    memcpy(function, &symbol, sizeof symbol);
    return true;
}

/* Opens the first of library_names that loads and finds its functions in it; otherwise leaves
 * dlerror's reasons (each name's, or the missing function's) in osmesa.error. Runs once. */
static void load(void)
{
    void *library = NULL;
    for (size_t i = 0; !library && i < sizeof library_names / sizeof *library_names; i++)
        if (!(library = dlopen(library_names[i], RTLD_NOW | RTLD_LOCAL)))
            add_error(dlerror());
    if (!library)
        return;
    osmesa.error[0] = '\0';
    if (!(find(library, "OSMesaCreateContextAttribs", &osmesa.create_context_attribs) &&
          find(library, "OSMesaMakeCurrent", &osmesa.make_current) &&
          find(library, "OSMesaGetProcAddress", &osmesa.get_proc_address) &&
          find(library, "OSMesaDestroyContext", &osmesa.destroy_context)))
        dlclose(library);
}

/* What the display draws over the image before read-back: a heat map's colour bar, or labels. */
struct overlay {
    const struct ao_glapi *gl;
    const struct ao_heatmap_scale *range;   /* the colour bar's, or NULL */
    const char *title;
    const struct ao_headless_label *labels;
    int count;
    bool failed;
};

static void draw_overlay(void *user, int width, int height)
{
    struct overlay *o = user;
    struct ao_hud *hud = ao_hud_create(o->gl);
    if (!hud) {
        o->failed = true;
        return;
    }
    if (o->range)
        ao_heatmap_draw_bar(hud, o->range, o->title, width - 8, 8, 1.0f, width, height);
    for (int k = 0; k < o->count; k++)
        ao_hud_draw(hud, o->labels[k].text, o->labels[k].x, o->labels[k].y, 1.0f, width, height);
    ao_hud_destroy(hud);
}

/* Writes rgb as ao_headless_write_png does, with overlay drawn over it unless overlay is NULL. */
static bool write_png(const char *path, const float *rgb, int width, int height, struct overlay *overlay)
{
    pthread_once(&osmesa_once, load);
    if (osmesa.error[0]) {
        fprintf(stderr, "aoview: %s: cannot load OSMesa (%s)\n", path, osmesa.error);
        return false;
    }

    /* An OpenGL 3.3 core context, like the window's, so the same shaders run. */
    static const int attribs[] = {
        OSMESA_FORMAT, OSMESA_RGBA,
        OSMESA_PROFILE, OSMESA_CORE_PROFILE,
        OSMESA_CONTEXT_MAJOR_VERSION, 3,
        OSMESA_CONTEXT_MINOR_VERSION, 3,
        0,
    };
    OSMesaContext context = osmesa.create_context_attribs(attribs, NULL);
    if (!context) {
        fprintf(stderr, "aoview: %s: no OpenGL 3.3 core context from OSMesa\n", path);
        return false;
    }

    /* The display draws into its own 1:1 offscreen framebuffer, exactly as the window's screenshot
     * does; OSMesa only needs some buffer to make the context current. */
    unsigned char buffer[4];
    bool ok = osmesa.make_current(context, buffer, GL_UNSIGNED_BYTE, 1, 1);
    if (!ok)
        fprintf(stderr, "aoview: %s: cannot make the OSMesa context current\n", path);

    struct ao_glapi gl;
    struct ao_display *display = NULL;
    ok = ok && ao_glapi_load(&gl, osmesa.get_proc_address) && (display = ao_display_create(&gl));
    if (overlay)
        overlay->gl = &gl;
    ok = ok && ao_display_upload(display, rgb, width, height) &&
         ao_display_write_png_with(display, path, overlay ? draw_overlay : NULL, overlay) &&
         !(overlay && overlay->failed);
    ao_display_destroy(display);
    osmesa.destroy_context(context);
    return ok;
}

bool ao_headless_write_png(const char *path, const float *rgb, int width, int height)
{
    return write_png(path, rgb, width, height, NULL);
}

bool ao_headless_write_heatmap(const char *path, const float *heat, int width, int height,
                               const struct ao_heatmap_scale *range, const char *title)
{
    struct overlay bar = {.range = range, .title = title};
    bool room = width >= AO_HEADLESS_BAR_WIDTH && height >= AO_HEADLESS_BAR_HEIGHT;
    return write_png(path, heat, width, height, room ? &bar : NULL);
}

bool ao_headless_write_labelled(const char *path, const float *rgb, int width, int height,
                                const struct ao_headless_label *labels, int count)
{
    struct overlay overlay = {.labels = labels, .count = count};
    return write_png(path, rgb, width, height, &overlay);
}
