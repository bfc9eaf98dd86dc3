/* What the ranks of an aoview-mpi run (cluster.h) tell each other when the run is interrupted or a
 * rank fails: a listener thread that hears another rank stop, the stop that makes every wait give
 * up, and after the interruption rank 0's questions and the others' answers (alive, by which
 * signal), the salvage gather's deadline and the exit status rank 0 releases them with. */
#ifndef AO_CLUSTER_FAULTS_H
#define AO_CLUSTER_FAULTS_H

#include <stdbool.h>
#include <stddef.h>

/* The cluster (cluster.h); opaque. */
struct ao_cluster;

/* Calls stopped(user) once, from the cluster's listener thread, when another rank stopped the run:
 * on rank 0 a rank that was interrupted (or failed), elsewhere rank 0's request to stop. */
void ao_cluster_listen(struct ao_cluster *cluster, void (*stopped)(void *user), void *user);

/* Makes the share's waits give up (loans, collectives and gathers return "none" and false) and
 * ends the listener: the run is ending. Main thread. */
void ao_cluster_stop(struct ao_cluster *cluster);

/* After an interruption, ranks other than 0: tells rank 0 that this rank is alive and stopped,
 * by signal sig (0: at rank 0's request, or its renderer failed). */
void ao_cluster_answer(struct ao_cluster *cluster, int sig);

/* After an interruption, rank 0: asks the ranks that did not stop by themselves to stop. */
void ao_cluster_halt(struct ao_cluster *cluster);

/* After an interruption, rank 0: waits up to `seconds` for every other rank's answer and writes
 * the ranks that did not answer ("2", "1, 3") into out, "" when all did. */
void ao_cluster_missing(struct ao_cluster *cluster, double seconds, char *out, size_t size);

/* After ao_cluster_missing, rank 0: the ranks that answered with a signal into out ("2", "1, 3"),
 * and the first of their signals (0: none did). */
int ao_cluster_signalled(struct ao_cluster *cluster, char *out, size_t size);

/* After an interruption: the gather of ao_render_resolve_stopped waits at most `seconds` from now
 * (on rank 0, for the others' tiles; elsewhere, for its own to leave). */
void ao_cluster_salvage(struct ao_cluster *cluster, double seconds);

/* Rank 0: seconds since the last image gather ended (the newest frame or safety copy); negative
 * when there was none. */
double ao_cluster_copy_age(struct ao_cluster *cluster);

/* After an interruption, rank 0: tells the ranks that answered to end, with the run's status. */
void ao_cluster_release(struct ao_cluster *cluster, int status);

/* After an interruption, ranks other than 0: waits up to `seconds` for rank 0's release; true with
 * its status in *status. */
bool ao_cluster_await_release(struct ao_cluster *cluster, double seconds, int *status);

#endif
