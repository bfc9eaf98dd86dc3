/* The processes of an MPI run that render one image together (aoview-mpi). Rank r owns the tiles
 * t with t mod N = r and keeps their sums; rank 0 leads, sending every pass's settings (its
 * window's) to the others. After each pass the ranks combine a few numbers in collectives; a rank
 * whose tiles run out borrows some of another's and sends it their sums; rank 0 gathers the image
 * only for a frame (at most at the window's rate), a safety copy, the end and an interruption.
 * This header includes no MPI: only cluster.c, cluster_loans.c and cluster_faults.c (through
 * their private cluster_state.h) do. */
#ifndef AO_CLUSTER_H
#define AO_CLUSTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "share.h"

/* The cluster; opaque. */
struct ao_cluster;

/* Starts MPI with threads (loans are served from render threads); false with one message when MPI
 * cannot give that. *rank and *size: this process's rank and the number of ranks. */
bool ao_cluster_init(int *argc, char ***argv, int *rank, int *size);

/* True when every rank passes ok (a collective: every rank calls it alike). */
bool ao_cluster_agree(bool ok);

/* Rank 0: the first rank whose value differs from rank 0's, or -1 when all agree (a collective). */
int ao_cluster_differs(uint64_t value);

/* Ends MPI after a run that every rank finished alike (a collective). */
void ao_cluster_finalize(void);

/* Sets up the share and the thread that listens for interruptions; NULL with one message when out
 * of memory or threads. A collective. */
struct ao_cluster *ao_cluster_create(void);

/* The render config's share for this rank; valid while the cluster lives. */
const struct ao_render_share *ao_cluster_share(struct ao_cluster *cluster);

/* Rank 0: gathers a frame at most every `seconds` by the clock (the window's frame rate, or
 * headless the safety copy; 0: only at the end and when the renderer idles). */
void ao_cluster_set_interval(struct ao_cluster *cluster, double seconds);

/* Calls stopped(user) once, from the cluster's listener thread, when another rank stopped the run:
 * on rank 0 a rank that was interrupted (or failed), elsewhere rank 0's request to stop. */
void ao_cluster_listen(struct ao_cluster *cluster, void (*stopped)(void *user), void *user);

/* Makes the share's waits give up (loans, collectives and gathers return "none" and false) and
 * ends the listener: the run is ending. Main thread. */
void ao_cluster_stop(struct ao_cluster *cluster);

/* After the render thread ended without an interruption: true when rank 0 ended the run (its
 * last step), false when this rank's own renderer stopped. */
bool ao_cluster_ended(struct ao_cluster *cluster);

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

/* At the end of a finished run (a collective): on rank 0, writes the tiles each rank traced, the
 * bytes through rank 0 per pass (and of them the loans'), the image gathers and the seconds rank 0
 * spent in collectives and gathers into out (one line, no newline). */
void ao_cluster_summary(struct ao_cluster *cluster, char *out, size_t size);

/* Frees the cluster (not a collective); accepts NULL. */
void ao_cluster_destroy(struct ao_cluster *cluster);

#endif
