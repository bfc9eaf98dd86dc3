/* What aoview's front ends share around a renderer: the process's standard descriptors, loading
 * the scene, tracer and reference from the options, the --stats rows and the progress bar,
 * SIGINT/SIGTERM/SIGHUP, and writing the output. */
#ifndef AO_APP_H
#define AO_APP_H

#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>

#include "cli.h"
#include "progress.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

/* Exit statuses besides 0 and 128 + signal. */
enum { AO_EXIT_RUNTIME = 1, AO_EXIT_USAGE = 2 };

/* The --stats file, shared by the reporters that write rows into it. It is opened before loading
 * without truncating it; the first row truncates it and writes the header, so that a run that
 * finishes no pass leaves an existing file as it was, and removes one it created. */
struct ao_stats {
    FILE *file;
    const char *path;
    atomic_bool created;   /* this run created the file */
    atomic_bool started;   /* the first row came (truncated, header written) */
    atomic_bool wrote;     /* a row reached the file (its flush succeeded) */
    bool failed;           /* a write failed, and was said */
    char header[128];
};

/* What the per-pass callback (ao_app_on_pass) reports to. */
struct ao_reporter {
    struct ao_stats *stats;   /* NULL: no rows */
    const char *side;      /* --compare's "A" or "B": the stats rows' first column; NULL: none */
    struct ao_render *_Atomic render;   /* --compare: the side's renderer, stopped at stop_at */
    double stop_at;        /* --compare: seconds whose nearest pass end ends the side; 0: none */
    double pass_end;       /* seconds at the end of the previous pass */
    atomic_bool progress;  /* a progress bar on stderr (a terminal, not --quiet); set by main while
                              the render thread reads it (the window's no-display fallback) */
    struct ao_progress eta;   /* the bar's time-left estimate */
    double drawn_at;          /* monotonic seconds of the bar's last redraw; 0: never */
    void (*notify)(void);     /* called after each pass (waking a window); NULL: none */
};

/* SIGINT/SIGTERM/SIGHUP: while loading (before ao_app_watch), the first exits at once with one
 * line; then it stops the renderer at the next tile so that the front end writes what it has
 * (graceful), or exits at once (the window: silently, as by default; without a renderer to stop,
 * --compare's sides: with one line); a second exits at once with one line saying whether the
 * output was written. Exiting at once removes the temporary files of writes in progress and a
 * --stats file this run created and got no row into; the status is 128 + the signal. The
 * signals are blocked in every thread and taken by a watcher thread with sigwait, so nothing runs
 * in a signal handler. */
struct ao_interrupt {
    sigset_t signals;
    struct ao_render *_Atomic render;  /* the renderer a graceful signal stops */
    atomic_bool rendering;   /* ao_app_watch was called: loading is over */
    atomic_bool graceful;    /* headless: stop and write; in the window: exit as by default */
    atomic_int caught;
    bool silent;             /* no line when a signal ends the process (aoview-mpi's other ranks) */
    const struct ao_stats *stats;
    const char *output;      /* -o as the lines name it (ao_app_load sets it) */
    atomic_bool writing;     /* ao_app_write began writing the output... */
    atomic_uint written_before;   /* ...when ao_image_written said this */
    pthread_t watcher;       /* the thread that takes the signals... */
    bool watching;           /* ...started by ao_app_start_watcher, not yet ended */
    atomic_bool closing;     /* ao_app_finish is ending the watcher */
};

/* Everything a front end owns around its renderer; zero-initialise, release with ao_app_finish. */
struct ao_app {
    struct ao_scene scene;
    struct ao_tracer *tracer;
    struct ao_render *render;
    float *reference;
    int reference_width, reference_height;
    struct ao_reporter reporter;
    struct ao_stats stats;
    struct ao_interrupt interrupt;
};

/* First thing in main: ignores SIGPIPE (a write to a closed pipe fails and is reported), and opens
 * /dev/null onto whichever of descriptors 0-2 is closed, so that no file opened later becomes
 * stdout or stderr; for reading on 1 and 2 (writing on 0), so that using them fails as before.
 * False after one line (to stderr, if it is open) when /dev/null cannot be opened. */
bool ao_app_begin(void);

/* Writes text (--help, --version) to stdout and flushes it; false after one line on stderr when
 * it cannot (a full disk, a closed stdout). Main thread. */
bool ao_app_print(const char *text);

/* "SIGINT", "SIGTERM" or "SIGHUP" (the signals the watcher takes). */
const char *ao_app_signal_name(int sig);

/* Blocks SIGINT, SIGTERM and SIGHUP (unless SIGHUP is ignored, as nohup leaves it) in the calling
 * thread and every thread it starts from now on. Call before any thread starts, Embree's
 * included. */
void ao_app_block_signals(struct ao_app *app);

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

/* The render config's on_pass: a --stats row, the progress bar, --compare's stop, notify. */
void ao_app_on_pass(const struct ao_frame_info *info, void *user);

/* The render config's on_preview: notify. */
void ao_app_on_preview(const struct ao_frame_info *info, void *user);

/* Mega-rays (eye and shadow) per second of the frame's run. Pure. */
double ao_app_mrays_per_second(const struct ao_frame_info *info);

/* Starts the thread that takes the blocked signals (struct ao_interrupt), before loading; silent:
 * no line when a signal ends the loading. False with a message when it cannot. */
bool ao_app_start_watcher(struct ao_app *app, bool silent);

/* Loading is over: from now on a signal stops render (NULL: none to stop, the signal exits at
 * once) when app->interrupt.graceful is set. Main thread. */
void ao_app_watch(struct ao_app *app, struct ao_render *render);

/* Writes frame to path: PFM or EXR (linear; EXR with the settings in its header) or PNG (through the
 * display code; with a difference reference, the difference view's heat map); false after one
 * message. */
bool ao_app_write_output(const char *path, const struct ao_frame *frame, const char *scene, uint64_t seed,
                         const float *difference);

/* Where no window could be opened (ao_window_run: no display): says on one line that the run goes
 * on headless to -o (aoview.png by default), as a front end does on a machine without a display;
 * false after one line when that -o cannot be written. Main thread. */
bool ao_app_go_headless(const struct ao_options *opts);

/* Waits for app->render to finish; true when it did, false when interrupted (*sig the signal) or
 * stopped otherwise (*sig 0). Main thread. */
bool ao_app_wait(struct ao_app *app, int *sig);

/* Writes -o from frame (NULL: none to write, a failure); after an interruption, `why` (what
 * stopped the run) is printed with frame's spp first, and with `last_row` the frame is added as a
 * last --stats row (the render thread must have been joined); a frame of no finished pass
 * (interrupted before its first pass ended: pixels without a sample) is not written, and existing
 * files are left alone. Returns the exit status, `status` when everything was written (or nothing
 * was to be). Main thread. */
int ao_app_write(struct ao_app *app, const struct ao_options *opts, const struct ao_frame *frame, const char *why,
                 bool last_row, int status);

/* Ends the signal watcher first (a signal from then on is ignored: the process is ending), then
 * destroys the renderer, closes --stats (a failed write turns a status of 0 into AO_EXIT_RUNTIME;
 * a file this run created and got no row into is removed), frees the rest; returns the
 * status. */
int ao_app_finish(struct ao_app *app, int status);

#endif
