#include "window.h"

#include <ctype.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <X11/Xlib.h>   /* the IO error handler: GLFW 3.3 leaves Xlib's in place */

#include "chart.h"
#include "chartview.h"
#include "display.h"
#include "glapi.h"
#include "heatmap.h"
#include "hud.h"
#include "image.h"
#include "notes.h"
#include "progress.h"

/* glfwPostEmptyEvent is legal from any thread, but only between glfwInit and glfwTerminate. */
static pthread_mutex_t wake_lock = PTHREAD_MUTEX_INITIALIZER;
static bool glfw_running;

static const char HELP[] =
    "U  uniform sphere sampling\n"
    "H  uniform hemisphere sampling\n"
    "C  cosine sampling\n"
    "A  anti-aliasing on/off\n"
    "Space  pause/resume\n"
    "R  restart accumulation\n"
    "+ -  double/halve samples per pass (leaves auto)\n"
    "G  adaptive sampling on/off\n"
    "E  estimated error map on/off\n"
    "D  difference from --reference on/off\n"
    "N  normals view on/off (restarts)\n"
    "F  flat/Phong mesh normals (restarts)\n"
    "S  save aoview-N.png and aoview-N.pfm (or .exr)\n"
    "left drag  orbit\n"
    "right drag  pan\n"
    "wheel  zoom\n"
    "F1 or ?  this help\n"
    "F2  hide/show the overlay and error chart\n"
    "Esc or Q  quit";

/* The redraw rate while the image changes; idle at the target spp. */
#define FRAME_SECONDS (1.0 / 60.0)

/* What the window shows of the frame: the image, or a heat map of its estimated error or of its
 * difference from the reference (display modes: the image accumulates on underneath). */
enum show {
    SHOW_IMAGE,
    SHOW_ERROR,
    SHOW_DIFFERENCE,
};

/* What the window shows: it is redrawn when this changes. */
struct look {
    int width, height;               /* framebuffer pixels */
    bool hud, help;
    char status[512];                /* ao_hud_format's text, as in the title */
};

struct viewer {
    struct ao_render *render;
    const struct ao_window_info *info;
    GLFWwindow *window;
    struct ao_glapi gl;
    struct ao_display *display;
    struct ao_hud *hud;
    const struct ao_frame *shown;    /* on screen; valid until the next ao_render_take_frame */
    double shown_at;                 /* glfwGetTime() when it was taken */
    bool show_hud, show_help, save;
    enum show show;
    float *heat;                     /* the heat map's colours, allocated on first use */
    struct ao_progress progress;     /* the time-left estimate, fed the frames taken */
    int drag;                        /* mouse button held over the window, or -1 */
    double cursor_x, cursor_y;
    double orbit_x, orbit_y, pan_x, pan_y, wheel;   /* mouse input not yet applied */
    struct ao_chart chart;           /* RMSE against time of the frames taken (with --reference) */
    struct look drawn;               /* as last drawn */
    bool dirty;                      /* redraw even if the look is the same: new frame, expose */
    bool reupload;                   /* upload the frame on screen again: the view changed */
};

void ao_window_notify(void)
{
    pthread_mutex_lock(&wake_lock);
    if (glfw_running)
        glfwPostEmptyEvent();
    pthread_mutex_unlock(&wake_lock);
}

static void set_glfw_running(bool running)
{
    pthread_mutex_lock(&wake_lock);
    glfw_running = running;
    pthread_mutex_unlock(&wake_lock);
}

/* ---- input: callbacks change settings at once; mouse moves and screenshots wait for the loop ---- */

/* Doubles (factor 2) or halves (factor 0) the samples per pass within 1..65536; from auto (0),
 * those of the pass on screen, so that the keys switch to manual where auto stood. */
static int scale_spppp(const struct viewer *v, int spppp, int factor)
{
    if (spppp == 0)
        spppp = v->shown && v->shown->info.spppp ? (int)v->shown->info.spppp : 1;
    long next = factor ? 2L * spppp : spppp / 2;
    return next < 1 ? 1 : next > 65536 ? 65536 : (int)next;
}

/* Printable keys, by character so that they follow the keyboard layout ('+' from either the main
 * keyboard or the keypad, '=' as the unshifted '+'). */
static void on_char(GLFWwindow *window, unsigned int codepoint)
{
    struct viewer *v = glfwGetWindowUserPointer(window);
    if (codepoint > 127)
        return;
    struct ao_settings s;
    ao_render_get_settings(v->render, &s);
    switch (tolower((int)codepoint)) {
    case 'u': s.sampling = AO_SAMPLING_UNIFORM; break;
    case 'h': s.sampling = AO_SAMPLING_HEMISPHERE; break;
    case 'c': s.sampling = AO_SAMPLING_COSINE; break;
    case 'a': s.aa = !s.aa; break;
    case ' ': s.paused = !s.paused; break;
    case '+': case '=': s.spppp = scale_spppp(v, s.spppp, 2); break;
    case '-': s.spppp = scale_spppp(v, s.spppp, 0); break;
    case 'g': s.adaptive = !s.adaptive; break;
    case 'n': s.output = s.output == AO_OUTPUT_NORMALS ? AO_OUTPUT_AO : AO_OUTPUT_NORMALS; break;
    case 'f': s.shading = s.shading == AO_SHADING_FLAT ? AO_SHADING_PHONG : AO_SHADING_FLAT; break;
    case 'e': v->show = v->show == SHOW_ERROR ? SHOW_IMAGE : SHOW_ERROR; v->reupload = true; return;
    case 'd':
        if (!v->info->reference) {
            if (!v->info->quiet) {
                printf("aoview: D shows the difference from --reference; none was given\n");
                fflush(stdout);
            }
            return;
        }
        v->show = v->show == SHOW_DIFFERENCE ? SHOW_IMAGE : SHOW_DIFFERENCE;
        v->reupload = true;
        return;
    case 'r': ao_render_restart(v->render); return;
    case 's': v->save = true; return;
    case '?': v->show_help = !v->show_help; return;
    case 'q': glfwSetWindowShouldClose(window, GLFW_TRUE); return;
    default: return;
    }
    ao_render_set_settings(v->render, &s);
}

/* Keys without a character. */
static void on_key(GLFWwindow *window, int key, int scancode, int action, int mods)
{
    (void)scancode;
    (void)mods;
    struct viewer *v = glfwGetWindowUserPointer(window);
    if (action != GLFW_PRESS)
        return;
    if (key == GLFW_KEY_ESCAPE)
        glfwSetWindowShouldClose(window, GLFW_TRUE);
    else if (key == GLFW_KEY_F1)
        v->show_help = !v->show_help;
    else if (key == GLFW_KEY_F2)
        v->show_hud = !v->show_hud;
}

static void on_button(GLFWwindow *window, int button, int action, int mods)
{
    (void)mods;
    struct viewer *v = glfwGetWindowUserPointer(window);
    if (action == GLFW_PRESS && v->drag < 0 &&
        (button == GLFW_MOUSE_BUTTON_LEFT || button == GLFW_MOUSE_BUTTON_RIGHT)) {
        v->drag = button;
        glfwGetCursorPos(window, &v->cursor_x, &v->cursor_y);
    } else if (action == GLFW_RELEASE && button == v->drag) {
        v->drag = -1;
    }
}

static void on_cursor(GLFWwindow *window, double x, double y)
{
    struct viewer *v = glfwGetWindowUserPointer(window);
    if (v->drag < 0)
        return;
    double *dx = v->drag == GLFW_MOUSE_BUTTON_LEFT ? &v->orbit_x : &v->pan_x;
    double *dy = v->drag == GLFW_MOUSE_BUTTON_LEFT ? &v->orbit_y : &v->pan_y;
    *dx += x - v->cursor_x;
    *dy += y - v->cursor_y;
    v->cursor_x = x;
    v->cursor_y = y;
}

/* X lost the window's contents (exposed, or shown for the first time). */
static void on_refresh(GLFWwindow *window)
{
    struct viewer *v = glfwGetWindowUserPointer(window);
    v->dirty = true;
}

static void on_scroll(GLFWwindow *window, double dx, double dy)
{
    (void)dx;
    struct viewer *v = glfwGetWindowUserPointer(window);
    v->wheel += dy;
}

/* Applies the mouse moves gathered since the last frame as one camera change (one restart):
 * a drag across the image's height orbits half a turn or pans the image along with the cursor,
 * a wheel step up zooms in by 15 %. */
static void apply_mouse(struct viewer *v)
{
    if (v->orbit_x == 0 && v->orbit_y == 0 && v->pan_x == 0 && v->pan_y == 0 && v->wheel == 0)
        return;
    int width, height;
    glfwGetWindowSize(v->window, &width, &height);
    struct ao_display_rect image = ao_display_fit(v->shown->width, v->shown->height, width, height);
    double size = image.height > 0 ? image.height : 1;
    struct ao_settings s;
    ao_render_get_settings(v->render, &s);
    const double pi = 3.14159265358979323846;
    ao_camera_orbit(&s.camera, (float)(pi * v->orbit_x / size), (float)(pi * v->orbit_y / size));
    ao_camera_pan(&s.camera, (float)(v->pan_x / size), (float)(v->pan_y / size));
    ao_camera_zoom(&s.camera, (float)pow(0.85, v->wheel));
    ao_render_set_settings(v->render, &s);
    v->orbit_x = v->orbit_y = v->pan_x = v->pan_y = v->wheel = 0;
}

/* ---- output ---- */

/* Saves the frame on screen as aoview-N.png (through the display shader at 1:1, without the
 * overlay) and aoview-N.pfm or .exr (linear) in the working directory, N the first free number. */
static void save(struct viewer *v)
{
    char png[32], linear[32];
    for (int n = 1;; n++) {
        snprintf(png, sizeof png, "aoview-%d.png", n);
        snprintf(linear, sizeof linear, "aoview-%d.%s", n, v->info->save_exr ? "exr" : "pfm");
        if (access(png, F_OK) != 0 && access(linear, F_OK) != 0)
            break;
    }
    const struct ao_frame *f = v->shown;
    struct ao_notes notes;
    ao_notes_make(&notes, &f->info, v->info->scene_name, v->info->seed);
    if (ao_display_write_png(v->display, png) &&
        ao_image_write_linear(linear, f->rgb, f->width, f->height, notes.notes, notes.count) &&
        !v->info->quiet) {
        printf("aoview: saved %s and %s (%u spp)\n", png, linear, f->info.spp);
        fflush(stdout);
    }
}

/* The status of the frame on screen; elapsed time runs on between frames while passes run. */
static struct ao_hud_status status(const struct viewer *v, const struct ao_settings *settings)
{
    struct ao_hud_status s = {.scene = v->info->scene_name, .info = v->shown->info,
                              .spppp = settings->spppp, .adaptive = settings->adaptive,
                              .paused = settings->paused};
    s.seconds = s.info.seconds;
    s.seconds_left = ao_progress_left(&v->progress, &s.info);
    if (!s.paused && !s.info.done) {
        double since = glfwGetTime() - v->shown_at;
        s.seconds += since;
        s.seconds_left = isnan(s.seconds_left) ? NAN : fmax(0.0, s.seconds_left - since);
    }
    return s;
}

/* The error chart's panel in the bottom right corner, in font pixels at its text scale. */
#define CHART_WIDTH 200
#define CHART_HEIGHT 130

/* Draws the error chart, when there is one, in the bottom right corner: its text at twice the
 * content scale where the panel then fits into a quarter of the window, else at the content scale
 * with the panel at most half the window wide and tall. */
static void draw_chart(struct viewer *v, const struct look *look, float content_scale)
{
    float scale = content_scale;
    if (2 * CHART_WIDTH * scale <= 0.5f * (float)look->width && 2 * CHART_HEIGHT * scale <= 0.5f * (float)look->height)
        scale *= 2;
    int margin = (int)(8 * content_scale);
    int width = (int)fminf(CHART_WIDTH * scale, 0.5f * (float)look->width);
    int height = (int)fminf(CHART_HEIGHT * scale, 0.5f * (float)look->height);
    ao_chartview_draw(v->hud, &v->chart, look->width - margin - width, look->height - margin - height,
                      width, height, scale, look->width, look->height);
}

/* Draws the image, then the overlay and the chart or the help, into the framebuffer look
 * describes. */
static void draw(struct viewer *v, const struct look *look, const struct ao_hud_status *s)
{
    ao_display_draw(v->display, look->width, look->height);
    float content_scale;
    glfwGetWindowContentScale(v->window, &content_scale, NULL);
    float scale = content_scale * (look->height >= 360 ? 2.0f : 1.0f);
    if (look->help) {
        int w, h;
        ao_hud_measure(v->hud, HELP, scale, &w, &h);
        w += (int)(2 * AO_HUD_PADDING * scale);
        h += (int)(2 * AO_HUD_PADDING * scale);
        ao_hud_draw(v->hud, HELP, (look->width - w) / 2, (look->height - h) / 2, scale, look->width,
                    look->height);
    } else if (look->hud) {
        char text[sizeof look->status];
        ao_hud_format(s, "\n", text, sizeof text);
        ao_hud_draw(v->hud, text, (int)(8 * scale), (int)(8 * scale), scale, look->width, look->height);
        if (v->show != SHOW_IMAGE)
            ao_heatmap_draw_bar(v->hud, v->show == SHOW_ERROR ? &ao_heatmap_error : &ao_heatmap_difference,
                                v->show == SHOW_ERROR ? "estimated error" : "|image - reference|",
                                look->width - (int)(8 * scale), (int)(8 * scale), scale, look->width, look->height);
        draw_chart(v, look, content_scale);
    }
}

/* Sets the title when the status changed, and redraws when what the window shows changed (or X
 * asked for it), so that drawing costs nothing while nothing changes. */
static void update(struct viewer *v, const struct ao_settings *settings)
{
    struct ao_hud_status s = status(v, settings);
    struct look look = {.hud = v->show_hud, .help = v->show_help};
    glfwGetFramebufferSize(v->window, &look.width, &look.height);
    ao_hud_format(&s, " \xe2\x80\x94 ", look.status, sizeof look.status);

    const struct look *old = &v->drawn;
    bool same_status = strcmp(look.status, old->status) == 0;
    if (!same_status) {
        char title[sizeof look.status + 16];
        snprintf(title, sizeof title, "aoview \xe2\x80\x94 %s", look.status);
        glfwSetWindowTitle(v->window, title);
    }
    if (v->dirty || !same_status || look.width != old->width || look.height != old->height ||
        look.hud != old->hud || look.help != old->help) {
        draw(v, &look, &s);
        glfwSwapBuffers(v->window);
        v->drawn = look;
        v->dirty = false;
    }
}

/* ---- life cycle ---- */

/* Xlib's handler for a broken connection (the X server died or went away), on whichever thread's
 * Xlib call noticed it (the GL thread's, or the render thread's glfwPostEmptyEvent): one line, and
 * exit status 1 at once. This is the one exit outside main.c, because no way back is sound: after
 * the handler returns Xlib calls exit(1) itself, from under the running threads, after printing
 * its own message; and an exit handler (XSetIOErrorExitHandler) that returns resumes the Xlib
 * call with the display's lock released twice (libX11 1.8 _XIOError; ThreadSanitizer reports it),
 * while GLFW 3.3's glfwWaitEvents spins for ever on the dead connection. Nothing is lost: stats
 * rows are flushed per pass, screenshots are renamed into place whole. */
static int on_io_error(Display *display)
{
    static atomic_flag reported = ATOMIC_FLAG_INIT;
    if (atomic_flag_test_and_set(&reported))
        for (;;)
            pause();   /* another thread is exiting */
    fprintf(stderr, "aoview: lost the connection to the X display %s\n", DisplayString(display));
    _exit(1);
}

/* The smallest window that keeps the overlay and the error chart readable. */
#define READABLE_WIDTH 640
#define READABLE_HEIGHT 480

/* The window size for a width x height image: magnified by the whole factor that brings it to
 * READABLE_WIDTH x READABLE_HEIGHT when it is smaller (pixels stay square blocks), and shrunk,
 * keeping its aspect, to fit 90 % of the primary monitor's work area when it is larger. */
static void fit_screen(int *width, int *height)
{
    int zoom = 1;
    while (*width * zoom < READABLE_WIDTH && *height * zoom < READABLE_HEIGHT)
        zoom++;
    *width *= zoom;
    *height *= zoom;
    GLFWmonitor *monitor = glfwGetPrimaryMonitor();
    int x, y, w = 0, h = 0;
    if (monitor)
        glfwGetMonitorWorkarea(monitor, &x, &y, &w, &h);
    double s = fmin(0.9 * w / *width, 0.9 * h / *height);
    if (s > 0 && s < 1) {
        *width = (int)fmax(1, *width * s);
        *height = (int)fmax(1, *height * s);
    }
}

/* Creates the window, hidden until the first frame gives its size, with an OpenGL 3.3 core
 * context current and the GL objects made; NO_DISPLAY or FAILED after one message. */
static enum ao_window_result open_window(struct viewer *v)
{
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
    v->window = glfwCreateWindow(640, 480, "aoview", NULL, NULL);
    if (!v->window) {
        /* A display whose OpenGL is too old fails (the user asked for a window, and can ask for
         * --headless); one without OpenGL at all is treated as no display. */
        const char *why = NULL;
        if (glfwGetError(&why) == GLFW_VERSION_UNAVAILABLE) {
            fprintf(stderr, "aoview: the X display %s offers no OpenGL 3.3 core context (%s); "
                    "--headless renders without a window\n", XDisplayName(NULL), why);
            return AO_WINDOW_FAILED;
        }
        fprintf(stderr, "aoview: cannot open an OpenGL 3.3 window: %s\n", why ? why : "unknown error");
        return AO_WINDOW_NO_DISPLAY;
    }
    glfwSetWindowUserPointer(v->window, v);
    glfwMakeContextCurrent(v->window);
    glfwSwapInterval(1);
    if (!ao_glapi_load(&v->gl, glfwGetProcAddress) || !(v->display = ao_display_create(&v->gl)) ||
        !(v->hud = ao_hud_create(&v->gl)))
        return AO_WINDOW_FAILED;
    glfwSetCharCallback(v->window, on_char);
    glfwSetKeyCallback(v->window, on_key);
    glfwSetMouseButtonCallback(v->window, on_button);
    glfwSetCursorPosCallback(v->window, on_cursor);
    glfwSetScrollCallback(v->window, on_scroll);
    glfwSetWindowRefreshCallback(v->window, on_refresh);
    return AO_WINDOW_OK;
}

/* Uploads the frame on screen as the view shows it: the image, its error map or its difference
 * from the reference; false when the upload failed. */
static bool upload(struct viewer *v)
{
    const struct ao_frame *f = v->shown;
    v->dirty = true;
    if (v->show == SHOW_IMAGE)
        return ao_display_upload(v->display, f->rgb, f->width, f->height);
    if (!v->heat && !(v->heat = malloc(3 * sizeof *v->heat * (size_t)f->width * (size_t)f->height))) {
        fprintf(stderr, "aoview: out of memory for the heat map\n");
        return false;
    }
    if (v->show == SHOW_ERROR)
        ao_heatmap_tiles(f, v->heat);
    else
        ao_heatmap_pixels(f->rgb, v->info->reference, f->width, f->height, v->heat);
    return ao_display_upload(v->display, v->heat, f->width, f->height);
}

/* Takes the newest frame, if one is new, into the texture; false when the upload failed. */
static bool take_frame(struct viewer *v)
{
    const struct ao_frame *f = ao_render_take_frame(v->render);
    if (!f) {
        if (!v->shown || !v->reupload)
            return true;
        v->reupload = false;
        return upload(v);
    }
    v->shown = f;
    v->shown_at = glfwGetTime();
    v->reupload = false;
    ao_chart_add(&v->chart, &f->info);
    ao_progress_add(&v->progress, &f->info);
    return upload(v);
}

/* Shows the window at the first frame's size (fitted to the screen) once the renderer has one. */
static bool show_first_frame(struct viewer *v)
{
    while (!v->shown) {
        glfwWaitEventsTimeout(0.1);   /* woken early by ao_window_notify */
        if (!take_frame(v))
            return false;
    }
    int width = v->shown->width, height = v->shown->height;
    fit_screen(&width, &height);
    glfwSetWindowSize(v->window, width, height);
    glfwShowWindow(v->window);
    return true;
}

/* Handles input and redraws what changed at up to 60 frames/s while passes run, and sleeps in
 * glfwWaitEvents once the image is done or paused, until the window is closed. */
static enum ao_window_result loop(struct viewer *v)
{
    if (!show_first_frame(v))
        return AO_WINDOW_FAILED;
    while (!glfwWindowShouldClose(v->window)) {
        /* Input first: the screenshot needs the frame on screen, which taking a new one ends. */
        apply_mouse(v);
        if (v->save)
            save(v);
        v->save = false;
        if (!take_frame(v))
            return AO_WINDOW_FAILED;

        struct ao_settings s;
        ao_render_get_settings(v->render, &s);
        double started = glfwGetTime();
        update(v, &s);

        /* Sleep until something happens once the image stops changing; then, and while passes
         * run, handle events until the next frame is due (vsync may have used the time up). */
        if (s.paused || v->shown->info.done)
            glfwWaitEvents();
        for (double rest; (rest = started + FRAME_SECONDS - glfwGetTime()) > 0 &&
                          !glfwWindowShouldClose(v->window);)
            glfwWaitEventsTimeout(rest);
        glfwPollEvents();
    }
    return AO_WINDOW_OK;
}

enum ao_window_result ao_window_run(struct ao_render *render, const struct ao_window_info *info)
{
    XIOErrorHandler xlib_handler = XSetIOErrorHandler(on_io_error);
    if (!glfwInit()) {
        XSetIOErrorHandler(xlib_handler);
        return AO_WINDOW_NO_DISPLAY;
    }
    set_glfw_running(true);
    struct viewer v = {.render = render, .info = info, .show_hud = true, .drag = -1,
                       .show = info->difference && info->reference ? SHOW_DIFFERENCE : SHOW_IMAGE};
    enum ao_window_result result = open_window(&v);
    if (result == AO_WINDOW_OK)
        result = loop(&v);
    ao_hud_destroy(v.hud);
    ao_display_destroy(v.display);
    free(v.heat);
    set_glfw_running(false);
    glfwTerminate();
    XSetIOErrorHandler(xlib_handler);
    return result;
}
