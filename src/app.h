/* What aoview's front ends share around a renderer: loading the scene, tracer and reference from
 * the options, the --stats rows and the progress bar, SIGINT/SIGTERM, and writing the output. */
#ifndef AO_APP_H
#define AO_APP_H

#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>

#include "cli.h"
#include "progress.h"
#include "render.h"
#include "scene.h"
#include "tracer.h"
#include "window.h"

/* Exit statuses besides 0 and 128 + signal. */
enum { AO_EXIT_RUNTIME = 1, AO_EXIT_USAGE = 2 };

/* What the per-pass callback (ao_app_on_pass) reports to. */
struct ao_reporter {
    FILE *stats;
    const char *stats_path;
    const char *side;      /* --compare's "A" or "B": the stats rows' first column; NULL: none */
    struct ao_render *_Atomic render;   /* --compare: the side's renderer, stopped at stop_at */
    double stop_at;        /* --compare: seconds whose nearest pass end ends the side; 0: none */
    double pass_end;       /* seconds at the end of the previous pass */
    atomic_bool progress;  /* a progress bar on stderr (a terminal, not --quiet); set by main while
                              the render thread reads it (the window's no-display fallback) */
    bool stats_failed;
    struct ao_progress eta;   /* the bar's time-left estimate */
    double drawn_at;          /* monotonic seconds of the bar's last redraw; 0: never */
    void (*notify)(void);     /* called after each pass (waking a window); NULL: none */
};

/* SIGINT/SIGTERM: the first stops the renderer at the next tile so that the front end writes what
 * it has (graceful), or exits at once; a second exits at once. The signals are blocked in every
 * thread and taken by a watcher thread with sigwait, so nothing runs in a signal handler. */
struct ao_interrupt {
    sigset_t signals;
    struct ao_render *render;
    atomic_bool graceful;    /* headless: stop and write; in the window: exit as by default */
    atomic_int caught;
};

/* Everything a front end owns around its renderer; zero-initialise, release with ao_app_finish. */
struct ao_app {
    struct ao_scene scene;
    struct ao_tracer *tracer;
    struct ao_render *render;
    float *reference;
    int reference_width, reference_height;
    struct ao_reporter reporter;
    struct ao_interrupt interrupt;
};

/* Blocks SIGINT and SIGTERM in the calling thread and every thread it starts from now on, and
 * ignores SIGPIPE (a write to a closed pipe fails and is reported). Call before any thread starts,
 * Embree's included. */
void ao_app_block_signals(struct ao_app *app);

/* Loads the scene, --reference and tracer, opens --stats with its header, and fills in the renderer's
 * config (its on_pass reporting to app->reporter) and initial settings; 0, or AO_EXIT_RUNTIME
 * after one message. The progress bar is left off. Main thread. */
int ao_app_load(struct ao_app *app, const struct ao_options *opts, struct ao_render_config *config,
                struct ao_settings *settings);

/* The render config's on_pass: a --stats row, the progress bar, --compare's stop, notify. */
void ao_app_on_pass(const struct ao_frame_info *info, void *user);

/* The render config's on_preview: notify. */
void ao_app_on_preview(const struct ao_frame_info *info, void *user);

/* Mega-rays (eye and shadow) per second of the frame's run. Pure. */
double ao_app_mrays_per_second(const struct ao_frame_info *info);

/* Starts the thread that takes the blocked signals for render (NULL: none to stop); false with a
 * message when it cannot. */
bool ao_app_start_watcher(struct ao_app *app, struct ao_render *render);

/* Writes frame to path: PFM or EXR (linear; EXR with the settings in its header) or PNG (through the
 * display code; with a difference reference, the difference view's heat map); false after one
 * message. */
bool ao_app_write_output(const char *path, const struct ao_frame *frame, const char *scene, uint64_t seed,
                         const float *difference);

/* Runs the window on app->render with info until the user quits: true, *status the exit status.
 * False where no window can be opened, after one line saying that the run goes on headless to -o
 * (aoview.png by default), as SPEC.md wants of a machine without a display. Main thread. */
bool ao_app_run_window(struct ao_app *app, const struct ao_options *opts, const struct ao_window_info *info,
                       int *status);

/* Waits for app->render to finish; true when it did, false when interrupted (*sig the signal) or
 * stopped otherwise (*sig 0). Main thread. */
bool ao_app_wait(struct ao_app *app, int *sig);

/* Writes -o from frame (NULL: none to write, a failure); after an interruption, `why` (what
 * stopped the run) is printed with frame's spp first, and with `last_row` the frame is added as a
 * last --stats row (the render thread must have been joined). Returns the exit status, `status`
 * when everything was written. Main thread. */
int ao_app_write(struct ao_app *app, const struct ao_options *opts, const struct ao_frame *frame, const char *why,
                 bool last_row, int status);

/* Destroys the renderer, closes --stats (a failed write turns a status of 0 into AO_EXIT_RUNTIME),
 * frees the rest; returns the status. */
int ao_app_finish(struct ao_app *app, const struct ao_options *opts, int status);

#endif
