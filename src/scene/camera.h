/* Pinhole camera (the convention of docs/contract.md: pixel (i, j) from the top left, vertical fov)
 * and the orbit / pan / zoom moves of the viewer. */
#ifndef AO_CAMERA_H
#define AO_CAMERA_H

#include <stdbool.h>

#include "vec3.h"

/* How far from the local origin, in every coordinate, the viewer's moves may take the eye and the
 * target: far beyond any scene (scene.h's AO_SCENE_MAX_EXTENT, 2^31, whose framed camera stands
 * within 4 times that), and with an orbit about a target there (at most 3 times this) well inside
 * Embree's bound on ray origins (1.844e18, about 2^60.7), beyond which its traversal aborts. */
#define AO_CAMERA_REACH 0x1p48f

/* A pinhole camera as the scene file states it; fov is vertical, in degrees. */
struct ao_camera {
    struct ao_vec3 eye, target, up;
    float fov;
};

/* A camera prepared for one image size: everything an eye ray needs. */
struct ao_view {
    struct ao_vec3 eye, forward, right, up;
    float tan_half_fov, aspect;
    int width, height;
};

/* Precomputes the view of camera c for a width x height image; false when the camera is
 * degenerate (eye on target, up parallel to the view direction, fov outside (0, 180)). */
bool ao_camera_view(const struct ao_camera *c, int width, int height, struct ao_view *v);

/* The view of a coarse grid over a width x height image, each of whose pixels covers block x block
 * pixels of the image from its top left (ceil(width / block) x ceil(height / block) of them): the
 * eye ray through its position (i + u, j + v) is the image's through (block (i + u), block (j + v)).
 * False as ao_camera_view. */
bool ao_camera_view_coarse(const struct ao_camera *c, int width, int height, int block, struct ao_view *v);

/* Unit eye-ray direction through image position (x, y) = (i + u, j + v), in pixels; inline, as
 * it runs once per pixel and pass. */
static inline struct ao_vec3 ao_camera_ray(const struct ao_view *v, float x, float y)
{
    float sx = (2.0f * x / (float)v->width - 1.0f) * v->tan_half_fov * v->aspect;
    float sy = (1.0f - 2.0f * y / (float)v->height) * v->tan_half_fov;
    struct ao_vec3 d = ao_vec3_add(ao_vec3_add(ao_vec3_scale(v->right, sx), ao_vec3_scale(v->up, sy)),
                                   v->forward);
    return ao_vec3_normalize(d);
}

/* Orbits the eye about the target by yaw and pitch radians, keeping it off the poles. */
void ao_camera_orbit(struct ao_camera *c, float yaw, float pitch);

/* Moves eye and target sideways and up by fractions of the view's height at the target; not where
 * either would pass AO_CAMERA_REACH from the origin in a coordinate. */
void ao_camera_pan(struct ao_camera *c, float dx, float dy);

/* Moves the eye towards the target by factor (< 1 zooms in), never onto it, nor past AO_CAMERA_REACH
 * from the origin in a coordinate. */
void ao_camera_zoom(struct ao_camera *c, float factor);

/* Points the camera at a bounding box from the front, slightly above, so that it fills the view:
 * the eye 1.1 / sin 20° = 3.22 half-diagonals from the box's centre, outside the box. */
void ao_camera_frame_box(struct ao_camera *c, struct ao_vec3 lo, struct ao_vec3 hi);

#endif
