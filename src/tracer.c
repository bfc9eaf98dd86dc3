/* Embree 3 back end; see tracer.h. The only file that includes Embree. */
#include "tracer.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <embree3/rtcore.h>
#if defined(__SSE__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#endif

struct ao_tracer {
    RTCDevice device;
    RTCScene scene;
    unsigned triangles_id, spheres_id;   /* RTC_INVALID_GEOMETRY_ID when absent */
};

static void report(void *user, enum RTCError code, const char *message)
{
    (void)user;
    fprintf(stderr, "aoview: Embree error %d: %s\n", (int)code, message ? message : "(no message)");
}

/* One triangle geometry holds every mesh and quad, so the scene has a single triangle BVH. */
static bool add_triangles(struct ao_tracer *t, const struct ao_scene *s)
{
    RTCGeometry g = rtcNewGeometry(t->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                       s->vertex_count);
    unsigned *idx = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                            s->triangle_count);
    if (!v || !idx) {
        rtcReleaseGeometry(g);
        return false;
    }
    for (size_t i = 0; i < s->vertex_count; i++) {
        v[3 * i + 0] = s->positions[i].x;
        v[3 * i + 1] = s->positions[i].y;
        v[3 * i + 2] = s->positions[i].z;
    }
    memcpy(idx, s->indices, 3 * s->triangle_count * sizeof *idx);
    rtcCommitGeometry(g);
    t->triangles_id = rtcAttachGeometry(t->scene, g);
    rtcReleaseGeometry(g);
    return true;
}

/* Spheres stay analytic: Embree's sphere primitive, radius in the fourth vertex component. */
static bool add_spheres(struct ao_tracer *t, const struct ao_scene *s)
{
    RTCGeometry g = rtcNewGeometry(t->device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float),
                                       s->sphere_count);
    if (!v) {
        rtcReleaseGeometry(g);
        return false;
    }
    for (size_t i = 0; i < s->sphere_count; i++) {
        v[4 * i + 0] = s->spheres[i].center.x;
        v[4 * i + 1] = s->spheres[i].center.y;
        v[4 * i + 2] = s->spheres[i].center.z;
        v[4 * i + 3] = s->spheres[i].radius;
    }
    rtcCommitGeometry(g);
    t->spheres_id = rtcAttachGeometry(t->scene, g);
    rtcReleaseGeometry(g);
    return true;
}

struct ao_tracer *ao_tracer_create(const struct ao_scene *scene)
{
    struct ao_tracer *t = calloc(1, sizeof *t);
    if (!t) {
        fprintf(stderr, "aoview: out of memory creating the tracer\n");
        return NULL;
    }
    t->triangles_id = t->spheres_id = RTC_INVALID_GEOMETRY_ID;
    t->device = rtcNewDevice(NULL);
    if (!t->device) {
        fprintf(stderr, "aoview: Embree could not create a device (error %d)\n", (int)rtcGetDeviceError(NULL));
        free(t);
        return NULL;
    }
    rtcSetDeviceErrorFunction(t->device, report, NULL);
    t->scene = rtcNewScene(t->device);
    /* Robust traversal keeps shared edges watertight, so closed meshes stay closed. */
    if (t->scene)
        rtcSetSceneFlags(t->scene, RTC_SCENE_FLAG_ROBUST);
    bool ok = t->scene && (scene->triangle_count == 0 || add_triangles(t, scene)) &&
              (scene->sphere_count == 0 || add_spheres(t, scene));
    if (ok) {
        rtcCommitScene(t->scene);
        ok = rtcGetDeviceError(t->device) == RTC_ERROR_NONE;
    }
    if (!ok) {
        ao_tracer_destroy(t);
        return NULL;
    }
    return t;
}

void ao_tracer_destroy(struct ao_tracer *tracer)
{
    if (!tracer)
        return;
    if (tracer->scene)
        rtcReleaseScene(tracer->scene);
    rtcReleaseDevice(tracer->device);
    free(tracer);
}

void ao_tracer_thread_init(void)
{
#if defined(__SSE__)
    /* Embree's traversal is slower with denormals and asks for both modes on every thread. */
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
}

bool ao_tracer_intersect(const struct ao_tracer *tracer, struct ao_vec3 org, struct ao_vec3 dir,
                         struct ao_hit *hit)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRayHit rh = {
        .ray = {.org_x = org.x, .org_y = org.y, .org_z = org.z, .tnear = 0.0f,
                .dir_x = dir.x, .dir_y = dir.y, .dir_z = dir.z, .tfar = INFINITY, .mask = ~0u},
        .hit = {.geomID = RTC_INVALID_GEOMETRY_ID, .instID = {RTC_INVALID_GEOMETRY_ID}},
    };
    rtcIntersect1(tracer->scene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return false;
    hit->t = rh.ray.tfar;
    hit->u = rh.hit.u;
    hit->v = rh.hit.v;
    hit->prim = rh.hit.primID;
    hit->sphere = rh.hit.geomID == tracer->spheres_id;
    return true;
}

void ao_tracer_occluded(const struct ao_tracer *tracer, struct ao_vec3 org,
                        const struct ao_vec3 *dirs, int count, float tfar, uint8_t *open)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (count == 1) {
        struct RTCRay ray = {.org_x = org.x, .org_y = org.y, .org_z = org.z, .tnear = 0.0f,
                             .dir_x = dirs[0].x, .dir_y = dirs[0].y, .dir_z = dirs[0].z,
                             .tfar = tfar, .mask = ~0u};
        rtcOccluded1(tracer->scene, &context, &ray);
        open[0] = ray.tfar >= 0.0f;
        return;
    }
    /* Packets of 16 rays from one origin; Embree marks an occluded ray by setting tfar = -inf. */
    for (int first = 0; first < count; first += 16) {
        _Alignas(64) struct RTCRay16 packet;
        _Alignas(64) int valid[16];
        int lanes = count - first < 16 ? count - first : 16;
        for (int k = 0; k < 16; k++) {
            const struct ao_vec3 d = dirs[first + (k < lanes ? k : 0)];
            valid[k] = k < lanes ? -1 : 0;
            packet.org_x[k] = org.x;
            packet.org_y[k] = org.y;
            packet.org_z[k] = org.z;
            packet.dir_x[k] = d.x;
            packet.dir_y[k] = d.y;
            packet.dir_z[k] = d.z;
            packet.tnear[k] = 0.0f;
            packet.tfar[k] = tfar;
            packet.time[k] = 0.0f;
            packet.mask[k] = ~0u;
            packet.id[k] = (unsigned)k;
            packet.flags[k] = 0;
        }
        rtcOccluded16(valid, tracer->scene, &context, &packet);
        for (int k = 0; k < lanes; k++)
            open[first + k] = packet.tfar[k] >= 0.0f;
    }
}
