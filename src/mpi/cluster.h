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

/* Rank 0's value, on every rank (a collective). */
uint64_t ao_cluster_first(uint64_t value);

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

/* After the render thread ended without an interruption: true when rank 0 ended the run (its
 * last step), false when this rank's own renderer stopped. */
bool ao_cluster_ended(struct ao_cluster *cluster);

/* At the end of a finished run (a collective): on rank 0, writes the tiles each rank traced, the
 * bytes through rank 0 per pass (and of them the loans'), the image gathers and the seconds rank 0
 * spent in collectives and gathers into out (one line, no newline). */
void ao_cluster_summary(struct ao_cluster *cluster, char *out, size_t size);

/* Frees the cluster (not a collective); accepts NULL. */
void ao_cluster_destroy(struct ao_cluster *cluster);

#endif
