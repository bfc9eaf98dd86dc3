/* The direct back end: every ray of a packet tested against every sphere and triangle of a small
 * scene, with no acceleration structure; the same results as the Embree back end up to rounding.
 * Includes no Embree; tracer.c dispatches to it. */
#ifndef AO_DIRECT_H
#define AO_DIRECT_H

#include <stdbool.h>
#include <stdint.h>

#include "ray.h"
#include "scene.h"

/* A copy of a scene's spheres and triangles laid out for the packet loops; opaque. */
struct ao_direct;

/* True when `scene` is small enough that testing every primitive beats Embree's BVH (the measured
 * rule in direct.c). Any thread. */
bool ao_direct_suits(const struct ao_scene *scene);

/* Copies the scene's geometry (the scene may go away afterwards); NULL after one message (text.h)
 * when memory is short. Works for any scene, but costs time linear in its primitives per ray. */
struct ao_direct *ao_direct_create(const struct ao_scene *scene);

/* Frees the copy; accepts NULL. */
void ao_direct_destroy(struct ao_direct *direct);

/* Closest hits as ao_tracer_intersect: t in [0, tfar], barycentrics of vertices 1 and 2 and the
 * unnormalized geometric normal on triangles, 0 on spheres. Any thread. */
void ao_direct_intersect(const struct ao_direct *direct, const struct ao_packet *rays, struct ao_hit *hits);

/* Blocked rays as ao_tracer_occluded: tfar set to -INFINITY on each ray that something blocks
 * within [0, tfar]. Any thread. */
void ao_direct_occluded(const struct ao_direct *direct, struct ao_batch *rays);

#endif
