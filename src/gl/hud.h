/* The on-screen overlay: text drawn with stb_easy_font, boxes and lines in GL core, and the status
 * text that the overlay and the window title share. */
#ifndef AO_HUD_H
#define AO_HUD_H

#include <stdbool.h>
#include <stddef.h>

#include "frame.h"
#include "glapi.h"

/* What the status line tells: the facts of the frame on screen plus the viewer's own state. */
struct ao_hud_status {
    const char *scene;
    struct ao_frame_info info;   /* of the frame on screen, or, while a preview stays on screen
                                    after full passes began, of the newest full frame */
    int width, height;           /* the image's size */
    int block;                   /* > 1: the image shown is a preview of block x block pixel cells */
    bool reference_differs;      /* --reference has another size: no RMSE */
    double seconds;              /* elapsed since the restart, ticking between frames */
    double seconds_left;         /* progress.h's estimate, ticking down between frames; NAN: none */
    int spppp;                   /* samples per pass as set (the next pass's); 0: auto */
    bool adaptive;               /* adaptive sampling as set */
    bool paused;
};

/* Writes the status facts joined by separator into out (always terminated, truncated to size):
 * scene; "WxH", with a preview on screen "WxH preview, N px cells"; sampling mode, "AA on|off",
 * "normals" in the normals view, "flat" with flat shading; then, once a full pass is done
 * (info.pass > 0), unless a preview is on screen, "mean N spp, up to T" (progress.h) and "error E
 * %" (E `unknown` until estimated); "Ns", "~N s left" while estimated ("finished" once the run
 * is), "M Mrays/s"; "pass P", "N
 * spp/pass" (or "auto N spp/pass"); unless a preview is on screen, "adaptive: C % converged" when
 * adaptive and "RMSE E" when the frame has one (else "no RMSE: reference of another size" when
 * --reference has another size); "paused" when paused. Every figure shown is measured (a
 * preview's run has none yet) and true of the view: the normals view shows no error, time left,
 * rate or RMSE, which are the AO estimate's. Pure. */
void ao_hud_format(const struct ao_hud_status *status, const char *separator, const char *unknown, char *out,
                   size_t size);

/* The overlay's GL objects and scratch buffers; opaque. */
struct ao_hud;

/* Inner margin of ao_hud_draw's box around its text, in font pixels (times the scale). */
#define AO_HUD_PADDING 4

/* An overlay colour: red, green, blue and opacity, each in [0, 1]. */
struct ao_hud_colour {
    float r, g, b, a;
};

/* Builds the overlay's program and buffers in the current context; gl must outlive it. NULL with
 * one message. GL thread. */
struct ao_hud *ao_hud_create(const struct ao_glapi *gl);

/* Deletes the GL objects (context still current) and frees; accepts NULL. GL thread. */
void ao_hud_destroy(struct ao_hud *hud);

/* Size in pixels of text ('\n' between lines) at scale, without a box. GL thread (uses scratch). */
void ao_hud_measure(struct ao_hud *hud, const char *text, float scale, int *width, int *height);

/* Draws text ('\n' between lines; bytes outside printable ASCII shown as '?') at scale in a
 * translucent box, AO_HUD_PADDING wider on each side, whose top left corner is (x, y) pixels from
 * the framebuffer's top left. GL thread. */
void ao_hud_draw(struct ao_hud *hud, const char *text, int x, int y, float scale, int fb_width,
                 int fb_height);

/* Starts drawing the primitives below into a fb_width x fb_height framebuffer, blended over what
 * it holds, in pixels from its top left. GL thread. */
void ao_hud_begin(struct ao_hud *hud, int fb_width, int fb_height);

/* Fills the rectangle from (x0, y0) to (x1, y1). Between ao_hud_begin and ao_hud_end. */
void ao_hud_fill(struct ao_hud *hud, float x0, float y0, float x1, float y1, struct ao_hud_colour colour);

/* Draws text as ao_hud_draw does, without the box, its top left at (x, y). Between ao_hud_begin
 * and ao_hud_end. */
void ao_hud_text(struct ao_hud *hud, const char *text, float x, float y, float scale,
                 struct ao_hud_colour colour);

/* Draws one-pixel lines through count points (x, y pairs in xy): one polyline when strip, else a
 * segment per two points. Between ao_hud_begin and ao_hud_end. */
void ao_hud_lines(struct ao_hud *hud, const float *xy, int count, bool strip, struct ao_hud_colour colour);

/* Ends drawing primitives. GL thread. */
void ao_hud_end(struct ao_hud *hud);

#endif
