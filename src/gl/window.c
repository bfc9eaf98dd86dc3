/* The interactive viewer (see window.h): the GLFW window and its GL context, the frames presented
 * when they change and the presentation's cost allows, and the loop that sleeps between events.
 * The keys and mouse are window_input.c's, the frames taken and saved window_frames.c's. */
#include "window.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "chart.h"
#include "compare.h"
#include "display.h"
#include "glapi.h"
#include "heatmap.h"
#include "hud.h"
#include "overlay.h"
#include "progress.h"
#include "window_viewer.h"
#include "x11.h"

/* glfwPostEmptyEvent is legal from any thread, but only between glfwInit and glfwTerminate. */
static pthread_mutex_t wake_lock = PTHREAD_MUTEX_INITIALIZER;
static bool glfw_running;

/* The status's clock (elapsed seconds, time left) changes the overlay and the title at most this
 * often between frames. */
#define CLOCK_SECONDS 0.5

/* While passes run and nobody navigates, each new frame is presented as it comes, one a display
 * frame at most (the monitor's refresh interval, 1/60 s where it is not known), and no sooner after
 * the last presentation than twice what a presentation of its kind costs (display.c measures it),
 * so that passes that come faster than the window can show them leave the GL thread at least half
 * its time; but never later than PRESENT_LATEST after the last one, so that a finished pass is on
 * screen within that (docs/views.md, "Frames"). */
#define PRESENT_SHARE 0.5
#define PRESENT_LATEST 0.1

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

/* ---- life cycle ---- */

/* The smallest window that keeps the overlay and the error chart readable. */
#define READABLE_WIDTH 640
#define READABLE_HEIGHT 480

/* The window size for a width x height image: magnified by the power of two (at most
 * MAX_PIXEL_SIZE) that brings it to READABLE_WIDTH x READABLE_HEIGHT when it is smaller (pixels
 * stay square blocks), and shrunk, keeping its aspect, to fit 90 % of the primary monitor's work
 * area when it is larger (said on stderr, unless quiet: the render follows the window's size);
 * returns the magnification. */
static int fit_screen(const struct viewer *v, int *width, int *height)
{
    int zoom = 1;
    while (*width * zoom < READABLE_WIDTH && *height * zoom < READABLE_HEIGHT && zoom < MAX_PIXEL_SIZE)
        zoom *= 2;
    *width *= zoom;
    *height *= zoom;
    GLFWmonitor *monitor = glfwGetPrimaryMonitor();
    int x, y, w = 0, h = 0;
    if (monitor)
        glfwGetMonitorWorkarea(monitor, &x, &y, &w, &h);
    double s = fmin(0.9 * w / *width, 0.9 * h / *height);
    if (s > 0 && s < 1) {
        int wanted_width = *width, wanted_height = *height;
        *width = (int)fmax(1, *width * s);
        *height = (int)fmax(1, *height * s);
        if (!v->info->quiet)
            fprintf(stderr, "aoview: a %dx%d window does not fit 90 %% of the %dx%d screen: it opens at %dx%d, "
                    "and the image follows its size\n", wanted_width, wanted_height, w, h, *width, *height);
    }
    return zoom;
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
                    "--headless renders without a window\n", ao_x11_display_name(), why);
            return AO_WINDOW_FAILED;
        }
        fprintf(stderr, "aoview: cannot open an OpenGL 3.3 window: %s\n", why ? why : "unknown error");
        return AO_WINDOW_NO_DISPLAY;
    }
    glfwSetWindowUserPointer(v->window, v);
    glfwMakeContextCurrent(v->window);
    glfwSwapInterval(1);
    GLFWmonitor *monitor = glfwGetPrimaryMonitor();
    const GLFWvidmode *mode = monitor ? glfwGetVideoMode(monitor) : NULL;
    v->refresh = 1.0 / (mode && mode->refreshRate > 0 ? mode->refreshRate : 60);
    if (!ao_glapi_load(&v->gl, glfwGetProcAddress) || !(v->display = ao_display_create(&v->gl)) ||
        !(v->hud = ao_hud_create(&v->gl)))
        return AO_WINDOW_FAILED;
    ao_viewer_listen(v);
    return AO_WINDOW_OK;
}

/* ---- presenting: what changed, whether it may be shown now, and showing it ---- */

/* True while passes run: the image and the status's clock change by themselves. */
static bool running(const struct viewer *v, const struct ao_settings *settings)
{
    if (v->compare)
        return ao_compare_running(v->compare);
    return !settings->paused && v->shown && !v->shown->info.done;
}

/* The status of the newest frame taken (the newest full one's facts under a kept preview); elapsed
 * time and time left run on between frames while passes run. */
static struct ao_hud_status status_of(const struct viewer *v, const struct ao_settings *settings)
{
    const struct ao_frame *f = v->shown;
    struct ao_hud_status s = {.scene = v->info->scene_name, .info = f->info, .width = f->image_width,
                              .height = f->image_height, .block = v->kept_block > 1 ? v->kept_block : f->block,
                              .reference_differs = !v->reference_fits, .spppp = settings->spppp,
                              .adaptive = settings->adaptive, .paused = settings->paused};
    s.seconds = s.info.seconds;
    s.seconds_left = ao_progress_left(&v->progress, &s.info);
    if (!s.paused && !s.info.done && s.info.pass > 0) {
        double since = glfwGetTime() - v->shown_at;
        s.seconds += since;
        s.seconds_left = isnan(s.seconds_left) ? NAN : fmax(0.0, s.seconds_left - since);
    }
    return s;
}

/* Draws the image, then the overlay (the status items, '\n' between them, or while comparing the
 * divider and the sides' labels) and the chart or the help, into the framebuffer look describes. */
static void draw(struct viewer *v, const struct look *look, const char *items)
{
    ao_display_draw(v->display, look->width, look->height);
    float content_scale;
    glfwGetWindowContentScale(v->window, &content_scale, NULL);
    struct ao_overlay o = {.width = look->width, .height = look->height,
                           .content_scale = content_scale > 0.0f ? content_scale : 1.0f, .hud = look->hud,
                           .help = look->help, .items = items, .compare = v->compare != NULL, .layout = v->layout,
                           .split = v->split, .chart = &v->chart};
    char labels[2][AO_COMPARE_LABEL];
    struct ao_chart both;
    if (v->compare) {
        ao_compare_labels(v->compare, "\n", labels);
        o.labels[0] = labels[0];
        o.labels[1] = labels[1];
        o.image = ao_display_fit(v->image_width, v->image_height, look->width, look->height);
        ao_compare_chart(v->compare, &both);
        o.chart = &both;
    }
    if (v->show != SHOW_IMAGE) {
        o.bar = v->show == SHOW_ERROR ? &ao_heatmap_error : &ao_heatmap_difference;
        o.bar_title = v->show == SHOW_ERROR ? "estimated error" : "|image - reference|";
        o.bar_unknown = v->show == SHOW_ERROR;
    }
    ao_overlay_draw(v->hud, &o);
}

/* Shows what changed: uploads the newest frame when image is set, makes the status (and the title
 * when it changed), draws, swaps and tells display.c, which measures what that cost; false when the
 * upload failed. */
static bool present(struct viewer *v, const struct ao_settings *settings, bool image)
{
    if (image && !ao_viewer_upload(v))
        return false;
    struct look look = {.hud = v->show_hud, .help = v->show_help};
    glfwGetFramebufferSize(v->window, &look.width, &look.height);
    char text[sizeof look.status] = "";
    if (v->compare) {
        ao_compare_status(v->compare, v->info->scene_name, " \xe2\x80\x94 ", look.status, sizeof look.status);
    } else {
        struct ao_hud_status s = status_of(v, settings);
        ao_hud_format(&s, " \xe2\x80\x94 ", "\xe2\x80\x94", look.status, sizeof look.status);
        ao_hud_format(&s, "\n", "--", text, sizeof text);
    }
    v->status_at = glfwGetTime();
    v->status_image = v->taken;
    if (strcmp(look.status, v->drawn.status) != 0) {
        char title[sizeof look.status + 16];
        snprintf(title, sizeof title, "aoview \xe2\x80\x94 %s", look.status);
        glfwSetWindowTitle(v->window, title);
    }
    draw(v, &look, text);
    glfwSwapBuffers(v->window);
    ao_display_presented(v->display);
    v->drawn = look;
    v->dirty = false;
    v->presented_at = glfwGetTime();
    return true;
}

/* Presents what changed since the last frame on screen: a new frame, a view change, the status
 * (its clock at most every CLOCK_SECONDS), the framebuffer's size, the overlay's or the help's
 * toggle, an expose. At once when the user acted, navigates or nothing renders, and for previews;
 * else a display frame after the last presentation, or later as its cost asks (PRESENT_SHARE), at
 * most PRESENT_LATEST after it. While navigating only new frames are shown. Returns the
 * glfwGetTime() when something waits to be shown, else a negative number; *ok false when an
 * upload failed. */
static double update(struct viewer *v, const struct ao_settings *settings, bool *ok)
{
    *ok = true;
    if (!(v->compare ? ao_compare_frame(v->compare, 0) && ao_compare_frame(v->compare, 1) : v->shown != NULL))
        return -1.0;
    double now = glfwGetTime();
    bool runs = running(v, settings);
    bool navigating = v->gestures.drag != AO_DRAG_NONE || now - v->navigated_at < NAVIGATION_SECONDS;
    bool image = v->reupload || (v->taken != v->uploaded && !ao_viewer_keeps_preview(v, settings));
    bool ticks = runs && !v->compare && v->shown->info.pass > 0;
    bool clock = v->taken != v->status_image || (ticks && now - v->status_at >= CLOCK_SECONDS);
    int width, height;
    glfwGetFramebufferSize(v->window, &width, &height);
    bool look = v->dirty || width != v->drawn.width || height != v->drawn.height || v->show_hud != v->drawn.hud ||
                v->show_help != v->drawn.help;
    if (!image && !look && clock && navigating) /* the status waits for the navigation's end */
        return v->gestures.drag != AO_DRAG_NONE ? -1.0 : v->navigated_at + NAVIGATION_SECONDS;
    if (!image && !look && !clock)
        return ticks ? v->status_at + CLOCK_SECONDS : -1.0;
    bool preview = !v->compare && v->shown->block > 1;
    double due = now;
    if (!look && !v->reupload && !navigating && runs && !(image && preview)) {
        struct ao_display_cost cost = ao_display_cost(v->display);
        double spacing = (image ? cost.new_image : cost.redraw) / PRESENT_SHARE;
        due = v->presented_at + fmax(v->refresh, fmin(spacing, PRESENT_LATEST));
    }
    if (now < due)
        return due;
    *ok = present(v, settings, image);
    return ticks ? v->status_at + CLOCK_SECONDS : -1.0;
}

/* Shows the window at the render's size, fitted to the screen, once the first frame is there; the
 * pixel size, unless --pixel-size set it, is the magnification of a small image times 2 on a HiDPI
 * screen (a content scale of 1.5 or more, as X's Xft.dpi of 144 or more gives, or framebuffer
 * pixels per window point of 2 or more). */
static bool show_first_frame(struct viewer *v)
{
    while (!(v->compare ? ao_compare_frame(v->compare, 0) && ao_compare_frame(v->compare, 1) : v->shown != NULL)) {
        glfwWaitEventsTimeout(0.1);   /* woken early by ao_window_notify */
        ao_viewer_take_frame(v);
    }
    struct ao_settings s;
    ao_viewer_get_settings(v, &s);
    int width = s.width, height = s.height, zoom = fit_screen(v, &width, &height);
    glfwSetWindowSize(v->window, width, height);
    glfwShowWindow(v->window);
    int points, pixels;
    float content_scale;
    glfwGetWindowSize(v->window, &points, NULL);
    glfwGetFramebufferSize(v->window, &pixels, NULL);
    glfwGetWindowContentScale(v->window, &content_scale, NULL);
    int hidpi = (points > 0 && pixels >= 2 * points) || content_scale >= 1.5f ? 2 : 1;
    v->pixel_size = v->info->pixel_size ? v->info->pixel_size : zoom * hidpi < MAX_PIXEL_SIZE ? zoom * hidpi
                                                                                             : MAX_PIXEL_SIZE;
    v->resized_at = -1.0;
    s.previews = true;
    ao_viewer_set_settings(v, &s);
    return true;
}

/* Handles input and presents what changed (update), and sleeps in glfwWaitEvents until an event, a
 * new frame (ao_window_notify) or what waits to be shown is due, until the window is closed. */
static enum ao_window_result loop(struct viewer *v)
{
    if (!show_first_frame(v))
        return AO_WINDOW_FAILED;
    while (!glfwWindowShouldClose(v->window)) {
        if (v->toggle_compare)
            ao_viewer_toggle_compare(v);
        v->toggle_compare = false;
        ao_viewer_apply_mouse(v);
        double resize_due = ao_viewer_follow_size(v), navigation_due = ao_viewer_end_navigation(v);
        ao_viewer_take_frame(v);
        struct ao_settings s;
        ao_viewer_get_settings(v, &s);
        /* S saves a full frame (during previews it waits for the first), the very one the texture
         * then holds: a frame not shown yet, or kept from view by a preview, is uploaded first. */
        const struct ao_frame *f = ao_viewer_frame(v);
        if (v->save && f && f->block == 1) {
            if (v->uploaded != v->taken && !ao_viewer_upload(v))
                return AO_WINDOW_FAILED;
            ao_viewer_save(v);
            v->save = false;
        }
        bool ok;
        double due = update(v, &s, &ok);
        if (!ok)
            return AO_WINDOW_FAILED;
        double wait = due >= 0.0 ? fmax(0.0, due - glfwGetTime()) : -1.0;
        if (resize_due >= 0.0)
            wait = wait >= 0.0 ? fmin(wait, resize_due) : resize_due;
        if (navigation_due >= 0.0)
            wait = wait >= 0.0 ? fmin(wait, navigation_due) : navigation_due;
        if (wait < 0.0)
            glfwWaitEvents();
        else if (wait > 0.0)
            glfwWaitEventsTimeout(wait);
        else
            glfwPollEvents();
    }
    return AO_WINDOW_OK;
}

enum ao_window_result ao_window_run(struct ao_render *render, const struct ao_window_info *info)
{
    ao_x11_catch_lost_display();
    if (!glfwInit()) {
        /* With a display named, say why it could not be used before main falls back to headless. */
        const char *why = NULL, *display = getenv("DISPLAY");
        glfwGetError(&why);
        if (display && display[0])
            fprintf(stderr, "aoview: cannot use the X display %s: %s\n", display, why ? why : "unknown error");
        ao_x11_restore();
        return AO_WINDOW_NO_DISPLAY;
    }
    set_glfw_running(true);
    struct viewer v = {.render = render, .info = info, .show_hud = true, .gestures = {.drag = AO_DRAG_NONE},
                       .split = 0.5, .pixel_size = 1,
                       .reference_fits = true,
                       .show = info->difference && info->reference ? SHOW_DIFFERENCE : SHOW_IMAGE};
    enum ao_window_result result = open_window(&v);
    if (result == AO_WINDOW_OK && info->resume) {
        struct ao_settings s;
        ao_render_get_settings(render, &s);
        s.paused = false;
        s.previews = true;
        ao_render_set_settings(render, &s);
    }
    /* --compare: main made the renderer paused; the comparison starts unpaused. */
    if (result == AO_WINDOW_OK && info->compare && !ao_viewer_start_compare(&v, false))
        result = AO_WINDOW_FAILED;
    if (result == AO_WINDOW_OK)
        result = loop(&v);
    if (result != AO_WINDOW_NO_DISPLAY) /* (main goes on headless with it) */
        ao_render_stop(render);   /* its threads stop at once, leaving the cores to the end below */
    ao_compare_destroy(v.compare);
    ao_hud_destroy(v.hud);
    ao_display_destroy(v.display);
    free(v.heat[0]);
    free(v.heat[1]);
    free(v.composite);
    set_glfw_running(false);
    glfwTerminate();
    ao_x11_restore();
    return result;
}
