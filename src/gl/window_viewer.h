/* Private to the window's files (window.c: its life cycle, presenting and loop; window_input.c: the
 * keys and mouse; window_frames.c: the frames taken, uploaded, compared and saved): the viewer that
 * the GL thread holds, and what the three call of each other. GL thread only. */
#ifndef AO_WINDOW_VIEWER_H
#define AO_WINDOW_VIEWER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "chart.h"
#include "compare.h"
#include "display.h"
#include "gestures.h"
#include "glapi.h"
#include "hud.h"
#include "progress.h"
#include "render.h"
#include "window.h"

struct GLFWwindow;

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
    struct GLFWwindow *window;
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

/* The settings of what is on screen: the comparison's while there is one, else the renderer's. */
void ao_viewer_get_settings(const struct viewer *v, struct ao_settings *s);

/* Changes the settings of what is on screen (ao_viewer_get_settings's). */
void ao_viewer_set_settings(const struct viewer *v, const struct ao_settings *s);

/* The frame whose facts the status and screenshots give: side A's while comparing. */
const struct ao_frame *ao_viewer_frame(const struct viewer *v);

/* Whether the texture keeps the finest preview of the run while the newest frame taken, a full
 * one of that run, is not as good yet (PREVIEW_UNTIL_SPP): only in the image view of a single run
 * going on, and never past a view change. */
bool ao_viewer_keeps_preview(const struct viewer *v, const struct ao_settings *settings);

/* Uploads the view of the newest frame (a preview's cells as blocks), or while comparing the two
 * sides' views as the layout shows them, once both sides have the same size; false when the upload
 * failed. */
bool ao_viewer_upload(struct viewer *v);

/* Takes the facts of every pass published since the last call into the chart and the time-left
 * estimate, and the newest frame (while comparing, each side's), if one is new; the loop uploads
 * it when it presents it. */
void ao_viewer_take_frame(struct viewer *v);

/* V: compares the current configuration with --compare's B, or else ao_compare_partner's, paused
 * if asked, the window's renderer paused meanwhile; false when the comparison cannot start. */
bool ao_viewer_start_compare(struct viewer *v, bool paused);

/* V: turns the comparison on, or off (the window's renderer then shows the current side A's
 * configuration). */
void ao_viewer_toggle_compare(struct viewer *v);

/* Restarts the render at the size the framebuffer asks for once it has kept its size for
 * RESIZE_SECONDS (at once after [ or ]); returns the seconds until that is due, or a negative
 * number when nothing waits. */
double ao_viewer_follow_size(struct viewer *v);

/* Saves what is on screen (a full frame, uploaded) as aoview-N.png (the image as the window shows
 * it, at the render's size: one pixel per image pixel, without the overlay, encoded through the
 * display shader as --headless -o does) and aoview-N.pfm or .exr (linear; while comparing, both
 * sides as the layout shows them) in the working directory, N the first free number. */
void ao_viewer_save(struct viewer *v);

/* Applies the mouse moves gathered since the last frame as one camera change (one restart). */
void ao_viewer_apply_mouse(struct viewer *v);

/* Tells the renderer that the camera has stopped moving, NAVIGATION_SECONDS after the last move:
 * its previews and passes go on. Returns the seconds until that is due, or a negative number. */
double ao_viewer_end_navigation(struct viewer *v);

/* Sets the window's input callbacks (window_input.c), which reach v through the window's user
 * pointer. */
void ao_viewer_listen(struct viewer *v);

#endif
