/* Rays as the estimator hands them to a tracer and what comes back: packets of eye rays, their
 * hits, and batches of occlusion rays, in structure-of-arrays layout. Header only: tracer.h (Embree)
 * and direct.h (loops over every primitive) trace them, ao.c makes and shades them. */
#ifndef AO_RAY_H
#define AO_RAY_H

#include <stdbool.h>
#include <stdint.h>

#include "vec3.h"

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
    uint32_t prim;          /* triangle index in its instance's mesh, or sphere index */
    uint32_t instance;      /* on triangles, the scene's instance */
    bool sphere;            /* true for a sphere, false for a triangle */
    struct ao_vec3 ng;      /* on triangles, the unnormalized geometric normal (p1 - p0) x (p2 - p0)
                               of the mesh's own vertices (in its own frame when instanced) */
};

/* Occlusion rays traced together, in structure-of-arrays layout, rays 0..count-1: Embree's stream
 * sorts a batch into packets of one direction octant, faster the longer the batch
 * (docs/performance.md). */
enum { AO_BATCH_RAYS = 1024 };
struct ao_batch {
    _Alignas(64) float org_x[AO_BATCH_RAYS];
    float org_y[AO_BATCH_RAYS], org_z[AO_BATCH_RAYS];
    float dir_x[AO_BATCH_RAYS], dir_y[AO_BATCH_RAYS], dir_z[AO_BATCH_RAYS];
    float tfar[AO_BATCH_RAYS];
    int count;
};

#endif
