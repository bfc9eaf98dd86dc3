/* The ambient-occlusion estimator: eye ray, hit, shading normal, occlusion rays, one value. */
#ifndef AO_AO_H
#define AO_AO_H

#include <stdbool.h>
#include <stdint.h>

#include "camera.h"
#include "modes.h"
#include "ray.h"
#include "scene.h"
#include "tile.h"
#include "vec3.h"

/* The tracer (tracer.h) a pass's rays go to; the estimator holds a pointer. */
struct ao_tracer;

/* Everything one pass's pixel samples share; read-only while a pass runs. */
struct ao_context {
    const struct ao_scene *scene;
    const struct ao_tracer *tracer;
    struct ao_view view;
    enum ao_sampling sampling;
    bool aa;                 /* jitter eye rays inside the pixel */
    float ao_distance;       /* occlusion rays longer than this do not occlude */
    uint64_t seed;
    enum ao_sequence sequence;
    enum ao_below below;
    enum ao_output output;
    enum ao_shading shading;
    bool (*cut)(const void *user);   /* unless NULL: true once the tile being traced is wanted no
                                        more (its pass aborted), asked between eye-ray packets */
    const void *cut_user;
};

/* A shading point: unit normals turned to face the eye ray, and where its occlusion rays start. */
struct ao_surface {
    struct ao_vec3 position, ng, ns, albedo;
    struct ao_vec3 origin;   /* position lifted along ng past its rounding error (ao_surface_lift) */
};

/* gamma(n) of the standard model of rounding: n successive roundings, each off by a relative 2^-24
 * at most, are off by at most n 2^-24 / (1 - n 2^-24) together (Higham; pbrt-v4's gamma). The
 * error bounds below are inline: they run once per eye hit, next to its memory loads. */
static inline float ao_gamma(int n)
{
    return (float)n * 0x1p-24f / (1.0f - (float)n * 0x1p-24f);
}

/* The point p0 + u (p1 - p0) + v (p2 - p0) of a triangle (u, v: Embree's barycentrics)
 * and in *error a bound per axis on its rounding error plus the tracer's when it tests this
 * triangle against rays leaving from near the point. Any thread. */
static inline struct ao_vec3 ao_triangle_point(struct ao_vec3 p0, struct ao_vec3 p1, struct ao_vec3 p2, float u,
                                               float v, struct ao_vec3 *error)
{
    /* p0 + (u e1 + v e2), with e1 = p1 - p0 and e2 = p2 - p0 rounded once each: the products and
     * their sum add two more roundings, so the sum is off by at most gamma3 (|u e1| + |v e2|)
     * <= gamma3 (|e1| + |e2|) (u, v in [0, 1]), and the final addition by gamma1 |p| more. Written
     * so, the point needs no barycentric weights that sum to 1, and a coordinate in which the
     * three vertices agree (an axis-aligned plane) comes out exact. The tracer, testing this
     * triangle against a ray that leaves from near the point, translates the vertices to the ray's
     * origin, rounding each coordinate by up to 2^-24 |v_i - o| <= 2^-24 (|e1| + |e2|), and its
     * cross and dot products add a few such terms: gamma5 (|e1| + |e2|) more. */
    struct ao_vec3 e1 = ao_vec3_sub(p1, p0), e2 = ao_vec3_sub(p2, p0);
    struct ao_vec3 point = ao_vec3_add(p0, ao_vec3_add(ao_vec3_scale(e1, u), ao_vec3_scale(e2, v)));
    *error = ao_vec3_add(ao_vec3_scale(ao_vec3_abs(point), ao_gamma(2)),
                         ao_vec3_scale(ao_vec3_add(ao_vec3_abs(e1), ao_vec3_abs(e2)), ao_gamma(8)));
    return point;
}

/* q projected onto the sphere (center, radius), its unit outward normal in *n, and an error bound
 * as ao_triangle_point's in *error. Any thread. */
static inline struct ao_vec3 ao_sphere_point(struct ao_vec3 center, float radius, struct ao_vec3 q,
                                             struct ao_vec3 *n, struct ao_vec3 *error)
{
    /* c + r n with n = normalize(q - c): n's components are off by gamma4 of themselves (a dot
     * product, a square root, a division, a product), r n by gamma5, and the addition by gamma1 |p|.
     * The tracer's test from a nearby origin o rounds o - c (2^-24 r |n| per axis) and compares
     * |o - c|^2 with r^2 (gamma3 r^2, r gamma2 radially): gamma5 r |n| more. */
    *n = ao_vec3_normalize(ao_vec3_sub(q, center));
    struct ao_vec3 point = ao_vec3_add(center, ao_vec3_scale(*n, radius));
    *error = ao_vec3_add(ao_vec3_scale(ao_vec3_abs(point), ao_gamma(2)), ao_vec3_scale(ao_vec3_abs(*n), radius * ao_gamma(10)));
    return point;
}

/* Where occlusion rays leave a surface point `position` that is off by at most error.x, .y, .z
 * per axis: moved along the unit normal ng (facing where the rays go) just past that box and the
 * rounding of the move itself. Scale-free: the lift follows the point's own precision, not the
 * distance from the eye. Any thread. */
static inline struct ao_vec3 ao_surface_lift(struct ao_vec3 position, struct ao_vec3 ng, struct ao_vec3 error)
{
    /* The distance along ng that clears the box of half-sizes `error` about the position (pbrt-v4's
     * OffsetRayOrigin; Wächter and Binder, Ray Tracing Gems ch. 6), enlarged so that the lift
     * survives its own rounding instead of stepping each coordinate one ulp further, as pbrt
     * does: adding d ng to the position rounds each coordinate by up to 2^-24 of it (gamma1 |p|
     * more, projected on ng); |ng| is 1 within gamma3; the lift's products by gamma2 of
     * themselves, and this sum by gamma5: a factor 1 + gamma12 covers them. Its floor, where every
     * error is 0 (a plane through 0 in an axis-aligned normal's coordinate), keeps the lifted
     * coordinate a normal number, which flush-to-zero would otherwise put back on the plane. */
    struct ao_vec3 a = ao_vec3_abs(ng), p = ao_vec3_abs(position);
    float d = a.x * (error.x + ao_gamma(1) * p.x) + a.y * (error.y + ao_gamma(1) * p.y) +
              a.z * (error.z + ao_gamma(1) * p.z);
    d *= 1.0f + ao_gamma(12);
    d = d > 0x1p-100f ? d : 0x1p-100f; /* the floor for NaN too */
    return ao_vec3_add(position, ao_vec3_scale(ng, d));
}

/* Shades the eye ray org + t dir's hit into *s: the point recomputed from the primitive and lifted
 * past its error bound, exact sphere normal, mesh normal per `shading` (Phong: the geometric one
 * where the vertex normals cancel), both turned to the eye's side. Any thread. */
void ao_surface_from_hit(const struct ao_scene *scene, enum ao_shading shading, struct ao_vec3 org,
                         struct ao_vec3 dir, const struct ao_hit *hit, struct ao_surface *s);

/* Sum over `count` AO samples (numbered first_sample, ...) at s of albedo * V * weight, whose
 * mean estimates AO; `pixel` keys the random streams; adds the rays traced to *shadow_rays. */
struct ao_vec3 ao_estimate_surface(const struct ao_context *ctx, const struct ao_surface *s,
                                   uint64_t pixel, uint64_t first_sample, int count,
                                   uint64_t *shadow_rays);

/* One pass over a tile: per pixel `rounds` eye rays (jittered with AA), each with `count` AO
 * samples (with AO_OUTPUT_NORMALS, `count` samples of the normal's colour and no AO rays); writes
 * each pixel's sum of sample values (background on a miss, black for normals) to sums, row by row,
 * and adds the rays traced to *eye_rays / *shadow_rays. Eye rays go to the tracer in packets of
 * 16, AO rays in batches of up to AO_BATCH_RAYS gathered across the tile. False when ctx->cut
 * stopped it, its sums unfinished (a large --spppp makes a tile a tenth of a second and more, which
 * a key or a stop need not wait for). Any thread. */
bool ao_estimate_tile(const struct ao_context *ctx, const struct ao_tile *tile, const struct ao_tile_work *work,
                      struct ao_vec3 *sums, uint64_t *eye_rays, uint64_t *shadow_rays);

#endif
