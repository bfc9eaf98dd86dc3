/* The window's frames (see window_viewer.h): taken from the renderer or the comparison, made into
 * the view on screen (the image, a heat map, the comparison's composite) and uploaded, the size
 * followed, and what is on screen saved. */
#include "window_viewer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "buffer.h"
#include "heatmap.h"
#include "screenshot.h"

/* The settings of what is on screen: the comparison's while there is one, else the renderer's. */
void ao_viewer_get_settings(const struct viewer *v, struct ao_settings *s)
{
    if (v->compare)
        ao_compare_get_settings(v->compare, s);
    else
        ao_render_get_settings(v->render, s);
}

void ao_viewer_set_settings(const struct viewer *v, const struct ao_settings *s)
{
    if (v->compare)
        ao_compare_set_settings(v->compare, s);
    else
        ao_render_set_settings(v->render, s);
}

/* The frame whose facts the status and screenshots give: side A's while comparing. */
const struct ao_frame *ao_viewer_frame(const struct viewer *v)
{
    return v->compare ? ao_compare_frame(v->compare, 0) : v->shown;
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
bool ao_viewer_keeps_preview(const struct viewer *v, const struct ao_settings *settings)
{
    const struct ao_frame *f = v->shown;
    return !v->compare && !v->reupload && v->kept_block > 1 && v->show == SHOW_IMAGE && f && f->block == 1 &&
           f->info.restarts == v->kept_run && f->info.mean_spp < PREVIEW_UNTIL_SPP && !f->info.done &&
           !settings->paused;
}

/* Uploads the view of the newest frame (a preview's cells as blocks), or while comparing the two
 * sides' views as the layout shows them, once both sides have the same size; false when the upload
 * failed. */
bool ao_viewer_upload(struct viewer *v)
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
void ao_viewer_take_frame(struct viewer *v)
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
bool ao_viewer_start_compare(struct viewer *v, bool paused)
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

void ao_viewer_toggle_compare(struct viewer *v)
{
    if (v->compare) {
        stop_compare(v);
        return;
    }
    struct ao_settings s;
    ao_render_get_settings(v->render, &s);
    if (!ao_viewer_start_compare(v, s.paused))
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
double ao_viewer_follow_size(struct viewer *v)
{
    if (v->resized_at == 0.0)
        return -1.0;
    double due = v->resized_at < 0.0 ? 0.0 : v->resized_at + RESIZE_SECONDS - glfwGetTime();
    if (due > 0.0)
        return due;
    v->resized_at = 0.0;
    struct ao_settings s;
    ao_viewer_get_settings(v, &s);
    wanted_size(v, &s.width, &s.height);
    ao_viewer_set_settings(v, &s);
    return -1.0;
}

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
void ao_viewer_save(struct viewer *v)
{
    const struct ao_frame *f = ao_viewer_frame(v);
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

