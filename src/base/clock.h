/* The monotonic clock in seconds: the one clock of every duration aoview measures (render time, a
 * frame's cost on screen, the waits of aoview-mpi, the progress bar's redraws). Header only. */
#ifndef AO_CLOCK_H
#define AO_CLOCK_H

#include <time.h>

/* Seconds of CLOCK_MONOTONIC, from an arbitrary start. Any thread. */
static inline double ao_clock_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif
