/* The ranks of an aoview-mpi run; see cluster.h. Four communicators keep the kinds of traffic
 * apart, since they come from different threads: passes (the render thread's begins and
 * collectives), loans (any render thread: asks, lends, repaid sums, given-up passes), images (the
 * gathers) and control (the listener and main: interruptions, the summary at the end). */
#include "cluster.h"
#include "pack.h"

#include <limits.h>
#include <mpi.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { TAG_ASK = 1, TAG_LEND, TAG_REPAY, TAG_GIVE_UP, TAG_GATHER, TAG_SALVAGE, TAG_ANSWER, TAG_STOP, TAG_RELEASE };

/* A rank waiting for a message or a collective tests its request without sleeping for SPIN_NS,
 * which most waits at the ends of passes take (a sleep's wake-up alone costs more), then sleeps
 * 50 us, doubling up to 1 ms while nothing comes: it leaves the cores to the render threads, at a
 * cost of at most 1 ms a wait. A rank waiting for rank 0 to begin a pass sleeps up to POLL_IDLE_NS
 * once it has waited IDLE_AFTER_NS: rank 0 may be paused or done, for as long as its window stays
 * open. The listener looks for interruptions every LISTEN_NS. */
static const long SPIN_NS = 200000, POLL_FIRST_NS = 50000, POLL_MOST_NS = 1000000, POLL_IDLE_NS = 20000000,
                  IDLE_AFTER_NS = 50000000, LISTEN_NS = 10000000;

/* Render threads look at the loans (asks to answer, sums come back, a pass given up) at most every
 * LOOK_NS, before a tile: a look takes the lock and tests three requests. */
static const long LOOK_NS = 100000;

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

/* What rank 0 sends before every pass: the step, and for a pass the settings and restarts that
 * every rank renders it with; as bytes, since the ranks run one binary. */
struct start {
    struct ao_settings settings;
    uint64_t restarts;
    int32_t step;
};

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

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void sleep_ns(long ns)
{
    struct timespec ts = {.tv_sec = ns / 1000000000L, .tv_nsec = ns % 1000000000L};
    nanosleep(&ts, NULL);
}

static void serve(struct ao_cluster *c);

/* Tests the n requests until all complete (true), *stopping is set or the deadline (if > 0) passes
 * (false; they are left pending: the process ends without MPI_Finalize), sleeping between tests
 * up to POLL_MOST_NS, or `most` ns once IDLE_AFTER_NS have passed; `most` 0: without sleeping
 * (data in flight). With `serving`, answers the loans between tests (lock not held). */
static bool await(struct ao_cluster *c, int n, MPI_Request *requests, long most, bool serving, double deadline)
{
    long pause = POLL_FIRST_NS, slept = 0;
    double spin_until = now_seconds() + 1e-9 * (double)SPIN_NS;
    for (;;) {
        int done = 0;
        if (serving)
            serve(c);
        MPI_Testall(n, requests, &done, MPI_STATUSES_IGNORE);
        if (done)
            return true;
        if (deadline > 0.0 ? now_seconds() > deadline : c && atomic_load_explicit(&c->stopping, memory_order_relaxed))
            return false;
        if (!most || now_seconds() < spin_until)
            continue;
        sleep_ns(pause);
        slept += pause;
        long cap = slept < IDLE_AFTER_NS && most > POLL_MOST_NS ? POLL_MOST_NS : most;
        pause = pause * 2 < cap ? pause * 2 : cap;
    }
}

/* ---- loans ---- */

static void answer(struct ao_cluster *c, int rank, uint64_t pass, uint64_t speed);

/* Lock held: pass's tiles are traced from now on; forgets the last pass's loans and answers the
 * asks that waited for this pass. */
static void open_pass(struct ao_cluster *c, const struct ao_share_pass *pass)
{
    if (pass->serial == c->pass)
        return;
    c->pass = pass->serial;
    c->opened_at = now_seconds();
    c->emptied_at = 0.0;
    atomic_store_explicit(&c->opened, pass->serial, memory_order_relaxed);
    c->current = pass;
    c->open = true;
    c->told = false;
    c->lent_count = c->lent_entries = 0;
    if (pass->count > c->lent_capacity) { /* a lend takes one entry at least; short of memory, none */
        struct lent *lent = realloc(c->lent, (size_t)pass->count * sizeof *lent);
        c->lent = lent ? lent : c->lent;
        MPI_Request *requests = realloc(c->lent_requests, (size_t)pass->count * sizeof *requests);
        c->lent_requests = requests ? requests : c->lent_requests;
        if (lent && requests)
            c->lent_capacity = pass->count;
    }
    c->misses = 0;
    c->exhausted = c->size < 2;
    uint64_t others = c->size > 1 ? (uint64_t)c->size - 1 : 1;
    c->start = (int)((pass->serial * 2654435761u + (uint64_t)c->rank * 40503u) % others);
    int waiting = c->deferred_count;
    c->deferred_count = 0;
    for (int k = 0; k < waiting; k++)
        answer(c, c->deferred[k].rank, c->deferred[k].pass, c->deferred[k].speed);
}

/* Lock held: whether the pass this rank traces is given up (by it or another rank), or the run
 * stops. */
static bool given_up(const struct ao_cluster *c)
{
    return c->given_up == c->pass || atomic_load_explicit(&c->stopping, memory_order_relaxed);
}

/* Lock held: this rank's speed in the pass so far (its own entries begun a second), once it has
 * begun two, else the last pass's; 0: unknown. `until`: when its list ran out, or now. */
static double own_speed(const struct ao_cluster *c, double until)
{
    double begun = (double)(c->current->count - c->current->left(c->current->renderer) - c->lent_entries);
    return begun >= 2.0 && until > c->opened_at ? begun / (until - c->opened_at) : c->speed;
}

/* Lock held: answers rank's ask for entries of pass, `speed` its speed (double bits): a lend of the
 * asker's share of what this rank has not begun, none once its list is done or the pass given up;
 * an ask for a later pass waits. */
static void answer(struct ao_cluster *c, int rank, uint64_t pass, uint64_t speed)
{
    if (pass > c->pass) {
        c->deferred[c->deferred_count].rank = rank;
        c->deferred[c->deferred_count].pass = pass;
        c->deferred[c->deferred_count++].speed = speed;
        return;
    }
    unsigned char message[LEND_BYTES];
    struct lend_header header = {.pass = pass};
    struct lend_entry entries[LEND_MOST];
    unsigned char *packed = NULL;
    if (pass == c->pass && c->open && !given_up(c) && c->lent_count < c->lent_capacity) {
        int tiles[LEND_MOST];
        struct ao_tile_work works[LEND_MOST];
        double theirs, ours = own_speed(c, now_seconds());
        memcpy(&theirs, &speed, sizeof theirs);
        double share = theirs > 0.0 && ours > 0.0 ? theirs / (theirs + ours) : 0.5;
        int left = c->current->left(c->current->renderer), first = 0;
        int want = (int)((double)left * share + 0.999);
        want = want < LEND_MOST ? want : LEND_MOST;
        packed = want > 0 ? malloc(ao_pack_bound((size_t)want * (size_t)c->current->pixels)) : NULL;
        header.count = packed ? c->current->lend(c->current->renderer, want, &first, tiles, works) : 0;
        header.first = first;
        for (int k = 0; k < header.count; k++)
            entries[k] = (struct lend_entry){.tile = tiles[k], .work = works[k]};
    }
    memcpy(message, &header, sizeof header);
    memcpy(message + sizeof header, entries, (size_t)header.count * sizeof *entries);
    int bytes = (int)(sizeof header + (size_t)header.count * sizeof *entries);
    if (header.count > 0) { /* the sums come back packed, in one message */
        size_t bound = ao_pack_bound((size_t)header.count * (size_t)c->current->pixels);
        MPI_Irecv(packed, (int)bound, MPI_BYTE, rank, TAG_REPAY, c->loans, &c->lent_requests[c->lent_count]);
        c->lent[c->lent_count++] = (struct lent){header.first, header.count, packed, false};
        c->lent_entries += header.count;
    } else {
        free(packed);
    }
    MPI_Send(message, bytes, MPI_BYTE, rank, TAG_LEND, c->loans);
    if (c->rank == 0)
        c->loan_out += bytes;
}

/* Lock held: answers the asks that came and notes the passes given up. */
static void serve_locked(struct ao_cluster *c)
{
    for (;;) {
        int done = 0;
        MPI_Status status;
        MPI_Test(&c->asked, &done, &status);
        if (!done)
            break;
        if (c->rank == 0)
            c->loan_in += sizeof c->ask;
        answer(c, status.MPI_SOURCE, c->ask[0], c->ask[1]);
        MPI_Irecv(c->ask, 2, MPI_UINT64_T, MPI_ANY_SOURCE, TAG_ASK, c->loans, &c->asked);
    }
    for (;;) {
        int done = 0;
        MPI_Test(&c->gave_up, &done, MPI_STATUS_IGNORE);
        if (!done)
            break;
        if (c->rank == 0)
            c->loan_in += sizeof c->give_up;
        c->given_up = c->give_up > c->given_up ? c->give_up : c->given_up;
        MPI_Irecv(&c->give_up, 1, MPI_UINT64_T, MPI_ANY_SOURCE, TAG_GIVE_UP, c->loans, &c->gave_up);
    }
}

/* Lock not held: as serve_locked. */
static void serve(struct ao_cluster *c)
{
    pthread_mutex_lock(&c->lock);
    serve_locked(c);
    pthread_mutex_unlock(&c->lock);
}

/* Lock held: the next range lent whose sums have come back, unpacked into the pass's sums, into
 * arrived; left as it is when none has. */
static void take_repaid(struct ao_cluster *c, int arrived[2])
{
    for (int k = 0; k < c->lent_count; k++) {
        int done = 0, bytes = 0;
        MPI_Status status;
        if (c->lent[k].reported)
            continue;
        MPI_Test(&c->lent_requests[k], &done, &status);
        if (done) {
            size_t pixels = (size_t)c->current->pixels;
            MPI_Get_count(&status, MPI_BYTE, &bytes);
            if (!ao_unpack_sums(c->lent[k].packed, (size_t)bytes, c->current->sums + (size_t)c->lent[k].first * pixels,
                                (size_t)c->lent[k].count * pixels)) { /* the ranks run one binary: never */
                fprintf(stderr, "aoview-mpi: rank %d sent sums that do not unpack\n", status.MPI_SOURCE);
                MPI_Abort(MPI_COMM_WORLD, 1);
            }
            free(c->lent[k].packed);
            c->lent[k].packed = NULL;
            if (c->rank == 0)
                c->loan_in += bytes;
            c->lent[k].reported = true;
            arrived[0] = c->lent[k].first;
            arrived[1] = c->lent[k].first + c->lent[k].count;
            return;
        }
    }
}

static bool poll(void *user, const struct ao_share_pass *pass, int arrived[2])
{
    struct ao_cluster *c = user;
    if (c->delay_ns)
        sleep_ns(c->delay_ns);
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    long long now = (long long)ts.tv_sec * 1000000000LL + ts.tv_nsec;
    if (pass->serial == atomic_load_explicit(&c->opened, memory_order_relaxed) &&
        now - atomic_load_explicit(&c->looked, memory_order_relaxed) < LOOK_NS)
        return !atomic_load_explicit(&c->stopping, memory_order_relaxed);
    atomic_store_explicit(&c->looked, now, memory_order_relaxed);
    pthread_mutex_lock(&c->lock);
    open_pass(c, pass);
    serve_locked(c);
    take_repaid(c, arrived);
    bool going = !given_up(c);
    pthread_mutex_unlock(&c->lock);
    return going;
}

/* Lock held: the grant's sums go to its owner once all its entries are traced. */
static void repay_if_traced(struct ao_cluster *c)
{
    if (!c->holding || c->repaid < c->count || c->repaying != MPI_REQUEST_NULL)
        return;
    size_t bytes = ao_pack_sums(c->loan_sums, (size_t)c->count * (size_t)c->current->pixels, c->repay_packed);
    MPI_Isend(c->repay_packed, (int)bytes, MPI_BYTE, c->owner, TAG_REPAY, c->loans, &c->repaying);
    if (c->rank == 0)
        c->loan_out += (double)bytes;
}

/* Lock held: whether the grant held is all traced and its sums have left (then it is let go). */
static bool grant_settled(struct ao_cluster *c)
{
    if (!c->holding)
        return true;
    int done = 0;
    if (c->repaying != MPI_REQUEST_NULL)
        MPI_Test(&c->repaying, &done, MPI_STATUS_IGNORE);
    if (c->repaying == MPI_REQUEST_NULL && c->repaid == c->count)
        c->holding = false;
    return !c->holding;
}

/* Lock held: takes the answer to this rank's ask if it came (true): a grant to hold, or a miss. In
 * a pass given up, a grant's entries are repaid at once (their sums do not count). */
static bool take_answer(struct ao_cluster *c)
{
    int done = 0;
    MPI_Test(&c->answering, &done, MPI_STATUS_IGNORE);
    if (!done)
        return false;
    struct lend_header header;
    memcpy(&header, c->answer, sizeof header);
    if (c->rank == 0)
        c->loan_in += (double)(sizeof header + (size_t)header.count * sizeof(struct lend_entry));
    c->victim = -1;
    if (header.count == 0) {
        c->misses++;
        c->exhausted = c->misses >= MISSES || c->misses >= c->size - 1;
        return true;
    }
    c->holding = true;
    c->first = header.first;
    c->count = header.count;
    c->handed = c->repaid = 0;
    if (given_up(c)) {
        memset(c->loan_sums, 0, (size_t)c->count * (size_t)c->current->pixels * sizeof *c->loan_sums);
        c->handed = c->repaid = c->count;
        repay_if_traced(c);
    }
    return true;
}

/* Lock held: asks the next rank in this rank's row for entries of the pass. */
static void ask(struct ao_cluster *c)
{
    int k = (c->start + c->misses) % (c->size - 1);
    c->victim = (c->rank + 1 + k) % c->size;
    c->owner = c->victim;
    if (c->emptied_at == 0.0)
        c->emptied_at = now_seconds();
    double speed = own_speed(c, c->emptied_at);
    uint64_t message[2] = {c->pass, 0};
    memcpy(&message[1], &speed, sizeof speed);
    MPI_Irecv(c->answer, LEND_BYTES, MPI_BYTE, c->victim, TAG_LEND, c->loans, &c->answering);
    MPI_Send(message, 2, MPI_UINT64_T, c->victim, TAG_ASK, c->loans);
    if (c->rank == 0)
        c->loan_out += sizeof message;
}

/* Lock held, then released and taken again: a short wait inside a loop over the loans. */
static void pause_locked(struct ao_cluster *c, long *pause)
{
    pthread_mutex_unlock(&c->lock);
    sleep_ns(*pause);
    *pause = *pause * 2 < POLL_MOST_NS ? *pause * 2 : POLL_MOST_NS;
    pthread_mutex_lock(&c->lock);
}

static bool borrow(void *user, const struct ao_share_pass *pass, struct ao_share_loan *loan)
{
    struct ao_cluster *c = user;
    long pause = POLL_FIRST_NS / 4;
    pthread_mutex_lock(&c->lock);
    open_pass(c, pass);
    for (;;) {
        serve_locked(c);
        if (atomic_load_explicit(&c->stopping, memory_order_relaxed)) {
            pthread_mutex_unlock(&c->lock);
            return false;
        }
        if (c->victim >= 0 && !take_answer(c)) {
            pause_locked(c, &pause);
            continue;
        }
        if (c->holding && c->handed < c->count && !given_up(c)) {
            int n = c->handed++;
            *loan = (struct ao_share_loan){.tile = 0, .ticket = n,
                                           .sums = c->loan_sums + (size_t)n * (size_t)pass->pixels};
            struct lend_entry entry;
            memcpy(&entry, c->answer + sizeof(struct lend_header) + (size_t)n * sizeof entry, sizeof entry);
            loan->tile = entry.tile;
            loan->work = entry.work;
            c->tiles++;
            pthread_mutex_unlock(&c->lock);
            return true;
        }
        if (given_up(c) || (c->exhausted && !c->holding)) {
            pthread_mutex_unlock(&c->lock);
            return false;
        }
        if (!grant_settled(c)) { /* another thread traces the grant's last entries */
            pause_locked(c, &pause);
            continue;
        }
        if (c->exhausted) {
            pthread_mutex_unlock(&c->lock);
            return false;
        }
        ask(c);
    }
}

static void repay(void *user, const struct ao_share_pass *pass, const struct ao_share_loan *loan)
{
    (void)pass;
    (void)loan;
    struct ao_cluster *c = user;
    pthread_mutex_lock(&c->lock);
    c->repaid++;
    repay_if_traced(c);
    pthread_mutex_unlock(&c->lock);
}

/* Lock held: tells every other rank that this one gives the pass up. */
static void tell_given_up(struct ao_cluster *c)
{
    if (c->told)
        return;
    c->told = true;
    c->given_up = c->pass > c->given_up ? c->pass : c->given_up;
    for (int r = 0; r < c->size; r++)
        if (r != c->rank)
            MPI_Send(&c->pass, 1, MPI_UINT64_T, r, TAG_GIVE_UP, c->loans);
    if (c->rank == 0)
        c->loan_out += (double)(c->size - 1) * sizeof c->pass;
}

static bool settle(void *user, const struct ao_share_pass *pass, bool finished, int arrived[2])
{
    struct ao_cluster *c = user;
    long pause = POLL_FIRST_NS / 4;
    double spin_until = now_seconds() + 1e-9 * (double)SPIN_NS;
    pthread_mutex_lock(&c->lock);
    open_pass(c, pass);
    if (c->open && finished) {
        c->tiles += (uint64_t)(pass->count - c->lent_entries);
        if (pass->count - c->lent_entries >= 2)
            c->speed = own_speed(c, c->emptied_at > 0.0 ? c->emptied_at : now_seconds());
    }
    c->open = false; /* its threads are done: nothing more to lend */
    if (!finished)
        tell_given_up(c);
    for (;;) {
        serve_locked(c);
        if (c->victim >= 0)
            take_answer(c);
        if (c->holding && c->handed < c->count) { /* not traced (the pass is given up): zeros */
            memset(c->loan_sums + (size_t)c->handed * (size_t)pass->pixels, 0,
                   (size_t)(c->count - c->handed) * (size_t)pass->pixels * sizeof *c->loan_sums);
            c->repaid += c->count - c->handed;
            c->handed = c->count;
            repay_if_traced(c);
        }
        take_repaid(c, arrived);
        if (arrived[0] < arrived[1]) {
            pthread_mutex_unlock(&c->lock);
            return true;
        }
        bool repaid = true;
        for (int k = 0; k < c->lent_count; k++)
            repaid = repaid && c->lent[k].reported;
        if (repaid && c->victim < 0 && grant_settled(c)) {
            pthread_mutex_unlock(&c->lock);
            return true;
        }
        if (atomic_load(&c->stopping)) {
            pthread_mutex_unlock(&c->lock);
            return false;
        }
        if (now_seconds() > spin_until)
            pause_locked(c, &pause);
    }
}

/* ---- passes ---- */

/* Broadcasts rank 0's start to every rank; false when the cluster stops first. */
static bool broadcast_start(struct ao_cluster *c, struct start *start)
{
    MPI_Request pending;
    MPI_Ibcast(start, sizeof *start, MPI_BYTE, 0, c->passes, &pending);
    if (c->rank == 0)
        c->bytes_out += (double)c->fan * sizeof *start;
    return await(c, 1, &pending, POLL_IDLE_NS, true, 0.0);
}

static enum ao_share_step begin_step(void *user, enum ao_share_step step, struct ao_settings *settings,
                                     uint64_t *restarts)
{
    struct ao_cluster *c = user;
    struct start start;
    memset(&start, 0, sizeof start);
    if (c->rank == 0) {
        start.settings = *settings;
        start.restarts = *restarts;
        start.step = step;
    }
    double began = now_seconds();
    if (!broadcast_start(c, &start))
        return AO_SHARE_END;
    if (c->rank == 0)
        c->seconds += now_seconds() - began;
    if (start.step == AO_SHARE_END)
        c->ended = true;
    if (start.step == AO_SHARE_PASS) {
        *settings = start.settings;
        *restarts = start.restarts;
    }
    return (enum ao_share_step)start.step;
}

static bool owns(void *user, int tile, int tiles)
{
    (void)tiles;
    struct ao_cluster *c = user;
    return tile % c->size == c->rank;
}

/* The tally's combination: exact sums merged, totals added, maxima taken. */
static void combine_tallies(void *in, void *inout, int *len, MPI_Datatype *type)
{
    (void)type;
    for (int k = 0; k < *len; k++) {
        struct ao_share_tally a, b;
        memcpy(&a, (unsigned char *)in + (size_t)k * sizeof a, sizeof a);
        memcpy(&b, (unsigned char *)inout + (size_t)k * sizeof b, sizeof b);
        for (int j = 0; j < AO_TALLY_EXACT; j++)
            ao_sum_merge(&b.exact[j], &a.exact[j]);
        for (int j = 0; j < AO_TALLY_TOTAL; j++)
            b.total[j] += a.total[j];
        for (int j = 0; j < AO_TALLY_MOST; j++)
            b.most[j] = a.most[j] > b.most[j] ? a.most[j] : b.most[j];
        memcpy((unsigned char *)inout + (size_t)k * sizeof b, &b, sizeof b);
    }
}

static bool combine(void *user, struct ao_share_tally *tally)
{
    struct ao_cluster *c = user;
    double began = now_seconds();
    MPI_Request pending;
    MPI_Iallreduce(MPI_IN_PLACE, tally, 1, c->tally_type, c->tally_op, c->passes, &pending);
    if (!await(c, 1, &pending, POLL_MOST_NS, true, 0.0))
        return false;
    if (c->rank == 0) {
        c->passes_combined++;
        c->bytes_in += (double)c->fan * sizeof *tally;
        c->bytes_out += (double)c->fan * sizeof *tally;
        c->seconds += now_seconds() - began;
    }
    return true;
}

static bool add_up(void *user, uint64_t *values, int count)
{
    struct ao_cluster *c = user;
    double began = now_seconds();
    MPI_Request pending;
    MPI_Iallreduce(MPI_IN_PLACE, values, count, MPI_UINT64_T, MPI_SUM, c->passes, &pending);
    if (!await(c, 1, &pending, POLL_MOST_NS, true, 0.0))
        return false;
    if (c->rank == 0) {
        c->bytes_in += (double)c->fan * (double)count * sizeof *values;
        c->bytes_out += (double)c->fan * (double)count * sizeof *values;
        c->seconds += now_seconds() - began;
    }
    return true;
}

static bool due(void *user)
{
    struct ao_cluster *c = user;
    double interval = atomic_load(&c->interval);
    return interval > 0.0 && now_seconds() - c->last_gather >= interval;
}

/* The gather: rank k's records are tiles k, k + N, k + 2N, ...: rank 0 receives each rank's
 * straight into place, as a strided datatype. After an interruption (salvage) the same with their
 * own tag, until the deadline. */
static bool gather(void *user, const void *mine, int count, size_t size, void *all, int tiles)
{
    struct ao_cluster *c = user;
    bool salvage = c->salvage_until > 0.0;
    int tag = salvage ? TAG_SALVAGE : TAG_GATHER;
    double began = now_seconds();
    if (c->rank != 0) {
        MPI_Request pending;
        MPI_Isend(mine, (int)((size_t)count * size), MPI_BYTE, 0, tag, c->images, &pending);
        return await(c, 1, &pending, POLL_MOST_NS, !salvage, c->salvage_until);
    }
    MPI_Request *pending = c->gather_requests;
    MPI_Datatype *types = c->gather_types;
    int receives = 0;
    double bytes = 0.0;
    for (int r = 1; r < c->size; r++) {
        int records = tiles > r ? (tiles - r + c->size - 1) / c->size : 0;
        if (!records)
            continue;
        MPI_Type_vector(records, (int)size, (int)((size_t)c->size * size), MPI_BYTE, &types[receives]);
        MPI_Type_commit(&types[receives]);
        MPI_Irecv((unsigned char *)all + (size_t)r * size, 1, types[receives], r, tag, c->images, &pending[receives]);
        receives++;
        bytes += (double)records * (double)size;
    }
    for (int k = 0; k < count; k++)
        memcpy((unsigned char *)all + (size_t)k * (size_t)c->size * size,
               (const unsigned char *)mine + (size_t)k * size, size);
    bool ok = await(c, receives, pending, POLL_MOST_NS, !salvage, c->salvage_until);
    for (int k = 0; k < receives; k++)
        MPI_Type_free(&types[k]);
    if (ok) {
        c->gathers++;
        c->gather_bytes += bytes;
        c->seconds += now_seconds() - began;
        c->last_gather = now_seconds();
        atomic_store(&c->copied, c->last_gather);
    }
    return ok;
}

/* Rank 0's render thread ends (the window closed, or the run is over): the others' end too. */
static void end_run(void *user)
{
    struct ao_cluster *c = user;
    if (c->rank != 0 || atomic_load(&c->stopping))
        return;
    struct ao_settings settings;
    memset(&settings, 0, sizeof settings);
    uint64_t restarts = 0;
    begin_step(c, AO_SHARE_END, &settings, &restarts);
}

/* ---- life cycle ---- */

bool ao_cluster_init(int *argc, char ***argv, int *rank, int *size)
{
    int provided;
    if (MPI_Init_thread(argc, argv, MPI_THREAD_MULTIPLE, &provided) != MPI_SUCCESS)
        return false;
    MPI_Comm_rank(MPI_COMM_WORLD, rank);
    MPI_Comm_size(MPI_COMM_WORLD, size);
    if (provided < MPI_THREAD_MULTIPLE) {
        if (*rank == 0)
            fprintf(stderr, "aoview-mpi: this MPI library does not support MPI_THREAD_MULTIPLE\n");
        MPI_Finalize();
        return false;
    }
    return true;
}

bool ao_cluster_agree(bool ok)
{
    int all = ok;
    MPI_Request pending;
    MPI_Iallreduce(MPI_IN_PLACE, &all, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD, &pending);
    await(NULL, 1, &pending, POLL_MOST_NS, false, 0.0);
    return all;
}

int ao_cluster_differs(uint64_t value)
{
    int rank, size;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    uint64_t *all = rank == 0 ? calloc((size_t)size, sizeof *all) : NULL;
    MPI_Request pending;
    MPI_Igather(&value, 1, MPI_UINT64_T, all, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD, &pending);
    await(NULL, 1, &pending, POLL_MOST_NS, false, 0.0);
    int first = -1;
    for (int r = 1; all && r < size && first < 0; r++)
        if (all[r] != all[0])
            first = r;
    if (rank == 0 && !all) /* out of memory: which rank is not known */
        first = 0;
    free(all);
    int verdict[2] = {first, first};
    MPI_Ibcast(verdict, 2, MPI_INT, 0, MPI_COMM_WORLD, &pending);
    await(NULL, 1, &pending, POLL_MOST_NS, false, 0.0);
    return verdict[0];
}

void ao_cluster_finalize(void)
{
    MPI_Finalize();
}

/* The listener: on rank 0, a rank's answer during the run (it was interrupted); elsewhere, rank 0's
 * request to stop. Either makes this rank stop, once. */
static void *listen_thread(void *arg)
{
    struct ao_cluster *c = arg;
    while (atomic_load(&c->listen)) {
        bool heard = false;
        for (int r = 1; r < c->size && c->rank == 0; r++) {
            int done = 0;
            if (c->answers[r] != MPI_REQUEST_NULL) {
                MPI_Test(&c->answers[r], &done, MPI_STATUS_IGNORE);
                if (done && !c->first_stop)
                    c->first_stop = r;
                heard = heard || done;
            }
        }
        if (c->rank != 0) {
            int done = 0;
            MPI_Test(&c->halt, &done, MPI_STATUS_IGNORE);
            heard = done;
        }
        if (heard) {
            if (c->stopped)
                c->stopped(c->stopped_user);
            return NULL;
        }
        sleep_ns(LISTEN_NS);
    }
    return NULL;
}

struct ao_cluster *ao_cluster_create(void)
{
    struct ao_cluster *c = calloc(1, sizeof *c);
    if (!ao_cluster_agree(c != NULL)) {
        if (!c)
            fprintf(stderr, "aoview-mpi: out of memory for the cluster\n");
        free(c);
        return NULL;
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &c->rank);
    MPI_Comm_size(MPI_COMM_WORLD, &c->size);
    MPI_Comm_dup(MPI_COMM_WORLD, &c->passes);
    MPI_Comm_dup(MPI_COMM_WORLD, &c->loans);
    MPI_Comm_dup(MPI_COMM_WORLD, &c->images);
    MPI_Comm_dup(MPI_COMM_WORLD, &c->control);
    MPI_Type_contiguous((int)sizeof(struct ao_share_tally), MPI_BYTE, &c->tally_type);
    MPI_Type_commit(&c->tally_type);
    MPI_Op_create(combine_tallies, 1, &c->tally_op);
    pthread_mutex_init(&c->lock, NULL);
    atomic_init(&c->stopping, false);
    atomic_init(&c->looked, 0);
    atomic_init(&c->opened, 0);
    atomic_init(&c->listen, false);
    c->share = (struct ao_render_share){.begin = begin_step, .owns = owns, .poll = poll, .borrow = borrow,
                                        .repay = repay, .settle = settle, .combine = combine, .add_up = add_up,
                                        .due = due, .gather = gather, .end = end_run, .follows = c->rank != 0,
                                        .user = c};
    const char *delay = getenv("AO_MPI_TEST_DELAY_US");
    c->delay_ns = delay ? 1000L * strtol(delay, NULL, 10) : 0;
    for (int n = 1; n < c->size; n *= 2)
        c->fan++;
    c->victim = -1;
    c->repaying = c->answering = MPI_REQUEST_NULL;
    c->last_gather = now_seconds();
    size_t ranks = (size_t)c->size;
    c->deferred = calloc(ranks, sizeof *c->deferred);
    c->answer = malloc(LEND_BYTES);
    c->loan_sums = malloc((size_t)LEND_MOST * AO_TILE_PIXELS * sizeof *c->loan_sums);
    c->repay_packed = malloc(ao_pack_bound((size_t)LEND_MOST * AO_TILE_PIXELS));
    c->answers = calloc(ranks, sizeof *c->answers);
    c->signals = calloc(ranks, sizeof *c->signals);
    c->tiles_by_rank = calloc(ranks, sizeof *c->tiles_by_rank);
    c->gather_requests = calloc(ranks, sizeof *c->gather_requests);
    c->gather_types = calloc(ranks, sizeof *c->gather_types);
    bool ok = c->deferred && c->answer && c->loan_sums && c->repay_packed && c->answers && c->signals &&
              c->tiles_by_rank && c->gather_requests && c->gather_types;
    if (ok) {
        MPI_Irecv(c->ask, 2, MPI_UINT64_T, MPI_ANY_SOURCE, TAG_ASK, c->loans, &c->asked);
        MPI_Irecv(&c->give_up, 1, MPI_UINT64_T, MPI_ANY_SOURCE, TAG_GIVE_UP, c->loans, &c->gave_up);
        for (int r = 0; r < c->size; r++)
            c->answers[r] = MPI_REQUEST_NULL;
        for (int r = 1; r < c->size && c->rank == 0; r++) {
            c->signals[r] = -1;
            MPI_Irecv(&c->signals[r], 1, MPI_INT, r, TAG_ANSWER, c->control, &c->answers[r]);
        }
        c->halt = c->released = MPI_REQUEST_NULL;
        if (c->rank != 0) {
            MPI_Irecv(&c->halt_word, 1, MPI_INT, 0, TAG_STOP, c->control, &c->halt);
            MPI_Irecv(&c->release_word, 1, MPI_INT, 0, TAG_RELEASE, c->control, &c->released);
        }
    } else {
        fprintf(stderr, "aoview-mpi: out of memory for the cluster\n");
    }
    if (!ao_cluster_agree(ok)) {
        ao_cluster_destroy(c);
        return NULL;
    }
    return c;
}

const struct ao_render_share *ao_cluster_share(struct ao_cluster *cluster)
{
    return &cluster->share;
}

void ao_cluster_set_interval(struct ao_cluster *cluster, double seconds)
{
    atomic_store(&cluster->interval, seconds);
}

void ao_cluster_listen(struct ao_cluster *cluster, void (*stopped)(void *user), void *user)
{
    cluster->stopped = stopped;
    cluster->stopped_user = user;
    atomic_store(&cluster->listen, true);
    cluster->listening = pthread_create(&cluster->listener, NULL, listen_thread, cluster) == 0;
}

/* Ends the listener thread (from main). */
static void stop_listening(struct ao_cluster *cluster)
{
    atomic_store(&cluster->listen, false);
    if (cluster->listening)
        pthread_join(cluster->listener, NULL);
    cluster->listening = false;
}

void ao_cluster_stop(struct ao_cluster *cluster)
{
    atomic_store(&cluster->stopping, true);
    stop_listening(cluster);
}

bool ao_cluster_ended(struct ao_cluster *cluster)
{
    return cluster->ended;
}

void ao_cluster_answer(struct ao_cluster *cluster, int sig)
{
    MPI_Send(&sig, 1, MPI_INT, 0, TAG_ANSWER, cluster->control);
}

void ao_cluster_halt(struct ao_cluster *cluster)
{
    if (cluster->halted)
        return;
    cluster->halted = true;
    static const int word = 1;
    for (int r = 1; r < cluster->size; r++) {
        MPI_Request sent;
        MPI_Isend(&word, 1, MPI_INT, r, TAG_STOP, cluster->control, &sent);
        MPI_Request_free(&sent);
    }
}

void ao_cluster_missing(struct ao_cluster *cluster, double seconds, char *out, size_t size)
{
    MPI_Request *pending = cluster->answers;
    int ranks = cluster->size;
    for (double deadline = now_seconds() + seconds; now_seconds() < deadline; sleep_ns(POLL_MOST_NS)) {
        int left = 0;
        for (int r = 1; r < ranks; r++) {
            int done = 0;
            if (pending[r] != MPI_REQUEST_NULL)
                MPI_Test(&pending[r], &done, MPI_STATUS_IGNORE);
            left += pending[r] != MPI_REQUEST_NULL;
        }
        if (!left)
            break;
    }
    size_t used = 0;
    out[0] = '\0';
    for (int r = 1; r < ranks; r++)
        if (pending[r] != MPI_REQUEST_NULL && used < size)
            used += (size_t)snprintf(out + used, size - used, "%s%d", used ? ", " : "", r);
}

int ao_cluster_signalled(struct ao_cluster *cluster, char *out, size_t size)
{
    size_t used = 0;
    int first = 0;
    out[0] = '\0';
    for (int r = 1; r < cluster->size; r++)
        if (cluster->answers[r] == MPI_REQUEST_NULL && cluster->signals[r] > 0 && used < size) {
            used += (size_t)snprintf(out + used, size - used, "%s%d", used ? ", " : "", r);
            first = first ? first : cluster->signals[r];
        }
    if (!out[0] && cluster->first_stop) /* stopped by itself without a signal: it failed */
        snprintf(out, size, "%d", cluster->first_stop);
    return first;
}

void ao_cluster_salvage(struct ao_cluster *cluster, double seconds)
{
    cluster->salvage_until = now_seconds() + seconds;
}

double ao_cluster_copy_age(struct ao_cluster *cluster)
{
    double copied = atomic_load(&cluster->copied);
    return copied > 0.0 ? now_seconds() - copied : -1.0;
}

void ao_cluster_release(struct ao_cluster *cluster, int status)
{
    cluster->release_word = status;
    for (int r = 1; r < cluster->size; r++)
        if (cluster->answers[r] == MPI_REQUEST_NULL) {
            MPI_Request sent;
            MPI_Isend(&cluster->release_word, 1, MPI_INT, r, TAG_RELEASE, cluster->control, &sent);
            MPI_Request_free(&sent);
        }
}

bool ao_cluster_await_release(struct ao_cluster *cluster, double seconds, int *status)
{
    if (!await(NULL, 1, &cluster->released, POLL_MOST_NS, false, now_seconds() + seconds))
        return false;
    *status = cluster->release_word;
    return true;
}

void ao_cluster_summary(struct ao_cluster *cluster, char *out, size_t size)
{
    stop_listening(cluster);
    unsigned long long mine = cluster->tiles, *all = cluster->tiles_by_rank;
    MPI_Request pending;
    MPI_Igather(&mine, 1, MPI_UNSIGNED_LONG_LONG, all, 1, MPI_UNSIGNED_LONG_LONG, 0, cluster->control, &pending);
    await(NULL, 1, &pending, POLL_IDLE_NS, false, 0.0);
    int used = snprintf(out, size, "%d rank%s, tiles traced by rank", cluster->size, cluster->size > 1 ? "s" : "");
    for (int r = 0; r < cluster->size && used >= 0 && (size_t)used < size; r++)
        used += snprintf(out + used, size - (size_t)used, "%s %d: %llu", r ? "," : "", r, all[r]);
    double passes = cluster->passes_combined ? (double)cluster->passes_combined : 1.0;
    if (used >= 0 && (size_t)used < size)
        snprintf(out + used, size - (size_t)used,
                 "; %llu passes, %.0f bytes into rank 0 and %.0f bytes out of it per pass (loans %.0f and %.0f), "
                 "%.0f bytes in %llu image gathers, %.3f s in collectives and gathers",
                 (unsigned long long)cluster->passes_combined, (cluster->bytes_in + cluster->loan_in) / passes,
                 (cluster->bytes_out + cluster->loan_out) / passes, cluster->loan_in / passes,
                 cluster->loan_out / passes, cluster->gather_bytes, (unsigned long long)cluster->gathers,
                 cluster->seconds);
}

void ao_cluster_destroy(struct ao_cluster *cluster)
{
    if (!cluster)
        return;
    ao_cluster_stop(cluster);
    MPI_Request *persistent[] = {&cluster->asked, &cluster->gave_up, &cluster->halt, &cluster->released};
    for (size_t k = 0; k < sizeof persistent / sizeof persistent[0]; k++)
        if (*persistent[k] != MPI_REQUEST_NULL) {
            MPI_Cancel(persistent[k]);
            MPI_Wait(persistent[k], MPI_STATUS_IGNORE);
        }
    for (int r = 1; cluster->answers && r < cluster->size; r++)
        if (cluster->answers[r] != MPI_REQUEST_NULL) {
            MPI_Cancel(&cluster->answers[r]);
            MPI_Wait(&cluster->answers[r], MPI_STATUS_IGNORE);
        }
    for (int k = 0; k < cluster->lent_count; k++) /* sums that never came (the run stopped) */
        if (cluster->lent[k].packed) {
            MPI_Cancel(&cluster->lent_requests[k]);
            MPI_Wait(&cluster->lent_requests[k], MPI_STATUS_IGNORE);
            free(cluster->lent[k].packed);
        }
    MPI_Op_free(&cluster->tally_op);
    MPI_Type_free(&cluster->tally_type);
    MPI_Comm_free(&cluster->passes);
    MPI_Comm_free(&cluster->loans);
    MPI_Comm_free(&cluster->images);
    MPI_Comm_free(&cluster->control);
    pthread_mutex_destroy(&cluster->lock);
    free(cluster->lent);
    free(cluster->lent_requests);
    free(cluster->deferred);
    free(cluster->answer);
    free(cluster->loan_sums);
    free(cluster->repay_packed);
    free(cluster->answers);
    free(cluster->signals);
    free(cluster->tiles_by_rank);
    free(cluster->gather_requests);
    free(cluster->gather_types);
    free(cluster);
}
