/* The window's mouse gestures (gestures.c): a left drag orbits, a right drag pans, the wheel zooms,
 * gathered between frames and applied as one camera change, the same as the moves one by one; a
 * left press on the comparison's divider drags the divider and moves no camera; a second button
 * changes nothing while one drags. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "gestures.h"
#include "unit_main.h"

static struct ao_camera camera(void)
{
    return (struct ao_camera){.eye = {0, 1, 4}, .target = {0, 0.5f, 0}, .up = {0, 1, 0}, .fov = 40};
}

/* A drag across the whole image height orbits half a turn: the eye ends on the far side. */
static void test_orbit(void **state)
{
    (void)state;
    struct ao_gestures g = {.drag = AO_DRAG_NONE};
    ao_gestures_press(&g, AO_DRAG_ORBIT, 100, 50, NAN);
    assert_int_equal(g.drag, AO_DRAG_ORBIT);
    assert_false(ao_gestures_move(&g, 150, 50));
    assert_false(ao_gestures_move(&g, 300, 50));
    assert_true(ao_gestures_pending(&g));
    struct ao_camera c = camera(), want = camera();
    ao_gestures_apply(&g, &c, 200);
    assert_false(ao_gestures_pending(&g));
    ao_camera_orbit(&want, (float)(3.14159265358979323846 * 200 / 200), 0.0f);
    ao_camera_pan(&want, 0.0f, 0.0f);
    ao_camera_zoom(&want, 1.0f);
    assert_memory_equal(&c, &want, sizeof c);
    assert_true(c.eye.z < 0.0f);
    ao_gestures_release(&g, AO_DRAG_ORBIT);
    assert_int_equal(g.drag, AO_DRAG_NONE);
    assert_false(ao_gestures_move(&g, 400, 60));
    assert_false(ao_gestures_pending(&g));
}

/* A right drag pans, the wheel zooms; a second button changes nothing while one drags. */
static void test_pan_and_zoom(void **state)
{
    (void)state;
    struct ao_gestures g = {.drag = AO_DRAG_NONE};
    ao_gestures_press(&g, AO_DRAG_PAN, 10, 10, NAN);
    ao_gestures_press(&g, AO_DRAG_ORBIT, 10, 10, NAN);
    assert_int_equal(g.drag, AO_DRAG_PAN);
    ao_gestures_move(&g, 30, 0);
    ao_gestures_release(&g, AO_DRAG_ORBIT);
    assert_int_equal(g.drag, AO_DRAG_PAN);
    ao_gestures_scroll(&g, 2);
    assert_true(g.pan_x == 20 && g.pan_y == -10 && g.orbit_x == 0 && g.wheel == 2);
    struct ao_camera c = camera(), want = camera();
    ao_gestures_apply(&g, &c, 100);
    ao_camera_orbit(&want, 0.0f, 0.0f);
    ao_camera_pan(&want, 0.2f, -0.1f);
    ao_camera_zoom(&want, (float)pow(0.85, 2));
    assert_memory_equal(&c, &want, sizeof c);
}

/* A left press within the grab distance of the divider drags it: moves say so, and no camera move
 * is gathered; farther away it orbits. */
static void test_divider(void **state)
{
    (void)state;
    struct ao_gestures g = {.drag = AO_DRAG_NONE};
    ao_gestures_press(&g, AO_DRAG_ORBIT, 105, 40, 100);
    assert_int_equal(g.drag, AO_DRAG_DIVIDER);
    assert_true(ao_gestures_move(&g, 150, 40));
    assert_false(ao_gestures_pending(&g));
    ao_gestures_release(&g, AO_DRAG_ORBIT);
    assert_int_equal(g.drag, AO_DRAG_NONE);
    ao_gestures_press(&g, AO_DRAG_ORBIT, 100 + AO_GESTURES_GRAB + 1, 40, 100);
    assert_int_equal(g.drag, AO_DRAG_ORBIT);
    ao_gestures_press(&g, AO_DRAG_PAN, 100, 40, 100);
    assert_int_equal(g.drag, AO_DRAG_ORBIT);
}

UNIT_TEST_MAIN(cmocka_unit_test(test_orbit), cmocka_unit_test(test_pan_and_zoom), cmocka_unit_test(test_divider))
