/* A front end's process around the renderer: its standard descriptors and SIGPIPE at the start,
 * then SIGINT, SIGTERM and SIGHUP taken by a watcher thread (struct ao_interrupt, app.h), which
 * ends the process or stops the renderer. */
#ifndef AO_APP_SIGNALS_H
#define AO_APP_SIGNALS_H

#include <stdbool.h>

#include "app.h"

/* First thing in main: ignores SIGPIPE (a write to a closed pipe fails and is reported), and opens
 * /dev/null onto whichever of descriptors 0-2 is closed, so that no file opened later becomes
 * stdout or stderr; for reading on 1 and 2 (writing on 0), so that using them fails as before.
 * False after one line (to stderr, if it is open) when /dev/null cannot be opened. */
bool ao_app_begin(void);

/* "SIGINT", "SIGTERM" or "SIGHUP" (the signals the watcher takes); "a signal" for any other. */
const char *ao_app_signal_name(int sig);

/* Blocks SIGINT, SIGTERM and SIGHUP (unless SIGHUP is ignored, as nohup leaves it) in the calling
 * thread and every thread it starts from now on. Call before any thread starts, Embree's
 * included. */
void ao_app_block_signals(struct ao_app *app);

/* Starts the thread that takes the blocked signals (struct ao_interrupt), before loading; silent:
 * no line when a signal ends the loading. False with a message when it cannot. */
bool ao_app_start_watcher(struct ao_app *app, bool silent);

/* Loading is over: from now on a signal stops render (NULL: none to stop, the signal exits at
 * once) when app->interrupt.graceful is set. Main thread. */
void ao_app_watch(struct ao_app *app, struct ao_render *render);

/* Waits for app->render to finish; true when it did, false when interrupted (*sig the signal) or
 * stopped otherwise (*sig 0). Main thread. */
bool ao_app_wait(struct ao_app *app, int *sig);

/* Ends the watcher, if started, without a signal taking effect: a signal from then on is ignored
 * (the process is ending). Joined on return, so the renderer it may stop can be destroyed. Main
 * thread. */
void ao_app_stop_watcher(struct ao_interrupt *interrupt);

#endif
