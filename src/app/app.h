/* What a front end (aoview, aoview-mpi) owns around its renderer, and the exit statuses: types
 * only, shared by the rooms that act on them: app_report.h (the --stats rows and the progress
 * bar), app_output.h (writing the output), app_signals.h (the signal watcher), app_load.h (loading
 * the scene, tracer and reference, and releasing them). */
#ifndef AO_APP_H
#define AO_APP_H

#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>

#include "progress.h"
#include "scene.h"

struct ao_render;
struct ao_tracer;

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

#endif
