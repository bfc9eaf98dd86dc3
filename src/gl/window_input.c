/* The window's keys and mouse (see window_viewer.h): callbacks change the settings at once; mouse
 * moves and screenshots wait for the loop. */
#include "window_viewer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "keys.h"

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
    ao_viewer_get_settings(v, &s);
    const struct ao_frame *f = ao_viewer_frame(v);
    switch (ao_keys_typed(codepoint, &s, f ? f->info.spppp : 0)) {
    case AO_KEY_SETTINGS: ao_viewer_set_settings(v, &s); return;
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
void ao_viewer_apply_mouse(struct viewer *v)
{
    if (!ao_gestures_pending(&v->gestures))
        return;
    struct ao_display_rect image = image_in_window(v);
    struct ao_settings s;
    ao_viewer_get_settings(v, &s);
    ao_gestures_apply(&v->gestures, &s.camera, image.height > 0 ? image.height : 1);
    s.navigating = true;
    ao_viewer_set_settings(v, &s);
    v->navigated_at = glfwGetTime();
}

/* Tells the renderer that the camera has stopped moving, NAVIGATION_SECONDS after the last move:
 * its previews and passes go on. Returns the seconds until that is due, or a negative number. */
double ao_viewer_end_navigation(struct viewer *v)
{
    struct ao_settings s;
    ao_viewer_get_settings(v, &s);
    if (!s.navigating)
        return -1.0;
    double due = v->navigated_at + NAVIGATION_SECONDS - glfwGetTime();
    if (due > 0.0)
        return due;
    s.navigating = false;
    ao_viewer_set_settings(v, &s);
    return -1.0;
}

void ao_viewer_listen(struct viewer *v)
{
    glfwSetCharCallback(v->window, on_char);
    glfwSetKeyCallback(v->window, on_key);
    glfwSetMouseButtonCallback(v->window, on_button);
    glfwSetCursorPosCallback(v->window, on_cursor);
    glfwSetScrollCallback(v->window, on_scroll);
    glfwSetWindowRefreshCallback(v->window, on_refresh);
    glfwSetFramebufferSizeCallback(v->window, on_framebuffer_size);
}
