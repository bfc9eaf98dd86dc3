/* The processes of an MPI run that render one image together (aoview-mpi): rank 0 leads, sending
 * every pass's settings (its window's) to the others, and hands out the tiles of each pass on
 * request, in chunks that shrink as the pass runs out, so that a slow rank takes fewer; receives
 * each chunk's sums as soon as it is traced, and sends its tile states with the next pass's
 * settings; the end of a run, interrupted or not. Only this file and main_mpi.c include mpi.h. */
#ifndef AO_CLUSTER_H
#define AO_CLUSTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "render.h"

/* The cluster; opaque. */
struct ao_cluster;

/* Starts MPI with threads (claims and merges come from render threads); false with one message
 * when MPI cannot give that. *rank and *size: this process's rank and the number of ranks. */
bool ao_cluster_init(int *argc, char ***argv, int *rank, int *size);

/* True when every rank passes ok (a collective: every rank calls it alike). */
bool ao_cluster_agree(bool ok);

/* True when every rank passes the same value (a collective). */
bool ao_cluster_same(uint64_t value);

/* Ends MPI after a run that every rank finished alike (a collective). */
void ao_cluster_finalize(void);

/* Sets up claims and merges and, on rank 0, the thread that serves claims; NULL with one message
 * when out of memory or threads. A collective. */
struct ao_cluster *ao_cluster_create(void);

/* The render config's share for this rank; valid while the cluster lives. */
const struct ao_render_share *ao_cluster_share(struct ao_cluster *cluster);

/* Makes claims and merges in flight give up (they return "none" and false): the run is ending.
 * Any thread. */
void ao_cluster_stop(struct ao_cluster *cluster);

/* After an interruption by sig, ranks other than 0: tells rank 0 this rank is alive, and was
 * interrupted (rank 0 stops the cluster when it was not itself). */
void ao_cluster_answer(struct ao_cluster *cluster, int sig);

/* Rank 0: the first other rank that was interrupted while rank 0 was not (the cluster stopped
 * then), or -1; *sig (unless NULL) its signal once ao_cluster_missing took its answer, else 0. */
int ao_cluster_interrupted(struct ao_cluster *cluster, int *sig);

/* After an interruption, rank 0: waits up to `seconds` for every other rank's answer and writes
 * the ranks that did not answer ("2", "1, 3") into out, "" when all did. */
void ao_cluster_missing(struct ao_cluster *cluster, double seconds, char *out, size_t size);

/* At the end of a finished run (a collective): on rank 0, writes the tiles each rank traced and
 * the merges' bytes and seconds, this rank's, into out (one line, no newline). */
void ao_cluster_summary(struct ao_cluster *cluster, char *out, size_t size);

/* Stops the claim server and frees the cluster (not a collective); accepts NULL. */
void ao_cluster_destroy(struct ao_cluster *cluster);

#endif
