/* Ray tracing for the estimator: eye and occlusion rays in packets, against one Embree 3 scene
 * built from an ao_scene, or through direct.h's loops for scenes of a few primitives. The only
 * file that includes Embree is tracer.c. */
#ifndef AO_TRACER_H
#define AO_TRACER_H

#include <stdbool.h>
#include <stdint.h>

#include "ray.h"
#include "scene.h"

/* An Embree device with the committed scene; opaque. */
struct ao_tracer;

/* Builds the tracer for `scene` (which must outlive it), Embree or direct as measured faster; NULL
 * after one message (text.h; Embree's own error first, if it gave one) on failure. Any thread, one
 * per tracer; the result is then shared read-only. */
struct ao_tracer *ao_tracer_create(const struct ao_scene *scene);

/* Which code traces: Embree's BVH, or direct.h's loops over every primitive of a small scene. */
enum ao_backend { AO_BACKEND_AUTO, AO_BACKEND_EMBREE, AO_BACKEND_DIRECT };

/* ao_tracer_create with the back end forced; AUTO (what ao_tracer_create does) takes the direct
 * one for scenes of a few primitives (ao_direct_suits), where it is measured faster. */
struct ao_tracer *ao_tracer_create_with(const struct ao_scene *scene, enum ao_backend backend);

/* ao_tracer_create for a big scene: builds LOW BVHs (Embree's Morton build, 3-4 times sooner,
 * slower rays); the scene's own (scene->bvh) are built later beside them, on a thread of their
 * own, from ao_tracer_switch's first call. The BVH never changes an image. Main thread. */
struct ao_tracer *ao_tracer_create_progressive(const struct ao_scene *scene);

/* For ao_tracer_create_progressive's second build: the first call starts it (the render thread
 * makes it after its first pass, which the build would slow); once it is done, traces with it from
 * now on, frees the LOW BVHs and returns true (false before, and after: nothing to switch; a build
 * that ran out of memory is dropped with one note and LOW traces on). The build's thread is routed
 * to the sink of the thread that starts it (text.h), which must outlive the tracer. Only while
 * nothing traces with this tracer: the render thread between passes, when its renderer is the
 * tracer's only user. */
bool ao_tracer_switch(struct ao_tracer *tracer);

/* Whether ao_tracer_create_progressive's second build is still to be switched to. Any thread that
 * may call ao_tracer_switch. */
bool ao_tracer_upgrading(const struct ao_tracer *tracer);

/* The back end that traces, "embree" or "direct", for --stats and benchmarks. Any thread. */
const char *ao_tracer_backend(const struct ao_tracer *tracer);

/* What a tracer built (zero for the direct back end): Embree BVHs (the top level and one per
 * instanced mesh), flat meshes' triangle geometries and instance geometries in the top level, and
 * the bytes Embree held once built and at most while building (its memory monitor). */
struct ao_tracer_stats {
    size_t bvhs, triangle_geometries, instances;
    int64_t embree_bytes, embree_peak_bytes;
};

/* Fills *out with what the tracer built. Any thread. */
void ao_tracer_describe(const struct ao_tracer *tracer, struct ao_tracer_stats *out);

/* Releases the Embree scene and device; accepts NULL. */
void ao_tracer_destroy(struct ao_tracer *tracer);

/* Sets the floating-point modes Embree wants (flush-to-zero, denormals-are-zero) on the calling
 * thread; every thread that traces calls it once. */
void ao_tracer_thread_init(void);

/* Closest hits of the packet's rays (coherent eye rays), t in (0, tfar]. Any thread. */
void ao_tracer_intersect(const struct ao_tracer *tracer, const struct ao_packet *rays, struct ao_hit *hits);

/* Traces the batch's rays as incoherent occlusion rays and sets tfar to -INFINITY on each one that
 * something blocks within t in [0, tfar] (Embree's convention); open rays keep theirs. Any thread. */
void ao_tracer_occluded(const struct ao_tracer *tracer, struct ao_batch *rays);

/* Benchmark instrument: copies of every stride-th packet (eye rays) or whole batch (occlusion rays,
 * 16 to a packet) offered, up to capacity packets; an occlusion recorder also times Embree's calls
 * on all the rays it is offered. */
struct ao_ray_recorder {
    struct ao_packet *packets;
    size_t count, capacity;
    size_t stride, seen;
    double embree_seconds;   /* inside rtcOccluded1M */
    uint64_t embree_rays;
};

/* While set, ao_tracer_occluded offers `occlusion` its batches and times its Embree calls, and
 * ao_tracer_intersect offers `eye` its packets; NULL stops. For a renderer with one thread only
 * (no lock is taken). */
void ao_tracer_record(struct ao_tracer *tracer, struct ao_ray_recorder *occlusion, struct ao_ray_recorder *eye);

/* How ao_tracer_time_bare traces: occlusion rays with plain rtcOccluded16 calls, or as incoherent
 * rtcOccluded1M streams of AO_BATCH_RAYS; eye rays with coherent rtcIntersect16 calls, as aoview. */
enum ao_bare { AO_BARE_OCCLUDED16, AO_BARE_OCCLUDED1M, AO_BARE_INTERSECT16 };

/* Benchmark instrument: the bare-Embree ceiling on given rays. Traces count packets as `how` says,
 * converted to Embree's layout outside the timed calls, and returns the seconds the tracing took. */
double ao_tracer_time_bare(const struct ao_tracer *tracer, const struct ao_packet *packets, size_t count,
                           enum ao_bare how);

/* The most a coordinate of ao_tracer_arrays' vertices, origins and directions may be in magnitude:
 * 2^60 = 1.153e18, below Embree's own limit on rays (derived in tracer.c). */
#define AO_TRACER_ARRAYS_LIMIT 0x1p60

/* One triangle mesh given as arrays, with its Embree BVH, for batches of rays; opaque. */
struct ao_tracer_arrays;

/* Builds the BVH of a triangle mesh given as arrays (vertex_count positions, 3 floats each;
 * triangle_count triangles, 3 indices below vertex_count each), copied: the caller's arrays may
 * change or go afterwards. The caller checks what tracer.c derives: every coordinate within
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
