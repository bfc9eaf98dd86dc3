/* What a saved linear image says about how it was made: EXR header attributes from the frame. */
#ifndef AO_NOTES_H
#define AO_NOTES_H

#include <stddef.h>
#include <stdint.h>

#include "frame.h"
#include "image_types.h"

enum { AO_NOTES_MAX = 9 };

/* The attributes and the text they point to; the caller owns it (usually on the stack). */
struct ao_notes {
    struct ao_image_note notes[AO_NOTES_MAX];
    size_t count;
    char values[AO_NOTES_MAX][160];
};

/* Fills out with "software" and aoview.* attributes (scene, spp, sampling, aa, view, shading,
 * seed, seconds) from the frame's info, the scene's name and the seed. Any thread. */
void ao_notes_make(struct ao_notes *out, const struct ao_frame_info *info, const char *scene,
                   uint64_t seed);

#endif
