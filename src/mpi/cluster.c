/* The ranks of an aoview-mpi run (see cluster.h): MPI's life cycle, the cluster's, the share's
 * per-pass collectives (the leader's step, the tally, the sums added up) and the image gathers;
 * the loans are cluster_loans.c's, the faults cluster_faults.c's. */
#include "cluster.h"
#include "cluster_faults.h"
#include "cluster_state.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "pack.h"

/* What rank 0 sends before every pass: the step, and for a pass the settings and restarts that
 * every rank renders it with; as bytes, since the ranks run one binary. */
struct start {
    struct ao_settings settings;
    uint64_t restarts;
    int32_t step;
};

/* ---- the share's collectives and gathers ---- */

/* Broadcasts rank 0's start to every rank; false when the cluster stops first. */
static bool broadcast_start(struct ao_cluster *c, struct start *start)
{
    MPI_Request pending;
    MPI_Ibcast(start, sizeof *start, MPI_BYTE, 0, c->passes, &pending);
    if (c->rank == 0)
        c->bytes_out += (double)c->fan * sizeof *start;
    return ao_cluster_await(c, 1, &pending, POLL_IDLE_NS, true, 0.0);
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
    double began = ao_clock_seconds();
    if (!broadcast_start(c, &start))
        return AO_SHARE_END;
    if (c->rank == 0)
        c->seconds += ao_clock_seconds() - began;
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
    double began = ao_clock_seconds();
    MPI_Request pending;
    MPI_Iallreduce(MPI_IN_PLACE, tally, 1, c->tally_type, c->tally_op, c->passes, &pending);
    if (!ao_cluster_await(c, 1, &pending, POLL_MOST_NS, true, 0.0))
        return false;
    if (c->rank == 0) {
        c->passes_combined++;
        c->bytes_in += (double)c->fan * sizeof *tally;
        c->bytes_out += (double)c->fan * sizeof *tally;
        c->seconds += ao_clock_seconds() - began;
    }
    return true;
}

static bool add_up(void *user, uint64_t *values, int count)
{
    struct ao_cluster *c = user;
    double began = ao_clock_seconds();
    MPI_Request pending;
    MPI_Iallreduce(MPI_IN_PLACE, values, count, MPI_UINT64_T, MPI_SUM, c->passes, &pending);
    if (!ao_cluster_await(c, 1, &pending, POLL_MOST_NS, true, 0.0))
        return false;
    if (c->rank == 0) {
        c->bytes_in += (double)c->fan * (double)count * sizeof *values;
        c->bytes_out += (double)c->fan * (double)count * sizeof *values;
        c->seconds += ao_clock_seconds() - began;
    }
    return true;
}

static bool due(void *user)
{
    struct ao_cluster *c = user;
    double interval = atomic_load(&c->interval);
    return interval > 0.0 && ao_clock_seconds() - c->last_gather >= interval;
}

/* The gather: rank k's records are tiles k, k + N, k + 2N, ...: rank 0 receives each rank's
 * straight into place, as a strided datatype. After an interruption (salvage) the same with their
 * own tag, until the deadline. */
static bool gather(void *user, const void *mine, int count, size_t size, void *all, int tiles)
{
    struct ao_cluster *c = user;
    bool salvage = c->salvage_until > 0.0;
    int tag = salvage ? TAG_SALVAGE : TAG_GATHER;
    double began = ao_clock_seconds();
    if (c->rank != 0) {
        MPI_Request pending;
        MPI_Isend(mine, (int)((size_t)count * size), MPI_BYTE, 0, tag, c->images, &pending);
        return ao_cluster_await(c, 1, &pending, POLL_MOST_NS, !salvage, c->salvage_until);
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
    bool ok = ao_cluster_await(c, receives, pending, POLL_MOST_NS, !salvage, c->salvage_until);
    for (int k = 0; k < receives; k++)
        MPI_Type_free(&types[k]);
    if (ok) {
        c->gathers++;
        c->gather_bytes += bytes;
        c->seconds += ao_clock_seconds() - began;
        c->last_gather = ao_clock_seconds();
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
    ao_cluster_await(NULL, 1, &pending, POLL_MOST_NS, false, 0.0);
    return all;
}

uint64_t ao_cluster_first(uint64_t value)
{
    MPI_Request pending;
    MPI_Ibcast(&value, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD, &pending);
    ao_cluster_await(NULL, 1, &pending, POLL_MOST_NS, false, 0.0);
    return value;
}

int ao_cluster_differs(uint64_t value)
{
    int rank, size;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    uint64_t *all = rank == 0 ? calloc((size_t)size, sizeof *all) : NULL;
    MPI_Request pending;
    MPI_Igather(&value, 1, MPI_UINT64_T, all, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD, &pending);
    ao_cluster_await(NULL, 1, &pending, POLL_MOST_NS, false, 0.0);
    int first = -1;
    for (int r = 1; all && r < size && first < 0; r++)
        if (all[r] != all[0])
            first = r;
    if (rank == 0 && !all) /* out of memory: which rank is not known */
        first = 0;
    free(all);
    int verdict[2] = {first, first};
    MPI_Ibcast(verdict, 2, MPI_INT, 0, MPI_COMM_WORLD, &pending);
    ao_cluster_await(NULL, 1, &pending, POLL_MOST_NS, false, 0.0);
    return verdict[0];
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
    c->share = (struct ao_render_share){.begin = begin_step, .owns = owns, .poll = ao_cluster_poll,
                                        .borrow = ao_cluster_borrow, .repay = ao_cluster_repay,
                                        .settle = ao_cluster_settle, .combine = combine, .add_up = add_up, .due = due,
                                        .gather = gather, .end = end_run, .follows = c->rank != 0, .user = c};
    const char *delay = getenv("AO_MPI_TEST_DELAY_US");
    c->delay_ns = delay ? 1000L * strtol(delay, NULL, 10) : 0;
    for (int n = 1; n < c->size; n *= 2)
        c->fan++;
    c->victim = -1;
    c->repaying = c->answering = MPI_REQUEST_NULL;
    c->last_gather = ao_clock_seconds();
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

bool ao_cluster_ended(struct ao_cluster *cluster)
{
    return cluster->ended;
}

void ao_cluster_summary(struct ao_cluster *cluster, char *out, size_t size)
{
    ao_cluster_stop_listening(cluster);
    unsigned long long mine = cluster->tiles, *all = cluster->tiles_by_rank;
    MPI_Request pending;
    MPI_Igather(&mine, 1, MPI_UNSIGNED_LONG_LONG, all, 1, MPI_UNSIGNED_LONG_LONG, 0, cluster->control, &pending);
    ao_cluster_await(NULL, 1, &pending, POLL_IDLE_NS, false, 0.0);
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
