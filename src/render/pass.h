/* A run of the renderer and its passes: the accumulation between two restarts with its tiles, work
 * list and frames (struct ao_run), and one pass over it, planned from the last one's survey, traced
 * by the thread team, surveyed (the error estimate, RMSE, whether the run is done) and published.
 * And the run share, the way its passes meet other processes' (none: the solo share). Private to
 * the renderer: render.c drives passes from its thread, solo.c and render_share.c are its shares;
 * neither the frames' consumers nor the cluster see this header. */
#ifndef AO_PASS_H
#define AO_PASS_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "accum.h"
#include "ao.h"
#include "frame.h"
#include "frames.h"
#include "pool.h"
#include "render_config.h"
#include "share.h"
#include "tile.h"

/* --spppp auto: each pass of a half (even, odd) takes AO_AUTO_PER_RAY samples, then doubles what that
 * half's sequence has given (ao_tile_work_of), up to about AO_AUTO_SAMPLES samples over the pixels it
 * traces (8 spp a pass at 640x480, 128 at 160x120) but never less than one round, in rounds of one
 * eye ray with AO_AUTO_PER_RAY AO samples; both chosen by time to 1 % and 0.5 % RMSE
 * (docs/adaptive.md, docs/estimator.md). The schedule depends on samples, not on
 * seconds, so that the image stays a function of the seed and settings alone. */
enum { AO_AUTO_SAMPLES = 1 << 22, AO_AUTO_PER_RAY = 8 };

/* A thread's share of a pass: the tiles of the pass's work list in tile rows k, k + threads,
 * k + 2 threads, ... for thread k, taken in order from `next`. Each thread keeps the same pixels
 * pass after pass, so their sums stay in its own cache (handed round between threads, they crossed
 * caches on every pass); a thread that has finished its lane helps with the others'. */
struct ao_lane {
    _Alignas(64) atomic_int next;        /* a line of its own: the other threads take from it too */
    int begin, end;                      /* its tiles in the work list */
};

struct ao_run;

/* What a pass is rendered with: the settings, the restarts (the generation of the sums: with an
 * aoview-mpi share, the leader's) and `own`, this renderer's restarts when it was taken, which a
 * later restart aborts. */
struct ao_pass_start {
    struct ao_settings settings;
    uint64_t own, restarts;
};

/* What a share may ask of the render thread's loop (render.c's, each under its lock): whether the
 * settings pause; when a pass is due now (neither stopped nor idle after the pass of info), its
 * start, taken into *p; whether the loop rests after a pass (not stopped, and done: `finishes`
 * at restarts `own`, or idle). Render thread. */
struct ao_run_loop {
    bool (*paused)(void *render);
    bool (*take)(void *render, const struct ao_frame_info *info, struct ao_pass_start *p);
    bool (*rests)(void *render, const struct ao_frame_info *info, bool finishes, uint64_t own);
    void *render;
};

/* How the passes of a run meet the other processes rendering the same image: the solo share
 * (solo.c) does nothing, one process renders every tile; render_share.c runs them with an
 * aoview-mpi share (share.h) and keeps that share's state. pass.c and render.c call these hooks on
 * the render thread, the loop's in its order: begin, run, publish, rest; end when it stops. */
struct ao_run_share {
    /* The share paces the passes (an aoview-mpi follower: the leader's): this renderer's own pause
     * and target neither hold nor end its loop, which the share's begin ends. */
    bool paced;
    /* The work list in row order, as loans take it, not dealt to the threads' lanes. */
    bool one_list;
    /* A run of `tiles` tiles begins (at ao_pass_restart); false with one message when memory is
     * short. */
    bool (*restart)(struct ao_run_share *s, int tiles);
    /* Whether tile t of the run is this process's, to plan, trace and keep. */
    bool (*owns)(const struct ao_run_share *s, int tile);
    /* Sums each of values[0..count) over the processes, in place; false when the run stops. */
    bool (*add_up)(struct ao_run_share *s, uint64_t *values, int count);
    /* The seconds spent in the share's waits since the last combine, which count in this pass. */
    double (*waited)(struct ao_run_share *s);
    /* Combines tally over the processes, in place; false when the run stops. */
    bool (*combine)(struct ao_run_share *s, struct ao_share_tally *tally);
    /* Begins the pass p (taken from the loop; info the last pass's facts) on every process: may
     * replace it with another start (the leader's, one begun already); false when the share ended
     * the run. */
    bool (*begin)(struct ao_run_share *s, struct ao_run *run, struct ao_pass_start *p,
                  const struct ao_frame_info *info);
    /* Whether a pass was begun already, which the loop runs whatever the settings. */
    bool (*begun)(const struct ao_run_share *s);
    /* Runs the pass readied (ao_pass_prepare); false when it was aborted or given up. */
    bool (*run)(struct ao_run_share *s, struct ao_run *run);
    /* After a pass that counts (run with settings, its facts info): publishes it where frames are
     * kept and reports it (config's on_pass); false when the run must stop; *ending when the share
     * ended the run after it (the pass is still reported). */
    bool (*publish)(struct ao_run_share *s, struct ao_run *run, const struct ao_settings *settings,
                    const struct ao_frame_info *info, bool *ending);
    /* After every pass (of settings, own its restarts; *finishes whether it ended the run): what
     * is due before the loop rests; false when the share stops or memory is short. */
    bool (*rest)(struct ao_run_share *s, struct ao_run *run, const struct ao_settings *settings,
                 const struct ao_frame_info *info, bool finishes, uint64_t own);
    /* After an interruption, the render thread joined: the accumulation as it stands as a frame
     * (see ao_render_resolve_stopped); NULL where frames are not kept or the share failed. Main. */
    struct ao_frame *(*stopped)(struct ao_run_share *s, struct ao_run *run, const struct ao_frame_info *info);
    /* The render thread ends. */
    void (*end)(struct ao_run_share *s);
    /* Frees the share's state; the solo share's does nothing. */
    void (*destroy)(struct ao_run_share *s);
};

/* The pass in flight: written by the render thread before the team runs it, read by the team,
 * which adds to the ray counts atomically. */
struct ao_pass {
    struct ao_pool *pool;                /* the thread team that traces it */
    uint64_t serial;                     /* numbers the passes */
    struct ao_context ctx;
    uint64_t restarts;                   /* the restarts it was begun at: another count aborts it */
    struct ao_tile_pass tile_pass;       /* what the pass gives each tile */
    int *work;                           /* its tiles, grouped by lane: the run's tiles at most */
    struct ao_lane *lanes;               /* one per thread, the render thread's first */
    atomic_uint_fast64_t eye_rays, shadow_rays;
};

/* A run: the accumulation between two restarts, its tiles and frames, what the last survey planned
 * and the pass in flight. Owned by the render thread; the team's threads write disjoint tiles. */
struct ao_run {
    struct ao_render_config config;
    int width, height;                   /* of the accumulation: the size of the current run */
    struct ao_accum accum;               /* render thread (and its team, pixel-disjoint) only */
    struct ao_frames frames;             /* to the consumer */
    struct ao_run_share *share;          /* how its passes meet other processes' (above) */
    atomic_uint_fast64_t live_restarts;  /* the renderer's restarts and stop, for the tile loop */
    atomic_bool live_stop;

    int tiles_x, tiles_y;
    struct ao_tile_state *tiles;         /* tiles_x * tiles_y, row by row */
    uint64_t *tile_stamps;               /* per tile: the stamp of its sums' last change */
    uint64_t stamp;                      /* of the changes made now: a fresh one from each frame begun
                                            and each frame resolved on */
    uint64_t run_stamp;                  /* the run's first: frames stamped before show another run */
    struct ao_frame *frame;              /* the back frame begun for the passes since the last
                                            resolve, into which each change is resolved as it is made
                                            (NULL: none) */
    uint64_t frame_kept;                 /* the stamp its pixels had when it was begun */
    double image_mean;                   /* of the running average, as of the last survey */

    /* What the last survey planned (or a restart: nothing sampled yet), for select_tiles (pass.c) and the
     * next pass's size: the busiest tile's spp and the largest gain among the tiles short of the
     * target, and the pixels the next pass traces without and with adaptive sampling (known[k]:
     * counted; with adaptive sampling off the survey counts only the first). */
    uint32_t busiest;
    double fastest;
    uint64_t next[2];
    bool next_known[2];

    struct ao_pass pass;                 /* the pass in flight */
};

/* Allocates the accumulation, tile states and work lists of a run of r->width x r->height; false
 * with one message when memory is short (ao_pass_free frees what was made). */
bool ao_pass_allocate(struct ao_run *r);

/* Frees what ao_pass_allocate allocated; accepts what it left half done. */
void ao_pass_free(struct ao_run *r);

/* Begins a run at width x height (the accumulation reallocated when the size changed): every tile
 * state cleared (the sums follow, tile by tile: ao_pass_add_tile) and every tile planned into the
 * first pass; false with one message when memory is short. Render thread. */
bool ao_pass_restart(struct ao_run *r, int width, int height);

/* True once the pass in flight is aborted: the renderer stops, or restarted since it was begun.
 * Any thread of the team. */
bool ao_pass_aborted(const struct ao_run *r);

/* The pixels of tile t, clipped to the image. */
struct ao_tile ao_pass_tile_rect(const struct ao_run *r, int t);

/* The part of its pixels' streams tile t traces in this pass. */
struct ao_tile_work ao_pass_tile_work(const struct ao_run *r, int t);

/* Adds tile t's sums of one pass (the work it was given) to the accumulation and brings its state
 * up to date, stamped for ao_pass_resolve (and resolved into the frame begun, while its sums are in
 * this core's cache). The thread that traced it. */
void ao_pass_add_tile(struct ao_run *r, int t, const struct ao_tile_work *work, const struct ao_vec3 *sums);

/* Clears tile t's sums (a tile not traced in this run, whose sums an earlier run left). Render
 * thread, between passes. */
void ao_pass_clear_tile(struct ao_run *r, int t);

/* Traces entry n of the work list and adds its sums, unless the pass was aborted while it traced
 * them (the tile is left as it was); adds the rays traced to *eye and *shadow. */
void ao_pass_render_tile(struct ao_run *r, int n, uint64_t *eye, uint64_t *shadow);

/* Readies the pass's counters (every lane from its first entry) and numbers it; returns the entries of the work list. Render thread. */
int ao_pass_begin(struct ao_run *r);

/* Runs one pass on every thread of the team, each from its lane (the solo share's run); false
 * when it was aborted. Render thread. */
bool ao_pass_run(struct ao_run *r);

/* The pixels of the next pass with adaptive sampling (`adaptive`) or without: as the last survey
 * planned it, or planned here (over the processes: every one takes the same path). False when the
 * share stops. Render thread. */
bool ao_pass_plan(struct ao_run *r, bool adaptive, uint64_t *pixels);

/* What a pass this process ran gives its survey: whether it finished it (not aborted nor given
 * up), its eye and shadow rays, its seconds and the most samples per pixel a tile of it took
 * (ao_pass_prepare's). */
struct ao_pass_result {
    bool finished;
    uint64_t rays[2];
    double seconds;
    uint32_t spppp;
};

/* After a pass this process ran (finished or not), with what it gave: combines the tally over the processes (the run's share), adds the pass's rays and
 * seconds to info and, when every process finished it, fills in info's per-pixel counts, error
 * estimate, RMSE, converged share and whether the run is done, keeps the image mean and plans the
 * next pass. *counts: whether the pass counts; false when the share stops. Render thread. */
bool ao_pass_survey(struct ao_run *r, struct ao_frame_info *info, bool adaptive, const struct ao_pass_result *pass,
                    bool *counts);

/* Readies the planned pass of `pixels` pixels (ao_pass_plan) with settings s: fills the work list
 * with the tiles of this process's (every tile with the solo share) that it traces, the tiles
 * ao_tile_wanted picks with the busiest tile's spp and the largest gain the last survey found,
 * dealt to the lanes by tile row, and sets what it gives each tile (its samples: the setting, or
 * --spppp auto's schedule). Returns the most samples per pixel a tile of it takes. Render thread. */
uint32_t ao_pass_prepare(struct ao_run *r, const struct ao_settings *s, uint64_t pixels);

/* Whether the reference (if any) has the image's size: the RMSE is taken only then. */
bool ao_pass_has_reference(const struct ao_run *r);

/* Tile t's estimated error, as struct ao_frame's tile_error holds it: NAN until both halves of the
 * tile have a pass. */
float ao_pass_tile_error(const struct ao_run *r, int t);

/* Frame f's facts for a whole image of this run, info's included. */
void ao_pass_frame_facts(const struct ao_run *r, struct ao_frame *f, const struct ao_frame_info *info);

/* Resolves the running average into the back frame with its tile errors and info; the frame, or
 * NULL when memory is short. Render thread (or main once it joined it). */
struct ao_frame *ao_pass_resolve(struct ao_run *r, const struct ao_frame_info *info);

/* Publishes the pass just surveyed; false when memory is short. Render thread. */
bool ao_pass_publish(struct ao_run *r, const struct ao_frame_info *info);

#endif
