/* The tracer's benchmark instruments; see tracer_bench.h. */
#include "tracer_bench.h"

#include <math.h>
#include <stdlib.h>

#include "clock.h"
#include "tracer_private.h"

void ao_tracer_record(struct ao_tracer *tracer, struct ao_ray_recorder *occlusion, struct ao_ray_recorder *eye)
{
    tracer->occlusion_recorder = occlusion;
    tracer->eye_recorder = eye;
}

/* Packets from *next on, as many whole ones as fit in one batch, into out in Embree's single-ray
 * layout; advances *next and returns the rays written. */
static unsigned fill_stream(const struct ao_packet *packets, size_t count, size_t *next, struct RTCRay *out)
{
    unsigned n = 0;
    for (; *next < count && n + (unsigned)packets[*next].count <= AO_BATCH_RAYS; ++*next) {
        const struct ao_packet *p = &packets[*next];
        for (int k = 0; k < p->count; k++)
            ao_embree_ray(p->org_x[k], p->org_y[k], p->org_z[k], p->dir_x[k], p->dir_y[k], p->dir_z[k], p->tfar[k],
                      &out[n++]);
    }
    return n;
}

double ao_tracer_time_bare(const struct ao_tracer *tracer, const struct ao_packet *packets, size_t count,
                           enum ao_bare how)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (how == AO_BARE_OCCLUDED1M) {
        /* Batch by batch, each written just before it is traced and timed, as aoview's are: one
         * array of all the rays would come from memory rather than the cache. */
        _Alignas(64) struct RTCRay stream[AO_BATCH_RAYS];
        double seconds = 0.0;
        for (size_t next = 0; next < count;) {
            unsigned n = fill_stream(packets, count, &next, stream);
            double start = ao_clock_seconds();
            rtcOccluded1M(tracer->scene, &context, stream, n, sizeof *stream);
            seconds += ao_clock_seconds() - start;
        }
        return seconds;
    }
    struct RTCRayHit16 *converted = aligned_alloc(64, count * sizeof *converted + 64);
    int (*valid)[AO_PACKET_SIZE] = aligned_alloc(64, count * sizeof *valid + 64);
    double seconds = NAN;
    if (converted && valid) {
        for (size_t p = 0; p < count; p++)
            ao_embree_packet(&packets[p], &converted[p], valid[p]);
        double start = ao_clock_seconds();
        if (how == AO_BARE_INTERSECT16) {
            context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
            for (size_t p = 0; p < count; p++)
                rtcIntersect16(valid[p], tracer->scene, &context, &converted[p]);
        } else {
            for (size_t p = 0; p < count; p++)
                rtcOccluded16(valid[p], tracer->scene, &context, &converted[p].ray);
        }
        seconds = ao_clock_seconds() - start;
    }
    free(converted);
    free(valid);
    return seconds;
}

