/* Embree 3 back end; see tracer.h. The only file that includes Embree. */
#include "tracer.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <embree3/rtcore.h>

#include "clock.h"
#include "direct.h"
#include "pool.h"
#include "text.h"
#if defined(__SSE__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#endif

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

/* Embree's error function: keeps the device's first error for say_errors, on whatever thread. */
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
static RTCDevice new_device(struct embree_errors *e)
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
static void say_errors(struct embree_errors *e, enum ao_text_level level)
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
    say_errors(&tracer->errors, AO_TEXT_NOTE);
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
    if (!(t->device = new_device(&t->errors))) {
        free(t);
        return NULL;
    }
    rtcSetDeviceMemoryMonitorFunction(t->device, embree_memory_monitor, t);
    t->mesh_count = scene->mesh_count;
    t->spheres_id = scene->sphere_count ? (unsigned)scene->instance_count : RTC_INVALID_GEOMETRY_ID;
    bool ok = build(t, scene, bvh, &t->bvhs, &t->stats, NULL);
    t->scene = t->bvhs.scene;
    say_errors(&t->errors, ok ? AO_TEXT_NOTE : AO_TEXT_ERROR);
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
static void to_embree_hit(const struct ao_packet *rays, struct RTCRayHit16 *out, int *valid)
{
    to_embree(rays, &out->ray, valid);
    for (int k = 0; k < AO_PACKET_SIZE; k++) {
        out->hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        out->hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
}

/* The recorder's next slot when this is the stride-th packet offered and there is room, else NULL. */
static struct ao_packet *recorder_slot(struct ao_ray_recorder *rec)
{
    if (rec->seen++ % rec->stride != 0 || rec->count == rec->capacity)
        return NULL;
    return &rec->packets[rec->count++];
}

void ao_tracer_intersect(const struct ao_tracer *tracer, const struct ao_packet *rays, struct ao_hit *hits)
{
    if (tracer->direct) {
        ao_direct_intersect(tracer->direct, rays, hits);
        return;
    }
    struct ao_packet *copy = tracer->eye_recorder ? recorder_slot(tracer->eye_recorder) : NULL;
    if (copy)
        *copy = *rays;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    _Alignas(64) struct RTCRayHit16 rh;
    _Alignas(64) int valid[AO_PACKET_SIZE];
    to_embree_hit(rays, &rh, valid);
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

/* Writes one ray into out in Embree's single-ray layout, field by field (a whole struct assigned
 * from a temporary stalls on store forwarding: measured 30% of the time). */
static inline void to_single(float ox, float oy, float oz, float dx, float dy, float dz, float tfar,
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

#if defined(__SSE__)
/* Writes rays first .. first + 3 of the batch into out[0..3] in Embree's single-ray layout with
 * three 4x4 transposes: a sixth of the stores of to_single's field-by-field writes. */
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

/* Offers the recorder the batch; it keeps every stride-th whole, in order, 16 rays to a packet (so
 * that a ceiling traced on the sample sees rays as coherent as aoview's batches). */
static void record(struct ao_ray_recorder *rec, const struct ao_batch *rays)
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

void ao_tracer_occluded(const struct ao_tracer *tracer, struct ao_batch *rays)
{
    if (tracer->direct) {
        ao_direct_occluded(tracer->direct, rays);
        return;
    }
    struct ao_ray_recorder *rec = tracer->occlusion_recorder;
    if (rec)
        record(rec, rays);
    /* One incoherent stream: Embree sorts it into packets by direction octant, and marks each
     * blocked ray by setting its tfar to -inf. */
    _Alignas(64) struct RTCRay stream[AO_BATCH_RAYS];
    int n = rays->count, k = 0;
#if defined(__SSE__)
    for (; k + 4 <= n; k += 4) /* the batch's arrays are 64-byte aligned, so are groups of four */
        to_single4(rays, k, &stream[k]);
#endif
    for (; k < n; k++)
        to_single(rays->org_x[k], rays->org_y[k], rays->org_z[k], rays->dir_x[k], rays->dir_y[k], rays->dir_z[k],
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
            to_single(p->org_x[k], p->org_y[k], p->org_z[k], p->dir_x[k], p->dir_y[k], p->dir_z[k], p->tfar[k],
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
            to_embree_hit(&packets[p], &converted[p], valid[p]);
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

/* ---- Ray batches against a mesh given as arrays (the Python module's ray_mesh_intersect).
 * Each ray is brought to the mesh before Embree sees it, so that what Embree's robust triangle test
 * (Pluecker's, in single precision, with flush-to-zero) forms stays between 2^-126 and 2^128 for
 * any ray the caller may give: coordinates within AO_TRACER_ARRAYS_LIMIT, a mesh from
 * AO_SCENE_MIN_EXTENT to AO_SCENE_MAX_EXTENT across (the scenes' range, scene_place.c). With E the
 * mesh's largest side:
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
    RTCDevice device = mesh->device = new_device(&mesh->errors);
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
    say_errors(&mesh->errors, ok ? AO_TEXT_NOTE : AO_TEXT_ERROR);
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
        to_single(o[0], o[1], o[2], ds[0], ds[1], ds[2], INFINITY, out);
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
    to_single((float)(o[0] + enter * ds[0]), (float)(o[1] + enter * ds[1]), (float)(o[2] + enter * ds[2]), ds[0],
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
