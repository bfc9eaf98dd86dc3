/* A triangle mesh given as arrays, with its own Embree BVH, for batches of rays: the Python module's
 * ray_mesh_intersect (python/aoview/rays.c). */
#ifndef AO_TRACER_ARRAYS_H
#define AO_TRACER_ARRAYS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* The most a coordinate of ao_tracer_arrays' vertices, origins and directions may be in magnitude:
 * 2^60 = 1.153e18, below Embree's own limit on rays (derived in tracer_arrays.c). */
#define AO_TRACER_ARRAYS_LIMIT 0x1p60

/* One triangle mesh given as arrays, with its Embree BVH, for batches of rays; opaque. */
struct ao_tracer_arrays;

/* Builds the BVH of a triangle mesh given as arrays (vertex_count positions, 3 floats each;
 * triangle_count triangles, 3 indices below vertex_count each), copied: the caller's arrays may
 * change or go afterwards. The caller checks what tracer_arrays.c derives: every coordinate within
 * AO_TRACER_ARRAYS_LIMIT, the box around the positions from AO_SCENE_MIN_EXTENT to
 * AO_SCENE_MAX_EXTENT across. NULL after one message (Embree's own error first, if it gave one)
 * when memory is short. Any thread. */
struct ao_tracer_arrays *ao_tracer_arrays_create(const float *positions, size_t vertex_count, const uint32_t *indices,
                                                 size_t triangle_count);

/* Frees the mesh; accepts NULL. Not while a batch traces on it. */
void ao_tracer_arrays_destroy(struct ao_tracer_arrays *mesh);

/* Closest hits of `count` rays (origins and directions: 3 floats each, every coordinate within
 * AO_TRACER_ARRAYS_LIMIT; directions need not be unit, t is in their units) on the mesh, at
 * t >= tnear (tnear >= 0), traced by Embree on `threads` threads (the calling one among them):
 * t[i] (INFINITY on a miss, and for a zero direction), ids[i] (the triangle, -1 on a miss) and
 * barys[3i..3i+2] (the hit's weights of the triangle's three corners, zero on a miss). False after
 * one message when threads are short. Any thread, several at once on one mesh. */
bool ao_tracer_intersect_arrays(const struct ao_tracer_arrays *mesh, const float *origins, const float *directions,
                                size_t count, float tnear, int threads, double *t, int32_t *ids, double *barys);

#endif
