/* The renderer's side of a share (share.h): a pass whose work list other processes borrow from
 * and whose borrowed tiles this process traces, and the image gathered from every process's tiles.
 * Private to the renderer: render.c calls these when its config has a share. */
#ifndef AO_RENDER_SHARE_H
#define AO_RENDER_SHARE_H

#include <stdbool.h>

#include "frame.h"
#include "pass.h"

/* Runs one pass on every thread of the team with the share: the entries of this process's list,
 * adding those that other processes traced for it as their sums come, then tiles borrowed from
 * other processes; then waits for the sums of the entries it lent. False when the pass was aborted
 * or given up by the share, or the share stops. Render thread. */
bool ao_render_share_pass(struct ao_run *r);

/* Gathers every process's tiles (a tile not traced in this run black, with no samples); the leader
 * resolves them into the back frame with info, its spp and mean spp those of the tiles gathered
 * when `counted` (after an interruption, when the aborted pass's finished tiles hold more than info
 * says). False when the share stops (or, the leader, memory is short). Render thread, or main
 * after the render thread was joined. */
bool ao_render_share_gather(struct ao_run *r, const struct ao_frame_info *info, bool counted);

/* The leader: tells the others that a gather comes (with settings, which it leaves as they are),
 * gathers the image and publishes it with info; false when the share stops or memory is short.
 * Render thread. */
bool ao_render_share_frame(struct ao_run *r, const struct ao_settings *settings, const struct ao_frame_info *info);

#endif
