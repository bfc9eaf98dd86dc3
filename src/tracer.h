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

/* Rays traced together: up to AO_PACKET_SIZE in structure-of-arrays layout, lanes 0..count-1. */
enum { AO_PACKET_SIZE = 16 };
struct ao_packet {
    float org_x[AO_PACKET_SIZE], org_y[AO_PACKET_SIZE], org_z[AO_PACKET_SIZE];
    float dir_x[AO_PACKET_SIZE], dir_y[AO_PACKET_SIZE], dir_z[AO_PACKET_SIZE];
    float tfar[AO_PACKET_SIZE];
    int count;
};

/* What an eye ray hit: enough for ao.c to shade it from the scene's arrays. */
struct ao_hit {
    float t;                /* distance along the unit ray; INFINITY on a miss */
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

/* Closest hits of the packet's rays (coherent eye rays), t in (0, tfar]. Any thread. */
void ao_tracer_intersect(const struct ao_tracer *tracer, const struct ao_packet *rays, struct ao_hit *hits);

/* Sets open[k] to 1 when nothing lies on ray k within t in [0, tfar], else 0 (incoherent
 * occlusion rays). Any thread. */
void ao_tracer_occluded(const struct ao_tracer *tracer, const struct ao_packet *rays, uint8_t *open);

#endif
