/* "How long?": the time left of a run, estimated from the frames a consumer sees, for the
 * headless progress bar and the window's overlay alike. */
#ifndef AO_PROGRESS_H
#define AO_PROGRESS_H

#include <stddef.h>
#include <stdint.h>

#include "frame.h"

/* What the estimate remembers of the full frames fed to it; zero-initialise. */
struct ao_progress {
    uint64_t restarts;       /* of the last frame fed; another value starts over */
    double seconds, spp;     /* of the last frame fed (spp: its mean_spp); seconds 0: none yet */
    double rate;             /* recent AO samples per pixel of the image per second, smoothed over
                                passes */
};

/* Feeds the facts of a newly taken full frame (frames in order; a restart starts over; a preview,
 * pass 0, is ignored). Pure. */
void ao_progress_add(struct ao_progress *p, const struct ao_frame_info *info);

/* The seconds left of the run whose newest full frame info was fed last: the least of the time the
 * work left (info's spp_left: the samples the tiles still sampled lack of target_spp) takes at the
 * recent rate, time_limit - seconds under a time limit, and under a target error seconds
 * ((error / target)^2 - 1) (the error falls as 1/sqrt(samples)); 0 once done; NAN while not known
 * (no rate yet: nothing of info's run fed, or a preview). Pure. */
double ao_progress_left(const struct ao_progress *p, const struct ao_frame_info *info);

/* The share of the run done, from 0 to 1: seconds / (seconds + the time left), 1 only once done;
 * from the samples (mean spp against mean spp and spp_left) while the time left is not known.
 * Pure. */
double ao_progress_share(const struct ao_progress *p, const struct ao_frame_info *info);

/* Writes "~N s left" (one decimal below 10 s; "<0.1 s left" for less than 0.05 s but more than
 * 0) into out, or "" for NAN. Pure. */
void ao_progress_format(double left, char *out, size_t size);

#endif
