/* The AO estimator; see ao.h.
 *
 * Derivation. Ambient occlusion with albedo rho is L = rho/pi * Int_H V(x,w) max(0, n.w) dw: a fully
 * open point gives rho/pi * pi = rho. Drawing N directions w_j from a density p gives the unbiased
 * estimator L ~ rho/(pi N) Sum_j V(x,w_j) max(0, n.w_j) / p(w_j). Per sampler the weight
 * max(0, n.w)/(pi p(w)) is 4 max(0, n.w) for the uniform sphere (p = 1/4pi), 2 n.w for the uniform
 * hemisphere (p = 1/2pi), and exactly 1 for cosine sampling (p = n.w/pi), where the estimator
 * reduces to rho times the fraction of open directions. Directions of weight 0 (the lower half of
 * the uniform sphere) add nothing and are not traced. */
#include "ao.h"

#include <float.h>

#include "rng.h"
#include "sampling.h"
#include "simd.h"
#include "tracer.h"

/* Keys of a pixel's eye-ray stream (indexed by eye ray) and AO stream (indexed by sample), in the
 * pass slot of the key, where no real pass number reaches. */
static const uint64_t EYE_STREAM = UINT64_MAX - 1, AO_STREAM = UINT64_MAX;

/* The pass slot of a stream for the given half of the passes. Random numbers are independent in
 * any split, so both halves share one stream and its numbering; an Owen-scrambled Sobol sequence
 * split by parity would leave each half on its own part of the square, so the odd half draws from
 * a second, independently scrambled sequence and the two halves are independent estimates. */
static uint64_t stream_for_half(const struct ao_context *ctx, uint64_t stream, int half)
{
    return ctx->sequence == AO_SEQUENCE_SOBOL && half ? stream - 2 : stream;
}

/* The unit vector along v, or zero when v is zero (or not finite). */
static inline struct ao_vec3 unit_or_zero(struct ao_vec3 v)
{
    float length = ao_vec3_length(v);
    return length > 0.0f && isfinite(length) ? ao_vec3_scale(v, 1.0f / length) : ao_vec3_make(0.0f, 0.0f, 0.0f);
}

/* The column-major 3x3 matrix n times v. */
static inline struct ao_vec3 times(const float *n, struct ao_vec3 v)
{
    return ao_vec3_make(n[0] * v.x + n[3] * v.y + n[6] * v.z, n[1] * v.x + n[4] * v.y + n[7] * v.z,
                        n[2] * v.x + n[5] * v.y + n[8] * v.z);
}

/* The affine map a (12 floats, affine.h's layout) of p, in double, narrowed once. */
static inline struct ao_vec3 map_point(const float *a, struct ao_vec3 p)
{
    double x = (double)a[0] * p.x + (double)a[3] * p.y + (double)a[6] * p.z + (double)a[9];
    double y = (double)a[1] * p.x + (double)a[4] * p.y + (double)a[7] * p.z + (double)a[10];
    double z = (double)a[2] * p.x + (double)a[5] * p.y + (double)a[8] * p.z + (double)a[11];
    return ao_vec3_make((float)x, (float)y, (float)z);
}

/* The hit on a triangle of an instanced mesh (the hit's u, v and ng in the mesh's own frame) shaded
 * into *r in the local frame: the normals mapped by the instance's normal matrix (each vertex normal
 * before it is interpolated, as flattening maps them), both turned to the eye; the point recomputed
 * and lifted in the mesh's own frame, where Embree tests the triangle, then mapped. The lift there
 * clears the point's error bound plus how far the origin moves when it is mapped into the local
 * frame and Embree maps it back (the instance's slack, derived in scene_place.c): at most
 * slack[0] max|o| + slack[1] per axis for an origin o. With max|o| <= max|p| + d for a lift d, the
 * slack is taken at max|p| + 2 d0, d0 the lift with the slack at max|p|: the final lift exceeds d0
 * by at most sqrt(3) (1 + gamma12) 2 slack[0] d0 <= d0 (slack[0] <= 2^-8), so max|o| stays within. */
static void shade_instanced(const struct ao_scene *scene, const struct ao_instance *in, enum ao_shading shading,
                            struct ao_vec3 dir, const struct ao_hit *hit, struct ao_surface *r)
{
    const struct ao_mesh *m = &scene->meshes[in->mesh];
    const uint32_t *i = &m->indices[3 * hit->prim];
    struct ao_vec3 error;
    struct ao_vec3 p = ao_triangle_point(m->positions[i[0]], m->positions[i[1]], m->positions[i[2]], hit->u, hit->v,
                                         &error);
    struct ao_vec3 ng_own = ao_vec3_normalize(hit->ng);
    r->ng = ao_vec3_normalize(times(in->normals, hit->ng));
    float w0 = 1.0f - hit->u - hit->v;
    struct ao_vec3 n = ao_vec3_scale(unit_or_zero(times(in->normals, m->normals[i[0]])), w0);
    n = ao_vec3_add(n, ao_vec3_scale(unit_or_zero(times(in->normals, m->normals[i[1]])), hit->u));
    n = ao_vec3_add(n, ao_vec3_scale(unit_or_zero(times(in->normals, m->normals[i[2]])), hit->v));
    float len = ao_vec3_length(n);
    r->ns = shading == AO_SHADING_PHONG && len > 1e-6f && isfinite(len) ? ao_vec3_scale(n, 1.0f / len) : r->ng;
    r->albedo = scene->albedos[in->albedo];
    r->position = map_point(in->to_local, p);
    float most = ao_vec3_max_abs(p), gap = 0.0f;
    if (!(ao_vec3_dot(r->ng, r->ng) > 0.25f) || !(ao_vec3_dot(ng_own, ng_own) > 0.25f)) {
        /* Degenerate: lifted towards the eye in the local frame, past the point's error box mapped
         * there (|L| times it and the slack, and the rounding of the map). */
        const float *a = in->to_local;
        float e = fmaxf(error.x, fmaxf(error.y, error.z)) + in->slack[0] * most + in->slack[1], big = 0.0f;
        for (int k = 0; k < 3; k++)
            big = fmaxf(big, fabsf(a[k]) + fabsf(a[3 + k]) + fabsf(a[6 + k]));
        r->ng = r->ns = ao_vec3_scale(dir, -1.0f);
        r->origin = ao_surface_lift(r->position, r->ng,
                                    ao_vec3_add(ao_vec3_make(big * e, big * e, big * e),
                                                ao_vec3_scale(ao_vec3_abs(r->position), ao_gamma(2))));
        return;
    }
    /* Turned to the eye; the normal matrix keeps the side (it is |det| times the inverse transpose),
     * so the mesh's own normal turns with it. */
    if (ao_vec3_dot(r->ng, dir) > 0.0f) {
        r->ng = ao_vec3_scale(r->ng, -1.0f);
        r->ns = ao_vec3_scale(r->ns, -1.0f);
        ng_own = ao_vec3_scale(ng_own, -1.0f);
    }
    for (int pass = 0; pass < 2; pass++) {
        float slack = in->slack[0] * (most + 2.0f * gap) + in->slack[1];
        struct ao_vec3 e = ao_vec3_add(error, ao_vec3_make(slack, slack, slack));
        struct ao_vec3 o = ao_surface_lift(p, ng_own, e);
        if (pass == 0)
            gap = ao_vec3_max_abs(ao_vec3_sub(o, p));
        else
            r->origin = map_point(in->to_local, o);
    }
}

/* A flat mesh's triangle (corners p, vertex normals n) hit at Embree's u, v with geometric normal
 * hit_ng: the point recomputed with its error bound, the unit geometric normal and the shading one
 * per `phong` (the geometric one where the vertex normals cancel). Branch-free. */
static inline void shade_triangle(const struct ao_vec3 p[3], const struct ao_vec3 n[3], float u, float v,
                                  struct ao_vec3 hit_ng, bool phong, struct ao_vec3 *position, struct ao_vec3 *error,
                                  struct ao_vec3 *ng, struct ao_vec3 *ns)
{
    *position = ao_triangle_point(p[0], p[1], p[2], u, v, error);
    *ng = ao_vec3_normalize(hit_ng);
    float w0 = 1.0f - u - v;
    struct ao_vec3 sum = ao_vec3_scale(n[0], w0);
    sum = ao_vec3_add(sum, ao_vec3_scale(n[1], u));
    sum = ao_vec3_add(sum, ao_vec3_scale(n[2], v));
    float len = ao_vec3_length(sum);
    bool smooth = phong && len > 1e-6f && len <= FLT_MAX; /* false for NaN and infinity too */
    *ns = ao_vec3_pick(smooth, ao_vec3_scale(sum, 1.0f / len), *ng);
}

/* The shading point's normals turned to the side the eye ray (direction dir) came from (the eye's
 * direction for both where ng is not a unit normal: a degenerate triangle, NaN), and where its
 * occlusion rays leave. Branch-free. */
static inline void face_eye(struct ao_vec3 position, struct ao_vec3 error, struct ao_vec3 dir, struct ao_vec3 *ng,
                            struct ao_vec3 *ns, struct ao_vec3 *origin)
{
    struct ao_vec3 back = ao_vec3_scale(dir, -1.0f);
    bool degenerate = !(ao_vec3_dot(*ng, *ng) > 0.25f);
    *ng = ao_vec3_pick(degenerate, back, *ng);
    *ns = ao_vec3_pick(degenerate, back, *ns);
    float side = ao_vec3_dot(*ng, dir) > 0.0f ? -1.0f : 1.0f;
    *ng = ao_vec3_scale(*ng, side);
    *ns = ao_vec3_scale(*ns, side);
    *origin = ao_surface_lift(position, *ng, error);
}

void ao_surface_from_hit(const struct ao_scene *scene, enum ao_shading shading, struct ao_vec3 org,
                         struct ao_vec3 dir, const struct ao_hit *hit, struct ao_surface *s)
{
    /* The hit point recomputed from the primitive, with its error bound: Embree's org + t dir
     * carries the error of t, which grows with the distance from the eye. (Built in a local and
     * written to *s field by field at the end: computed in place through s, gcc spilled dir in
     * halves and reloaded it across them, and a whole-struct copy stalled the same way on the
     * stack; those store-forwarding stalls cost about a third of this function.) */
    struct ao_surface r;
    struct ao_vec3 error;
    if (hit->sphere) {
        const struct ao_sphere *sp = &scene->spheres[hit->prim];
        struct ao_vec3 q = ao_vec3_add(org, ao_vec3_scale(dir, hit->t));
        r.position = ao_sphere_point(sp->center, sp->radius, q, &r.ng, &error);
        r.ns = r.ng;
        r.albedo = sp->albedo;
    } else {
        const struct ao_instance *in = &scene->instances[hit->instance];
        if (!in->flat) {
            shade_instanced(scene, in, shading, dir, hit, &r);
            s->position = r.position;
            s->ng = r.ng;
            s->ns = r.ns;
            s->albedo = r.albedo;
            s->origin = r.origin;
            return;
        }
        const struct ao_mesh *m = &scene->meshes[in->mesh];
        const uint32_t *i = &m->indices[3 * hit->prim];
        struct ao_vec3 p[3] = {m->positions[i[0]], m->positions[i[1]], m->positions[i[2]]};
        struct ao_vec3 n[3] = {m->normals[i[0]], m->normals[i[1]], m->normals[i[2]]};
        shade_triangle(p, n, hit->u, hit->v, hit->ng, shading == AO_SHADING_PHONG, &r.position, &error, &r.ng, &r.ns);
        r.albedo = scene->albedos[in->albedo];
    }
    face_eye(r.position, error, dir, &r.ng, &r.ns, &r.origin);
    s->position = r.position;
    s->ng = r.ng;
    s->ns = r.ns;
    s->albedo = r.albedo;
    s->origin = r.origin;
}

/* A packet's shading points in structure-of-arrays layout, lane by lane as its eye rays. */
struct surfaces {
    float ng[3][AO_PACKET_SIZE], ns[3][AO_PACKET_SIZE], albedo[3][AO_PACKET_SIZE], origin[3][AO_PACKET_SIZE];
};

/* What shade_triangles reads besides the eye rays, gathered lane by lane: the corners and vertex
 * normals of each lane's triangle, component by component (corner c's x, y, z at 3c, 3c + 1,
 * 3c + 2), and Embree's u, v and geometric normal. */
struct triangle_lanes {
    float p[9][AO_PACKET_SIZE], n[9][AO_PACKET_SIZE];
    float u[AO_PACKET_SIZE], v[AO_PACKET_SIZE], hit_ng[3][AO_PACKET_SIZE];
};

/* The vector of three of a lane's components, from row `first` on. */
static inline struct ao_vec3 lane_vec3(float (*rows)[AO_PACKET_SIZE], int first, int k)
{
    return ao_vec3_make(rows[first][k], rows[first + 1][k], rows[first + 2][k]);
}

/* Writes v as lane k of the rows. */
static inline void set_lane(float (*rows)[AO_PACKET_SIZE], int k, struct ao_vec3 v)
{
    rows[0][k] = v.x, rows[1][k] = v.y, rows[2][k] = v.z;
}

/* shade_triangle and face_eye for all AO_PACKET_SIZE lanes at once (lanes without a triangle hold
 * zeros and are overwritten after), as ao_surface_from_hit computes them one by one. */
AO_VECTOR_CLONES
static void shade_triangles(struct triangle_lanes *restrict t, const struct ao_packet *restrict eye, bool phong,
                            struct surfaces *restrict out)
{
    for (int k = 0; k < AO_PACKET_SIZE; k++) {
        struct ao_vec3 p[3] = {lane_vec3(t->p, 0, k), lane_vec3(t->p, 3, k), lane_vec3(t->p, 6, k)};
        struct ao_vec3 n[3] = {lane_vec3(t->n, 0, k), lane_vec3(t->n, 3, k), lane_vec3(t->n, 6, k)};
        struct ao_vec3 position, error, ng, ns, origin;
        shade_triangle(p, n, t->u[k], t->v[k], lane_vec3(t->hit_ng, 0, k), phong, &position, &error, &ng, &ns);
        face_eye(position, error, ao_vec3_make(eye->dir_x[k], eye->dir_y[k], eye->dir_z[k]), &ng, &ns, &origin);
        set_lane(out->ng, k, ng);
        set_lane(out->ns, k, ns);
        set_lane(out->origin, k, origin);
    }
}

/* The packet's hits (hit[k].t finite) shaded into *out as ao_surface_from_hit does: flat meshes'
 * triangles in one loop across the lanes, spheres and instanced meshes' triangles one by one. */
static void shade_packet(const struct ao_context *ctx, const struct ao_packet *eye, const struct ao_hit *hits,
                         struct surfaces *out)
{
    const struct ao_scene *scene = ctx->scene;
    struct triangle_lanes t;
    bool alone[AO_PACKET_SIZE];
    for (int k = 0; k < AO_PACKET_SIZE; k++) {
        const struct ao_hit *h = &hits[k];
        bool hit = k < eye->count && h->t != INFINITY;
        const struct ao_instance *in = hit && !h->sphere ? &scene->instances[h->instance] : NULL;
        alone[k] = !in || !in->flat;
        if (alone[k]) { /* zeros, so that the loop reads no garbage */
            for (int row = 0; row < 9; row++)
                t.p[row][k] = t.n[row][k] = 0.0f;
            t.u[k] = t.v[k] = t.hit_ng[0][k] = t.hit_ng[1][k] = t.hit_ng[2][k] = 0.0f;
            continue;
        }
        const struct ao_mesh *m = &scene->meshes[in->mesh];
        const uint32_t *i = &m->indices[3 * h->prim];
        for (int c = 0; c < 3; c++) {
            set_lane(t.p + 3 * c, k, m->positions[i[c]]);
            set_lane(t.n + 3 * c, k, m->normals[i[c]]);
        }
        t.u[k] = h->u, t.v[k] = h->v;
        set_lane(t.hit_ng, k, h->ng);
        set_lane(out->albedo, k, scene->albedos[in->albedo]);
    }
    shade_triangles(&t, eye, ctx->shading == AO_SHADING_PHONG, out);
    for (int k = 0; k < eye->count; k++) {
        if (!alone[k] || hits[k].t == INFINITY) /* shaded above, or a miss */
            continue;
        struct ao_surface s;
        ao_surface_from_hit(scene, ctx->shading, ctx->view.eye,
                            ao_vec3_make(eye->dir_x[k], eye->dir_y[k], eye->dir_z[k]), &hits[k], &s);
        set_lane(out->ng, k, s.ng);
        set_lane(out->ns, k, s.ns);
        set_lane(out->albedo, k, s.albedo);
        set_lane(out->origin, k, s.origin);
    }
}

/* Occlusion rays waiting for a full batch, each remembering its weight and whose sum the weight
 * joins when the ray is open. Rays from `drawn` on hold their origins only, with their streams,
 * sample numbers and normals in the pending arrays: their numbers and directions are drawn
 * AO_RNG_LANES at a time, so that the generator and the sampler run across lanes even at one
 * sample a pixel, four vectors at once whose chains of multiplies and square roots overlap. */
struct queue {
    const struct ao_context *ctx;
    struct ao_batch rays;
    int drawn;                     /* rays whose directions are drawn; fewer than AO_RNG_LANES pending */
    struct ao_rng_lanes rng;                                      /* streams, sample numbers */
    float u1[AO_RNG_LANES], u2[AO_RNG_LANES];
    float nx[AO_RNG_LANES], ny[AO_RNG_LANES], nz[AO_RNG_LANES];  /* shading normals */
    float gx[AO_RNG_LANES], gy[AO_RNG_LANES], gz[AO_RNG_LANES];  /* geometric normals */
    float weight[AO_BATCH_RAYS];
    double *sum[AO_BATCH_RAYS];
    uint64_t traced;
};

/* An empty queue for ctx's rays; only the counters are set (the arrays are large). */
static void queue_start(struct queue *q, const struct ao_context *ctx)
{
    q->ctx = ctx;
    q->rays.count = q->drawn = 0;
    q->traced = 0;
}

/* Mirrors the directions that point below the surface with geometric normal g across it, keeping
 * their weights (taken about the shading normal); branch-free so that it vectorizes. */
static void reflect_below(int n, const float *restrict gx, const float *restrict gy, const float *restrict gz,
                          float *restrict x, float *restrict y, float *restrict z)
{
    for (int k = 0; k < n; k++) {
        float d = x[k] * gx[k] + y[k] * gy[k] + z[k] * gz[k];
        float twice_below = d - fabsf(d); /* 2d below the surface, 0 above */
        x[k] -= twice_below * gx[k];
        y[k] -= twice_below * gy[k];
        z[k] -= twice_below * gz[k];
    }
}

/* Drops the rays from `first` whose weight is zero (directions that cannot contribute, such as
 * the lower half of the uniform sphere), keeping the others in order. */
static void compact(struct ao_batch *r, float *weight, double **sum, int first)
{
    int kept = first;
    for (int k = first; k < r->count; k++) {
        if (weight[k] <= 0.0f)
            continue;
        r->org_x[kept] = r->org_x[k];
        r->org_y[kept] = r->org_y[k];
        r->org_z[kept] = r->org_z[k];
        r->dir_x[kept] = r->dir_x[k];
        r->dir_y[kept] = r->dir_y[k];
        r->dir_z[kept] = r->dir_z[k];
        r->tfar[kept] = r->tfar[k];
        sum[kept] = sum[k];
        weight[kept++] = weight[k];
    }
    r->count = kept;
}

static void flush(struct queue *q);

/* Draws the directions of the pending rays; traces the batch when it is full. */
static void draw_directions(struct queue *q)
{
    struct ao_batch *r = &q->rays;
    int first = q->drawn, n = r->count - first;
    ao_rng_pairs(q->ctx->sequence, &q->rng, n, q->u1, q->u2);
    ao_sample_directions(q->ctx->sampling, n, q->nx, q->ny, q->nz, q->u1, q->u2, r->dir_x + first,
                         r->dir_y + first, r->dir_z + first, q->weight + first);
    if (q->ctx->below == AO_BELOW_REFLECT)
        reflect_below(n, q->gx, q->gy, q->gz, r->dir_x + first, r->dir_y + first, r->dir_z + first);
    if (q->ctx->sampling == AO_SAMPLING_UNIFORM)
        compact(r, q->weight, q->sum, first);
    q->drawn = r->count;
    if (r->count == AO_BATCH_RAYS)
        flush(q);
}

/* Traces the queued rays and adds the weights of the open ones to their sums. */
static void flush(struct queue *q)
{
    struct ao_batch *r = &q->rays;
    if (q->drawn < r->count)
        draw_directions(q);
    if (r->count == 0)
        return;
    ao_tracer_occluded(q->ctx->tracer, r);
    /* Blocked rays came back with tfar = -inf and count 0. */
    float *weight = q->weight;
    for (int k = 0; k < r->count; k++)
        weight[k] = r->tfar[k] >= 0.0f ? weight[k] : 0.0f;
    /* Consecutive rays mostly share a sum: add each run's weights in four independent chains,
     * store once. */
    for (int k = 0, end; k < r->count; k = end) {
        double *target = q->sum[k], chain[4] = {0.0, 0.0, 0.0, 0.0};
        for (end = k + 1; end < r->count && q->sum[end] == target;)
            end++;
        int j = k;
        for (; j + 4 <= end; j += 4)
            for (int c = 0; c < 4; c++)
                chain[c] += weight[j + c];
        for (; j < end; j++)
            chain[0] += weight[j];
        *target += (chain[0] + chain[1]) + (chain[2] + chain[3]);
    }
    q->traced += (uint64_t)r->count;
    r->count = q->drawn = 0;
}

/* Queues the `count` AO samples of the surface with these normals and origin (stream `key`, from
 * first_sample) into *sum. */
static void queue_samples(struct queue *q, struct ao_vec3 ns, struct ao_vec3 ng, struct ao_vec3 origin,
                          const struct ao_rng_stream *stream, uint64_t first_sample, int count, double *sum)
{
    enum ao_sequence sequence = q->ctx->sequence;
    struct ao_batch *r = &q->rays;
    for (int done = 0; done < count;) {
        /* As many as fit among the pending rays and in the batch. */
        int lane = r->count - q->drawn, n = count - done;
        n = n < AO_RNG_LANES - lane ? n : AO_RNG_LANES - lane;
        n = n < AO_BATCH_RAYS - r->count ? n : AO_BATCH_RAYS - r->count;
        for (int k = lane; k < lane + n; k++) {
            ao_rng_lanes_set(&q->rng, sequence, k, stream, first_sample + (uint64_t)(done + k - lane));
            q->nx[k] = ns.x, q->ny[k] = ns.y, q->nz[k] = ns.z;
            q->gx[k] = ng.x, q->gy[k] = ng.y, q->gz[k] = ng.z;
        }
        for (int k = r->count; k < r->count + n; k++) {
            r->org_x[k] = origin.x, r->org_y[k] = origin.y, r->org_z[k] = origin.z;
            r->tfar[k] = q->ctx->ao_distance;
            q->sum[k] = sum;
        }
        r->count += n;
        done += n;
        if (lane + n == AO_RNG_LANES || r->count == AO_BATCH_RAYS)
            draw_directions(q);
    }
}

struct ao_vec3 ao_estimate_surface(const struct ao_context *ctx, const struct ao_surface *s,
                                   uint64_t pixel, uint64_t first_sample, int count,
                                   uint64_t *shadow_rays)
{
    struct queue q;
    queue_start(&q, ctx);
    double sum = 0.0;
    struct ao_rng_stream stream = ao_rng_stream(ao_rng_key(ctx->seed, pixel, AO_STREAM));
    queue_samples(&q, s->ns, s->ng, s->origin, &stream, first_sample, count, &sum);
    flush(&q);
    *shadow_rays += q.traced;
    return ao_vec3_scale(s->albedo, (float)sum);
}

/* Streams of a tile's pixels, row by row, in one pass slot: the same for every round of a pass,
 * so derived once per tile and pass (structure of arrays; ao_rng_stream's fields). */
struct tile_streams {
    uint64_t key[AO_TILE_PIXELS];
    uint32_t seed_index[AO_TILE_PIXELS], seed_x[AO_TILE_PIXELS], seed_y[AO_TILE_PIXELS];
};

/* The streams of the tile's pixels in pass slot `slot`; a loop that vectorizes across a row. */
AO_VECTOR_CLONES
static void make_tile_streams(const struct ao_context *ctx, const struct ao_tile *tile, uint64_t slot,
                              struct tile_streams *restrict out)
{
    int width = tile->x1 - tile->x0;
    for (int y = tile->y0, first = 0; y < tile->y1; y++, first += width) {
        uint64_t row = (uint64_t)y * (uint64_t)ctx->view.width + (uint64_t)tile->x0;
        for (int i = 0; i < width; i++) {
            struct ao_rng_stream s = ao_rng_stream(ao_rng_key(ctx->seed, row + (uint64_t)i, slot));
            out->key[first + i] = s.key, out->seed_index[first + i] = s.seed_index;
            out->seed_x[first + i] = s.seed_x, out->seed_y[first + i] = s.seed_y;
        }
    }
}

/* Stream k of the tile's streams. */
static inline struct ao_rng_stream tile_stream(const struct tile_streams *streams, int k)
{
    struct ao_rng_stream s = {streams->key[k], streams->seed_index[k], streams->seed_x[k], streams->seed_y[k]};
    return s;
}

/* The eye rays of the tile's pixels first, first + 1, ... (at column[k], row[k]), number `ray` of
 * their eye streams, for the packet's count: through the pixel centres, or jittered inside the
 * pixel with AA; loops that vectorize. */
AO_VECTOR_CLONES
static void make_eye_rays(const struct ao_context *ctx, const struct tile_streams *streams, int first, uint64_t ray,
                          const int *column, const int *row, struct ao_packet *eye)
{
    float du[AO_PACKET_SIZE], dv[AO_PACKET_SIZE];
    if (!ctx->aa)
        for (int k = 0; k < eye->count; k++)
            du[k] = dv[k] = 0.5f;
    else if (ctx->sequence == AO_SEQUENCE_SOBOL) /* pair `ray` of each pixel's eye stream */
        for (int k = 0; k < eye->count; k++)
            ao_rng_sobol_seeded(streams->seed_index[first + k], streams->seed_x[first + k], streams->seed_y[first + k],
                                (uint32_t)ray, &du[k], &dv[k]);
    else
        for (int k = 0; k < eye->count; k++)
            ao_rng_pair(streams->key[first + k], ray, &du[k], &dv[k]);
    const struct ao_view *view = &ctx->view;
    for (int k = 0; k < eye->count; k++) {
        struct ao_vec3 d = ao_camera_ray(view, (float)column[k] + du[k], (float)row[k] + dv[k]);
        eye->org_x[k] = view->eye.x;
        eye->org_y[k] = view->eye.y;
        eye->org_z[k] = view->eye.z;
        eye->dir_x[k] = d.x;
        eye->dir_y[k] = d.y;
        eye->dir_z[k] = d.z;
        eye->tfar[k] = INFINITY;
    }
}

/* One eye ray per pixel of the tile (number `ray` of its eye stream) and `count` AO samples from
 * `first_sample` of its AO stream; adds each pixel's sum of sample values (background on a miss)
 * to sums. The normals view gives each of the `count` samples the value (n + 1) / 2 and a miss
 * black: a unit normal's colour is never black, whereas a background's value could pass for one.
 * False when ctx->cut stopped it. */
AO_VECTOR_CLONES
static bool trace_round(const struct ao_context *ctx, const struct ao_tile *tile, const struct tile_streams *eye_streams,
                        const struct tile_streams *ao_streams, uint64_t ray, uint64_t first_sample, int count,
                        struct ao_vec3 *sums, uint64_t *eye_rays, uint64_t *shadow_rays)
{
    int width = tile->x1 - tile->x0, pixels = width * (tile->y1 - tile->y0);
    struct queue q;
    queue_start(&q, ctx);
    double sum[AO_TILE_PIXELS] = {0};
    struct ao_vec3 albedo[AO_TILE_PIXELS];
    bool miss[AO_TILE_PIXELS];
    int x = tile->x0, y = tile->y0; /* the next pixel's column and row */
    for (int first = 0; first < pixels; first += AO_PACKET_SIZE) {
        if (ctx->cut && ctx->cut(ctx->cut_user))
            return false;
        struct ao_packet eye = {.count = pixels - first < AO_PACKET_SIZE ? pixels - first : AO_PACKET_SIZE};
        struct ao_hit hits[AO_PACKET_SIZE];
        int column[AO_PACKET_SIZE], row[AO_PACKET_SIZE];
        for (int k = 0; k < eye.count; k++) {
            column[k] = x, row[k] = y;
            if (++x == tile->x1) /* row by row, without a division per pixel */
                x = tile->x0, y++;
        }
        make_eye_rays(ctx, eye_streams, first, ray, column, row, &eye);
        ao_tracer_intersect(ctx->tracer, &eye, hits);
        *eye_rays += (uint64_t)eye.count;
        struct surfaces s;
        shade_packet(ctx, &eye, hits, &s);
        /* Their AO samples, queued across the tile so that batches fill at one sample per pass. */
        for (int k = 0; k < eye.count; k++) {
            miss[first + k] = hits[k].t == INFINITY;
            if (miss[first + k])
                continue;
            struct ao_vec3 ns = lane_vec3(s.ns, 0, k);
            if (ctx->output == AO_OUTPUT_NORMALS) {
                albedo[first + k] = ao_vec3_scale(ao_vec3_add(ns, ao_vec3_make(1.0f, 1.0f, 1.0f)), 0.5f);
                sum[first + k] = (double)count;
                continue;
            }
            albedo[first + k] = lane_vec3(s.albedo, 0, k);
            struct ao_rng_stream stream = tile_stream(ao_streams, first + k);
            queue_samples(&q, ns, lane_vec3(s.ng, 0, k), lane_vec3(s.origin, 0, k), &stream, first_sample, count,
                          &sum[first + k]);
        }
    }
    flush(&q);
    for (int k = 0; k < pixels; k++)
        sums[k] = ao_vec3_add(sums[k], !miss[k] ? ao_vec3_scale(albedo[k], (float)sum[k])
                                       : ctx->output == AO_OUTPUT_NORMALS ? ao_vec3_make(0.0f, 0.0f, 0.0f)
                                       : ao_vec3_scale(ctx->scene->background, (float)count));
    *shadow_rays += q.traced;
    return true;
}

bool ao_estimate_tile(const struct ao_context *ctx, const struct ao_tile *tile, const struct ao_tile_work *work,
                      struct ao_vec3 *sums, uint64_t *eye_rays, uint64_t *shadow_rays)
{
    int pixels = (tile->x1 - tile->x0) * (tile->y1 - tile->y0);
    for (int k = 0; k < pixels; k++)
        sums[k] = ao_vec3_make(0.0f, 0.0f, 0.0f);
    struct tile_streams eye, ao;
    if (ctx->aa)
        make_tile_streams(ctx, tile, stream_for_half(ctx, EYE_STREAM, work->half), &eye);
    if (ctx->output != AO_OUTPUT_NORMALS)
        make_tile_streams(ctx, tile, stream_for_half(ctx, AO_STREAM, work->half), &ao);
    for (int r = 0; r < work->rounds; r++)
        if (!trace_round(ctx, tile, &eye, &ao, work->first_ray + (uint64_t)r,
                         work->first_sample + (uint64_t)r * (uint64_t)work->count, work->count, sums, eye_rays,
                         shadow_rays))
            return false;
    return true;
}
