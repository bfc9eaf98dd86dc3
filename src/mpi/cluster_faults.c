/* The faults and interruptions of an aoview-mpi run (see cluster.h and cluster_state.h): the
 * listener thread that hears another rank stop, and what rank 0 and the others tell each other
 * after an interruption (answers, halts, the salvage gather's deadline, the release). */
#include "cluster_faults.h"
#include "cluster_state.h"

#include <stdio.h>

#include "clock.h"

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
        ao_cluster_sleep(LISTEN_NS);
    }
    return NULL;
}

void ao_cluster_listen(struct ao_cluster *cluster, void (*stopped)(void *user), void *user)
{
    cluster->stopped = stopped;
    cluster->stopped_user = user;
    atomic_store(&cluster->listen, true);
    cluster->listening = pthread_create(&cluster->listener, NULL, listen_thread, cluster) == 0;
}

void ao_cluster_stop_listening(struct ao_cluster *cluster)
{
    atomic_store(&cluster->listen, false);
    if (cluster->listening)
        pthread_join(cluster->listener, NULL);
    cluster->listening = false;
}

void ao_cluster_stop(struct ao_cluster *cluster)
{
    atomic_store(&cluster->stopping, true);
    ao_cluster_stop_listening(cluster);
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
    for (double deadline = ao_clock_seconds() + seconds; ao_clock_seconds() < deadline;
         ao_cluster_sleep(POLL_MOST_NS)) {
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
    cluster->salvage_until = ao_clock_seconds() + seconds;
}

double ao_cluster_copy_age(struct ao_cluster *cluster)
{
    double copied = atomic_load(&cluster->copied);
    return copied > 0.0 ? ao_clock_seconds() - copied : -1.0;
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
    if (!ao_cluster_await(NULL, 1, &cluster->released, POLL_MOST_NS, false, ao_clock_seconds() + seconds))
        return false;
    *status = cluster->release_word;
    return true;
}
