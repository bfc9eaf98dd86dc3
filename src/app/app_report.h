/* What a front end reports as its renderer runs: the --stats file's rows, the progress bar on
 * stderr, --compare's equal-time stop, and the rays' rate they show. */
#ifndef AO_APP_REPORT_H
#define AO_APP_REPORT_H

#include <stdbool.h>

#include "app.h"
#include "frame.h"

/* Opens path as the --stats file (struct ao_stats: not truncated until the first row) for rows with
 * a first column "side" (--compare) and an "rmse" column (--reference); false after one line.
 * Main thread, before loading. */
bool ao_app_open_stats(struct ao_stats *stats, const char *path, bool sides, bool rmse);

/* Closes the --stats file, if open, and removes it if this run created it and got no row into it
 * (none, or none whole: a full disk); false when a write failed (said once). Main thread, the
 * reporters' threads joined. */
bool ao_app_close_stats(struct ao_stats *stats);

/* The render config's on_pass (user: a struct ao_reporter): a --stats row, the progress bar,
 * --compare's stop, notify. The render thread (or main, for a last row once it is joined). */
void ao_app_on_pass(const struct ao_frame_info *info, void *user);

/* The render config's on_preview: notify. */
void ao_app_on_preview(const struct ao_frame_info *info, void *user);

/* Mega-rays (eye and shadow) per second of the frame's run. Pure. */
double ao_app_mrays_per_second(const struct ao_frame_info *info);

#endif
