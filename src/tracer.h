/* The only Embree user: builds one Embree 3 scene from an ao_scene and traces eye and occlusion
 * rays against it. */
#ifndef AO_TRACER_H
#define AO_TRACER_H

#include <stdbool.h>
#include <stdint.h>

#include "scene.h"
#include "vec3.h"

/* An Embree device with the committed scene; opaque. */
struct ao_tracer;

/* What an eye ray hit: enough for ao.c to shade it from the scene's arrays. */
struct ao_hit {
    float t;                /* distance along the unit ray */
    float u, v;             /* barycentrics of vertices 1 and 2 on triangles */
    uint32_t prim;          /* triangle index, or sphere index */
    bool sphere;            /* true for a sphere, false for a triangle */
};

/* Builds the Embree scene for `scene` (which must outlive the tracer); NULL with one message on
 * stderr when Embree fails. Call from one thread; the result is then shared read-only. */
struct ao_tracer *ao_tracer_create(const struct ao_scene *scene);

/* Releases the Embree scene and device; accepts NULL. */
void ao_tracer_destroy(struct ao_tracer *tracer);

/* Sets the floating-point modes Embree wants (flush-to-zero, denormals-are-zero) on the calling
 * thread; every thread that traces calls it once. */
void ao_tracer_thread_init(void);

/* Closest hit of the ray org + t dir, t in (0, inf); false on a miss. Any thread. */
bool ao_tracer_intersect(const struct ao_tracer *tracer, struct ao_vec3 org, struct ao_vec3 dir,
                         struct ao_hit *hit);

/* For count rays from one origin along dirs[k], t in [0, tfar], sets open[k] to 1 when nothing is
 * hit and 0 otherwise; traced in packets. Any thread. */
void ao_tracer_occluded(const struct ao_tracer *tracer, struct ao_vec3 org,
                        const struct ao_vec3 *dirs, int count, float tfar, uint8_t *open);

#endif
