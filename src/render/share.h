/* How processes render one image together (aoview-mpi's cluster): the share a renderer is given
 * (struct ao_render_config's share), which it calls to learn which tiles are its own, to lend and
 * borrow tiles during a pass, to combine a few numbers after it and to gather the image. The
 * renderer knows nothing of ranks or messages; cluster.c implements this for MPI. */
#ifndef AO_SHARE_H
#define AO_SHARE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "frame.h"
#include "sum.h"
#include "tile.h"
#include "vec3.h"

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

#endif
