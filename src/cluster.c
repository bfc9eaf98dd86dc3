/* The ranks of an aoview-mpi run; see cluster.h. Three communicators keep the kinds of traffic
 * apart, since they come from different threads: claims (render threads and rank 0's server: the
 * requests, grants and sums of chunks), passes (the render thread's starts and ends of passes) and
 * control (main: answers after an interruption, the tile counts at the end). */
#include "cluster.h"

#include <assert.h>
#include <limits.h>
#include <mpi.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { TAG_REQUEST = 1, TAG_GRANT, TAG_SUMS, TAG_ANSWER };

/* A rank waiting for a message or for the slowest rank at a merge tests its request without
 * sleeping for SPIN_NS, which most waits at the ends of passes and for chunks take (a sleep's
 * wake-up alone costs more), then sleeps 50 us, doubling up to 1 ms while nothing comes: it leaves
 * the cores to the render threads, at a cost of at most 1 ms a wait; sleeps of 10 to 200 us took
 * 0.55 s of system time in a 5 s run against 0.3 s, for no shorter waits (docs/mpi.md). A rank
 * waiting for rank 0 to begin a pass sleeps up to POLL_IDLE_NS once it has waited IDLE_AFTER_NS:
 * rank 0 may be paused or done, for as long as its window stays open. */
static const long SPIN_NS = 200000, POLL_FIRST_NS = 50000, POLL_MOST_NS = 1000000, POLL_IDLE_NS = 20000000,
                  IDLE_AFTER_NS = 50000000;
/* How often rank 0's claim server looks for an interrupted rank's answer between passes. */
static const long ANSWER_POLL_NS = 100000000;

/* Rank 0 grants a rank 1 / (CHUNKS x ranks) of the entries still to hand out, so that chunks
 * shrink as the pass runs out: a rank holds at most two chunks (the one it traces and the next,
 * asked for ahead), 1/16 of a pass between two ranks however slow one of them is. But at least
 * what the rank traces in CHUNK_SECONDS, by its own measure, so that the next chunk's round trip
 * (0.1 ms here, a few ms when the machine is busy) hides behind the one it traces; and, near the
 * end of a pass, at most 1 / (LAST x ranks) of what is left, so that the last chunks shrink to
 * single entries and rank 0's threads, which take one at a time, do not wait at the merge for
 * another rank's two last chunks of 2 ms each (docs/mpi.md). */
enum { CHUNKS = 16, LAST = 4 };
static const double CHUNK_SECONDS = 2e-3;

struct ao_cluster {
    struct ao_render_share share;
    int rank, size;
    MPI_Comm claims, passes, control;
    atomic_bool stopping;
    atomic_int interrupted;  /* rank 0: another rank that said it was interrupted, or -1 */
    bool closed;             /* rank 0: it gave up the pass (a restart or stop); nothing is handed
                                out until the next pass begins */
    bool open;               /* rank 0: from a pass's begin (or its giving up) to its merge, when
                                requests may come: the server thread polls */
    bool claiming;           /* rank 0: its threads claimed since the server thread last looked */
    pthread_cond_t opened;   /* rank 0: signalled when a pass opens, and on stop */
    long delay_ns;           /* tests only: AO_MPI_TEST_DELAY_US per tile claimed, a slow rank */

    pthread_mutex_t lock;    /* the claim state below */
    uint64_t pass;           /* rank 0: the pass being handed out; others: the pass of the chunk */
    int next, count;         /* rank 0: the next entry to hand out, of count */
    int begin, end;          /* other ranks: what is left of the chunk granted */
    bool exhausted;          /* other ranks: rank 0 has nothing left of this pass */
    bool asked;              /* other ranks: a request for the next chunk is out */
    double last_claim;       /* other ranks: when an entry was last claimed without waiting */
    double entry_seconds;    /* other ranks: the time between claims, smoothed; 0: unknown */
    int grant[2];            /* other ranks: its answer, [begin, end) */
    MPI_Request granted;
    struct range *ranges;    /* the chunks of the pass: rank 0, those it granted; others, those they
                                were granted */
    int range_count, range_capacity;
    MPI_Request *moves;      /* range_capacity: each chunk's sums, rank 0 receiving, others sending */
    int moving;              /* the first chunks whose sums are on their way: rank 0 posted their
                                receives, the others sent them */
    int arrived;             /* rank 0: the first chunks whose sums arrived and went to be added */
    float *pass_sums;        /* the passes' sums (NULL until known), entry_floats an entry of the
                                work list */
    int entry_floats;
    bool starved;            /* reserve failed once (and said so) */
    uint64_t tiles;          /* entries this rank claimed */
    uint64_t request[3];     /* rank 0: the request being received (pass, count, least) */
    MPI_Request incoming;

    double merge_seconds;    /* the last merge's duration (render thread) */
    uint64_t merges;         /* merges so far, the bytes this rank sent and received, the seconds */
    double merge_bytes, waited, moved;  /* waiting for the slowest rank, and moving sums and states */
    pthread_t server;
    bool serving;

    /* Rank 0's buffers for ao_cluster_missing and ao_cluster_tiles, one entry per rank. */
    MPI_Request *pending;
    int *answers;
    unsigned long long *tiles_by_rank;
};

/* A chunk of a pass's work list that rank 0 granted: entries [begin, end) to rank `rank`, of which
 * `left` are not traced yet (other ranks). */
struct range {
    int rank, begin, end, left;
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

static void serve_claims(struct ao_cluster *c);

/* Tests the n requests until all complete (true) or *stopping is set (false; they are left
 * pending: the process ends without MPI_Finalize), sleeping between tests up to POLL_MOST_NS, or
 * `most` ns once IDLE_AFTER_NS have passed; `most` 0: without sleeping (data in flight). Rank 0
 * answers the others' requests between tests when `serving` is set. */
static bool await(const atomic_bool *stopping, int n, MPI_Request *requests, long most, struct ao_cluster *serving)
{
    long pause = POLL_FIRST_NS, slept = 0;
    double spin_until = now_seconds() + 1e-9 * (double)SPIN_NS;
    for (;;) {
        int done = 0;
        if (serving)
            serve_claims(serving);
        MPI_Testall(n, requests, &done, MPI_STATUSES_IGNORE);
        if (done)
            return true;
        if (stopping && atomic_load_explicit(stopping, memory_order_relaxed))
            return false;
        if (!most || now_seconds() < spin_until)
            continue;
        sleep_ns(pause);
        slept += pause;
        long cap = slept < IDLE_AFTER_NS && most > POLL_MOST_NS ? POLL_MOST_NS : most;
        pause = pause * 2 < cap ? pause * 2 : cap;
    }
}

/* Lock held: makes room for the chunks of a pass of count entries (each has one at least) and
 * forgets the last pass's; false, with one message the first time, when memory is short (the
 * rank then takes no chunks: rank 0's threads trace the pass). */
static bool reserve(struct ao_cluster *c, int count)
{
    c->range_count = c->moving = c->arrived = 0;
    if (count <= c->range_capacity)
        return true;
    struct range *ranges = realloc(c->ranges, (size_t)count * sizeof *ranges);
    c->ranges = ranges ? ranges : c->ranges;
    MPI_Request *moves = realloc(c->moves, (size_t)count * sizeof *moves);
    c->moves = moves ? moves : c->moves;
    if (!ranges || !moves) {
        if (!c->starved)
            fprintf(stderr, "aoview-mpi: rank %d: out of memory for a pass of %d tiles\n", c->rank, count);
        c->starved = true;
        return false;
    }
    c->range_capacity = count;
    return true;
}

/* Rank 0, lock held: opens pass `pass` of `count` entries when it is new, and hands out a chunk of
 * what is left, at least `least` and at most `most` entries: [*begin, *end), empty when nothing is. */
static void hand_out(struct ao_cluster *c, uint64_t pass, int count, int least, int most, int *begin, int *end)
{
    if (pass > c->pass) {
        c->pass = pass;
        c->next = 0;
        c->count = count;
        c->open = true;
        pthread_cond_signal(&c->opened);
        reserve(c, count);
    }
    int left = pass == c->pass && !c->closed ? c->count - c->next : 0;
    int chunk = left / (CHUNKS * c->size), last = left / (LAST * c->size);
    chunk = chunk < least ? least : chunk > most ? most : chunk;
    if (last < 1)
        last = 1;
    if (chunk > last)
        chunk = last;
    if (chunk > left)
        chunk = left;
    *begin = c->next;
    *end = c->next += chunk;
}

/* The sums of chunk k of the pass, as a buffer and a count of floats. */
static float *chunk_sums(const struct ao_cluster *c, int k, int *floats)
{
    *floats = (c->ranges[k].end - c->ranges[k].begin) * c->entry_floats;
    return c->pass_sums + (size_t)c->ranges[k].begin * (size_t)c->entry_floats;
}

/* Rank 0, lock held: posts the receives of the sums of the chunks granted so far, once it knows
 * where the sums go (a request may come before rank 0's first claim). */
static void post_receives(struct ao_cluster *c)
{
    for (int floats; c->pass_sums && c->moving < c->range_count; c->moving++) {
        float *sums = chunk_sums(c, c->moving, &floats);
        MPI_Irecv(sums, floats, MPI_FLOAT, c->ranges[c->moving].rank, TAG_SUMS, c->claims, &c->moves[c->moving]);
        c->merge_bytes += (double)floats * sizeof(float);
    }
}

/* Rank 0, lock held: answers every request that has come with a chunk, after posting the receive
 * of the chunk's sums; true if there was one. */
static bool serve_pending(struct ao_cluster *c)
{
    bool served = false;
    for (;;) {
        int done = 0;
        MPI_Status status;
        MPI_Test(&c->incoming, &done, &status);
        if (!done)
            return served;
        int grant[2];
        hand_out(c, c->request[0], (int)c->request[1], (int)c->request[2], INT_MAX, &grant[0], &grant[1]);
        if (grant[0] < grant[1] && c->range_count < c->range_capacity) {
            c->ranges[c->range_count++] = (struct range){status.MPI_SOURCE, grant[0], grant[1], 0};
            post_receives(c);
        } else { /* not recorded (memory was short): kept for rank 0's threads */
            c->next = grant[1] = grant[0];
        }
        MPI_Send(grant, 2, MPI_INT, status.MPI_SOURCE, TAG_GRANT, c->claims);
        MPI_Irecv(c->request, 3, MPI_UINT64_T, MPI_ANY_SOURCE, TAG_REQUEST, c->claims, &c->incoming);
        served = true;
    }
}

/* Rank 0, lock not held: answers the requests that have come and posts their sums' receives. */
static void serve_claims(struct ao_cluster *c)
{
    pthread_mutex_lock(&c->lock);
    serve_pending(c);
    pthread_mutex_unlock(&c->lock);
}

/* Rank 0's server thread: answers requests while rank 0's own threads are not claiming (inside
 * long tiles, or not yet started on the pass), when a woken thread may take milliseconds to run on
 * a busy machine. Each claim of rank 0's answers them first, and so does its wait at the pass's
 * end; while its threads claim, the server looks only every CHUNK_SECONDS, as long as a chunk
 * lasts at least, since each of its wake-ups interrupts a render thread (on a virtual machine, at
 * a cost of 3 % of rank 0's time when it looked every 1 ms). Between passes, when no request can
 * come, it sleeps until the next pass opens, waking every ANSWER_POLL_NS: a rank interrupted by
 * itself (ao_cluster_answer) would leave rank 0 waiting for it for ever, at the pass's end or for
 * the sums of a chunk it did not finish, and the server stops the cluster when one answers. */
static void *serve(void *arg)
{
    struct ao_cluster *c = arg;
    long pause = POLL_FIRST_NS;
    while (!atomic_load_explicit(&c->stopping, memory_order_relaxed)) {
        pthread_mutex_lock(&c->lock);
        bool open = c->open, served = false, claiming = false;
        if (!open && !atomic_load(&c->stopping)) { /* the next pass's first requests come as soon as it opens */
            struct timespec until;
            clock_gettime(CLOCK_REALTIME, &until);
            until.tv_nsec += ANSWER_POLL_NS;
            until.tv_sec += until.tv_nsec / 1000000000L;
            until.tv_nsec %= 1000000000L;
            pthread_cond_timedwait(&c->opened, &c->lock, &until);
            pause = POLL_FIRST_NS;
        } else if (open) {
            served = serve_pending(c);
            claiming = c->claiming;
            c->claiming = false;
        }
        pthread_mutex_unlock(&c->lock);
        int answered = 0;
        MPI_Status status;
        MPI_Iprobe(MPI_ANY_SOURCE, TAG_ANSWER, c->control, &answered, &status);
        if (answered) { /* left for ao_cluster_missing to receive */
            atomic_store(&c->interrupted, status.MPI_SOURCE);
            ao_cluster_stop(c);
        }
        if (!open)
            continue;
        pause = claiming ? (long)(CHUNK_SECONDS * 1e9) : served ? POLL_FIRST_NS
                                                    : pause * 2 < POLL_MOST_NS ? pause * 2 : POLL_MOST_NS;
        sleep_ns(pause);
    }
    return NULL;
}

/* Other ranks, lock held: asks rank 0 for the next chunk of the pass. */
static void ask(struct ao_cluster *c, uint64_t pass, int count)
{
    double least = c->entry_seconds > 0.0 ? CHUNK_SECONDS / c->entry_seconds : 1.0;
    uint64_t request[3] = {pass, (uint64_t)count, least < 1.0 ? 1 : least > count ? (uint64_t)count : (uint64_t)least};
    MPI_Send(request, 3, MPI_UINT64_T, 0, TAG_REQUEST, c->claims);
    MPI_Irecv(c->grant, 2, MPI_INT, 0, TAG_GRANT, c->claims, &c->granted);
    c->asked = true;
}

/* Other ranks, lock held: entry n is traced; sends rank 0 the sums of the chunks traced in full, in
 * the order they were granted, which is the order rank 0 posted their receives in. */
static void traced(struct ao_cluster *c, int n)
{
    for (int k = c->range_count - 1; k >= 0; k--)
        if (c->ranges[k].begin <= n && n < c->ranges[k].end) {
            c->ranges[k].left--;
            break;
        }
    for (int floats; c->moving < c->range_count && c->ranges[c->moving].left == 0; c->moving++) {
        float *sums = chunk_sums(c, c->moving, &floats);
        MPI_Isend(sums, floats, MPI_FLOAT, 0, TAG_SUMS, c->claims, &c->moves[c->moving]);
        c->merge_bytes += (double)floats * sizeof(float);
    }
}

/* Other ranks, lock held: the next entry of the pass, or -1 when none is left or the cluster
 * stops. A chunk is asked for as soon as the one before it arrives, so that the answer's round
 * trip overlaps tracing. */
static int claim_remote(struct ao_cluster *c, uint64_t pass, int count)
{
    if (c->pass != pass) { /* tiles cost more in some passes than in others: measure anew */
        c->pass = pass;
        c->begin = c->end = 0;
        c->exhausted = !reserve(c, count);
        c->last_claim = c->entry_seconds = 0.0;
    }
    bool waited = false;
    while (!c->exhausted && c->begin == c->end) {
        if (!c->asked)
            ask(c, pass, count);
        if (!await(&c->stopping, 1, &c->granted, POLL_MOST_NS, NULL))
            return -1;
        waited = true;
        c->asked = false;
        c->begin = c->grant[0];
        c->end = c->grant[1];
        c->exhausted = c->begin == c->end;
        if (!c->exhausted) {
            c->ranges[c->range_count++] = (struct range){c->rank, c->begin, c->end, c->end - c->begin};
            ask(c, pass, count);
        }
    }
    if (c->exhausted)
        return -1;
    double now = now_seconds();
    if (!waited && c->last_claim > 0.0)
        c->entry_seconds = c->entry_seconds > 0.0 ? 0.8 * c->entry_seconds + 0.2 * (now - c->last_claim)
                                                  : now - c->last_claim;
    c->last_claim = now;
    return c->begin++;
}

/* Lock held: where the sums of pass's entries go. */
static void locate_sums(struct ao_cluster *c, const struct ao_share_pass *pass)
{
    _Static_assert(sizeof(struct ao_vec3) == 3 * sizeof(float), "pixel sums are 3 packed floats");
    c->pass_sums = &pass->sums->x;
    c->entry_floats = 3 * pass->pixels;
}

/* Rank 0, lock held: the next chunk, in the order they were granted, whose sums have arrived, as
 * entries [arrived[0], arrived[1]); left as they are when it has not. */
static void take_arrived(struct ao_cluster *c, int arrived[2])
{
    int done = 0;
    if (c->arrived < c->moving)
        MPI_Test(&c->moves[c->arrived], &done, MPI_STATUS_IGNORE);
    if (done) {
        arrived[0] = c->ranges[c->arrived].begin;
        arrived[1] = c->ranges[c->arrived++].end;
    }
}

static int claim(void *user, const struct ao_share_pass *pass, int done, int arrived[2])
{
    struct ao_cluster *c = user;
    int n = -1, end;
    pthread_mutex_lock(&c->lock);
    locate_sums(c, pass);
    if (c->rank == 0) {
        serve_pending(c);
        post_receives(c);
        hand_out(c, pass->serial, pass->count, 1, 1, &n, &end);
        n = n < end ? n : -1;
        c->claiming = n >= 0;
        take_arrived(c, arrived);
    } else {
        if (done >= 0)
            traced(c, done);
        n = claim_remote(c, pass->serial, pass->count);
    }
    c->tiles += n >= 0;
    pthread_mutex_unlock(&c->lock);
    if (n >= 0 && c->delay_ns)
        sleep_ns(c->delay_ns);
    return n;
}

/* What rank 0 sends at the beginning of every pass: the settings and restarts that every rank
 * renders it with, or (go 0) the end of the run; as bytes, since the ranks run one binary. */
struct start {
    struct ao_settings settings;
    uint64_t restarts;
    uint64_t go;
};

/* Broadcasts rank 0's start to every rank; false when the cluster stops first. */
static bool broadcast_start(struct ao_cluster *c, struct start *start)
{
    MPI_Request pending;
    MPI_Ibcast(start, sizeof *start, MPI_BYTE, 0, c->passes, &pending);
    return await(&c->stopping, 1, &pending, POLL_IDLE_NS, NULL);
}

/* Rank 0 sends its settings and restarts; the others wait for them. */
static bool begin_pass(void *user, struct ao_settings *settings, uint64_t *restarts)
{
    struct ao_cluster *c = user;
    struct start start;
    memset(&start, 0, sizeof start);
    if (c->rank == 0) { /* the others' requests come before rank 0's first claim: serve them */
        pthread_mutex_lock(&c->lock);
        c->closed = false;
        c->open = true;
        pthread_cond_signal(&c->opened);
        pthread_mutex_unlock(&c->lock);
        start.settings = *settings;
        start.restarts = *restarts;
        start.go = 1;
    }
    if (!broadcast_start(c, &start) || !start.go)
        return false;
    *settings = start.settings;
    *restarts = start.restarts;
    return true;
}

/* Rank 0 sends its tile states; the others wait for them. */
static bool pass_states(void *user, void *tiles, size_t size)
{
    struct ao_cluster *c = user;
    assert(size <= INT_MAX);
    double began = now_seconds();
    MPI_Request pending;
    MPI_Ibcast(tiles, (int)size, MPI_BYTE, 0, c->passes, &pending);
    if (!await(&c->stopping, 1, &pending, 0, NULL)) /* in flight: rank 0 sent the start and its states */
        return false;
    pthread_mutex_lock(&c->lock);
    c->merge_bytes += (double)size * (c->rank == 0 ? c->size - 1 : 1);
    c->moved += now_seconds() - began;
    pthread_mutex_unlock(&c->lock);
    return true;
}

/* Rank 0's render thread ends (the window closed, or the run is over): the others' end too. */
static void end_run(void *user)
{
    struct ao_cluster *c = user;
    struct start start;
    memset(&start, 0, sizeof start);
    if (c->rank == 0 && !atomic_load(&c->stopping))
        broadcast_start(c, &start);
}

/* The pass's seconds are the slowest rank's, the previous merge included; waiting for it doubles
 * as the barrier, with sleeps (rank 0 answering the others' last requests meanwhile), and tells
 * whether a rank gave the pass up (rank 0 then hands out no more of it, so that the others come
 * soon). Then the sums of the chunks, sent as they were traced, have arrived or are the last in
 * flight: every rank waits for its receives or sends without sleeping, even for a pass given up
 * (rank 0's receives write into the pass's sums), and rank 0 adds up the rays. */
static bool merge(void *user, const struct ao_share_pass *pass, bool finished, uint64_t rays[2], double *seconds)
{
    struct ao_cluster *c = user;
    double start = now_seconds(), slowest[2] = {*seconds + c->merge_seconds, finished ? 0.0 : 1.0};
    if (!finished && c->rank == 0) { /* nothing more is handed out: the others come soon */
        pthread_mutex_lock(&c->lock);
        c->closed = true;
        pthread_mutex_unlock(&c->lock);
    }
    MPI_Request pending;
    MPI_Iallreduce(MPI_IN_PLACE, slowest, 2, MPI_DOUBLE, MPI_MAX, c->passes, &pending);
    if (!await(&c->stopping, 1, &pending, POLL_MOST_NS, c->rank == 0 ? c : NULL))
        return false;
    /* every rank is here: no request is left for rank 0's server thread, no chunk to trace */
    pthread_mutex_lock(&c->lock);
    c->open = false;
    locate_sums(c, pass);
    if (c->rank == 0)
        post_receives(c);
    int moves = c->moving;
    pthread_mutex_unlock(&c->lock);
    double arrived = now_seconds();
    if (!await(&c->stopping, moves, c->moves, 0, NULL) || slowest[1] > 0.0)
        return false;
    MPI_Reduce(c->rank == 0 ? MPI_IN_PLACE : rays, rays, 2, MPI_UINT64_T, MPI_SUM, 0, c->passes);
    *seconds = slowest[0];
    c->merge_seconds = now_seconds() - start;
    c->merges++;
    c->waited += arrived - start;
    c->moved += now_seconds() - arrived;
    return true;
}

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
    await(NULL, 1, &pending, POLL_MOST_NS, NULL);
    return all;
}

bool ao_cluster_same(uint64_t value)
{
    uint64_t range[2] = {value, ~value}; /* the smallest value, and the largest as its complement */
    MPI_Request pending;
    MPI_Iallreduce(MPI_IN_PLACE, range, 2, MPI_UINT64_T, MPI_MIN, MPI_COMM_WORLD, &pending);
    await(NULL, 1, &pending, POLL_MOST_NS, NULL);
    return range[0] == ~range[1];
}

void ao_cluster_finalize(void)
{
    MPI_Finalize();
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
    MPI_Comm_dup(MPI_COMM_WORLD, &c->claims);
    MPI_Comm_dup(MPI_COMM_WORLD, &c->passes);
    MPI_Comm_dup(MPI_COMM_WORLD, &c->control);
    pthread_mutex_init(&c->lock, NULL);
    pthread_cond_init(&c->opened, NULL);
    atomic_init(&c->stopping, false);
    atomic_init(&c->interrupted, -1);
    c->share = (struct ao_render_share){.begin = begin_pass, .states = pass_states, .claim = claim, .merge = merge,
                                        .end = end_run,
                                        .follows = c->rank != 0, .user = c};
    const char *delay = getenv("AO_MPI_TEST_DELAY_US");
    c->delay_ns = delay ? 1000L * strtol(delay, NULL, 10) : 0;
    size_t ranks = (size_t)c->size;
    bool ok = true;
    if (c->rank == 0) {
        c->pending = calloc(ranks, sizeof *c->pending);
        c->answers = calloc(ranks, sizeof *c->answers);
        c->tiles_by_rank = calloc(ranks, sizeof *c->tiles_by_rank);
        ok = c->pending && c->answers && c->tiles_by_rank;
        if (ok) {
            MPI_Irecv(c->request, 3, MPI_UINT64_T, MPI_ANY_SOURCE, TAG_REQUEST, c->claims, &c->incoming);
            ok = c->serving = pthread_create(&c->server, NULL, serve, c) == 0;
        }
    }
    if (!ok)
        fprintf(stderr, "aoview-mpi: out of memory or threads for the cluster\n");
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

void ao_cluster_stop(struct ao_cluster *cluster)
{
    atomic_store(&cluster->stopping, true);
    pthread_mutex_lock(&cluster->lock);
    pthread_cond_broadcast(&cluster->opened);
    pthread_mutex_unlock(&cluster->lock);
}

void ao_cluster_answer(struct ao_cluster *cluster, int sig)
{
    MPI_Send(&sig, 1, MPI_INT, 0, TAG_ANSWER, cluster->control);
}

int ao_cluster_interrupted(struct ao_cluster *cluster, int *sig)
{
    int rank = atomic_load(&cluster->interrupted);
    if (sig)
        *sig = rank > 0 && cluster->pending[rank] == MPI_REQUEST_NULL ? cluster->answers[rank] : 0;
    return rank;
}

void ao_cluster_missing(struct ao_cluster *cluster, double seconds, char *out, size_t size)
{
    MPI_Request *pending = cluster->pending;
    int ranks = cluster->size, left = ranks - 1;
    for (int r = 1; r < ranks; r++)
        MPI_Irecv(&cluster->answers[r], 1, MPI_INT, r, TAG_ANSWER, cluster->control, &pending[r]);
    for (double deadline = now_seconds() + seconds; left > 0 && now_seconds() < deadline; sleep_ns(POLL_MOST_NS))
        for (int r = 1; r < ranks; r++) {
            int done = 0;
            if (pending[r] != MPI_REQUEST_NULL && MPI_Test(&pending[r], &done, MPI_STATUS_IGNORE) == MPI_SUCCESS && done)
                left--;
        }
    size_t used = 0;
    out[0] = '\0';
    for (int r = 1; r < ranks; r++)
        if (pending[r] != MPI_REQUEST_NULL && used < size)
            used += (size_t)snprintf(out + used, size - used, "%s%d", used ? ", " : "", r);
}

void ao_cluster_summary(struct ao_cluster *cluster, char *out, size_t size)
{
    unsigned long long mine = cluster->tiles, *all = cluster->tiles_by_rank;
    MPI_Request pending;
    MPI_Igather(&mine, 1, MPI_UNSIGNED_LONG_LONG, all, 1, MPI_UNSIGNED_LONG_LONG, 0, cluster->control, &pending);
    await(NULL, 1, &pending, POLL_IDLE_NS, NULL);
    int used = snprintf(out, size, "%d rank%s, tiles traced by rank", cluster->size, cluster->size > 1 ? "s" : "");
    for (int r = 0; all && r < cluster->size && used >= 0 && (size_t)used < size; r++)
        used += snprintf(out + used, size - (size_t)used, "%s %d: %llu", r ? "," : "", r, all[r]);
    if (used >= 0 && (size_t)used < size)
        snprintf(out + used, size - (size_t)used, "; %llu merges moved %.1f MB (tiles in, tile states out) in %.3f s, after %.3f s waiting for the slowest rank",
                 (unsigned long long)cluster->merges, cluster->merge_bytes / 1e6, cluster->moved, cluster->waited);
}

void ao_cluster_destroy(struct ao_cluster *cluster)
{
    if (!cluster)
        return;
    ao_cluster_stop(cluster);
    if (cluster->serving) {
        pthread_join(cluster->server, NULL);
        MPI_Cancel(&cluster->incoming);
        MPI_Wait(&cluster->incoming, MPI_STATUS_IGNORE);
    }
    MPI_Comm_free(&cluster->claims);
    MPI_Comm_free(&cluster->passes);
    MPI_Comm_free(&cluster->control);
    pthread_cond_destroy(&cluster->opened);
    pthread_mutex_destroy(&cluster->lock);
    free(cluster->ranges);
    free(cluster->moves);
    free(cluster->pending);
    free(cluster->answers);
    free(cluster->tiles_by_rank);
    free(cluster);
}
