/* What the window's S saves: the image on screen as aoview-N.png (drawn through the display shader
 * at one pixel per image pixel, without the overlay, as --headless -o draws it) and its linear
 * average as aoview-N.pfm or aoview-N.exr (the settings in the EXR's header), N the first number
 * free for both in the working directory; one line on stdout names them. */
#ifndef AO_SCREENSHOT_H
#define AO_SCREENSHOT_H

#include <stdbool.h>
#include <stdint.h>

#include "display.h"
#include "frame.h"

/* A screenshot's linear image and what its files record; strings owned by the caller. */
struct ao_screenshot {
    const float *linear;                 /* width x height x 3 linear floats, top row first */
    int width, height;
    const struct ao_frame_info *info;    /* the facts of the frame it shows */
    const char *scene;                   /* the scene's name, and the seed, for the EXR's header */
    uint64_t seed;
    bool exr;                            /* .exr beside the PNG rather than .pfm */
    bool quiet;                          /* no line on stdout */
};

/* Saves shot: the PNG from the image the display holds (uploaded at shot's size), then the linear
 * file; false after one message when either cannot be written. GL thread. */
bool ao_screenshot_save(struct ao_display *display, const struct ao_screenshot *shot);

#endif
