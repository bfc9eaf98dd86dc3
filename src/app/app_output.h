/* What a front end writes: text on stdout (--help, --version) and the output image (-o, PFM, EXR or
 * PNG), with the lines that say what was written. */
#ifndef AO_APP_OUTPUT_H
#define AO_APP_OUTPUT_H

#include <stdbool.h>
#include <stdint.h>

#include "app.h"
#include "cli.h"
#include "frame.h"

/* Writes text (--help, --version) to stdout and flushes it; false after one line on stderr when
 * it cannot (a full disk, a closed stdout). Main thread. */
bool ao_app_print(const char *text);

/* Writes frame to path: PFM or EXR (linear; EXR with the settings in its header) or PNG (through the
 * display code; with a difference reference, the difference view's heat map); false after one
 * message. */
bool ao_app_write_output(const char *path, const struct ao_frame *frame, const char *scene, uint64_t seed,
                         const float *difference);

/* Where no window could be opened (ao_window_run: no display): says on one line that the run goes
 * on headless to -o (aoview.png by default), as a front end does on a machine without a display;
 * false after one line when that -o cannot be written. Main thread. */
bool ao_app_go_headless(const struct ao_options *opts);

/* Writes -o from frame (NULL: none to write, a failure); after an interruption, `why` (what
 * stopped the run) is printed with frame's spp first, and with `last_row` the frame is added as a
 * last --stats row (the render thread must have been joined); a frame of no finished pass
 * (interrupted before its first pass ended: pixels without a sample) is not written, and existing
 * files are left alone. Returns the exit status, `status` when everything was written (or nothing
 * was to be). Main thread. */
int ao_app_write(struct ao_app *app, const struct ao_options *opts, const struct ao_frame *frame, const char *why,
                 bool last_row, int status);

#endif
