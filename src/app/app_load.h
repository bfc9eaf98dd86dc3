/* A front end's run from its options: the files checked before and after loading, the scene,
 * --reference, tracer and --stats loaded, the renderer's config filled in, and all of it released
 * at the end. */
#ifndef AO_APP_LOAD_H
#define AO_APP_LOAD_H

#include <stdbool.h>
#include <stddef.h>

#include "app.h"
#include "cli.h"
#include "frame.h"
#include "render_config.h"

/* Before loading: the files the run writes (-o, or --compare's two, when given or headless: `outputs`
 * of them, and --stats) are none of those it reads (the scene, --reference) nor one another, compared
 * as files (through links, existing or to be made in a folder); false after one line naming both.
 * Main thread. */
bool ao_app_check_files(const struct ao_options *opts, const char *const *outputs, size_t count);

/* Opens --stats (struct ao_stats), loads the scene, --reference and tracer, and fills in the
 * renderer's config (its on_pass reporting to app->reporter) and initial settings; 0, or
 * AO_EXIT_RUNTIME after one message. Once the scene is loaded, -o (headless or given) and --stats
 * must not be any file it read (a mesh, a glTF buffer). The progress bar is left off. Main thread. */
int ao_app_load(struct ao_app *app, const struct ao_options *opts, struct ao_render_config *config,
                struct ao_settings *settings);

/* Ends the signal watcher first (a signal from then on is ignored: the process is ending), then
 * destroys the renderer, closes --stats (a failed write turns a status of 0 into AO_EXIT_RUNTIME;
 * a file this run created and got no row into is removed), frees the rest; returns the
 * status. */
int ao_app_finish(struct ao_app *app, int status);

#endif
