/* The renderer's side of an aoview-mpi share (share.h): the run share (pass.h's struct
 * ao_run_share) that begins each pass on every process, runs it lending and borrowing tiles,
 * combines what the decisions need and gathers the image for the leader, which alone keeps frames;
 * and the solo share, which does nothing. Private to the renderer: render.c picks one of them. */
#ifndef AO_RENDER_SHARE_H
#define AO_RENDER_SHARE_H

#include "pass.h"

/* The run share of run with share, its arrays fitted to run's tiles; loop: the render thread's,
 * which the leader asks between passes. NULL with one message when memory is short. Frees with its
 * destroy hook. Whichever thread creates the renderer. */
struct ao_run_share *ao_render_share_create(struct ao_run *run, const struct ao_render_share *share,
                                            const struct ao_run_loop *loop);

/* The solo share (solo.c): one process renders every tile; it begins, combines and adds up
 * nothing, runs a pass on the threads' lanes (ao_pass_run), publishes every pass and resolves the
 * accumulation after an interruption. Stateless: one for every renderer. */
struct ao_run_share *ao_solo_share(void);

#endif
