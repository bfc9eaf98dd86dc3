/* The interactive viewer: a GLFW window on the running renderer, with the keys and mouse of
 * docs/contract.md, the status overlay and title, screenshots, and the live comparison of two
 * configurations. */
#ifndef AO_WINDOW_H
#define AO_WINDOW_H

#include <stdbool.h>
#include <stdint.h>

#include "modes.h"
#include "render.h"

/* What the window shows besides the frames; strings owned by the caller for the whole run. */
struct ao_window_info {
    const char *scene_name;
    bool quiet;              /* no screenshot names on stdout */
    uint64_t seed;           /* for the saved EXR's header */
    bool save_exr;           /* S saves aoview-N.exr beside the PNG instead of aoview-N.pfm */
    const float *reference;  /* --reference for the difference view, or NULL */
    int reference_width, reference_height;
    int pixel_size;          /* --pixel-size: 1, 2, 4 or 8; 0: auto */
    bool difference;         /* start in the difference view (needs reference) */
    const struct ao_render_config *config;   /* the window's renderer's, for V's two renderers; NULL:
                                                no V (aoview-mpi) */
    bool compare;            /* --compare: start in the comparison, B being sides[1] */
    bool resume;             /* the renderer was made paused, so that the window opens on free
                                cores: it is unpaused, with previews, once the window and its GL
                                are ready */
    struct ao_compare_side sides[2];
    void *users[2];          /* config->on_pass's argument for each side of a comparison */
};

/* How ao_window_run ended. */
enum ao_window_result {
    AO_WINDOW_OK,            /* the user quit */
    AO_WINDOW_NO_DISPLAY,    /* no window could be opened; no frame was taken from the renderer */
    AO_WINDOW_FAILED,        /* OpenGL failed after the window opened; one message printed */
};

/* Opens the GLFW window on the running renderer, sized to its image (fitted to the screen), and
 * runs until the user quits, the render following the framebuffer's size; it is the renderer's
 * frame consumer meanwhile, and stops it (ao_render_stop) as the user quits. NO_DISPLAY when no
 * window can be opened (main then falls back to headless, the renderer untouched). Main thread
 * only. */
enum ao_window_result ao_window_run(struct ao_render *render, const struct ao_window_info *info);

/* Wakes the window's event wait (glfwPostEmptyEvent) so that it takes a new frame; a no-op when
 * no window is running. Any thread: main's on_pass calls it after each published pass. */
void ao_window_notify(void);

#endif
