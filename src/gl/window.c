/* The interactive viewer (see window.h): the GLFW window and its GL context, the keys and mouse,
 * the frames taken from the renderer (or the comparison) and presented when they change and the
 * presentation's cost allows, resizes, screenshots, and the loop that sleeps between events. */
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

#include "buffer.h"
#include "chart.h"
#include "compare.h"
#include "display.h"
#include "gestures.h"
#include "glapi.h"
#include "heatmap.h"
#include "hud.h"
#include "keys.h"
#include "overlay.h"
#include "progress.h"
#include "screenshot.h"
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

/* A camera change from the mouse makes the window present every new frame at once, and nothing
 * else, for this long (and while a button is held); for as long, the renderer traces no fine
 * preview that the next move would abort (struct ao_settings' navigating). */
#define NAVIGATION_SECONDS 0.3

/* The finest preview of a run stays on screen until the run's average has this many samples per
 * pixel (mean): from then on the average's RMSE against a converged image, taken at every pixel of
 * the screen as the eye sees them, is below the preview's (the bunny at 1920x1080 and 3840x2160:
 * from 11 spp; tests/bench/bench_preview.c, docs/performance.md). */
#define PREVIEW_UNTIL_SPP 11.0

/* A resize restarts the render at the new size once the framebuffer has kept its size this long;
 * meanwhile the last frame is scaled. */
#define RESIZE_SECONDS 0.15

/* The largest pixel size ([ and ] stay within 1 to this). */
#define MAX_PIXEL_SIZE 8

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
    struct ao_render *render;        /* the single view's; paused while comparing */
    const struct ao_window_info *info;
    GLFWwindow *window;
    struct ao_glapi gl;
    struct ao_display *display;
    struct ao_hud *hud;
    const struct ao_frame *shown;    /* the newest frame taken; valid until the next
                                        ao_render_take_frame */
    double shown_at;                 /* glfwGetTime() when it was taken */
    uint64_t taken;                  /* frames taken (while comparing: either side's new ones),
                                        counting up: the newest frame's generation */
    uint64_t uploaded;               /* the generation the texture shows */
    int kept_block;                  /* > 1: the texture holds a preview of block x block cells of
                                        run kept_run, which stays until the run's average is as
                                        good (PREVIEW_UNTIL_SPP) */
    uint64_t kept_run;
    char status[512];                /* the status as last made (ao_hud_format, the title's) */
    double status_at;                /* glfwGetTime() when it was made */
    uint64_t status_image;           /* the frame taken it was made for */
    double presented_at;             /* glfwGetTime() when the last frame was on screen */
    double refresh;                  /* the monitor's refresh interval, in seconds */
    double navigated_at;             /* glfwGetTime() of the last camera change from the mouse */
    bool show_hud, show_help, save;
    enum show show;
    float *heat[2];                  /* the heat maps' colours (one per side), grown on use */
    size_t heat_room[2], composite_room;   /* their floats, and the composite's */
    struct ao_compare *compare;      /* the comparison while V has it on, else NULL */
    bool toggle_compare;             /* V was pressed: the loop turns the comparison on or off */
    enum ao_compare_layout layout;
    double split;                    /* the divider, as a share of the image's width */
    float *composite;                /* the comparison's two views as the layout shows them */
    int image_width, image_height;   /* of the image uploaded; 0 before the first */
    const float *view;               /* the linear image on screen (a frame's, a heat map or the
                                        composite), image_width x image_height, while its frames are
                                        held; NULL for a preview's cells */
    int pixel_size;                  /* framebuffer pixels per image pixel, each way */
    double resized_at;               /* glfwGetTime() of the last framebuffer size change; a
                                        negative value: apply the size at once */
    bool reference_fits;             /* the frame on screen has the reference's size (else no RMSE
                                        or difference view: said once on stderr) */
    struct ao_progress progress;     /* the time-left estimate, fed the frames taken */
    struct ao_gestures gestures;     /* the mouse's drag and the moves not applied yet */
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

/* The settings of what is on screen: the comparison's while there is one, else the renderer's. */
static void get_settings(const struct viewer *v, struct ao_settings *s)
{
    if (v->compare)
        ao_compare_get_settings(v->compare, s);
    else
        ao_render_get_settings(v->render, s);
}

static void set_settings(const struct viewer *v, const struct ao_settings *s)
{
    if (v->compare)
        ao_compare_set_settings(v->compare, s);
    else
        ao_render_set_settings(v->render, s);
}

/* The frame whose facts the status and screenshots give: side A's while comparing. */
static const struct ao_frame *current_frame(const struct viewer *v)
{
    return v->compare ? ao_compare_frame(v->compare, 0) : v->shown;
}

/* Where the image lies in the window, in window coordinates (origin at the bottom left). */
static struct ao_display_rect image_in_window(const struct viewer *v)
{
    int width, height;
    glfwGetWindowSize(v->window, &width, &height);
    return ao_display_fit(v->image_width ? v->image_width : 1, v->image_height ? v->image_height : 1, width, height);
}

/* Printable keys (keys.h): a change of the settings on screen, or the viewer's own action. */
static void on_char(GLFWwindow *window, unsigned int codepoint)
{
    struct viewer *v = glfwGetWindowUserPointer(window);
    struct ao_settings s;
    get_settings(v, &s);
    const struct ao_frame *f = current_frame(v);
    switch (ao_keys_typed(codepoint, &s, f ? f->info.spppp : 0)) {
    case AO_KEY_SETTINGS: set_settings(v, &s); return;
    case AO_KEY_ERROR_VIEW: v->show = v->show == SHOW_ERROR ? SHOW_IMAGE : SHOW_ERROR; v->reupload = true; return;
    case AO_KEY_DIFFERENCE_VIEW:
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
    case AO_KEY_RESTART:
        if (v->compare)
            ao_compare_restart(v->compare);
        else
            ao_render_restart(v->render);
        return;
    case AO_KEY_COMPARE:
        if (!v->info->config && !v->info->quiet) {
            printf("aoview: V compares two configurations; not available here\n");
            fflush(stdout);
        }
        v->toggle_compare = v->info->config != NULL;
        return;
    case AO_KEY_LAYOUT:
        v->layout = v->layout == AO_COMPARE_SPLIT ? AO_COMPARE_SIDE_BY_SIDE : AO_COMPARE_SPLIT;
        v->reupload = true;
        return;
    case AO_KEY_SAVE: v->save = true; return;
    case AO_KEY_FINER:
        v->pixel_size = v->pixel_size > 1 ? v->pixel_size / 2 : 1;
        v->resized_at = -1.0;
        return;
    case AO_KEY_COARSER:
        v->pixel_size = v->pixel_size < MAX_PIXEL_SIZE ? v->pixel_size * 2 : MAX_PIXEL_SIZE;
        v->resized_at = -1.0;
        return;
    case AO_KEY_HELP: v->show_help = !v->show_help; return;
    case AO_KEY_QUIT: glfwSetWindowShouldClose(window, GLFW_TRUE); return;
    case AO_KEY_NONE: return;
    }
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

/* Mouse buttons: the left one orbits (or takes the comparison's divider), the right one pans. */
static void on_button(GLFWwindow *window, int button, int action, int mods)
{
    (void)mods;
    struct viewer *v = glfwGetWindowUserPointer(window);
    if (button != GLFW_MOUSE_BUTTON_LEFT && button != GLFW_MOUSE_BUTTON_RIGHT)
        return;
    enum ao_drag drag = button == GLFW_MOUSE_BUTTON_LEFT ? AO_DRAG_ORBIT : AO_DRAG_PAN;
    if (action == GLFW_PRESS && v->gestures.drag == AO_DRAG_NONE) {
        double x, y;
        glfwGetCursorPos(window, &x, &y);
        struct ao_display_rect r = image_in_window(v);
        bool divider = v->compare && v->layout == AO_COMPARE_SPLIT;
        ao_gestures_press(&v->gestures, drag, x, y, divider ? r.x + v->split * r.width : NAN);
    } else if (action == GLFW_RELEASE) {
        ao_gestures_release(&v->gestures, drag);
    }
}

static void on_cursor(GLFWwindow *window, double x, double y)
{
    struct viewer *v = glfwGetWindowUserPointer(window);
    if (!ao_gestures_move(&v->gestures, x, y))
        return;
    struct ao_display_rect r = image_in_window(v);
    v->split = r.width > 0 ? fmin(1.0, fmax(0.0, (x - r.x) / r.width)) : 0.5;
    v->reupload = true;
}

/* The framebuffer changed size: the render follows once it keeps it (follow_size). */
static void on_framebuffer_size(GLFWwindow *window, int width, int height)
{
    (void)width;
    (void)height;
    struct viewer *v = glfwGetWindowUserPointer(window);
    v->resized_at = glfwGetTime();
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
    ao_gestures_scroll(&v->gestures, dy);
}

/* Applies the mouse moves gathered since the last frame as one camera change (one restart). */
static void apply_mouse(struct viewer *v)
{
    if (!ao_gestures_pending(&v->gestures))
        return;
    struct ao_display_rect image = image_in_window(v);
    struct ao_settings s;
    get_settings(v, &s);
    ao_gestures_apply(&v->gestures, &s.camera, image.height > 0 ? image.height : 1);
    s.navigating = true;
    set_settings(v, &s);
    v->navigated_at = glfwGetTime();
}

/* Tells the renderer that the camera has stopped moving, NAVIGATION_SECONDS after the last move:
 * its previews and passes go on. Returns the seconds until that is due, or a negative number. */
static double end_navigation(struct viewer *v)
{
    struct ao_settings s;
    get_settings(v, &s);
    if (!s.navigating)
        return -1.0;
    double due = v->navigated_at + NAVIGATION_SECONDS - glfwGetTime();
    if (due > 0.0)
        return due;
    s.navigating = false;
    set_settings(v, &s);
    return -1.0;
}

/* ---- output ---- */

/* The comparison's two images, linear, as the layout shows them, in memory the caller frees; NULL
 * with one message when memory is short. */
static float *compose_images(const struct viewer *v)
{
    const struct ao_frame *a = ao_compare_frame(v->compare, 0), *b = ao_compare_frame(v->compare, 1);
    float *out = malloc(3 * sizeof *out * (size_t)ao_compare_width(v->layout, a->width) * (size_t)a->height);
    if (!out) {
        fprintf(stderr, "aoview: out of memory for the comparison's screenshot\n");
        return NULL;
    }
    ao_compare_compose(v->layout, (int)lround(v->split * a->width), a->rgb, b->rgb, a->width, a->height, out);
    return out;
}

/* Saves what is on screen (a full frame, uploaded) as aoview-N.png (the image as the window shows
 * it, at the render's size: one pixel per image pixel, without the overlay, encoded through the
 * display shader as --headless -o does) and aoview-N.pfm or .exr (linear; while comparing, both
 * sides as the layout shows them) in the working directory, N the first free number. */
static void save(struct viewer *v)
{
    const struct ao_frame *f = current_frame(v);
    if (!f || !v->view || (v->compare && !ao_compare_frame(v->compare, 1)))
        return;
    if (!ao_display_upload(v->display, v->view, v->image_width, v->image_height))
        return;
    float *both = v->compare ? compose_images(v) : NULL;
    if (v->compare && !both)
        return;
    struct ao_screenshot shot = {.linear = both ? both : f->rgb, .width = v->image_width, .height = v->image_height,
                                 .info = &f->info, .scene = v->info->scene_name, .seed = v->info->seed,
                                 .exr = v->info->save_exr, .quiet = v->info->quiet};
    ao_screenshot_save(v->display, &shot);
    free(both);
}

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
    glfwSetCharCallback(v->window, on_char);
    glfwSetKeyCallback(v->window, on_key);
    glfwSetMouseButtonCallback(v->window, on_button);
    glfwSetCursorPosCallback(v->window, on_cursor);
    glfwSetScrollCallback(v->window, on_scroll);
    glfwSetWindowRefreshCallback(v->window, on_refresh);
    glfwSetFramebufferSizeCallback(v->window, on_framebuffer_size);
    return AO_WINDOW_OK;
}

/* Makes *buffer hold 3 floats for each of `pixels` pixels, *room counting its floats; false with one
 * message when memory is short. */
static bool grow(float **buffer, size_t *room, size_t pixels, const char *what)
{
    if (ao_buffer_grow(buffer, room, 3 * pixels))
        return true;
    fprintf(stderr, "aoview: out of memory for %s\n", what);
    return false;
}

/* True when frame f has the reference's size, so that its RMSE and difference view exist. */
static bool fits_reference(const struct viewer *v, const struct ao_frame *f)
{
    return v->info->reference && f->width == v->info->reference_width && f->height == v->info->reference_height;
}

/* Keeps reference_fits for the full frame f, saying on stderr when the sizes stop matching. */
static void check_reference(struct viewer *v, const struct ao_frame *f)
{
    bool fits = !v->info->reference || fits_reference(v, f);
    if (!fits && v->reference_fits)
        fprintf(stderr, "aoview: the image is %dx%d and --reference %dx%d: no RMSE or difference view until the "
                "sizes match\n", f->width, f->height, v->info->reference_width, v->info->reference_height);
    v->reference_fits = fits;
}

/* The view of frame f as the window shows it: its image, or its error map (a preview's: all not
 * known) or its difference from the reference painted into heat[k] (grown on use); NULL when memory
 * is short. A preview, or a frame of another size than the reference, shows its image in the
 * difference view. */
static const float *view_of(struct viewer *v, const struct ao_frame *f, int k)
{
    if (v->show == SHOW_IMAGE || (v->show == SHOW_DIFFERENCE && (f->block > 1 || !fits_reference(v, f))))
        return f->rgb;
    if (!grow(&v->heat[k], &v->heat_room[k], (size_t)f->width * (size_t)f->height, "the heat map"))
        return NULL;
    if (v->show == SHOW_ERROR)
        ao_heatmap_tiles(f, v->heat[k]);
    else
        ao_heatmap_pixels(f->rgb, v->info->reference, f->width, f->height, v->heat[k]);
    return v->heat[k];
}

/* Whether the texture keeps the finest preview of the run while the newest frame taken, a full
 * one of that run, is not as good yet (PREVIEW_UNTIL_SPP): only in the image view of a single run
 * going on, and never past a view change. */
static bool keeps_preview(const struct viewer *v, const struct ao_settings *settings)
{
    const struct ao_frame *f = v->shown;
    return !v->compare && !v->reupload && v->kept_block > 1 && v->show == SHOW_IMAGE && f && f->block == 1 &&
           f->info.restarts == v->kept_run && f->info.mean_spp < PREVIEW_UNTIL_SPP && !f->info.done &&
           !settings->paused;
}

/* Uploads the view of the newest frame (a preview's cells as blocks), or while comparing the two
 * sides' views as the layout shows them, once both sides have the same size; false when the upload
 * failed. */
static bool upload(struct viewer *v)
{
    v->uploaded = v->taken;
    v->reupload = false;
    v->kept_block = 0;
    if (!v->compare) {
        const struct ao_frame *f = v->shown;
        const float *image = view_of(v, f, 0);
        v->image_width = f->image_width;
        v->image_height = f->image_height;
        v->view = f->block == 1 ? image : NULL;
        if (f->block > 1) {
            v->kept_block = f->block;
            v->kept_run = f->info.restarts;
        }
        return image && ao_display_show(v->display, image, f->width, f->height, f->block, f->image_width,
                                        f->image_height);
    }
    const struct ao_frame *a = ao_compare_frame(v->compare, 0), *b = ao_compare_frame(v->compare, 1);
    if (a->width != b->width || a->height != b->height) /* one side has restarted at a new size */
        return true;
    const float *view_a = view_of(v, a, 0), *view_b = view_of(v, b, 1);
    size_t pixels = (size_t)ao_compare_width(v->layout, a->width) * (size_t)a->height;
    if (!view_a || !view_b || !grow(&v->composite, &v->composite_room, pixels, "the comparison"))
        return false;
    ao_compare_compose(v->layout, (int)lround(v->split * a->width), view_a, view_b, a->width, a->height, v->composite);
    v->image_width = ao_compare_width(v->layout, a->width);
    v->image_height = a->height;
    v->view = v->composite;
    return ao_display_show(v->display, v->composite, v->image_width, v->image_height, 1, v->image_width,
                           v->image_height);
}

/* Takes the facts of every pass published since the last call into the chart and the time-left
 * estimate, and the newest frame (while comparing, each side's), if one is new; the loop uploads
 * it when it presents it. */
static void take_frame(struct viewer *v)
{
    if (v->compare) {
        if (ao_compare_take_frames(v->compare) && ao_compare_frame(v->compare, 0) && ao_compare_frame(v->compare, 1)) {
            v->taken++;
            check_reference(v, ao_compare_frame(v->compare, 0));
        }
        return;
    }
    struct ao_frame_info log[64];
    for (int n; (n = ao_render_take_log(v->render, log, 64)) > 0;)
        for (int k = 0; k < n; k++) {
            ao_chart_add(&v->chart, &log[k]);
            ao_progress_add(&v->progress, &log[k]);
        }
    const struct ao_frame *f = ao_render_take_frame(v->render);
    if (!f)
        return;
    v->shown = f;
    v->shown_at = glfwGetTime();
    v->taken++;
    if (f->block == 1)
        check_reference(v, f);
}

/* V: compares the current configuration with --compare's B, or else ao_compare_partner's, paused
 * if asked, the window's renderer paused meanwhile; false when the comparison cannot start. */
static bool start_compare(struct viewer *v, bool paused)
{
    struct ao_settings s, single;
    ao_render_get_settings(v->render, &s);
    single = s;
    single.paused = true;
    ao_render_set_settings(v->render, &single);
    s.paused = paused;
    struct ao_compare_side sides[2] = {{.sampling = s.sampling, .sequence = v->info->config->sequence, .aa = s.aa}};
    sides[1] = v->info->compare ? v->info->sides[1] : ao_compare_partner(sides[0]);
    v->reupload = true;
    return (v->compare = ao_compare_create(v->info->config, &s, sides, v->info->users)) != NULL;
}

/* V again: ends the comparison, handing the window's renderer its settings (it goes on where it
 * stopped unless they changed its estimate). */
static void stop_compare(struct viewer *v)
{
    struct ao_settings s;
    ao_compare_get_settings(v->compare, &s);
    ao_compare_destroy(v->compare);
    v->compare = NULL;
    ao_render_set_settings(v->render, &s);
    v->reupload = true;
}

static void toggle_compare(struct viewer *v)
{
    if (v->compare) {
        stop_compare(v);
        return;
    }
    struct ao_settings s;
    ao_render_get_settings(v->render, &s);
    if (!start_compare(v, s.paused))
        ao_render_set_settings(v->render, &s);
}

/* The image size the framebuffer asks for: its pixels over the pixel size, each way. */
static void wanted_size(const struct viewer *v, int *width, int *height)
{
    glfwGetFramebufferSize(v->window, width, height);
    *width = *width / v->pixel_size > 0 ? *width / v->pixel_size : 1;
    *height = *height / v->pixel_size > 0 ? *height / v->pixel_size : 1;
}

/* Restarts the render at the size the framebuffer asks for once it has kept its size for
 * RESIZE_SECONDS (at once after [ or ]); returns the seconds until that is due, or a negative
 * number when nothing waits. */
static double follow_size(struct viewer *v)
{
    if (v->resized_at == 0.0)
        return -1.0;
    double due = v->resized_at < 0.0 ? 0.0 : v->resized_at + RESIZE_SECONDS - glfwGetTime();
    if (due > 0.0)
        return due;
    v->resized_at = 0.0;
    struct ao_settings s;
    get_settings(v, &s);
    wanted_size(v, &s.width, &s.height);
    set_settings(v, &s);
    return -1.0;
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
    if (image && !upload(v))
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
    bool image = v->reupload || (v->taken != v->uploaded && !keeps_preview(v, settings));
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
        take_frame(v);
    }
    struct ao_settings s;
    get_settings(v, &s);
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
    set_settings(v, &s);
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
            toggle_compare(v);
        v->toggle_compare = false;
        apply_mouse(v);
        double resize_due = follow_size(v), navigation_due = end_navigation(v);
        take_frame(v);
        struct ao_settings s;
        get_settings(v, &s);
        /* S saves a full frame (during previews it waits for the first), the very one the texture
         * then holds: a frame not shown yet, or kept from view by a preview, is uploaded first. */
        const struct ao_frame *f = current_frame(v);
        if (v->save && f && f->block == 1) {
            if (v->uploaded != v->taken && !upload(v))
                return AO_WINDOW_FAILED;
            save(v);
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
    if (result == AO_WINDOW_OK && info->compare && !start_compare(&v, false))
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
