/* Ray batches against a triangle mesh given as arrays, for the Python module; see tracer_arrays.h. */
#include "tracer_arrays.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "pool.h"
#include "tracer_private.h"
#if defined(__SSE__)
#include <xmmintrin.h>
#endif

/* The Python module's ray_mesh_intersect. Each ray is brought to the mesh before Embree sees it,
 * so that what Embree's robust triangle test (Pluecker's, in single precision, with flush-to-zero)
 * forms stays between 2^-126 and 2^128 for any ray the caller may give: coordinates within
 * AO_TRACER_ARRAYS_LIMIT, a mesh from AO_SCENE_MIN_EXTENT to AO_SCENE_MAX_EXTENT across (the
 * scenes' range, scene_place.c). With E the mesh's largest side:
 * - The direction is scaled by a power of two that puts its largest component in [1, 2): exact,
 *   and the triangle test's t and weights scale with it exactly, so t comes back in the caller's
 *   units (in double: a short direction's t may pass the float range). A zero direction meets
 *   nothing and is not traced.
 * - An origin outside the box around the mesh grown by FAR E on each side starts at the ray's
 *   entry into that box, or at tnear if later (in double; that part's t is added back; nothing of
 *   the mesh lies there); a ray that misses the grown box, or leaves it before tnear, meets
 *   nothing. Every origin Embree sees is then within (2 FAR + 1) E = 33 E of each vertex per axis.
 * - So the test's edges (at most 2E per axis), offsets from the origin (33E), their cross products
 *   (2 * 2E * 66E) and Ng = e1 x e2 (2 (2E)^2), dotted with an offset (3 * 33E * 8E^2) or the
 *   direction (< 2), stay below 2^14 E^3 < 2^108 for E <= 2^31: finite. A facet spanning the mesh
 *   (E >= 2^-12) has |Ng| near E^2 >= 2^-24, far above 2^-126; finer detail is not checked, as in
 *   scenes. The far origin's precision is that of the box, not of its own distance.
 * - Embree aborts the process on a ray whose |org| or |dir| component passes FLT_LARGE = 1.844e18
 *   (its ray.valid() check): origins, directions and vertices within 2^60 = 1.153e18 keep every
 *   moved origin (at most 2^60 + 33 * 2^31) and scaled direction below it. */
enum { FAR = 16 };

struct ao_tracer_arrays {
    RTCDevice device;
    struct embree_errors errors;   /* the device's */
    RTCScene scene;
    double lo[3], hi[3];   /* the box around the positions grown by FAR times its largest side */
};

struct ao_tracer_arrays *ao_tracer_arrays_create(const float *positions, size_t vertex_count, const uint32_t *indices,
                                                 size_t triangle_count)
{
    struct ao_tracer_arrays *mesh = calloc(1, sizeof *mesh);
    if (!mesh) {
        ao_text_report("aoview: out of memory for the mesh's tracer");
        return NULL;
    }
    RTCDevice device = mesh->device = ao_embree_device(&mesh->errors);
    if (!device) {
        free(mesh);
        return NULL;
    }
    RTCScene scene = mesh->scene = rtcNewScene(device);
    RTCGeometry g = scene ? rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE) : NULL;
    /* Embree's own copies: it reads 16 bytes at a time past the last position. */
    float *p = g ? rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                           vertex_count) : NULL;
    uint32_t *i3 = p ? rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t),
                                               triangle_count) : NULL;
    bool ok = i3 != NULL;
    if (ok) {
        memcpy(p, positions, 3 * sizeof(float) * vertex_count);
        memcpy(i3, indices, 3 * sizeof(uint32_t) * triangle_count);
        rtcCommitGeometry(g);
        rtcAttachGeometry(scene, g);
        rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
        rtcCommitScene(scene);
        ok = rtcGetDeviceError(device) == RTC_ERROR_NONE;
    }
    if (g)
        rtcReleaseGeometry(g);
    ao_embree_say(&mesh->errors, ok ? AO_TEXT_NOTE : AO_TEXT_ERROR);
    if (!ok) {
        ao_text_report("aoview: Embree could not build the mesh (out of memory?)");
        ao_tracer_arrays_destroy(mesh);
        return NULL;
    }
    double side = 0.0;
    for (int k = 0; k < 3; k++) {
        mesh->lo[k] = INFINITY, mesh->hi[k] = -INFINITY;
        for (size_t v = 0; v < vertex_count; v++) {
            mesh->lo[k] = fmin(mesh->lo[k], positions[3 * v + k]);
            mesh->hi[k] = fmax(mesh->hi[k], positions[3 * v + k]);
        }
        side = fmax(side, mesh->hi[k] - mesh->lo[k]);
    }
    for (int k = 0; k < 3; k++)
        mesh->lo[k] -= FAR * side, mesh->hi[k] += FAR * side;
    return mesh;
}

void ao_tracer_arrays_destroy(struct ao_tracer_arrays *mesh)
{
    if (!mesh)
        return;
    if (mesh->scene)
        rtcReleaseScene(mesh->scene);
    rtcReleaseDevice(mesh->device);
    pthread_mutex_destroy(&mesh->errors.lock);
    free(mesh);
}

/* The ray o + t d, t >= tnear, brought to the mesh as the derivation above says: into *out, its
 * direction d * *scale, with *skip (the t of the part skipped, in the units of that direction):
 * the caller's t is (*skip + Embree's t) * *scale. False when it meets nothing. */
static bool bring(const struct ao_tracer_arrays *mesh, const float o[3], const float d[3], float tnear,
                  struct RTCRay *out, double *skip, double *scale)
{
    float most = fmaxf(fmaxf(fabsf(d[0]), fabsf(d[1])), fabsf(d[2]));
    if (!(most > 0.0f))   /* zero, or subnormal (flushed to zero where Embree traces) */
        return false;
    /* 2^(1 - e) for most = m 2^e, m in [0.5, 1), from most's exponent bits: e = E - 126 for a
     * normal float of biased exponent E; |d| <= 2^60 keeps it normal. */
    uint32_t bits;
    memcpy(&bits, &most, sizeof bits);
    uint32_t power = (127u + 1u + 126u - (bits >> 23)) << 23;
    float by;
    memcpy(&by, &power, sizeof by);
    *scale = by;
    float ds[3] = {d[0] * by, d[1] * by, d[2] * by}, near = tnear / by;
    *skip = 0.0;
    if (o[0] >= mesh->lo[0] && o[0] <= mesh->hi[0] && o[1] >= mesh->lo[1] && o[1] <= mesh->hi[1] &&
        o[2] >= mesh->lo[2] && o[2] <= mesh->hi[2]) {
        ao_embree_ray(o[0], o[1], o[2], ds[0], ds[1], ds[2], INFINITY, out);
        out->tnear = near;
        return true;
    }
    double enter = near, leave = INFINITY;
    for (int k = 0; k < 3; k++) {
        if (ds[k] != 0.0f) {
            double a = (mesh->lo[k] - o[k]) / ds[k], b = (mesh->hi[k] - o[k]) / ds[k];
            enter = fmax(enter, fmin(a, b));
            leave = fmin(leave, fmax(a, b));
        } else if (o[k] < mesh->lo[k] || o[k] > mesh->hi[k]) {
            return false;
        }
    }
    if (enter > leave)
        return false;
    *skip = enter;
    ao_embree_ray((float)(o[0] + enter * ds[0]), (float)(o[1] + enter * ds[1]), (float)(o[2] + enter * ds[2]), ds[0],
              ds[1], ds[2], INFINITY, out);
    return true;
}

/* ao_tracer_intersect_arrays's job: the rays, the mesh, the outputs, the next ray to take. */
struct arrays_job {
    const struct ao_tracer_arrays *mesh;
    const float *origins, *directions;
    size_t count;
    float tnear;
    double *t;
    int32_t *ids;
    double *barys;
    atomic_size_t next;
};

/* Each thread takes runs of rays until none are left, traced one by one with rtcIntersect1: on 1M
 * random rays at the bunny it measured as fast as rtcIntersect1M streams of 256 and rtcIntersect16
 * packets of the same rays, or faster (interleaved runs; the rays of a run share nothing). */
static void intersect_arrays_job(void *user, int self)
{
    (void)self;
    enum { RUN = 256 };
    struct arrays_job *job = user;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (;;) {
        size_t first = atomic_fetch_add(&job->next, RUN);
        if (first >= job->count)
            return;
        size_t end = job->count - first < RUN ? job->count : first + RUN;
        for (size_t i = first; i < end; i++) {
            _Alignas(16) struct RTCRayHit rh;
            double skip, scale;
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            if (bring(job->mesh, job->origins + 3 * i, job->directions + 3 * i, job->tnear, &rh.ray, &skip, &scale))
                rtcIntersect1(job->mesh->scene, &context, &rh);
            bool hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            double u = hit ? rh.hit.u : 0.0, v = hit ? rh.hit.v : 0.0;
            job->t[i] = hit ? (skip + rh.ray.tfar) * scale : INFINITY;
            job->ids[i] = hit ? (int32_t)rh.hit.primID : -1;
            job->barys[3 * i] = hit ? 1.0 - u - v : 0.0;
            job->barys[3 * i + 1] = u;
            job->barys[3 * i + 2] = v;
        }
    }
}

bool ao_tracer_intersect_arrays(const struct ao_tracer_arrays *mesh, const float *origins, const float *directions,
                                size_t count, float tnear, int threads, double *t, int32_t *ids, double *barys)
{
    struct ao_pool *pool = ao_pool_create(threads, ao_tracer_thread_init);
    if (!pool)
        return false;
    struct arrays_job job = {.mesh = mesh, .origins = origins, .directions = directions, .count = count,
                             .tnear = tnear, .t = t, .ids = ids, .barys = barys};
#if defined(__SSE__)
    unsigned modes = _mm_getcsr();   /* the caller's floating-point modes, given back */
#endif
    ao_tracer_thread_init();
    ao_pool_run(pool, intersect_arrays_job, &job);
#if defined(__SSE__)
    _mm_setcsr(modes);
#endif
    ao_pool_destroy(pool);
    return true;
}
