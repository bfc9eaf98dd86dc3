/* The window's mouse gestures: a left drag orbits the camera (or, pressed on the comparison's
 * divider, moves the divider), a right drag pans, the wheel zooms. Moves are gathered between
 * frames and applied as one camera change. No window system: window.c hands the events in. */
#ifndef AO_GESTURES_H
#define AO_GESTURES_H

#include <stdbool.h>

#include "camera.h"

/* What a held button drags. */
enum ao_drag {
    AO_DRAG_NONE = -1,
    AO_DRAG_ORBIT,           /* the left button */
    AO_DRAG_PAN,             /* the right button */
    AO_DRAG_DIVIDER,         /* the left button, pressed within AO_GESTURES_GRAB of the divider */
};

/* How near the comparison's divider (in window units) a left press takes it. */
#define AO_GESTURES_GRAB 6.0

/* The gestures in progress: the drag, the cursor's last position, and the moves not applied yet
 * (cursor travel in window units, wheel steps). Zero it but for drag (AO_DRAG_NONE). The window's
 * thread only. */
struct ao_gestures {
    enum ao_drag drag;
    double cursor_x, cursor_y;
    double orbit_x, orbit_y, pan_x, pan_y, wheel;
};

/* A button pressed at (x, y): starts its drag (ORBIT or PAN) unless one is held; an ORBIT press
 * within AO_GESTURES_GRAB of the divider at x = divider (NAN: none shown) drags the divider. */
void ao_gestures_press(struct ao_gestures *g, enum ao_drag button, double x, double y, double divider);

/* A button released: ends the drag it started. */
void ao_gestures_release(struct ao_gestures *g, enum ao_drag button);

/* The cursor moved to (x, y): a camera drag gathers the move. True while the divider is dragged
 * (the caller moves it to x). */
bool ao_gestures_move(struct ao_gestures *g, double x, double y);

/* The wheel turned by steps (up positive). */
void ao_gestures_scroll(struct ao_gestures *g, double steps);

/* True when moves wait to be applied. */
bool ao_gestures_pending(const struct ao_gestures *g);

/* Applies the gathered moves to camera c, for an image `size` window units high, and forgets them:
 * a drag across the image's height orbits half a turn or pans the image along with the cursor, a
 * wheel step up zooms in by 15 %. */
void ao_gestures_apply(struct ao_gestures *g, struct ao_camera *c, double size);

#endif
