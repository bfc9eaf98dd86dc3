/* The window's mouse gestures; see gestures.h. */
#include "gestures.h"

#include <math.h>

void ao_gestures_press(struct ao_gestures *g, enum ao_drag button, double x, double y, double divider)
{
    if (g->drag != AO_DRAG_NONE)
        return;
    g->drag = button;
    g->cursor_x = x;
    g->cursor_y = y;
    if (button == AO_DRAG_ORBIT && fabs(x - divider) <= AO_GESTURES_GRAB)
        g->drag = AO_DRAG_DIVIDER;
}

void ao_gestures_release(struct ao_gestures *g, enum ao_drag button)
{
    if (button == g->drag || (g->drag == AO_DRAG_DIVIDER && button == AO_DRAG_ORBIT))
        g->drag = AO_DRAG_NONE;
}

bool ao_gestures_move(struct ao_gestures *g, double x, double y)
{
    if (g->drag == AO_DRAG_NONE)
        return false;
    if (g->drag == AO_DRAG_DIVIDER)
        return true;
    double *dx = g->drag == AO_DRAG_ORBIT ? &g->orbit_x : &g->pan_x;
    double *dy = g->drag == AO_DRAG_ORBIT ? &g->orbit_y : &g->pan_y;
    *dx += x - g->cursor_x;
    *dy += y - g->cursor_y;
    g->cursor_x = x;
    g->cursor_y = y;
    return false;
}

void ao_gestures_scroll(struct ao_gestures *g, double steps)
{
    g->wheel += steps;
}

bool ao_gestures_pending(const struct ao_gestures *g)
{
    return g->orbit_x != 0 || g->orbit_y != 0 || g->pan_x != 0 || g->pan_y != 0 || g->wheel != 0;
}

void ao_gestures_apply(struct ao_gestures *g, struct ao_camera *c, double size)
{
    const double pi = 3.14159265358979323846;
    ao_camera_orbit(c, (float)(pi * g->orbit_x / size), (float)(pi * g->orbit_y / size));
    ao_camera_pan(c, (float)(g->pan_x / size), (float)(g->pan_y / size));
    ao_camera_zoom(c, (float)pow(0.85, g->wheel));
    g->orbit_x = g->orbit_y = g->pan_x = g->pan_y = g->wheel = 0;
}
