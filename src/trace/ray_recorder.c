/* A recorder of the rays a tracer is offered; see ray_recorder.h. */
#include "ray_recorder.h"

struct ao_packet *ao_ray_recorder_slot(struct ao_ray_recorder *rec)
{
    if (rec->seen++ % rec->stride != 0 || rec->count == rec->capacity)
        return NULL;
    return &rec->packets[rec->count++];
}

void ao_ray_recorder_keep(struct ao_ray_recorder *rec, const struct ao_batch *rays)
{
    if (rec->seen++ % rec->stride != 0)
        return;
    for (int first = 0; first < rays->count && rec->count < rec->capacity; first += AO_PACKET_SIZE) {
        struct ao_packet *p = &rec->packets[rec->count++];
        p->count = rays->count - first < AO_PACKET_SIZE ? rays->count - first : AO_PACKET_SIZE;
        for (int k = 0; k < p->count; k++) {
            p->org_x[k] = rays->org_x[first + k];
            p->org_y[k] = rays->org_y[first + k];
            p->org_z[k] = rays->org_z[first + k];
            p->dir_x[k] = rays->dir_x[first + k];
            p->dir_y[k] = rays->dir_y[first + k];
            p->dir_z[k] = rays->dir_z[first + k];
            p->tfar[k] = rays->tfar[first + k];
        }
    }
}
