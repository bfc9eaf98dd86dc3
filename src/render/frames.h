/* The triple buffer that hands frames from the render thread to their one consumer (the GL thread,
 * or main when headless) without either waiting: the producer fills the back frame and publishes
 * it with one atomic exchange; the consumer takes the newest. Frames grow to the size asked (their
 * pixels as pages.h gives big buffers). */
#ifndef AO_FRAMES_H
#define AO_FRAMES_H

#include <stdatomic.h>
#include <stddef.h>

#include "frame.h"

/* How many published frames' facts the log keeps for its consumer. */
enum { AO_FRAMES_LOG = 256 };

/* The three frames: the producer owns frames[back], the consumer frames[front]; `middle` holds the
 * third index, with a flag set while it is newer than what the consumer has. Each frame's buffers
 * hold room[k] floats of pixels and of tile errors. And the log of every published frame's facts,
 * a ring of which the producer has written `logged` entries and the consumer read `read`. */
struct ao_frames {
    struct ao_frame frames[3];
    size_t room[3][2];
    uint64_t stamp[3];       /* ao_frames_stamp_back's stamp of each frame's pixels, or 0 */
    int back, front;
    atomic_uint middle;
    struct ao_frame_info log[AO_FRAMES_LOG];
    atomic_uint_fast64_t logged, read;
};

/* Starts with three empty frames. */
void ao_frames_init(struct ao_frames *fs);

/* Frees the frames' buffers. */
void ao_frames_finish(struct ao_frames *fs);

/* The back frame, made width x height pixels with room for `tiles` tile errors (its buffers grown
 * where short, never shrunk); NULL with one message when memory is short. Producer thread. */
struct ao_frame *ao_frames_back(struct ao_frames *fs, int width, int height, int tiles);

/* ao_frames_back for a producer that brings the back frame's pixels up to date in place: *kept is
 * the stamp ao_frames_stamp_back last gave them (0 when they were filled otherwise since, or their
 * size changed); until it stamps them again they count as filled otherwise. Producer thread. */
struct ao_frame *ao_frames_back_stamped(struct ao_frames *fs, int width, int height, int tiles, uint64_t *kept);

/* Stamps the back frame's pixels, now up to date as of `stamp`. Producer thread. */
void ao_frames_stamp_back(struct ao_frames *fs, uint64_t stamp);

/* Publishes the back frame, filled in: it becomes the newest, and its facts go into the log
 * (unless AO_FRAMES_LOG entries wait there unread). Producer thread. */
void ao_frames_publish(struct ao_frames *fs);

/* The newest frame published since the last call, or NULL; valid until the next call. Consumer. */
const struct ao_frame *ao_frames_take(struct ao_frames *fs);

/* Copies the facts of up to `most` frames published since the last call into out, oldest first,
 * and returns how many; the frames a consumer never takes are there too (but for those published
 * while the log was full). Consumer. */
int ao_frames_take_log(struct ao_frames *fs, struct ao_frame_info *out, int most);

#endif
