/* The render thread: progressive AO passes over tiles on worker threads into an accumulation
 * buffer it alone owns, each finished pass published as a frame through a lock-free triple buffer. */
#ifndef AO_RENDER_H
#define AO_RENDER_H

#include <stdbool.h>
#include <stdint.h>

#include "ao.h"
#include "camera.h"
#include "sampling.h"
#include "scene.h"
#include "tracer.h"

/* What the user can change while rendering. */
struct ao_settings {
    int width, height;       /* image size in pixels (the window's, or --size) */
    enum ao_sampling sampling;
    bool aa;
    int spppp;               /* AO samples per pixel per pass; 0: auto (render.c's schedule) */
    bool adaptive;           /* samples go where the estimated error is (render.c) */
    bool paused;
    bool previews;           /* coarse frames after each restart (preview.h), for a window's eye */
    enum ao_output output;   /* AO or the normals view */
    enum ao_shading shading; /* Phong or flat mesh normals */
    struct ao_camera camera;
};

/* Facts about one published frame (one finished pass). */
struct ao_frame_info {
    uint64_t restarts;       /* how many times accumulation restarted before this frame */
    uint32_t pass;           /* passes since the last restart, this one included */
    uint32_t spp;            /* AO samples per pixel since the last restart (the most any pixel has) */
    uint32_t target_spp;
    double target_error;     /* the configuration's, 0 for none */
    double time_limit;       /* the configuration's, 0 for none */
    uint32_t spppp;          /* AO samples per pixel of this pass */
    double mean_spp;         /* AO samples per pixel, averaged over the image */
    double error;            /* estimated RMSE relative to the image mean, from the even and odd
                                passes without a reference; NAN until both halves have a pass */
    double converged;        /* share of the pixels that adaptive sampling leaves out of the next pass */
    double seconds;          /* wall time since the last restart */
    uint64_t eye_rays, shadow_rays;
    double rmse;             /* against the reference; NAN without one */
    enum ao_sampling sampling;
    bool aa;
    enum ao_output output;
    enum ao_shading shading;
    bool done;               /* spp reached target_spp, or the estimated error reached target_error,
                                or seconds reached time_limit, or adaptive sampling found nothing
                                left to sample */
};

/* A published frame: the running average, 3 linear floats per pixel, top row first, and the
 * estimated error of each tile of tile x tile pixels (the unit adaptive sampling decides on), as
 * an RMSE relative to the image mean, tiles_x per row, top row first; 0 until estimated. A preview
 * (block > 1, preview.h) holds width x height cells of block x block pixels of an image_width x
 * image_height image, its info that of the run it begins (pass 0), and no tile errors. */
struct ao_frame {
    struct ao_frame_info info;
    int width, height;
    float *rgb;
    int tile, tiles_x, tiles_y;
    float *tile_error;
    int block;
    int image_width, image_height;
};

/* A pass as the processes sharing it number it alike: its work list has `count` entries, whose
 * sums go to sums, `pixels` pixel sums an entry. */
struct ao_share_pass {
    uint64_t serial;
    int count;
    struct ao_vec3 *sums;
    int pixels;
};

/* How processes rendering the same image split each pass (aoview-mpi's cluster.c): one process
 * leads (its settings, restarts and stop decide), the others follow; each traces the work-list
 * entries it claims, the followers send the leader the sums of theirs as they trace them, the
 * leader accumulates every entry, and the followers, which keep no image, take its tile states
 * with each pass's settings, so that every process plans the same passes. */
struct ao_render_share {
    /* Before each pass: replaces *settings and *restarts (this process's own) by those every
     * process renders the pass with, the leader's, which a follower waits here for; false when
     * the leader ended the run or it is being stopped. Render thread. */
    bool (*begin)(void *user, struct ao_settings *settings, uint64_t *restarts);
    /* After begin, unless the pass restarts accumulation: replaces a follower's tile states (size
     * bytes at tiles, what passes are planned from) by the leader's; false as begin. Render thread. */
    bool (*states)(void *user, void *tiles, size_t size);
    /* The next entry of the pass's work list for this process to trace, or -1 when none is left;
     * `traced` is the entry this thread traced since its last claim of the pass, or -1 (a
     * follower sends the sums of what it was given once it is traced). On the leader, entries
     * [arrived[0], arrived[1]) of the pass's sums came from another process, for this thread to
     * add (empty when none). Any render thread. */
    int (*claim)(void *user, const struct ao_share_pass *pass, int traced, int arrived[2]);
    /* At the end of a pass this process finished (or gave up: a restart or stop): waits until the
     * sums of the other processes' entries are in the leader's pass sums, adds their rays (eye,
     * shadow) to the leader's rays, and sets seconds to the largest over the processes; true
     * when the pass counts, false when a process gave it up or the run is being stopped. Render
     * thread. */
    bool (*merge)(void *user, const struct ao_share_pass *pass, bool finished, uint64_t rays[2], double *seconds);
    /* The render thread is ending (stopped): the leader tells the followers. Render thread. */
    void (*end)(void *user);
    bool follows;            /* a follower: waits in begin, not for its own settings or pause; keeps
                                no image (publishes no frame) and is never done by itself */
    void *user;
};

/* How to render; scene, tracer, reference and share must outlive the renderer. The image size is
 * a setting (struct ao_settings). */
struct ao_render_config {
    const struct ao_scene *scene;
    const struct ao_tracer *tracer;
    int threads;
    uint64_t seed;
    uint32_t target_spp;     /* per pixel; with adaptive sampling the most a pixel gets */
    double target_error;     /* stop when the estimated relative RMSE is at most this; 0: never */
    double time_limit;       /* stop at the first pass boundary after this many seconds; 0: never */
    float ao_distance;
    enum ao_sequence sequence;   /* random or Sobol numbers for jitter and directions */
    enum ao_below below;         /* directions below the geometric surface */
    const float *reference;  /* reference_width x reference_height x 3 linear floats, or NULL; the
                                RMSE is taken while the image has its size */
    int reference_width, reference_height;
    /* Called on the render thread after each published pass (stats rows, waking the GL thread). */
    void (*on_pass)(const struct ao_frame_info *info, void *user);
    /* Called on the render thread after each published preview, with the facts of the run it
     * begins (waking the GL thread); may be NULL. */
    void (*on_preview)(const struct ao_frame_info *info, void *user);
    void *user;
    const struct ao_render_share *share;   /* NULL: this process traces every tile */
};

/* The renderer; opaque. */
struct ao_render;

/* Allocates buffers, starts the render thread and its workers with the initial settings; NULL with
 * one message on stderr when memory or threads are short. Call from the main thread. */
struct ao_render *ao_render_create(const struct ao_render_config *config,
                                   const struct ao_settings *settings);

/* Stops the pass in flight at the next tile, joins every thread, frees everything; accepts NULL. */
void ao_render_destroy(struct ao_render *render);

/* Copies the current settings into *out. Any thread. */
void ao_render_get_settings(struct ao_render *render, struct ao_settings *out);

/* Applies new settings: a change of size, sampling, AA, output, shading or camera aborts the pass in flight and
 * restarts accumulation (and returns true); spppp and pause take effect at the next pass boundary. Any thread. */
bool ao_render_set_settings(struct ao_render *render, const struct ao_settings *settings);

/* Restarts accumulation with the current settings, aborting the pass in flight. Any thread. */
void ao_render_restart(struct ao_render *render);

/* The newest frame published since the last call, or NULL when none is new; the frame stays valid
 * until the next call. One consumer thread only (the GL thread, or main when headless). */
const struct ao_frame *ao_render_take_frame(struct ao_render *render);

/* Blocks until the target spp is reached (true) or ao_render_stop was called or, with a share, the
 * leader ended the run (false: a follower is never done by itself). */
bool ao_render_wait(struct ao_render *render);

/* After an interruption: stops and joins the render thread, then resolves the accumulation as it
 * stands, the aborted pass's finished tiles included (with a share, those the leader added: its own
 * and those whose sums arrived), into a frame whose info.spp is the smallest per-pixel sample count.
 * Main thread, as the frame consumer; call ao_render_destroy afterwards. */
const struct ao_frame *ao_render_resolve_stopped(struct ao_render *render);

/* Asks the render thread to stop at the next tile boundary and wakes ao_render_wait. Any thread. */
void ao_render_stop(struct ao_render *render);

#endif
