/* Text on stdout and the output image; see app_output.h. */
#include "app_output.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "app_report.h"
#include "headless.h"
#include "heatmap.h"
#include "image.h"
#include "notes.h"
#include "text.h"

bool ao_app_print(const char *text)
{
    if (fputs(text, stdout) >= 0 && fflush(stdout) == 0)
        return true;
    fprintf(stderr, "aoview: cannot write to standard output: %s\n", strerror(errno));
    return false;
}

/* The difference view of frame from reference as a heat map PNG with its colour bar. */
static bool write_difference_png(const char *path, const struct ao_frame *frame, const float *reference)
{
    float *heat = malloc(3 * sizeof *heat * (size_t)frame->width * (size_t)frame->height);
    if (!heat) {
        fprintf(stderr, "aoview: %s: out of memory for the difference image\n", path);
        return false;
    }
    ao_heatmap_pixels(frame->rgb, reference, frame->width, frame->height, heat);
    bool ok = ao_headless_write_heatmap(path, heat, frame->width, frame->height, &ao_heatmap_difference,
                                        "|image - reference|");
    free(heat);
    return ok;
}

bool ao_app_write_output(const char *path, const struct ao_frame *frame, const char *scene, uint64_t seed,
                         const float *difference)
{
    if (ao_image_has_extension(path, ".png"))
        return difference ? write_difference_png(path, frame, difference)
                          : ao_headless_write_png(path, frame->rgb, frame->width, frame->height);
    struct ao_notes notes;
    ao_notes_make(&notes, &frame->info, scene, seed);
    return ao_image_write_linear(path, frame->rgb, frame->width, frame->height, notes.notes,
                                 notes.count);
}

bool ao_app_go_headless(const struct ao_options *opts)
{
    const char *output = opts->output ? opts->output : "aoview.png";
    char name[AO_TEXT_SIZE];
    if (!ao_image_check_output(output))
        return false;
    fprintf(stderr, "aoview: no display available; rendering headless to %s\n",
            ao_text_escape(output, name, sizeof name));
    return true;
}

int ao_app_write(struct ao_app *app, const struct ao_options *opts, const struct ao_frame *frame, const char *why,
                 bool last_row, int status)
{
    const char *output = opts->output ? opts->output : "aoview.png";
    const char *bar = app->reporter.drawn_at > 0.0 ? "\n" : ""; /* ends the progress bar's line */
    if (why && frame && frame->info.pass == 0) {
        fprintf(stderr, "%saoview: %s before the first pass ended: nothing written\n", bar, why);
        return status;
    }
    if (why && frame) {
        fprintf(stderr, "%saoview: %s at %u spp\n", bar, why, frame->info.spp);
        if (last_row)
            ao_app_on_pass(&frame->info, &app->reporter);
    }
    const float *difference = opts->view == AO_VIEW_MODE_DIFFERENCE ? app->reference : NULL;
    atomic_store(&app->interrupt.written_before, ao_image_written());
    atomic_store(&app->interrupt.writing, true);
    if (!frame || !ao_app_write_output(output, frame, app->scene.name, opts->seed, difference))
        return AO_EXIT_RUNTIME;
    char name[AO_TEXT_SIZE];
    if (!opts->quiet)
        fprintf(stderr, "aoview: wrote %s (%u spp, %.2f s, %.1f Mrays/s)\n", ao_text_escape(output, name, sizeof name),
                frame->info.spp, frame->info.seconds, ao_app_mrays_per_second(&frame->info));
    return status;
}
