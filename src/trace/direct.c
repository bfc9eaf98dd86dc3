/* The direct back end; see direct.h. The packet is the structure of arrays: each primitive's data is
 * broadcast while the 16 rays of a packet run through one branch-free loop that the compiler turns
 * into SIMD code, so a scene of a few primitives costs a few vector operations per ray and no
 * traversal at all. */
#include "direct.h"

#include <math.h>
#include <stdlib.h>

#include "simd.h"
#include "text.h"

/* The rule of ao_direct_suits, measured on 25 scenes (the shipped ones and random spheres and quads,
 * one core, SSE2 code): the loops cost about 2.5 ns per primitive per occlusion ray, whatever
 * the ray does; Embree costs 45-75 ns per ray once the scene has a sphere (traversed as a curve)
 * but only 10-40 ns on a few triangles. So the loops win up to 16 primitives with a sphere (1.3x
 * there, break-even near 24) and up to 4 triangles without one. Their AVX clones (simd.h) have
 * since made the loops up to 1.8x faster, so the rule now errs towards Embree. */
enum { DIRECT_MAX_WITH_SPHERES = 16, DIRECT_MAX_TRIANGLES_ONLY = 4 };

/* A sphere: centre and squared radius. */
struct sphere {
    float cx, cy, cz, r2;
};

/* A triangle: vertex 0, a = p0 - p1, b = p2 - p0 and n = a x b (unnormalized), see triangle_hit. */
struct triangle {
    float px, py, pz, ax, ay, az, bx, by, bz, nx, ny, nz;
};

/* Which triangle of the scene a stored one is: its instance and its index in the instance's mesh. */
struct source {
    uint32_t instance, prim;
};

struct ao_direct {
    size_t sphere_count, triangle_count;
    struct sphere *spheres;
    struct triangle *triangles;
    struct source *sources;      /* parallel to triangles */
};

bool ao_direct_suits(const struct ao_scene *scene)
{
    size_t limit = scene->sphere_count > 0 ? DIRECT_MAX_WITH_SPHERES : DIRECT_MAX_TRIANGLES_ONLY;
    for (size_t i = 0; i < scene->instance_count; i++)
        if (!scene->instances[i].flat)   /* instanced meshes are large by AUTO's rule (scene.h) */
            return false;
    return scene->sphere_count + scene->triangle_count <= limit;
}

struct ao_direct *ao_direct_create(const struct ao_scene *scene)
{
    size_t ns = scene->sphere_count, nt = scene->triangle_count;
    /* One block: the header, then the spheres, then the triangles (all float-aligned), then their
     * sources. */
    struct ao_direct *d = calloc(1, sizeof *d + ns * sizeof(struct sphere) + nt * sizeof(struct triangle) +
                                        nt * sizeof(struct source));
    if (!d) {
        ao_text_report("aoview: out of memory creating the direct tracer");
        return NULL;
    }
    d->sphere_count = ns;
    d->triangle_count = nt;
    d->spheres = (struct sphere *)(d + 1);
    d->triangles = (struct triangle *)(d->spheres + ns);
    d->sources = (struct source *)(d->triangles + nt);
    for (size_t i = 0; i < ns; i++) {
        const struct ao_sphere *s = &scene->spheres[i];
        d->spheres[i] = (struct sphere){s->center.x, s->center.y, s->center.z, s->radius * s->radius};
    }
    /* Every placed triangle in the local frame (an instanced mesh's mapped there: not bit for bit
     * what Embree traces, but this back end is chosen for flat scenes only). */
    size_t i = 0;
    for (size_t k = 0; k < scene->instance_count; k++) {
        size_t count = scene->meshes[scene->instances[k].mesh].triangle_count;
        for (size_t prim = 0; prim < count && i < nt; prim++, i++) {
            struct ao_vec3 c[3];
            ao_scene_triangle(scene, k, prim, c);
            struct ao_vec3 a = ao_vec3_sub(c[0], c[1]), b = ao_vec3_sub(c[2], c[0]);
            struct ao_vec3 n = ao_vec3_cross(a, b);
            d->triangles[i] = (struct triangle){c[0].x, c[0].y, c[0].z, a.x, a.y, a.z, b.x, b.y, b.z, n.x, n.y, n.z};
            d->sources[i] = (struct source){(uint32_t)k, (uint32_t)prim};
        }
    }
    return d;
}

void ao_direct_destroy(struct ao_direct *direct)
{
    free(direct);
}

/* a = d.d and its inverse for each of n rays of directions d, shared by every sphere. */
static inline void squared_lengths(int n, const float *restrict dx, const float *restrict dy,
                                   const float *restrict dz, float *restrict a, float *restrict inv_a)
{
    for (int k = 0; k < n; k++) {
        a[k] = dx[k] * dx[k] + dy[k] * dy[k] + dz[k] * dz[k];
        inv_a[k] = 1.0f / a[k];
    }
}

/* Where ray o + t d meets sphere s within [0, tfar] (a = d.d): the first point ahead, on the far
 * side when the origin is inside; returns whether there is one and leaves its t in *t. Ray Tracing
 * Gems ch. 7's form: with f = o - c and beta = -f.d, the discriminant a (r^2 - |f + (beta/a) d|^2)
 * measures the ray's distance from the centre directly (no cancellation of two large squares far
 * away), and the roots are q/a and c/q with q = beta + sign(beta) sqrt(disc), c = |f|^2 - r^2, free
 * of cancellation. From outside (c > 0) the roots share a sign and c/q is the nearer; from inside,
 * the root ahead is c/q when the ray points away from the centre (beta < 0), else q/a. A ray that
 * leaves the surface outwards from just outside it gets t = c/q < 0: it never hits that sphere.
 * A negative discriminant gives NaN, which fails every comparison. */
static inline int sphere_hit(const struct sphere *s, float ox, float oy, float oz, float dx, float dy, float dz,
                             float a, float inv_a, float tfar, float *t)
{
    float fx = ox - s->cx, fy = oy - s->cy, fz = oz - s->cz;
    float beta = -(fx * dx + fy * dy + fz * dz);
    float m = beta * inv_a;
    float lx = fx + m * dx, ly = fy + m * dy, lz = fz + m * dz;
    float disc = a * (s->r2 - (lx * lx + ly * ly + lz * lz));
    float c = fx * fx + fy * fy + fz * fz - s->r2;
    float q = beta + copysignf(sqrtf(disc), beta);
    int c_over_q = (c > 0.0f) | (beta < 0.0f);
    *t = (c_over_q ? c : q) / (c_over_q ? q : a);   /* one division either way: GCC vectorizes it */
    return (*t >= 0.0f) & (*t <= tfar);
}

/* Where ray o + t d meets triangle tr within [0, tfar], both sides, with Embree's barycentrics (u
 * for vertex 1, v for vertex 2); returns whether it does. Cramer's rule on o + t d = p0 + u e1 +
 * v e2 with w = p0 - o, s = d x w and the stored a = -e1, b = e2, N = a x b = -(e1 x e2):
 * t = (w.N)/(d.N), u = (b.s)/(d.N), v = (a.s)/(d.N), signs folded into the stored vectors. The two
 * triangles of a quad, (0, 1, 2) and (0, 2, 3), share p0 and the diagonal: the first's b and the
 * second's a are exact negatives, so on the diagonal its u and the other's v are too and no ray
 * slips through. A ray parallel to the plane divides by 0 and fails the comparisons. */
static inline int triangle_hit(const struct triangle *tr, float ox, float oy, float oz, float dx, float dy,
                               float dz, float tfar, float *t, float *u, float *v)
{
    float wx = tr->px - ox, wy = tr->py - oy, wz = tr->pz - oz;
    float sx = dy * wz - dz * wy, sy = dz * wx - dx * wz, sz = dx * wy - dy * wx;
    float inv = 1.0f / (dx * tr->nx + dy * tr->ny + dz * tr->nz);
    *u = (tr->bx * sx + tr->by * sy + tr->bz * sz) * inv;
    *v = (tr->ax * sx + tr->ay * sy + tr->az * sz) * inv;
    *t = (wx * tr->nx + wy * tr->ny + wz * tr->nz) * inv;
    return (*u >= 0.0f) & (*v >= 0.0f) & (*u + *v <= 1.0f) & (*t >= 0.0f) & (*t <= tfar);
}

AO_VECTOR_CLONES
void ao_direct_intersect(const struct ao_direct *direct, const struct ao_packet *rays, struct ao_hit *hits)
{
    const float *restrict ox = rays->org_x, *restrict oy = rays->org_y, *restrict oz = rays->org_z;
    const float *restrict dx = rays->dir_x, *restrict dy = rays->dir_y, *restrict dz = rays->dir_z;
    int n = rays->count;
    float best[AO_PACKET_SIZE];
    uint32_t prim[AO_PACKET_SIZE];
    int32_t found[AO_PACKET_SIZE], sphere[AO_PACKET_SIZE];
    float a[AO_PACKET_SIZE], inv_a[AO_PACKET_SIZE];
    squared_lengths(n, dx, dy, dz, a, inv_a);
    for (int k = 0; k < n; k++) {
        best[k] = rays->tfar[k];
        prim[k] = 0;
        found[k] = sphere[k] = 0;
    }
    /* Each primitive shortens the rays it hits first; later ones must then be closer. */
    for (size_t i = 0; i < direct->sphere_count; i++) {
        const struct sphere s = direct->spheres[i];
        for (int k = 0; k < n; k++) {
            float t;
            int hit = sphere_hit(&s, ox[k], oy[k], oz[k], dx[k], dy[k], dz[k], a[k], inv_a[k], best[k], &t);
            best[k] = hit ? t : best[k];
            prim[k] = hit ? (uint32_t)i : prim[k];
            found[k] |= hit;
            sphere[k] |= hit;
        }
    }
    for (size_t i = 0; i < direct->triangle_count; i++) {
        const struct triangle tr = direct->triangles[i];
        for (int k = 0; k < n; k++) {
            float t, u, v;
            int hit = triangle_hit(&tr, ox[k], oy[k], oz[k], dx[k], dy[k], dz[k], best[k], &t, &u, &v);
            best[k] = hit ? t : best[k];
            prim[k] = hit ? (uint32_t)i : prim[k];
            found[k] |= hit;
            sphere[k] &= !hit;
        }
    }
    /* Barycentrics of the winning triangle only, by the same test (carrying them through the loop
     * above keeps GCC from vectorizing it). */
    for (int k = 0; k < n; k++) {
        float t, u = 0.0f, v = 0.0f;
        struct ao_vec3 ng = {0.0f, 0.0f, 0.0f};
        struct source source = {0, prim[k]};
        if (found[k] && !sphere[k]) {
            const struct triangle *tr = &direct->triangles[prim[k]];
            triangle_hit(tr, ox[k], oy[k], oz[k], dx[k], dy[k], dz[k], INFINITY, &t, &u, &v);
            ng = ao_vec3_make(-tr->nx, -tr->ny, -tr->nz); /* the stored N is -(e1 x e2) */
            source = direct->sources[prim[k]];
        }
        hits[k] = (struct ao_hit){.t = found[k] ? best[k] : INFINITY, .u = u, .v = v, .prim = source.prim,
                                  .instance = source.instance, .sphere = sphere[k], .ng = ng};
    }
}

/* Marks the blocked rays among rays first .. first + n - 1 (n at most AO_PACKET_SIZE) of the batch,
 * as ao_direct_occluded: each primitive broadcast against the rays in registers. */
AO_VECTOR_CLONES
static void occluded_packet(const struct ao_direct *direct, struct ao_batch *rays, int first, int n)
{
    const float *restrict ox = rays->org_x + first, *restrict oy = rays->org_y + first;
    const float *restrict oz = rays->org_z + first, *restrict dx = rays->dir_x + first;
    const float *restrict dy = rays->dir_y + first, *restrict dz = rays->dir_z + first;
    float *restrict tfar = rays->tfar + first;
    int32_t blocked[AO_PACKET_SIZE] = {0};
    float a[AO_PACKET_SIZE], inv_a[AO_PACKET_SIZE];
    squared_lengths(n, dx, dy, dz, a, inv_a);
    for (size_t i = 0; i < direct->sphere_count; i++) {
        const struct sphere s = direct->spheres[i];
        for (int k = 0; k < n; k++) {
            float t;
            blocked[k] |= sphere_hit(&s, ox[k], oy[k], oz[k], dx[k], dy[k], dz[k], a[k], inv_a[k], tfar[k], &t);
        }
    }
    for (size_t i = 0; i < direct->triangle_count; i++) {
        const struct triangle tr = direct->triangles[i];
        for (int k = 0; k < n; k++) {
            float t, u, v;
            blocked[k] |= triangle_hit(&tr, ox[k], oy[k], oz[k], dx[k], dy[k], dz[k], tfar[k], &t, &u, &v);
        }
    }
    for (int k = 0; k < n; k++)
        tfar[k] = blocked[k] ? -INFINITY : tfar[k];
}

void ao_direct_occluded(const struct ao_direct *direct, struct ao_batch *rays)
{
    for (int first = 0; first < rays->count; first += AO_PACKET_SIZE) {
        int left = rays->count - first;
        occluded_packet(direct, rays, first, left < AO_PACKET_SIZE ? left : AO_PACKET_SIZE);
    }
}
