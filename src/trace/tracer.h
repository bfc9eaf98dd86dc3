/* Ray tracing for the estimator: eye and occlusion rays in packets, against one Embree 3 scene
 * built from an ao_scene, or through direct.h's loops for scenes of a few primitives. Only tracer.c
 * and its two neighbours (tracer_bench.c, tracer_arrays.c) include Embree. */
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

#endif
