/* The live equal-time comparison: two renderers of the same scene, tracer and camera, each with its
 * own configuration and accumulation, taking turns pass by pass so that each gets the same render
 * time; and the pure pieces the window and the headless comparison show them with. No GL. */
#ifndef AO_COMPARE_H
#define AO_COMPARE_H

#include <stdbool.h>
#include <stddef.h>

#include "chart.h"
#include "frame.h"
#include "modes.h"
#include "render.h"

/* The comparison; opaque. */
struct ao_compare;

/* Starts one renderer per side on config (its sequence replaced by the side's) and settings (their
 * sampling and AA replaced by the side's), A first; config's on_pass is called for side k with
 * users[k] in place of config's user, one call at a time. NULL with one message. Main or GL thread. */
struct ao_compare *ao_compare_create(const struct ao_render_config *config, const struct ao_settings *settings,
                                     const struct ao_compare_side sides[2], void *const users[2]);

/* Stops and frees both renderers; accepts NULL. The thread that created it. */
void ao_compare_destroy(struct ao_compare *compare);

/* The settings as the user sees them: side A's sampling and AA, paused as the user set it (not as
 * the turns are). Any thread. */
void ao_compare_get_settings(struct ao_compare *compare, struct ao_settings *out);

/* Applies settings to both sides (the sampling and AA to side A's configuration): anything that
 * changes either side's estimate restarts both, so that their times start together. Any thread. */
void ao_compare_set_settings(struct ao_compare *compare, const struct ao_settings *settings);

/* Restarts both sides. Any thread. */
void ao_compare_restart(struct ao_compare *compare);

/* True while a side is rendering: not paused, and neither both done nor the side behind a finished
 * side caught up with it. Any thread. */
bool ao_compare_running(struct ao_compare *compare);

/* Takes each side's newest frame, feeding its chart; true when either is new. The frames stay
 * valid until the next call. The window's thread only. */
bool ao_compare_take_frames(struct ao_compare *compare);

/* Side k's frame on screen, NULL before its first. The window's thread only. */
const struct ao_frame *ao_compare_frame(const struct ao_compare *compare, int k);

/* Both sides' error charts in one: each side's newest curves, A's first. The window's thread only. */
void ao_compare_chart(const struct ao_compare *compare, struct ao_chart *out);

/* The second configuration V compares the current one with when --compare gave none: the same
 * sampler and AA with cosine sampling, or uniform sampling where the current one is cosine. Pure. */
struct ao_compare_side ao_compare_partner(struct ao_compare_side current);

/* Writes a side's label, "A: cosine+sobol+aa", "N spp  S s" and with a reference "RMSE E", the
 * three joined by separator, into out (truncated to size). Pure. */
void ao_compare_label(const char *name, const struct ao_compare_side *side, const struct ao_frame_info *info,
                      const char *separator, char *out, size_t size);

/* The size of a side's label as ao_compare_labels writes it. */
#define AO_COMPARE_LABEL 160

/* Writes the sides' labels, "A" and "B", of their frames on screen (both must have one) into
 * labels. The window's thread only. */
void ao_compare_labels(struct ao_compare *compare, const char *separator, char labels[2][AO_COMPARE_LABEL]);

/* Writes the title's status: the scene, "compare", both sides' labels (parts two spaces apart),
 * then "paused" or "finished" when so, joined by separator. The window's thread only. */
void ao_compare_status(struct ao_compare *compare, const char *scene, const char *separator, char *out, size_t size);

/* The width of the image the layout shows for two width x height sides. Pure. */
int ao_compare_width(enum ao_compare_layout layout, int width);

/* Composes the sides a and b (3 floats per pixel, width x height, top row first) into out as the
 * layout shows them: split, columns left of split from a and the others from b; side by side,
 * out twice as wide. Pure. */
void ao_compare_compose(enum ao_compare_layout layout, int split, const float *a, const float *b, int width,
                        int height, float *out);

#endif
