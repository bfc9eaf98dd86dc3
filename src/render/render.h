/* The render thread: progressive AO passes over tiles on worker threads into an accumulation
 * buffer it alone owns, each finished pass published as a frame through a lock-free triple buffer. */
#ifndef AO_RENDER_H
#define AO_RENDER_H

#include <stdbool.h>
#include <stdint.h>

#include "frame.h"
#include "render_config.h"

/* The renderer; opaque. */
struct ao_render;

/* Allocates buffers, starts the render thread and its workers with the initial settings; NULL after
 * one message (text.h) when memory or threads are short. The render thread's messages go to the
 * calling thread's sink, which must outlive the renderer. Any thread; several renderers at once. */
struct ao_render *ao_render_create(const struct ao_render_config *config,
                                   const struct ao_settings *settings);

/* Stops the pass in flight at the next tile, joins every thread, frees everything; accepts NULL. */
void ao_render_destroy(struct ao_render *render);

/* The samples a pixel takes in a run's first pass with samples per pixel per pass spppp (0: auto
 * passes, their first round); a run to no more samples a pixel is one pass. Any thread. */
uint32_t ao_render_first_pass_spp(uint32_t spppp);

/* Copies the current settings into *out. Any thread. */
void ao_render_get_settings(struct ao_render *render, struct ao_settings *out);

/* Applies new settings: a change of size, sampling, AA, output, shading or camera aborts the pass in flight and
 * restarts accumulation (and returns true); spppp and pause take effect at the next pass boundary. Any thread. */
bool ao_render_set_settings(struct ao_render *render, const struct ao_settings *settings);

/* Restarts accumulation with the current settings, aborting the pass in flight. Any thread. */
void ao_render_restart(struct ao_render *render);

/* The newest frame published since the last call, or NULL when none is new; the frame stays valid
 * until the next call. One consumer thread only (the GL thread, or main when headless). */
const struct ao_frame *ao_render_take_frame(struct ao_render *render);

/* Copies the facts of up to `most` frames published since the last call (passes and previews,
 * those never taken included; frames.h's AO_FRAMES_LOG at most wait) into out, oldest first; returns
 * how many. The frame consumer's thread. */
int ao_render_take_log(struct ao_render *render, struct ao_frame_info *out, int most);

/* Blocks until the target spp is reached (true) or ao_render_stop was called or, with a share, the
 * leader ended the run (false: a follower is never done by itself). */
bool ao_render_wait(struct ao_render *render);

/* After an interruption: stops and joins the render thread, then resolves the accumulation as it
 * stands, the aborted pass's finished tiles included, into a frame whose info.spp is the most
 * samples a pixel has (as after every pass) and info.mean_spp their mean, both counted from the
 * pixels. With a share every process calls it: each sends its tiles through the
 * share's gather, and the leader gets the frame (NULL elsewhere, and when the gather failed).
 * Main thread, as the frame consumer; call ao_render_destroy afterwards. */
const struct ao_frame *ao_render_resolve_stopped(struct ao_render *render);

/* Asks the render thread to stop at the next tile boundary and wakes ao_render_wait. Any thread. */
void ao_render_stop(struct ao_render *render);

#endif
