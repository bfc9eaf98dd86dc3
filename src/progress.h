/* "How long?": the time left of a run, estimated from the frames a consumer sees, for the
 * headless progress bar and the window's overlay alike. */
#ifndef AO_PROGRESS_H
#define AO_PROGRESS_H

#include <stddef.h>
#include <stdint.h>

#include "render.h"

/* What the estimate remembers of the frames fed to it; zero-initialise. */
struct ao_progress {
    uint64_t restarts;       /* of the last frame fed; another value starts over */
    double seconds, spp;     /* of the last frame fed; seconds 0: none yet */
    double rate;             /* recent samples per pixel per second, smoothed over passes */
};

/* Feeds the facts of a newly taken frame (frames in order; a restart starts over). Pure. */
void ao_progress_add(struct ao_progress *p, const struct ao_frame_info *info);

/* The seconds left of the run whose newest frame info was fed last: the least of the time toward
 * target_spp at the recent rate, time_limit - seconds under a time limit, and under a target
 * error seconds ((error / target)^2 - 1) (the error falls as 1/sqrt(samples)); 0 once done, NAN
 * before any estimate. Pure. */
double ao_progress_left(const struct ao_progress *p, const struct ao_frame_info *info);

/* Writes "~N s left" (one decimal below 10 s) into out, or "" for NAN. Pure. */
void ao_progress_format(double left, char *out, size_t size);

#endif
