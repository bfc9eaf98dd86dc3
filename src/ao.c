/* The AO estimator; see ao.h.
 *
 * Derivation. Ambient occlusion with albedo rho is L = rho/pi * Int_H V(x,w) max(0, n.w) dw: a fully
 * open point gives rho/pi * pi = rho. Drawing N directions w_j from a density p gives the unbiased
 * estimator L ~ rho/(pi N) Sum_j V(x,w_j) max(0, n.w_j) / p(w_j). Per sampler the weight
 * max(0, n.w)/(pi p(w)) is 4 max(0, n.w) for the uniform sphere (p = 1/4pi), 2 n.w for the uniform
 * hemisphere (p = 1/2pi), and exactly 1 for cosine sampling (p = n.w/pi), where the estimator
 * reduces to rho times the fraction of open directions. Directions of weight 0 (below the
 * shading hemisphere) add nothing and are not traced. */
#include "ao.h"

#include <float.h>

#include "rng.h"

/* Directions traced per batch, a multiple of the tracer's 16-ray packets. */
enum { BATCH = 64 };

/* Key of the eye-ray stream in the sample slot and of the AO streams in the pass slot, so that the
 * two never share a stream: real pass and sample numbers stay far below it. */
static const uint64_t STREAM_TAG = UINT64_MAX;

float ao_surface_offset(struct ao_vec3 origin, float t, struct ao_vec3 position)
{
    /* org + t dir carries a rounding error of a few ulps of max(|org|, t, |p|) per component, and
     * Embree's t adds a few more; 2^-18 of their sum is 32 ulps of the largest, scale-free. */
    float scale = ao_vec3_max_abs(origin) + t + ao_vec3_max_abs(position);
    return fmaxf(scale * 0x1.0p-18f, FLT_MIN);
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

struct ao_vec3 ao_estimate_surface(const struct ao_context *ctx, const struct ao_surface *s,
                                   uint64_t pixel, uint64_t first_sample, int count,
                                   uint64_t *shadow_rays)
{
    struct ao_basis basis = ao_basis_from_normal(s->ns);
    struct ao_vec3 origin = ao_vec3_add(s->position, ao_vec3_scale(s->ng, s->offset));
    double sum = 0.0;
    for (int first = 0; first < count; first += BATCH) {
        struct ao_vec3 dirs[BATCH];
        float weights[BATCH];
        uint8_t open[BATCH];
        int traced = 0;
        /* Draw the batch, keeping only directions that can contribute. */
        for (int k = first; k < count && k < first + BATCH; k++) {
            struct ao_rng rng = ao_rng_make(ctx->seed, pixel, STREAM_TAG, first_sample + (uint64_t)k);
            float u1 = ao_rng_float(&rng), u2 = ao_rng_float(&rng);
            float w = ao_sample_direction(ctx->sampling, &basis, u1, u2, &dirs[traced]);
            if (w > 0.0f)
                weights[traced++] = w;
        }
        /* Trace them and add the open ones' weights. */
        if (traced)
            ao_tracer_occluded(ctx->tracer, origin, dirs, traced, ctx->ao_distance, open);
        *shadow_rays += (uint64_t)traced;
        for (int k = 0; k < traced; k++)
            sum += open[k] ? weights[k] : 0.0f;
    }
    return ao_vec3_scale(s->albedo, (float)sum);
}

struct ao_vec3 ao_estimate_pixel(const struct ao_context *ctx, int i, int j, uint64_t pass,
                                 uint64_t first_sample, int count, uint64_t *eye_rays,
                                 uint64_t *shadow_rays)
{
    uint64_t pixel = (uint64_t)j * (uint64_t)ctx->view.width + (uint64_t)i;
    float du = 0.5f, dv = 0.5f;
    if (ctx->aa) {
        struct ao_rng rng = ao_rng_make(ctx->seed, pixel, pass, STREAM_TAG);
        du = ao_rng_float(&rng);
        dv = ao_rng_float(&rng);
    }
    struct ao_vec3 dir = ao_camera_ray(&ctx->view, (float)i + du, (float)j + dv);
    struct ao_hit hit;
    *eye_rays += 1;
    if (!ao_tracer_intersect(ctx->tracer, ctx->view.eye, dir, &hit))
        return ao_vec3_scale(ctx->scene->background, (float)count);
    struct ao_surface s;
    ao_surface_from_hit(ctx->scene, ctx->view.eye, dir, &hit, &s);
    return ao_estimate_surface(ctx, &s, pixel, first_sample, count, shadow_rays);
}
