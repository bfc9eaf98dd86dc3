/* The state of an aoview-mpi run's cluster (struct ao_cluster) and what its files share: the loans
 * and the waits that serve them (cluster_loans.c), the faults and interruptions
 * (cluster_faults.c), the life cycle and collectives (cluster.c). Four communicators keep the
 * kinds of traffic apart, since they come from different threads: passes (the render thread's
 * begins and collectives), loans (any render thread: asks, lends, repaid sums, given-up passes),
 * images (the gathers) and control (the listener and main: interruptions, the summary at the end).
 * Private to those three files, the only ones that include mpi.h. */
#ifndef AO_CLUSTER_STATE_H
#define AO_CLUSTER_STATE_H

#include <mpi.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "share.h"

/* The tags of the cluster's point-to-point messages. */
enum { TAG_ASK = 1, TAG_LEND, TAG_REPAY, TAG_GIVE_UP, TAG_GATHER, TAG_SALVAGE, TAG_ANSWER, TAG_STOP, TAG_RELEASE };

/* A rank waiting for a message or a collective tests its request without sleeping for SPIN_NS,
 * which most waits at the ends of passes take (a sleep's wake-up alone costs more), then sleeps
 * 50 us, doubling up to 1 ms while nothing comes: it leaves the cores to the render threads, at a
 * cost of at most 1 ms a wait. A rank waiting for rank 0 to begin a pass sleeps up to POLL_IDLE_NS
 * once it has waited IDLE_AFTER_NS: rank 0 may be paused or done, for as long as its window stays
 * open. The listener looks for interruptions every LISTEN_NS. */
enum {
    SPIN_NS = 200000, POLL_FIRST_NS = 50000, POLL_MOST_NS = 1000000, POLL_IDLE_NS = 20000000,
    IDLE_AFTER_NS = 50000000, LISTEN_NS = 10000000
};

/* Render threads look at the loans (asks to answer, sums come back, a pass given up) at most every
 * LOOK_NS, before a tile: a look takes the lock and tests three requests. */
enum { LOOK_NS = 100000 };

/* A lend carries at most LEND_MOST entries (one message of 9 kB): of what the lender has not begun,
 * the borrower's share of the two ranks' speed (entries a second, measured in the pass, or in the
 * last one early on), so that both finish together and one or two loans balance a pass whatever
 * the ratio (half each time took log2 of the ratio round trips, each waiting for the slow rank's
 * next tile). A rank that was told "none" by MISSES ranks in a row (or by every other rank)
 * borrows no more in that pass. The lenders are taken in a row from a random start, so that
 * borrowers spread over the ranks. */
enum { LEND_MOST = 256, MISSES = 4 };

/* What a lend carries: a header, then its entries. */
struct lend_header {
    uint64_t pass;
    int32_t first, count;
};
struct lend_entry {
    int32_t tile;
    struct ao_tile_work work;
};
enum { LEND_BYTES = sizeof(struct lend_header) + LEND_MOST * sizeof(struct lend_entry) };

/* A range of this rank's list lent to another rank, whose sums come back packed (pack.h) and are
 * unpacked into the pass's sums. */
struct lent {
    int first, count;
    unsigned char *packed;   /* the receive's buffer, until the sums are unpacked */
    bool reported;           /* handed to the renderer to add */
};

/* The cluster (cluster.h): its communicators, the loans' state, rank 0's accounting, the
 * interruptions' requests. */
struct ao_cluster {
    struct ao_render_share share;
    int rank, size;
    MPI_Comm passes, loans, images, control;
    MPI_Datatype tally_type;
    MPI_Op tally_op;
    atomic_bool stopping;
    bool ended;              /* rank 0's END arrived */
    long delay_ns;           /* tests only: AO_MPI_TEST_DELAY_US before each tile, a slow rank */

    /* Rank 0's gathers by the clock (set from main), and the last one's end. */
    _Atomic double interval;
    double last_gather;

    /* Loans, under `lock`: the pass this rank traces and whether it is open to lend, given up
     * (the newest pass any rank gave up), and told (this rank told the others it gives it up). */
    pthread_mutex_t lock;
    atomic_llong looked;     /* when a render thread last looked at the loans, ns */
    uint64_t pass, given_up;
    atomic_uint_fast64_t opened;  /* a copy of pass, for a look without the lock */
    const struct ao_share_pass *current;
    bool open, told;
    /* As a lender: the ranges lent in this pass and their sums' receives. */
    struct lent *lent;
    MPI_Request *lent_requests;
    int lent_count, lent_capacity, lent_entries;
    /* Asks for a later pass, from ranks already in it: answered when this rank gets there. */
    struct {
        int rank;
        uint64_t pass, speed;
    } *deferred;
    int deferred_count;
    uint64_t ask[2];         /* the ask being received (pass, the asker's speed as double bits) and
                                the give-up (pass) */
    uint64_t give_up;
    MPI_Request asked, gave_up;
    /* Speeds: when the pass opened here and when this rank's list ran out (0: not yet), and the
     * entries a second its threads traced in the last pass (0: unknown). */
    double opened_at, emptied_at, speed;
    /* As a borrower: the victim asked (-1: none), the answer, the rank's misses, the grant held
     * (entries handed out to threads, and traced) and its sums, sent when all are traced. */
    int victim, misses, start;
    bool exhausted, holding;
    unsigned char *answer;
    MPI_Request answering;
    int owner, first, count, handed, repaid;
    struct ao_vec3 *loan_sums;
    unsigned char *repay_packed;  /* loan_sums packed, while their send is in flight */
    MPI_Request repaying;
    uint64_t tiles;          /* tiles this rank traced: its own and borrowed */

    /* Rank 0's accounting: passes combined, bytes in and out besides gathers, gathers and their
     * bytes, seconds in collectives and gathers. */
    uint64_t passes_combined, gathers;
    double bytes_in, bytes_out, gather_bytes, seconds;  /* render thread (or main after it) */
    double loan_in, loan_out;                           /* under `lock` */
    _Atomic double copied;   /* when the last gather ended; 0: none yet */
    int fan;                 /* ceil(log2 size): the rounds of a tree or recursive-doubling collective */

    /* Interruptions: the listener thread, rank 0's answers (the signal of each, -1 until it came),
     * the others' stop request and rank 0's release; the salvage gather's deadline. */
    pthread_t listener;
    bool listening;
    atomic_bool listen;
    void (*stopped)(void *user);
    void *stopped_user;
    MPI_Request *answers, halt, released;
    int *signals, halt_word, release_word;
    bool halted;
    int first_stop;          /* rank 0: the rank whose answer the listener heard first (0: none) */
    double salvage_until;
    unsigned long long *tiles_by_rank;
    MPI_Request *gather_requests;  /* rank 0: a gather's receives and their datatypes, a rank each */
    MPI_Datatype *gather_types;
};

/* Sleeps ns nanoseconds. */
void ao_cluster_sleep(long ns);

/* Tests the n requests until all complete (true), c->stopping is set or the deadline (if > 0)
 * passes (false; they are left pending: the process ends without MPI_Finalize), sleeping between
 * tests up to POLL_MOST_NS, or `most` ns once IDLE_AFTER_NS have passed; `most` 0: without
 * sleeping (data in flight). With `serving`, answers the loans between tests (c's lock not held).
 * c may be NULL (no loans, no stop: collectives before the cluster exists). Any thread. */
bool ao_cluster_await(struct ao_cluster *c, int n, MPI_Request *requests, long most, bool serving, double deadline);

/* The share's poll, borrow, repay and settle (share.h): the loans. Render threads. */
bool ao_cluster_poll(void *user, const struct ao_share_pass *pass, int arrived[2]);
bool ao_cluster_borrow(void *user, const struct ao_share_pass *pass, struct ao_share_loan *loan);
void ao_cluster_repay(void *user, const struct ao_share_pass *pass, const struct ao_share_loan *loan);
bool ao_cluster_settle(void *user, const struct ao_share_pass *pass, bool finished, int arrived[2]);

/* Ends the listener thread, if it runs. Main thread. */
void ao_cluster_stop_listening(struct ao_cluster *cluster);

#endif
