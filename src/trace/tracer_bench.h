/* The tracer's benchmark instruments (tests/bench/): a recorder of the rays a renderer traces, and
 * the bare-Embree ceiling on them. Nothing the programs or the Python module call. */
#ifndef AO_TRACER_BENCH_H
#define AO_TRACER_BENCH_H

#include <stddef.h>
#include <stdint.h>

#include "ray_recorder.h"
#include "tracer.h"

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

#endif
