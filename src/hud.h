/* The on-screen overlay: text drawn with stb_easy_font over a translucent box in GL core, and the
 * status text that the overlay and the window title share. */
#ifndef AO_HUD_H
#define AO_HUD_H

#include <stdbool.h>
#include <stddef.h>

#include "glapi.h"
#include "render.h"

/* What the status line tells: the facts of the frame on screen plus the viewer's own state. */
struct ao_hud_status {
    const char *scene;
    struct ao_frame_info info;   /* of the frame on screen */
    double seconds;              /* elapsed since the restart, ticking between frames */
    int spppp;                   /* samples per pass as set (the next pass's) */
    bool paused;
};

/* Writes the status facts joined by separator into out (always terminated, truncated to size):
 * scene, sampling mode, "AA on|off", "spp X of Y", "Ns", "M Mrays/s", "pass P", "N spp/pass", then
 * "RMSE E" when the frame has one and "paused" when paused. Pure. */
void ao_hud_format(const struct ao_hud_status *status, const char *separator, char *out, size_t size);

/* The overlay's GL objects and scratch buffers; opaque. */
struct ao_hud;

/* Builds the overlay's program and buffers in the current context; gl must outlive it. NULL with
 * one message. GL thread. */
struct ao_hud *ao_hud_create(const struct ao_glapi *gl);

/* Deletes the GL objects (context still current) and frees; accepts NULL. GL thread. */
void ao_hud_destroy(struct ao_hud *hud);

/* Size in pixels of the box that ao_hud_draw draws for text at scale. GL thread (uses scratch). */
void ao_hud_measure(struct ao_hud *hud, const char *text, float scale, int *width, int *height);

/* Draws text ('\n' between lines; bytes outside printable ASCII shown as '?') at scale in a
 * translucent box whose top left corner is (x, y) pixels from the framebuffer's top left. GL thread. */
void ao_hud_draw(struct ao_hud *hud, const char *text, int x, int y, float scale, int fb_width,
                 int fb_height);

#endif
