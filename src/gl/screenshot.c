/* What the window's S saves; see screenshot.h. */
#include "screenshot.h"

#include <stdio.h>
#include <unistd.h>

#include "image.h"
#include "notes.h"

bool ao_screenshot_save(struct ao_display *display, const struct ao_screenshot *shot)
{
    char png[32], linear[32];
    for (int n = 1;; n++) {
        snprintf(png, sizeof png, "aoview-%d.png", n);
        snprintf(linear, sizeof linear, "aoview-%d.%s", n, shot->exr ? "exr" : "pfm");
        if (access(png, F_OK) != 0 && access(linear, F_OK) != 0)
            break;
    }
    struct ao_notes notes;
    ao_notes_make(&notes, shot->info, shot->scene, shot->seed);
    if (!ao_display_write_png(display, png) ||
        !ao_image_write_linear(linear, shot->linear, shot->width, shot->height, notes.notes, notes.count))
        return false;
    if (!shot->quiet) {
        printf("aoview: saved %s and %s (%u spp)\n", png, linear, shot->info->spp);
        fflush(stdout);
    }
    return true;
}
