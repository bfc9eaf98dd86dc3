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

/* A shading point: unit normals turned to face the eye ray, and the ray-origin offset. */
struct ao_surface {
    struct ao_vec3 position, ng, ns, albedo;
    float offset;            /* distance along ng that clears the position's rounding error */
};

/* The offset that lifts occlusion rays off a surface at `position` reached by a ray of length t
 * from `origin`: a few ulps of the largest magnitude involved, so it holds at any scene scale. */
float ao_surface_offset(struct ao_vec3 origin, float t, struct ao_vec3 position);

/* Shades the eye ray org + t dir's hit into *s: exact sphere normal, Phong-interpolated mesh
 * normal (the geometric one where the vertex normals cancel), both turned to the eye's side. */
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

/* Which part of its pixels' random streams a tile traces in one pass: `rounds` eye rays per pixel
 * (numbered from first_ray), each with `count` AO samples (numbered on from first_sample). `half`
 * is the pass's half of the accumulation (0 even, 1 odd); with Sobol numbers each half has streams
 * of its own, numbered within the half, so that the halves are independent estimates. */
struct ao_tile_work {
    uint64_t first_ray, first_sample;
    int rounds, count, half;
};

/* One pass over a tile: per pixel `rounds` eye rays (jittered with AA), each with `count` AO
 * samples; writes each pixel's sum of sample values (background on a miss) to sums, row by row,
 * and adds the rays traced to *eye_rays / *shadow_rays. Eye rays go to the tracer in packets of
 * 16, AO rays in batches of up to AO_BATCH_RAYS gathered across the tile. Any thread. */
void ao_estimate_tile(const struct ao_context *ctx, const struct ao_tile *tile, const struct ao_tile_work *work,
                      struct ao_vec3 *sums, uint64_t *eye_rays, uint64_t *shadow_rays);

#endif
