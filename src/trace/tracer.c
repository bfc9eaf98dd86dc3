/* Embree 3 back end; see tracer.h. With tracer_bench.c and tracer_arrays.c, the only files that
 * include Embree (tracer_private.h). */
#include "tracer.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "direct.h"
#include "ray_recorder.h"
#include "tracer_private.h"
#if defined(__SSE__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#endif

/* Embree's error function: keeps the device's first error for ao_embree_say, on whatever thread. */
static void record_error(void *user, enum RTCError code, const char *message)
{
    struct embree_errors *e = user;
    if (code == RTC_ERROR_CANCELLED) /* an upgrade's build, cancelled as its tracer goes */
        return;
    const char *text = message ? message : "(no message)";
    size_t length = strnlen(text, sizeof e->message - 1);
    pthread_mutex_lock(&e->lock);
    if (e->code == RTC_ERROR_NONE) {
        e->code = (int)code;
        memcpy(e->message, text, length);
        e->message[length] = '\0';
    }
    pthread_mutex_unlock(&e->lock);
}

/* A new device whose errors e keeps (its lock initialized here, destroyed by the caller after the
 * device); NULL after one message. */
RTCDevice ao_embree_device(struct embree_errors *e)
{
    RTCDevice device = rtcNewDevice(NULL);
    if (!device) {
        ao_text_report("aoview: Embree could not create a device (error %d)", (int)rtcGetDeviceError(NULL));
        return NULL;
    }
    pthread_mutex_init(&e->lock, NULL);
    e->code = RTC_ERROR_NONE;
    rtcSetDeviceErrorFunction(device, record_error, e);
    return device;
}

/* Says the error e keeps, if any, at level, on the calling thread, and forgets it. */
void ao_embree_say(struct embree_errors *e, enum ao_text_level level)
{
    pthread_mutex_lock(&e->lock);
    int code = e->code;
    char message[sizeof e->message];
    memcpy(message, e->message, sizeof message);
    e->code = RTC_ERROR_NONE;
    pthread_mutex_unlock(&e->lock);
    if (code == RTC_ERROR_NONE)
        return;
    if (level == AO_TEXT_ERROR)
        ao_text_report("aoview: Embree error %d: %s", code, message);
    else
        ao_text_note("aoview: Embree error %d: %s", code, message);
}

/* Embree's memory monitor: what the device holds now and at most (Embree calls it from its build
 * threads; it never refuses). */
static bool embree_memory_monitor(void *user, ssize_t bytes, bool post)
{
    (void)post;
    struct ao_tracer *t = user;
    int64_t now = atomic_fetch_add(&t->embree_bytes, (int64_t)bytes) + (int64_t)bytes;
    int64_t peak = atomic_load(&t->embree_peak);
    while (now > peak && !atomic_compare_exchange_weak(&t->embree_peak, &peak, now))
        ;
    return true;
}

/* Embree's progress monitor of an upgrade's build: false (which cancels the build) once the tracer
 * is being destroyed. */
static bool going_on(void *cancel, double done)
{
    (void)done;
    return !atomic_load((atomic_bool *)cancel);
}

/* Sets how Embree builds a scene's BVH (budget.h's enum ao_bvh): always robust traversal, which
 * keeps shared edges watertight so that closed meshes stay closed; compact leaves or Morton's build
 * where asked; a build that `cancel` (unless NULL) stops. */
static void set_build(RTCScene scene, enum ao_bvh bvh, atomic_bool *cancel)
{
    bool compact = bvh == AO_BVH_COMPACT || bvh == AO_BVH_LOW_COMPACT;
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST | (compact ? RTC_SCENE_FLAG_COMPACT : 0));
    if (bvh == AO_BVH_LOW || bvh == AO_BVH_LOW_COMPACT)
        rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_LOW);
    if (cancel)
        rtcSetSceneProgressMonitorFunction(scene, going_on, cancel);
}

/* A triangle geometry over the mesh's own vertex and index arrays, shared, not copied (scene.h:
 * the positions are padded as Embree needs). */
static RTCGeometry triangles_of(struct ao_tracer *t, const struct ao_mesh *m, enum ao_bvh bvh)
{
    RTCGeometry g = rtcNewGeometry(t->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!g)
        return NULL;
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, m->positions, 0,
                               sizeof *m->positions, m->vertex_count);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m->indices, 0, 3 * sizeof *m->indices,
                               m->triangle_count);
    if (bvh == AO_BVH_LOW || bvh == AO_BVH_LOW_COMPACT)
        rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_LOW);
    rtcCommitGeometry(g);
    return g;
}

/* Instanced mesh m's own scene in b, built once: one triangle geometry, one BVH. */
static RTCScene mesh_scene(struct ao_tracer *t, struct bvhs *b, const struct ao_scene *s, uint32_t m, enum ao_bvh bvh,
                           struct ao_tracer_stats *stats, atomic_bool *cancel)
{
    if (b->meshes[m])
        return b->meshes[m];
    RTCScene scene = rtcNewScene(t->device);
    RTCGeometry g = scene ? triangles_of(t, &s->meshes[m], bvh) : NULL;
    if (!g) {
        if (scene)
            rtcReleaseScene(scene);
        return NULL;
    }
    set_build(scene, bvh, cancel);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    stats->bvhs++;
    return b->meshes[m] = scene;
}

/* Instance i of the scene, under geometry id i of b's top level: a flat mesh's triangles, or an
 * Embree instance of its mesh's own scene under its map into the local frame. */
static bool add_instance(struct ao_tracer *t, struct bvhs *b, const struct ao_scene *s, size_t i, enum ao_bvh bvh,
                         struct ao_tracer_stats *stats, atomic_bool *cancel)
{
    const struct ao_instance *in = &s->instances[i];
    RTCGeometry g;
    if (in->flat) {
        if (!(g = triangles_of(t, &s->meshes[in->mesh], bvh)))
            return false;
        stats->triangle_geometries++;
    } else {
        RTCScene scene = mesh_scene(t, b, s, in->mesh, bvh, stats, cancel);
        if (!scene || !(g = rtcNewGeometry(t->device, RTC_GEOMETRY_TYPE_INSTANCE)))
            return false;
        rtcSetGeometryInstancedScene(g, scene);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, in->to_local);
        rtcCommitGeometry(g);
        stats->instances++;
    }
    rtcAttachGeometryByID(b->scene, g, (unsigned)i);
    rtcReleaseGeometry(g);
    return true;
}

/* Spheres stay analytic: Embree's sphere primitive, radius in the fourth vertex component. */
static bool add_spheres(struct ao_tracer *t, struct bvhs *b, const struct ao_scene *s)
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
    rtcAttachGeometryByID(b->scene, g, t->spheres_id);
    rtcReleaseGeometry(g);
    return true;
}

/* Releases what a build made (accepts one half done). */
static void release_bvhs(struct bvhs *b, size_t mesh_count)
{
    if (b->scene)
        rtcReleaseScene(b->scene);
    for (size_t i = 0; b->meshes && i < mesh_count; i++)
        if (b->meshes[i])
            rtcReleaseScene(b->meshes[i]);
    free(b->meshes);
    b->scene = NULL;
    b->meshes = NULL;
}

/* Builds the scene's BVHs into b as `bvh` says, counting them in *stats; false when Embree or
 * memory fails or `cancel` (unless NULL) stopped it (b then holds what to release). */
static bool build(struct ao_tracer *t, const struct ao_scene *scene, enum ao_bvh bvh, struct bvhs *b,
                  struct ao_tracer_stats *stats, atomic_bool *cancel)
{
    b->meshes = calloc(scene->mesh_count ? scene->mesh_count : 1, sizeof *b->meshes);
    b->scene = b->meshes ? rtcNewScene(t->device) : NULL;
    if (!b->scene)
        return false;
    set_build(b->scene, bvh, cancel);
    stats->bvhs = 1;
    bool ok = true;
    for (size_t i = 0; ok && i < scene->instance_count; i++)
        ok = add_instance(t, b, scene, i, bvh, stats, cancel);
    ok = ok && (scene->sphere_count == 0 || add_spheres(t, b, scene));
    if (ok)
        rtcCommitScene(b->scene);
    return ok && rtcGetDeviceError(t->device) == RTC_ERROR_NONE;
}

struct ao_tracer *ao_tracer_create(const struct ao_scene *scene)
{
    return ao_tracer_create_with(scene, AO_BACKEND_AUTO);
}

static struct ao_tracer *create(const struct ao_scene *scene, enum ao_backend backend, enum ao_bvh bvh);

struct ao_tracer *ao_tracer_create_with(const struct ao_scene *scene, enum ao_backend backend)
{
    return create(scene, backend, scene->bvh);
}

/* The upgrade's thread: builds the source scene's BVHs as the scene asks. */
static void *build_upgrade(void *user)
{
    struct ao_tracer *t = user;
    struct upgrade *u = &t->upgrade;
    ao_text_route(u->sink);
    ao_tracer_thread_init();
    u->ok = build(t, u->source, u->source->bvh, &u->built, &u->stats, &u->cancel);
    atomic_store(&u->done, true);
    return NULL;
}

struct ao_tracer *ao_tracer_create_progressive(const struct ao_scene *scene)
{
    struct ao_tracer *t = create(scene, AO_BACKEND_AUTO, AO_BVH_LOW);
    if (!t || t->direct)
        return t;
    t->upgrade.source = scene;
    t->upgrade.pending = true;
    return t;
}

bool ao_tracer_upgrading(const struct ao_tracer *tracer)
{
    return tracer->upgrade.pending || tracer->upgrade.started;
}

/* Starts the upgrade's thread; without one the LOW BVH traces on: slower rays, the same image. */
static void start_upgrade(struct ao_tracer *t)
{
    struct upgrade *u = &t->upgrade;
    u->pending = false;
    atomic_store(&u->done, false);
    atomic_store(&u->cancel, false);
    u->sink = ao_text_current();
    u->started = pthread_create(&u->thread, NULL, build_upgrade, t) == 0;
    if (!u->started)
        ao_text_note("aoview: no thread for the faster BVH's build; tracing on with the quick one");
}

bool ao_tracer_switch(struct ao_tracer *tracer)
{
    struct upgrade *u = &tracer->upgrade;
    if (u->pending)
        start_upgrade(tracer);
    if (!u->started || !atomic_load(&u->done))
        return false;
    pthread_join(u->thread, NULL);
    u->started = false;
    ao_embree_say(&tracer->errors, AO_TEXT_NOTE);
    if (!u->ok) { /* out of memory beside the quick BVH: keep it */
        release_bvhs(&u->built, tracer->mesh_count);
        ao_text_note("aoview: the faster BVH did not fit beside the quick one; tracing on with the quick one");
        return false;
    }
    release_bvhs(&tracer->bvhs, tracer->mesh_count);
    tracer->bvhs = u->built;
    tracer->scene = tracer->bvhs.scene;
    tracer->stats = u->stats;
    tracer->stats.embree_bytes = atomic_load(&tracer->embree_bytes);
    tracer->stats.embree_peak_bytes = atomic_load(&tracer->embree_peak);
    return true;
}

static struct ao_tracer *create(const struct ao_scene *scene, enum ao_backend backend, enum ao_bvh bvh)
{
    struct ao_tracer *t = calloc(1, sizeof *t);
    if (!t) {
        ao_text_report("aoview: out of memory creating the tracer");
        return NULL;
    }
    /* Scenes of a few primitives skip Embree: testing each one directly is faster (direct.c). */
    if (backend == AO_BACKEND_DIRECT || (backend == AO_BACKEND_AUTO && ao_direct_suits(scene))) {
        if (!(t->direct = ao_direct_create(scene))) {
            free(t);
            return NULL;
        }
        return t;
    }
    t->spheres_id = RTC_INVALID_GEOMETRY_ID;
    if (!(t->device = ao_embree_device(&t->errors))) {
        free(t);
        return NULL;
    }
    rtcSetDeviceMemoryMonitorFunction(t->device, embree_memory_monitor, t);
    t->mesh_count = scene->mesh_count;
    t->spheres_id = scene->sphere_count ? (unsigned)scene->instance_count : RTC_INVALID_GEOMETRY_ID;
    bool ok = build(t, scene, bvh, &t->bvhs, &t->stats, NULL);
    t->scene = t->bvhs.scene;
    ao_embree_say(&t->errors, ok ? AO_TEXT_NOTE : AO_TEXT_ERROR);
    if (!ok) {
        ao_text_report("aoview: Embree could not build the scene (out of memory?)");
        ao_tracer_destroy(t);
        return NULL;
    }
    t->stats.embree_bytes = atomic_load(&t->embree_bytes);
    t->stats.embree_peak_bytes = atomic_load(&t->embree_peak);
    return t;
}

void ao_tracer_describe(const struct ao_tracer *tracer, struct ao_tracer_stats *out)
{
    *out = tracer->stats;
}

void ao_tracer_destroy(struct ao_tracer *tracer)
{
    if (!tracer)
        return;
    ao_direct_destroy(tracer->direct);
    if (tracer->upgrade.started) { /* an upgrade still building: cancel it, then free what it made */
        atomic_store(&tracer->upgrade.cancel, true);
        pthread_join(tracer->upgrade.thread, NULL);
        release_bvhs(&tracer->upgrade.built, tracer->mesh_count);
    }
    release_bvhs(&tracer->bvhs, tracer->mesh_count);
    if (tracer->device) {
        rtcReleaseDevice(tracer->device);
        pthread_mutex_destroy(&tracer->errors.lock);
    }
    free(tracer);
}

const char *ao_tracer_backend(const struct ao_tracer *tracer)
{
    return tracer->direct ? "direct" : "embree";
}

void ao_tracer_thread_init(void)
{
#if defined(__SSE__)
    /* Embree's traversal is slower with denormals and asks for both modes on every thread. */
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
}

/* Copies our packet into Embree's ray layout, with a validity mask for the unused lanes (which get
 * lane 0's ray, so that no garbage reaches Embree). Every ray is within Embree's bound on origins
 * and directions (1.844e18; beyond it its traversal aborts): scenes are refused beyond 2^31
 * across, and the viewer's moves stop at 2^48 (camera.c). */
static void to_embree(const struct ao_packet *rays, struct RTCRay16 *out, int *valid)
{
    for (int k = 0; k < AO_PACKET_SIZE; k++) { /* every lane, so that the loop vectorizes */
        valid[k] = k < rays->count ? -1 : 0;
        out->org_x[k] = rays->org_x[k];
        out->org_y[k] = rays->org_y[k];
        out->org_z[k] = rays->org_z[k];
        out->dir_x[k] = rays->dir_x[k];
        out->dir_y[k] = rays->dir_y[k];
        out->dir_z[k] = rays->dir_z[k];
        out->tnear[k] = 0.0f;
        out->tfar[k] = rays->tfar[k];
        out->time[k] = 0.0f;
        out->mask[k] = ~0u;
        out->id[k] = (unsigned)k;
        out->flags[k] = 0;
    }
    for (int k = rays->count; k < AO_PACKET_SIZE; k++) {
        out->org_x[k] = rays->org_x[0];
        out->org_y[k] = rays->org_y[0];
        out->org_z[k] = rays->org_z[0];
        out->dir_x[k] = rays->dir_x[0];
        out->dir_y[k] = rays->dir_y[0];
        out->dir_z[k] = rays->dir_z[0];
        out->tfar[k] = rays->tfar[0];
    }
}

/* The packet in Embree's layout for rtcIntersect16, with no hit yet. */
void ao_embree_packet(const struct ao_packet *rays, struct RTCRayHit16 *out, int *valid)
{
    to_embree(rays, &out->ray, valid);
    for (int k = 0; k < AO_PACKET_SIZE; k++) {
        out->hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        out->hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
}

void ao_tracer_intersect(const struct ao_tracer *tracer, const struct ao_packet *rays, struct ao_hit *hits)
{
    if (tracer->direct) {
        ao_direct_intersect(tracer->direct, rays, hits);
        return;
    }
    struct ao_packet *copy = tracer->eye_recorder ? ao_ray_recorder_slot(tracer->eye_recorder) : NULL;
    if (copy)
        *copy = *rays;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    _Alignas(64) struct RTCRayHit16 rh;
    _Alignas(64) int valid[AO_PACKET_SIZE];
    ao_embree_packet(rays, &rh, valid);
    rtcIntersect16(valid, tracer->scene, &context, &rh);
    for (int k = 0; k < rays->count; k++) {
        bool found = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
        hits[k].t = found ? rh.ray.tfar[k] : INFINITY;
        hits[k].u = rh.hit.u[k];
        hits[k].v = rh.hit.v[k];
        hits[k].prim = rh.hit.primID[k];
        bool instanced = rh.hit.instID[0][k] != RTC_INVALID_GEOMETRY_ID;
        hits[k].instance = instanced ? rh.hit.instID[0][k] : rh.hit.geomID[k];
        hits[k].sphere = !instanced && rh.hit.geomID[k] == tracer->spheres_id;
        hits[k].ng = ao_vec3_make(rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]); /* Embree's: as ours */
    }
}

#if defined(__SSE__)
/* Writes rays first .. first + 3 of the batch into out[0..3] in Embree's single-ray layout with
 * three 4x4 transposes: a sixth of the stores of ao_embree_ray's field-by-field writes. */
static inline void to_single4(const struct ao_batch *rays, int first, struct RTCRay *out)
{
    __m128 zero = _mm_setzero_ps(), mask = _mm_castsi128_ps(_mm_set1_epi32(-1));
    __m128 ox = _mm_load_ps(&rays->org_x[first]), oy = _mm_load_ps(&rays->org_y[first]);
    __m128 oz = _mm_load_ps(&rays->org_z[first]), tnear = zero;
    __m128 dx = _mm_load_ps(&rays->dir_x[first]), dy = _mm_load_ps(&rays->dir_y[first]);
    __m128 dz = _mm_load_ps(&rays->dir_z[first]), time = zero;
    _MM_TRANSPOSE4_PS(ox, oy, oz, tnear);
    _MM_TRANSPOSE4_PS(dx, dy, dz, time);
    __m128 tfar = _mm_load_ps(&rays->tfar[first]);
    __m128 low = _mm_unpacklo_ps(tfar, mask), high = _mm_unpackhi_ps(tfar, mask); /* tfar, mask pairs */
    __m128 rest[4] = {_mm_movelh_ps(low, zero), _mm_movehl_ps(zero, low), _mm_movelh_ps(high, zero),
                      _mm_movehl_ps(zero, high)};  /* tfar, mask, id 0, flags 0 */
    __m128 org[4] = {ox, oy, oz, tnear}, dir[4] = {dx, dy, dz, time};
    for (int k = 0; k < 4; k++) {
        _mm_store_ps(&out[k].org_x, org[k]);
        _mm_store_ps(&out[k].dir_x, dir[k]);
        _mm_store_ps(&out[k].tfar, rest[k]);
    }
}
#endif

void ao_tracer_occluded(const struct ao_tracer *tracer, struct ao_batch *rays)
{
    if (tracer->direct) {
        ao_direct_occluded(tracer->direct, rays);
        return;
    }
    struct ao_ray_recorder *rec = tracer->occlusion_recorder;
    if (rec)
        ao_ray_recorder_keep(rec, rays);
    /* One incoherent stream: Embree sorts it into packets by direction octant, and marks each
     * blocked ray by setting its tfar to -inf. */
    _Alignas(64) struct RTCRay stream[AO_BATCH_RAYS];
    int n = rays->count, k = 0;
#if defined(__SSE__)
    for (; k + 4 <= n; k += 4) /* the batch's arrays are 64-byte aligned, so are groups of four */
        to_single4(rays, k, &stream[k]);
#endif
    for (; k < n; k++)
        ao_embree_ray(rays->org_x[k], rays->org_y[k], rays->org_z[k], rays->dir_x[k], rays->dir_y[k], rays->dir_z[k],
                  rays->tfar[k], &stream[k]);
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    double start = rec ? ao_clock_seconds() : 0.0;
    rtcOccluded1M(tracer->scene, &context, stream, (unsigned)n, sizeof *stream);
    if (rec) {
        rec->embree_seconds += ao_clock_seconds() - start;
        rec->embree_rays += (uint64_t)n;
    }
    for (k = 0; k < n; k++)
        rays->tfar[k] = stream[k].tfar;
}

