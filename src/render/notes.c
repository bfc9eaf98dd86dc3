/* EXR header attributes of a frame; see notes.h. */
#include "notes.h"

#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>

#include "config.h"
#include "sampling.h"

/* Appends the attribute key with a printf-formatted value. */
static void add(struct ao_notes *out, const char *key, const char *format, ...)
{
    char *value = out->values[out->count];
    va_list args;
    va_start(args, format);
    vsnprintf(value, sizeof out->values[0], format, args);
    va_end(args);
    out->notes[out->count++] = (struct ao_image_note){key, value};
}

void ao_notes_make(struct ao_notes *out, const struct ao_frame_info *info, const char *scene,
                   uint64_t seed)
{
    out->count = 0;
    add(out, "software", "aoview %s", AO_VERSION);
    add(out, "aoview.scene", "%s", scene);
    add(out, "aoview.spp", "%" PRIu32, info->spp);
    add(out, "aoview.sampling", "%s", ao_sampling_name(info->sampling));
    add(out, "aoview.aa", "%s", info->aa ? "on" : "off");
    add(out, "aoview.view", "%s", info->output == AO_OUTPUT_NORMALS ? "normals" : "ao");
    add(out, "aoview.shading", "%s", info->shading == AO_SHADING_FLAT ? "flat" : "phong");
    add(out, "aoview.seed", "%" PRIu64, seed);
    add(out, "aoview.seconds", "%.3f", info->seconds);
}
