/* A recorder of the rays a tracer is offered, for the benchmarks' ceilings (tracer_bench.h): the
 * tracer offers it packets and batches while one is set. */
#ifndef AO_RAY_RECORDER_H
#define AO_RAY_RECORDER_H

#include <stddef.h>
#include <stdint.h>

#include "ray.h"

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

/* Offers the eye-ray recorder a packet: its slot for a copy when this is the stride-th packet
 * offered and there is room, else NULL. */
struct ao_packet *ao_ray_recorder_slot(struct ao_ray_recorder *rec);

/* Offers the occlusion recorder the batch; it keeps every stride-th whole, in order, 16 rays to a
 * packet (so that a ceiling traced on the sample sees rays as coherent as aoview's batches). */
void ao_ray_recorder_keep(struct ao_ray_recorder *rec, const struct ao_batch *rays);

#endif
