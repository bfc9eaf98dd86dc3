/* The ambient-occlusion estimator: eye ray, hit, shading normal, occlusion rays, one value. */
#ifndef AO_AO_H
#define AO_AO_H

#include <stdbool.h>
#include <stdint.h>

#include "camera.h"
#include "rng.h"
#include "sampling.h"
#include "scene.h"
#include "tracer.h"
#include "vec3.h"

/* What happens to sampled directions that point below the geometric surface (possible where the
 * interpolated shading normal differs from it). */
enum ao_below {
    AO_BELOW_REFLECT,        /* mirrored across the geometric surface, then traced */
    AO_BELOW_TRACE,          /* traced as they are: they hit the surface itself and count occluded */
};

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
};

/* A shading point: unit normals turned to face the eye ray, and where its occlusion rays start. */
struct ao_surface {
    struct ao_vec3 position, ng, ns, albedo;
    struct ao_vec3 origin;   /* position lifted along ng past its rounding error (ao_surface_lift) */
};

/* The point p[0] + u (p[1] - p[0]) + v (p[2] - p[0]) of a triangle (u, v: Embree's barycentrics)
 * and in *error a bound per axis on its rounding error plus the tracer's when it tests this
 * triangle against rays leaving from near the point. Any thread. */
struct ao_vec3 ao_triangle_point(const struct ao_vec3 p[3], float u, float v, struct ao_vec3 *error);

/* q projected onto the sphere (center, radius), its unit outward normal in *n, and an error bound
 * as ao_triangle_point's in *error. Any thread. */
struct ao_vec3 ao_sphere_point(struct ao_vec3 center, float radius, struct ao_vec3 q, struct ao_vec3 *n,
                               struct ao_vec3 *error);

/* Where occlusion rays leave a surface point `position` that is off by at most error.x, .y, .z
 * per axis: moved along the unit normal ng (facing where the rays go) just past that box and the
 * rounding of the move itself. Scale-free: the lift follows the point's own precision, not the
 * distance from the eye. Any thread. */
struct ao_vec3 ao_surface_lift(struct ao_vec3 position, struct ao_vec3 ng, struct ao_vec3 error);

/* Shades the eye ray org + t dir's hit into *s: the point recomputed from the primitive and lifted
 * past its error bound, exact sphere normal, Phong-interpolated mesh normal (the geometric one
 * where the vertex normals cancel), both turned to the eye's side. */
void ao_surface_from_hit(const struct ao_scene *scene, struct ao_vec3 org, struct ao_vec3 dir,
                         const struct ao_hit *hit, struct ao_surface *s);

/* Sum over `count` AO samples (numbered first_sample, ...) at s of albedo * V * weight, whose
 * mean estimates AO; `pixel` keys the random streams; adds the rays traced to *shadow_rays. */
struct ao_vec3 ao_estimate_surface(const struct ao_context *ctx, const struct ao_surface *s,
                                   uint64_t pixel, uint64_t first_sample, int count,
                                   uint64_t *shadow_rays);

/* A rectangle of pixels [x0, x1) x [y0, y1) holding at most AO_TILE_PIXELS. */
enum { AO_TILE_PIXELS = 256 };
struct ao_tile {
    int x0, y0, x1, y1;
};

/* One pass over a tile: per pixel one eye ray (jittered with AA) and `count` AO samples; writes
 * each pixel's sum of sample values (background on a miss) to sums, row by row, and adds the rays
 * traced to *eye_rays / *shadow_rays. Eye rays go to the tracer in packets of 16, AO rays in
 * batches of up to AO_BATCH_RAYS gathered across the tile. Any thread. */
void ao_estimate_tile(const struct ao_context *ctx, const struct ao_tile *tile, uint64_t pass,
                      uint64_t first_sample, int count, struct ao_vec3 *sums, uint64_t *eye_rays,
                      uint64_t *shadow_rays);

#endif
