/* The image on screen and in PNG files. The screen's: the running average encoded to 8-bit sRGB on
 * the CPU once per new image (image.c's table), uploaded as the window's own BGRA pixels and
 * blitted, letterboxed, into any framebuffer, with the wall time each shown frame costs measured.
 * The files': the float image in a texture drawn at 1:1 offscreen through the display shader (the
 * sRGB curve). Knows no window and no OSMesa: GL comes through struct ao_glapi. */
#ifndef AO_DISPLAY_H
#define AO_DISPLAY_H

#include <stdbool.h>
#include <stdint.h>

#include "glapi.h"

/* A rectangle in framebuffer pixels, origin at the bottom left as glViewport takes it. */
struct ao_display_rect {
    int x, y, width, height;
};

/* The display's GL objects; opaque. */
struct ao_display;

/* Compiles the embedded display shaders and creates the GL objects in the current context; gl
 * must outlive it. NULL with one message (naming the shader that failed). GL thread. */
struct ao_display *ao_display_create(const struct ao_glapi *gl);

/* ao_display_create with the given GLSL in place of shaders/display.vert and .frag, so that tests
 * can feed it a broken shader. GL thread. */
struct ao_display *ao_display_create_from_source(const struct ao_glapi *gl, const char *vertex,
                                                 const char *fragment);

/* Deletes the GL objects (context still current) and frees; accepts NULL. GL thread. */
void ao_display_destroy(struct ao_display *display);

/* Copies a width x height linear RGB image, top row first, into the texture the PNG files are
 * drawn from: glTexSubImage2D, or a new texture when the size changed; false with one message when
 * the size exceeds GL's limit. GL thread. */
bool ao_display_upload(struct ao_display *display, const float *rgb, int width, int height);

/* As ao_display_upload, for width x height cells of block x block pixels that cover an image_width x
 * image_height image from its top left (a preview): the display then shows and fits that image,
 * each cell a block. GL thread. */
bool ao_display_upload_cells(struct ao_display *display, const float *rgb, int width, int height, int block,
                             int image_width, int image_height);

/* Where the image goes in a framebuffer: magnified by the whole factor k that fills it to within k
 * pixels each way, if one does, else the largest centred rectangle of its aspect ratio. Pure. */
struct ao_display_rect ao_display_fit(int image_width, int image_height, int fb_width, int fb_height);

/* Makes a width x height linear RGB image (top row first), or the width x height cells of block x
 * block pixels that cover an image_width x image_height image from its top left (a preview), the
 * screen's image: encoded to 8-bit sRGB on the CPU (ao_image_encode_srgb8_bgra) and uploaded once.
 * Starts the frame's clock. False with one message when memory or GL's size limit is short. GL
 * thread. */
bool ao_display_show(struct ao_display *display, const float *rgb, int width, int height, int block, int image_width,
                     int image_height);

/* Draws the screen's image into ao_display_fit's rectangle of the default framebuffer (fb_width x
 * fb_height) and the letterbox colour around it (all of it before the first ao_display_show): a
 * blit, a plain copy at 1:1, each texel a block when magnified (filtered when shrunk). Starts the
 * frame's clock unless ao_display_show did. GL thread. */
void ao_display_draw(struct ao_display *display, int fb_width, int fb_height);

/* What showing a frame costs, in wall seconds from its first GL call (ao_display_show or draw) to
 * its presentation (ao_display_presented): of a frame with a new image (encoding, upload, blit,
 * overlay, swap) and of a redraw of an image already shown, each the median of the last
 * AO_DISPLAY_COSTS such frames (the first of each kind, which compiles the shaders and makes the
 * textures, is not measured; a later one-off does not move a median); 0 before one. */
enum { AO_DISPLAY_COSTS = 5 };
struct ao_display_cost {
    double new_image, redraw;
};

/* The frame begun by ao_display_show or ao_display_draw is on screen (the caller swapped buffers):
 * waits for GL to finish it and stops its clock. GL thread. */
void ao_display_presented(struct ao_display *display);

/* The costs measured so far. GL thread. */
struct ao_display_cost ao_display_cost(const struct ao_display *display);

/* Renders the uploaded image at its size into an offscreen framebuffer and writes it as an 8-bit PNG
 * (the displayed image without overlays); false with one message. GL thread. */
bool ao_display_write_png(struct ao_display *display, const char *path);

/* Draws over the image at 1:1 (framebuffer width x height, bound) before it is read back. */
typedef void ao_display_overlay(void *user, int width, int height);

/* As ao_display_write_png, with overlay(user, ...) drawn over the image first. GL thread. */
bool ao_display_write_png_with(struct ao_display *display, const char *path, ao_display_overlay *overlay,
                               void *user);

#endif
