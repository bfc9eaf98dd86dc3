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
#include "sum.h"
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
    bool navigating;         /* the camera is being moved (a drag): previews stop at cells of about
                                1/256 of the long side and the run waits there until a restart or
                                until this is cleared, which no restart needs */
    enum ao_output output;   /* AO or the normals view */
    enum ao_shading shading; /* Phong or flat mesh normals */
    struct ao_camera camera;
};

/* Facts about one published frame (one finished pass, or a preview: pass 0). A figure not known
 * yet is NAN, never 0: a preview's error, RMSE and converged share, and the error until both halves
 * have a pass. */
struct ao_frame_info {
    uint64_t restarts;       /* how many times accumulation restarted before this frame */
    uint32_t pass;           /* passes since the last restart, this one included; 0: a preview */
    uint32_t spp;            /* AO samples per pixel since the last restart (the most any pixel has) */
    uint32_t target_spp;
    double target_error;     /* the configuration's, 0 for none */
    double time_limit;       /* the configuration's, 0 for none */
    uint32_t spppp;          /* AO samples per pixel of this pass; 0 before the first */
    double mean_spp;         /* AO samples per pixel, averaged over the image */
    double spp_left;         /* AO samples per pixel still to trace, averaged over the image: what the
                                tiles that join the next pass lack of target_spp (adaptive sampling
                                may leave them sooner); 0 when none joins (the last pass); NAN
                                before the first pass */
    double error;            /* estimated RMSE relative to the image mean, from the even and odd
                                passes without a reference; NAN until both halves have a pass */
    double converged;        /* share of the pixels that adaptive sampling leaves out of the next
                                pass; NAN before the first pass */
    double seconds;          /* render time since the last restart (previews' not counted) */
    uint64_t eye_rays, shadow_rays;
    double rmse;             /* against the reference; NAN without one, and before the first pass */
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
 * an RMSE relative to the image mean, tiles_x per row, top row first; NAN until estimated. A preview
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

/* What processes sharing an image combine after each pass (struct ao_render_share's combine):
 * each fills it in for its own pass and the tiles it owns; combined, every process holds the sums
 * over all of them (`exact` as by ao_sum_merge, `total` as integers) and the maxima (`most`, never
 * negative), from which each makes one process's decisions. */
enum { AO_TALLY_EXACT = 3, AO_TALLY_TOTAL = 5, AO_TALLY_MOST = 8 };
struct ao_share_tally {
    struct ao_sum exact[AO_TALLY_EXACT];
    uint64_t total[AO_TALLY_TOTAL];
    double most[AO_TALLY_MOST];
};

/* A pass as a share sees it on one process: the entries of this process's work list (its own
 * tiles) that other processes trace send their sums to `sums`, entry n's at n x pixels. */
struct ao_share_pass {
    uint64_t serial;         /* numbers the passes alike on every process */
    int count;               /* entries in this process's list */
    int pixels;              /* pixel sums an entry */
    struct ao_vec3 *sums;
    /* How many entries of this process's list are not begun yet. Any thread. */
    int (*left)(void *renderer);
    /* Hands up to `most` entries this process has not begun, from the end of its list, to another
     * process: returns how many (0: none left), the first's number in *first, their tiles and work
     * in tiles and works. Any thread. */
    int (*lend)(void *renderer, int most, int *first, int *tiles, struct ao_tile_work *works);
    void *renderer;
};

/* A tile of another process's that this one traces for it (struct ao_render_share's borrow): its
 * number, its work in this pass, where its pixel sums go (tile-sized, row by row). */
struct ao_share_loan {
    int tile;
    struct ao_tile_work work;
    struct ao_vec3 *sums;
    int ticket;              /* the share's */
};

/* What a share's leader sends before each pass (and the others wait for): the pass, a gather of
 * the image, or the end of the run. */
enum ao_share_step { AO_SHARE_PASS, AO_SHARE_GATHER, AO_SHARE_END };

/* How processes render the same image together (aoview-mpi's cluster.c). Each owns a fixed set of
 * tiles, keeps their accumulation and state and plans its own part of every pass; after a pass
 * they combine a few numbers (struct ao_share_tally), so that every one makes the decisions one
 * process would. One process leads: its settings, restarts and stop decide, and it alone keeps
 * frames, whose pixels it gathers from the owners when a frame is due. A process whose list runs
 * out borrows tiles of another's and sends their sums to the owner. */
struct ao_render_share {
    /* The leader sends `step` (with a pass, *settings and *restarts, which every process renders it
     * with); another process waits for the leader's next step and takes them. AO_SHARE_END when the
     * leader ended the run or the run is being stopped. Render thread. */
    enum ao_share_step (*begin)(void *user, enum ao_share_step step, struct ao_settings *settings,
                                uint64_t *restarts);
    /* Whether tile t of `tiles` is this process's: the same answer on every process for every
     * run, each tile owned once. Whichever thread allocates a run (ao_render_create's, the render
     * thread's on a resize). */
    bool (*owns)(void *user, int tile, int tiles);
    /* Before each tile of a pass (any render thread): lends entries to processes that ask, and
     * sets [arrived[0], arrived[1]) to entries whose sums came back, for this thread to add; false
     * once the pass is given up somewhere or the run stops. */
    bool (*poll)(void *user, const struct ao_share_pass *pass, int arrived[2]);
    /* When this process's list is empty (any render thread): a tile to trace for another process,
     * or false when the pass has none left to lend or is given up. */
    bool (*borrow)(void *user, const struct ao_share_pass *pass, struct ao_share_loan *loan);
    /* The loan's sums are traced: they go to its owner. Any render thread. */
    void (*repay)(void *user, const struct ao_share_pass *pass, const struct ao_share_loan *loan);
    /* After this process's part of a pass, `finished` or given up (which the others are told, so
     * that they stop tracing it): waits for the sums of the entries it lent, a range at a time into
     * arrived (empty once all are back), as poll; false when the run stops. Render thread. */
    bool (*settle)(void *user, const struct ao_share_pass *pass, bool finished, int arrived[2]);
    /* After every pass: combines tally over the processes, in place; false when the run stops.
     * Render thread. */
    bool (*combine)(void *user, struct ao_share_tally *tally);
    /* Sums each of values[0..count) over the processes, in place; false as combine. Render thread. */
    bool (*add_up)(void *user, uint64_t *values, int count);
    /* The leader, after a pass: whether a frame is due by the share's clock (a window's frame rate,
     * a safety copy); the renderer also gathers for the last pass and before it idles. Render thread. */
    bool (*due)(void *user);
    /* Gathers the image: `count` records of `size` bytes, this process's tiles' in tile order, go to
     * the leader, which receives every tile's (`tiles` of them, in tile order) in all (NULL
     * elsewhere); false when the run stops. Render thread, or main after ao_render_resolve_stopped
     * joined it. */
    bool (*gather)(void *user, const void *mine, int count, size_t size, void *all, int tiles);
    /* The render thread is ending (stopped): the leader tells the others. Render thread. */
    void (*end)(void *user);
    bool follows;            /* not the leader: waits in begin, not for its own settings or pause;
                                keeps no frames and is never done by itself */
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

/* Copies the facts of up to `most` frames published since the last call (passes and previews,
 * those never taken included; frames.h's AO_FRAMES_LOG at most wait) into out, oldest first; returns
 * how many. The frame consumer's thread. */
int ao_render_take_log(struct ao_render *render, struct ao_frame_info *out, int most);

/* Blocks until the target spp is reached (true) or ao_render_stop was called or, with a share, the
 * leader ended the run (false: a follower is never done by itself). */
bool ao_render_wait(struct ao_render *render);

/* After an interruption: stops and joins the render thread, then resolves the accumulation as it
 * stands, the aborted pass's finished tiles included, into a frame whose info.spp is the most
 * samples a pixel has (as after every pass) and info.mean_spp their mean, both counted from the
 * pixels. With a share every process calls it: each sends its tiles through the
 * share's gather, and the leader gets the frame (NULL elsewhere, and when the gather failed).
 * Main thread, as the frame consumer; call ao_render_destroy afterwards. */
const struct ao_frame *ao_render_resolve_stopped(struct ao_render *render);

/* Asks the render thread to stop at the next tile boundary and wakes ao_render_wait. Any thread. */
void ao_render_stop(struct ao_render *render);

#endif
