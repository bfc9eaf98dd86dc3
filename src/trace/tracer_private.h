/* Private to the tracer's three files (tracer.c, tracer_bench.c, tracer_arrays.c), the only ones
 * that include Embree: the tracer's state, an Embree device's error keeping, and rays written in
 * Embree's layouts. */
#ifndef AO_TRACER_PRIVATE_H
#define AO_TRACER_PRIVATE_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include <embree3/rtcore.h>

#include "ray.h"
#include "ray_recorder.h"
#include "scene.h"
#include "text.h"
#include "tracer.h"


/* One build of a scene's BVHs: the top level (flat meshes, instances, spheres) and, per scene mesh,
 * its own BVH when instances place it, else NULL. */
struct bvhs {
    RTCScene scene;
    RTCScene *meshes;
};

/* The better build made beside the one that traces (ao_tracer_create_progressive): whether it is
 * still to start, its thread, what it builds from, and whether it is done (set by its thread, read
 * by the switch). */
struct upgrade {
    pthread_t thread;
    const struct ao_text_sink *sink;   /* its starter's: its thread's route */
    bool pending, started;
    atomic_bool done, cancel;
    bool ok;
    const struct ao_scene *source;
    struct bvhs built;
    struct ao_tracer_stats stats;
};

/* The first error Embree reported on a device since it was last said. Embree may call its error
 * function on a thread of its own (a build's), where no message may go: the error waits here for
 * the thread whose call failed to say it (say_errors). */
struct embree_errors {
    pthread_mutex_t lock;
    int code;                            /* RTC_ERROR_NONE: none */
    char message[256];
};

struct ao_tracer {
    struct ao_direct *direct;            /* set when the direct back end traces: no Embree at all */
    RTCDevice device;
    RTCScene scene;                      /* the top level that traces: bvhs.scene */
    struct bvhs bvhs;
    size_t mesh_count;
    unsigned spheres_id;                 /* RTC_INVALID_GEOMETRY_ID when absent */
    struct ao_tracer_stats stats;
    struct upgrade upgrade;
    struct embree_errors errors;         /* the device's, Embree's only */
    _Atomic int64_t embree_bytes, embree_peak;   /* Embree's memory monitor */
    struct ao_ray_recorder *occlusion_recorder, *eye_recorder;  /* benchmarks only */
};

/* A new device whose errors e keeps (its lock initialized here, destroyed by the caller after the
 * device); NULL after one message. */
RTCDevice ao_embree_device(struct embree_errors *e);

/* Says the error e keeps, if any, at level, on the calling thread, and forgets it. */
void ao_embree_say(struct embree_errors *e, enum ao_text_level level);

/* The packet in Embree's layout for rtcIntersect16, with no hit yet, and its lanes' validity mask
 * (unused lanes get lane 0's ray, so that no garbage reaches Embree). */
void ao_embree_packet(const struct ao_packet *rays, struct RTCRayHit16 *out, int *valid);

/* Writes one ray into out in Embree's single-ray layout, field by field (a whole struct assigned
 * from a temporary stalls on store forwarding: measured 30% of the time). */
static inline void ao_embree_ray(float ox, float oy, float oz, float dx, float dy, float dz, float tfar,
                                 struct RTCRay *out)
{
    out->org_x = ox;
    out->org_y = oy;
    out->org_z = oz;
    out->tnear = 0.0f;
    out->dir_x = dx;
    out->dir_y = dy;
    out->dir_z = dz;
    out->time = 0.0f;
    out->tfar = tfar;
    out->mask = ~0u;
    out->id = 0;
    out->flags = 0;
}


#endif
