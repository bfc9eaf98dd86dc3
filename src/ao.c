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

#include "simd.h"

/* Keys of a pixel's eye-ray stream (indexed by pass) and AO stream (indexed by sample), in the
 * pass slot of the key, where no real pass number reaches. */
static const uint64_t EYE_STREAM = UINT64_MAX - 1, AO_STREAM = UINT64_MAX;

/* Pairs first .. first + n - 1 of the random stream `key` into u1/u2; one loop that vectorizes. */
AO_VECTOR_CLONES
static void random_pairs(uint64_t key, uint64_t first, int n, float *restrict u1, float *restrict u2)
{
    for (int k = 0; k < n; k++)
        ao_rng_pair(key, first + (uint64_t)k, &u1[k], &u2[k]);
}

/* The index-th pair of uniform numbers of the stream `key`, from the context's sequence. */
static inline void draw_pair(const struct ao_context *ctx, uint64_t key, uint64_t index, float *u1, float *u2)
{
    if (ctx->sequence == AO_SEQUENCE_SOBOL)
        ao_rng_sobol_pair(key, index, u1, u2);
    else
        ao_rng_pair(key, index, u1, u2);
}

/* Pairs first .. first + n - 1 of the stream `key` into u1/u2, from the context's sequence: the
 * random sequence's in one vectorized loop, others one by one. */
static void draw_pairs(const struct ao_context *ctx, uint64_t key, uint64_t first, int n, float *u1, float *u2)
{
    if (ctx->sequence == AO_SEQUENCE_RANDOM)
        random_pairs(key, first, n, u1, u2);
    else
        for (int k = 0; k < n; k++)
            draw_pair(ctx, key, first + (uint64_t)k, &u1[k], &u2[k]);
}

float ao_surface_offset(struct ao_vec3 origin, float t, struct ao_vec3 position)
{
    /* org + t dir carries a rounding error of a few ulps of max(|org|, t, |p|) per component, and
     * Embree's t adds a few more; 2^-18 of their sum is 32 ulps of the largest, scale-free. */
    float scale = ao_vec3_max_abs(origin) + t + ao_vec3_max_abs(position);
    float offset = scale * 0x1.0p-18f;
    return offset > FLT_MIN ? offset : FLT_MIN; /* FLT_MIN for NaN too, as fmaxf would give */
}

void ao_surface_from_hit(const struct ao_scene *scene, struct ao_vec3 org, struct ao_vec3 dir,
                         const struct ao_hit *hit, struct ao_surface *s)
{
    s->position = ao_vec3_add(org, ao_vec3_scale(dir, hit->t));
    if (hit->sphere) {
        const struct ao_sphere *sp = &scene->spheres[hit->prim];
        s->ng = ao_vec3_normalize(ao_vec3_sub(s->position, sp->center));
        s->ns = s->ng;
        s->albedo = sp->albedo;
    } else {
        const uint32_t *i = &scene->indices[3 * hit->prim];
        struct ao_vec3 p0 = scene->positions[i[0]];
        s->ng = ao_vec3_normalize(ao_vec3_cross(ao_vec3_sub(scene->positions[i[1]], p0),
                                                ao_vec3_sub(scene->positions[i[2]], p0)));
        float w0 = 1.0f - hit->u - hit->v;
        struct ao_vec3 n = ao_vec3_scale(scene->normals[i[0]], w0);
        n = ao_vec3_add(n, ao_vec3_scale(scene->normals[i[1]], hit->u));
        n = ao_vec3_add(n, ao_vec3_scale(scene->normals[i[2]], hit->v));
        float len = ao_vec3_length(n);
        s->ns = len > 1e-6f && isfinite(len) ? ao_vec3_scale(n, 1.0f / len) : s->ng;
        s->albedo = scene->albedos[scene->triangle_albedo[hit->prim]];
    }
    if (!(ao_vec3_length(s->ng) > 0.5f))
        s->ng = s->ns = ao_vec3_scale(dir, -1.0f);
    /* Turn the surface to the side the eye ray came from. */
    if (ao_vec3_dot(s->ng, dir) > 0.0f) {
        s->ng = ao_vec3_scale(s->ng, -1.0f);
        s->ns = ao_vec3_scale(s->ns, -1.0f);
    }
    s->offset = ao_surface_offset(org, hit->t, s->position);
}

/* Occlusion rays waiting for a full batch, in packets filled in order, each ray remembering its
 * weight and whose sum the weight joins when the ray is open. The lanes of the packet being
 * filled from `drawn` on hold their numbers and normals only: their directions are drawn together
 * when the packet is full, so that the sampler runs across lanes even at one sample a pixel. */
enum { QUEUE_RAYS = AO_BATCH_PACKETS * AO_PACKET_SIZE };
struct queue {
    const struct ao_context *ctx;
    struct ao_packet packets[AO_BATCH_PACKETS];
    int full;                      /* packets filled; packets[full] takes the next rays */
    int drawn;                     /* lanes of packets[full] whose directions are drawn */
    float u1[AO_PACKET_SIZE], u2[AO_PACKET_SIZE];
    float nx[AO_PACKET_SIZE], ny[AO_PACKET_SIZE], nz[AO_PACKET_SIZE];  /* shading normals */
    float gx[AO_PACKET_SIZE], gy[AO_PACKET_SIZE], gz[AO_PACKET_SIZE];  /* geometric normals */
    float weight[QUEUE_RAYS];
    double *sum[QUEUE_RAYS];
    uint64_t traced;
};

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

/* Drops the lanes from `first` of packet r whose weight is zero (directions that cannot
 * contribute, such as the lower half of the uniform sphere), keeping the others in order. */
static void compact(struct ao_packet *r, float *weight, double **sum, int first)
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

/* Draws the directions of the packet being filled, lanes `drawn` on; moves to the next packet
 * when it is full, and traces the batch when that was the last. */
static void draw_directions(struct queue *q)
{
    struct ao_packet *r = &q->packets[q->full];
    float *weight = q->weight + q->full * AO_PACKET_SIZE;
    int lane = q->drawn, n = r->count - lane;
    ao_sample_directions(q->ctx->sampling, n, q->nx + lane, q->ny + lane, q->nz + lane, q->u1 + lane,
                         q->u2 + lane, r->dir_x + lane, r->dir_y + lane, r->dir_z + lane, weight + lane);
    if (q->ctx->below == AO_BELOW_REFLECT)
        reflect_below(n, q->gx + lane, q->gy + lane, q->gz + lane, r->dir_x + lane, r->dir_y + lane,
                      r->dir_z + lane);
    if (q->ctx->sampling == AO_SAMPLING_UNIFORM)
        compact(r, weight, q->sum + q->full * AO_PACKET_SIZE, lane);
    q->drawn = r->count;
    if (r->count == AO_PACKET_SIZE) {
        q->drawn = 0;
        if (++q->full == AO_BATCH_PACKETS)
            flush(q);
    }
}

/* Traces the queued rays and adds the weights of the open ones to their sums. */
static void flush(struct queue *q)
{
    uint8_t open[QUEUE_RAYS];
    if (q->full < AO_BATCH_PACKETS && q->drawn < q->packets[q->full].count)
        draw_directions(q);
    int count = q->full + (q->full < AO_BATCH_PACKETS && q->packets[q->full].count > 0);
    if (count == 0)
        return;
    ao_tracer_occluded(q->ctx->tracer, q->packets, count, open);
    /* Consecutive rays mostly share a sum: add their weights in a register, store once. */
    double *target = q->sum[0], open_weight = 0.0;
    for (int p = 0; p < count; p++) {
        for (int k = 0; k < q->packets[p].count; k++) {
            int ray = p * AO_PACKET_SIZE + k;
            if (q->sum[ray] != target) {
                *target += open_weight;
                target = q->sum[ray];
                open_weight = 0.0;
            }
            open_weight += open[ray] ? q->weight[ray] : 0.0f;
        }
        q->traced += (uint64_t)q->packets[p].count;
        q->packets[p].count = 0;
    }
    *target += open_weight;
    q->full = q->drawn = 0;
}

/* Queues the `count` AO samples of surface s (stream `key`, from first_sample) into *sum. */
static void queue_samples(struct queue *q, const struct ao_surface *s, uint64_t key, uint64_t first_sample,
                          int count, double *sum)
{
    struct ao_vec3 origin = ao_vec3_add(s->position, ao_vec3_scale(s->ng, s->offset));
    for (int done = 0; done < count;) {
        struct ao_packet *r = &q->packets[q->full];
        double **sums = q->sum + q->full * AO_PACKET_SIZE;
        int lane = r->count, n = count - done < AO_PACKET_SIZE - lane ? count - done : AO_PACKET_SIZE - lane;
        draw_pairs(q->ctx, key, first_sample + (uint64_t)done, n, q->u1 + lane, q->u2 + lane);
        for (int k = lane; k < lane + n; k++) {
            q->nx[k] = s->ns.x, q->ny[k] = s->ns.y, q->nz[k] = s->ns.z;
            q->gx[k] = s->ng.x, q->gy[k] = s->ng.y, q->gz[k] = s->ng.z;
            r->org_x[k] = origin.x, r->org_y[k] = origin.y, r->org_z[k] = origin.z;
            r->tfar[k] = q->ctx->ao_distance;
            sums[k] = sum;
        }
        r->count += n;
        done += n;
        if (r->count == AO_PACKET_SIZE)
            draw_directions(q);
    }
}

struct ao_vec3 ao_estimate_surface(const struct ao_context *ctx, const struct ao_surface *s,
                                   uint64_t pixel, uint64_t first_sample, int count,
                                   uint64_t *shadow_rays)
{
    struct queue q = {.ctx = ctx};
    double sum = 0.0;
    queue_samples(&q, s, ao_rng_key(ctx->seed, pixel, AO_STREAM), first_sample, count, &sum);
    flush(&q);
    *shadow_rays += q.traced;
    return ao_vec3_scale(s->albedo, (float)sum);
}

void ao_estimate_tile(const struct ao_context *ctx, const struct ao_tile *tile, uint64_t pass,
                      uint64_t first_sample, int count, struct ao_vec3 *sums, uint64_t *eye_rays,
                      uint64_t *shadow_rays)
{
    int width = tile->x1 - tile->x0, pixels = width * (tile->y1 - tile->y0);
    struct queue q = {.ctx = ctx};
    double sum[AO_TILE_PIXELS] = {0};
    struct ao_vec3 albedo[AO_TILE_PIXELS];
    bool miss[AO_TILE_PIXELS];
    for (int first = 0; first < pixels; first += AO_PACKET_SIZE) {
        struct ao_packet eye = {.count = pixels - first < AO_PACKET_SIZE ? pixels - first : AO_PACKET_SIZE};
        struct ao_hit hits[AO_PACKET_SIZE];
        uint64_t index[AO_PACKET_SIZE];
        /* Eye rays of up to 16 pixels, jittered inside the pixel with AA. */
        for (int k = 0; k < eye.count; k++) {
            int i = tile->x0 + (first + k) % width, j = tile->y0 + (first + k) / width;
            float du = 0.5f, dv = 0.5f;
            index[k] = (uint64_t)j * (uint64_t)ctx->view.width + (uint64_t)i;
            if (ctx->aa)
                draw_pair(ctx, ao_rng_key(ctx->seed, index[k], EYE_STREAM), pass, &du, &dv);
            struct ao_vec3 d = ao_camera_ray(&ctx->view, (float)i + du, (float)j + dv);
            eye.org_x[k] = ctx->view.eye.x;
            eye.org_y[k] = ctx->view.eye.y;
            eye.org_z[k] = ctx->view.eye.z;
            eye.dir_x[k] = d.x;
            eye.dir_y[k] = d.y;
            eye.dir_z[k] = d.z;
            eye.tfar[k] = INFINITY;
        }
        ao_tracer_intersect(ctx->tracer, &eye, hits);
        *eye_rays += (uint64_t)eye.count;
        /* Their AO samples, queued across the tile so that batches fill at one sample per pass. */
        for (int k = 0; k < eye.count; k++) {
            miss[first + k] = hits[k].t == INFINITY;
            if (miss[first + k])
                continue;
            struct ao_surface s;
            struct ao_vec3 d = ao_vec3_make(eye.dir_x[k], eye.dir_y[k], eye.dir_z[k]);
            ao_surface_from_hit(ctx->scene, ctx->view.eye, d, &hits[k], &s);
            albedo[first + k] = s.albedo;
            queue_samples(&q, &s, ao_rng_key(ctx->seed, index[k], AO_STREAM), first_sample, count, &sum[first + k]);
        }
    }
    flush(&q);
    for (int k = 0; k < pixels; k++)
        sums[k] = miss[k] ? ao_vec3_scale(ctx->scene->background, (float)count) : ao_vec3_scale(albedo[k], (float)sum[k]);
    *shadow_rays += q.traced;
}
