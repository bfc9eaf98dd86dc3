/* "How long?": how far a run is and the time it has left, from the frames a consumer sees, for
 * the headless progress bar and the window's status alike (docs/views.md, "How long?"). */
#ifndef AO_PROGRESS_H
#define AO_PROGRESS_H

#include <stddef.h>
#include <stdint.h>

#include "frame.h"

/* How many of a run's latest passes the rate is taken over. */
enum { AO_PROGRESS_RECENT = 8 };

/* What the estimate remembers of the full frames fed to it; zero-initialise. */
struct ao_progress {
    uint64_t restarts;       /* of the last frame fed; another value starts over */
    uint32_t pass;           /* of the last frame fed; 0: none of its run yet */
    double seconds, spp;     /* of the last frame fed (spp: its mean_spp) */
    uint64_t rays, eye_rays; /* of the last frame fed: all its rays, and its eye rays */
    int count;               /* passes kept below: the run's latest, the first left out once there
                                is a second (its single samples on an eye ray each cost the most) */
    double rays_of[AO_PROGRESS_RECENT];   /* each one's rays (eye and AO) */
    double seconds_of[AO_PROGRESS_RECENT];/* and seconds */
    double eye_share[AO_PROGRESS_RECENT]; /* and eye rays per AO sample */
    double longest;          /* the longest pass of the run, in seconds */
    double share;            /* the most ao_progress_share said of the run */
};

/* Feeds the facts of a newly taken full frame (frames in order; a restart starts over; a preview,
 * pass 0, is ignored). Pure. */
void ao_progress_add(struct ao_progress *p, const struct ao_frame_info *info);

/* The seconds left of the run whose newest full frame info was fed last, an estimate that errs
 * long: the work the run may still do, each sample a pixel lacks of target_spp (the mean's lack:
 * no pixel passes the target) taken as an AO ray and its share of an eye ray (the largest of the
 * recent passes'), at the slowest recent rate of rays per second: of the last AO_PROGRESS_RECENT
 * passes together, and of each of them that took an AO_PROGRESS_RECENT-th of their time or more
 * (a pass of a few tiles, slow for its fixed costs, does not stand for the run); the least of that,
 * time_limit - seconds plus the longest pass (the run ends at the first pass end past the limit),
 * and under a target error seconds ((error / target)^2 - 1) (the error falls as 1/sqrt(samples),
 * faster with adaptive sampling); 0 once done; NAN while not known (nothing of info's run fed, or
 * a preview). Pure. */
double ao_progress_left(const struct ao_progress *p, const struct ao_frame_info *info);

/* The share of the run done, from 0 to 1, for the frame fed last (info): seconds / (seconds + the
 * time left) or, while that is not known, mean_spp / target_spp, but never less than it said
 * before in the run (the time left errs long, so the share errs short: the largest is the best);
 * below 1 until done, 1 once done. */
double ao_progress_share(struct ao_progress *p, const struct ao_frame_info *info);

/* Writes "~N s left" (one decimal below 10 s; "<0.1 s left" for less than 0.05 s but more than
 * 0) into out, or "" for NAN. Pure. */
void ao_progress_format(double left, char *out, size_t size);

/* Writes what the run's samples are into out: "mean N spp, up to T", N the mean samples per pixel
 * rounded down (so that it reads T only once every pixel has T) and T target_spp; "" for a
 * preview (pass 0). Pure. */
void ao_progress_format_spp(const struct ao_frame_info *info, char *out, size_t size);

#endif
