/* The loans of an aoview-mpi pass (see cluster_state.h): a rank whose list runs out asks another
 * for entries it has not begun, traces them and sends their sums back packed; the lender answers
 * asks between its own tiles and adds the sums when they come. And the waits, which serve the
 * loans while they wait. */
#include "cluster_state.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "clock.h"
#include "pack.h"

void ao_cluster_sleep(long ns)
{
    struct timespec ts = {.tv_sec = ns / 1000000000L, .tv_nsec = ns % 1000000000L};
    nanosleep(&ts, NULL);
}

static void serve(struct ao_cluster *c);

bool ao_cluster_await(struct ao_cluster *c, int n, MPI_Request *requests, long most, bool serving, double deadline)
{
    long pause = POLL_FIRST_NS, slept = 0;
    double spin_until = ao_clock_seconds() + 1e-9 * (double)SPIN_NS;
    for (;;) {
        int done = 0;
        if (serving)
            serve(c);
        MPI_Testall(n, requests, &done, MPI_STATUSES_IGNORE);
        if (done)
            return true;
        if (deadline > 0.0 ? ao_clock_seconds() > deadline
                           : c && atomic_load_explicit(&c->stopping, memory_order_relaxed))
            return false;
        if (!most || ao_clock_seconds() < spin_until)
            continue;
        ao_cluster_sleep(pause);
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
    c->opened_at = ao_clock_seconds();
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
        double theirs, ours = own_speed(c, ao_clock_seconds());
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

bool ao_cluster_poll(void *user, const struct ao_share_pass *pass, int arrived[2])
{
    struct ao_cluster *c = user;
    if (c->delay_ns)
        ao_cluster_sleep(c->delay_ns);
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
        c->emptied_at = ao_clock_seconds();
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
    ao_cluster_sleep(*pause);
    *pause = *pause * 2 < POLL_MOST_NS ? *pause * 2 : POLL_MOST_NS;
    pthread_mutex_lock(&c->lock);
}

bool ao_cluster_borrow(void *user, const struct ao_share_pass *pass, struct ao_share_loan *loan)
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

void ao_cluster_repay(void *user, const struct ao_share_pass *pass, const struct ao_share_loan *loan)
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

bool ao_cluster_settle(void *user, const struct ao_share_pass *pass, bool finished, int arrived[2])
{
    struct ao_cluster *c = user;
    long pause = POLL_FIRST_NS / 4;
    double spin_until = ao_clock_seconds() + 1e-9 * (double)SPIN_NS;
    pthread_mutex_lock(&c->lock);
    open_pass(c, pass);
    if (c->open && finished) {
        c->tiles += (uint64_t)(pass->count - c->lent_entries);
        if (pass->count - c->lent_entries >= 2)
            c->speed = own_speed(c, c->emptied_at > 0.0 ? c->emptied_at : ao_clock_seconds());
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
        if (ao_clock_seconds() > spin_until)
            pause_locked(c, &pause);
    }
}
