/* Screenshots without a display server (see headless.h): libOSMesa opened at the first PNG, a
 * core-profile context made, the display code drawing into it, the pixels read back and written;
 * the room such a context needs checked first under a limit on the address space. */
#include "headless.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "display.h"
#include "glapi.h"
#include "hud.h"
#include "text.h"

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
    atomic_bool tried;   /* load ran: the library is mapped, or will not be */
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
    atomic_store(&osmesa.tried, true);
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

/* The address space that drawing one PNG through OSMesa takes beyond what aoview holds, measured
 * with Mesa 22.3's llvmpipe (VmPeak over the write, 64x48 to 7680x4320, 0 to 16 llvmpipe
 * threads): loading libOSMesa and LLVM 181 MB; a context and its draw about 140 MB; each
 * llvmpipe thread 144 MB (its stack and malloc arena); the texture, framebuffer and read-back
 * 16-21 bytes a pixel. Rounded up here, so that a limit leaving less is refused in one line:
 * Mesa does not check all its allocations, and under `ulimit -v` a 4K PNG crashed inside
 * OSMesaCreateContextAttribs. */
static const double LOAD_MB = 192, CONTEXT_MB = 160, THREAD_MB = 150, PIXEL_BYTES = 24;
/* llvmpipe's most threads (LP_MAX_THREADS is 16 in Mesa 22, 32 in later ones). */
enum { MOST_LLVMPIPE_THREADS = 32 };

/* The threads llvmpipe will start: LP_NUM_THREADS, else one a core. */
static long llvmpipe_threads(void)
{
    const char *set = getenv("LP_NUM_THREADS");
    long threads = set && *set ? strtol(set, NULL, 10) : sysconf(_SC_NPROCESSORS_ONLN);
    return threads < 0 ? 0 : threads > MOST_LLVMPIPE_THREADS ? MOST_LLVMPIPE_THREADS : threads;
}

/* Under a limit on the address space (ulimit -v), whether what drawing a width x height PNG takes
 * is left of it, tried by allocating that much (untouched, so it costs no memory) and freeing it;
 * false after one line. Without a limit, true: address space is not what runs out first. */
static bool room_to_draw(const char *name, int width, int height)
{
    struct rlimit limit;
    if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY)
        return true;
    double mb = (atomic_load(&osmesa.tried) ? 0.0 : LOAD_MB) + CONTEXT_MB + THREAD_MB * (double)llvmpipe_threads() +
                PIXEL_BYTES * (double)width * (double)height / (1 << 20);
    void *room = (double)SIZE_MAX / (1 << 20) > mb ? malloc((size_t)(mb * (1 << 20))) : NULL;
    free(room);
    if (room)
        return true;
    fprintf(stderr, "aoview: %s: drawing a %dx%d PNG through OSMesa takes about %.0f MB of address space more "
                    "than the limit leaves (ulimit -v %llu)\n", name, width, height, mb,
            (unsigned long long)(limit.rlim_cur / 1024));
    return false;
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
        ao_heatmap_draw_bar(hud, o->range, o->title, false, width - 8, 8, 1.0f, width, height);
    for (int k = 0; k < o->count; k++)
        ao_hud_draw(hud, o->labels[k].text, o->labels[k].x, o->labels[k].y, 1.0f, width, height);
    ao_hud_destroy(hud);
}

/* Writes rgb as ao_headless_write_png does, with overlay drawn over it unless overlay is NULL. */
static bool write_png(const char *path, const float *rgb, int width, int height, struct overlay *overlay)
{
    char name[AO_TEXT_SIZE];
    ao_text_escape(path, name, sizeof name);
    if (!room_to_draw(name, width, height))
        return false;
    pthread_once(&osmesa_once, load);
    if (osmesa.error[0]) {
        fprintf(stderr, "aoview: %s: cannot load OSMesa (%s)\n", name, osmesa.error);
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
        fprintf(stderr, "aoview: %s: no OpenGL 3.3 core context from OSMesa\n", name);
        return false;
    }

    /* The display draws into its own 1:1 offscreen framebuffer, exactly as the window's screenshot
     * does; OSMesa only needs some buffer to make the context current. */
    unsigned char buffer[4];
    bool ok = osmesa.make_current(context, buffer, GL_UNSIGNED_BYTE, 1, 1);
    if (!ok)
        fprintf(stderr, "aoview: %s: cannot make the OSMesa context current\n", name);

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

bool ao_headless_check_room(const char *path, int width, int height)
{
    char name[AO_TEXT_SIZE];
    return room_to_draw(ao_text_escape(path, name, sizeof name), width, height);
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
