/* The direct back end against Embree: the same hits on random rays through the spheres scene and
 * through random scenes of spheres and quads (rays within a tiny distance of a silhouette, an edge
 * or a tie excepted, found by a double-precision check), no self-occlusion, and statistically the
 * same image of the spheres scene. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "ao.h"
#include "render.h"
#include "rng.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

/* Rays whose outcome turns on less than this (relative) are too close to call and are skipped. */
static const double EPS = 1e-4;
/* Triangle hits at a smaller cosine of incidence are too close to call: float t then carries a
 * relative error of about 2^-24 / cosine, which nears 1e-4 there. */
static const double GRAZING = 1e-2;
/* Hits this close to t = 0, relative to |origin| (16 ulps), are too close to call. AO rays start
 * closer than that to the surface they leave (ao_surface_lift: a few ulps of the point), which
 * too_close() therefore leaves out: neither back end may find it. */
static const double T_NEAR = 1e-6;

/* ---- random numbers ---- */

static double uniform(uint64_t *state)
{
    *state += 0x9e3779b97f4a7c15u;
    return (double)(ao_rng_mix(*state) >> 11) * 0x1.0p-53;
}

static double between(uint64_t *state, double lo, double hi)
{
    return lo + (hi - lo) * uniform(state);
}

/* A uniform direction on the unit sphere. */
static void unit_vector(uint64_t *state, double v[3])
{
    double z = between(state, -1, 1), phi = between(state, 0, 6.283185307179586), r = sqrt(1 - z * z);
    v[0] = r * cos(phi);
    v[1] = r * sin(phi);
    v[2] = z;
}

/* ---- a double-precision judge of which rays are too close to call ---- */

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void from_vec3(struct ao_vec3 p, double out[3])
{
    out[0] = p.x;
    out[1] = p.y;
    out[2] = p.z;
}

/* The corners of the scene's triangle i, counting the triangles of its instances in order, in the
 * local frame. */
static void corners(const struct ao_scene *s, size_t i, struct ao_vec3 c[3])
{
    size_t k = 0;
    while (i >= s->meshes[s->instances[k].mesh].triangle_count)
        i -= s->meshes[s->instances[k++].mesh].triangle_count;
    ao_scene_triangle(s, k, i, c);
}

/* Records a candidate hit at t; returns true when it is too close to 0 or to tfar to call. */
static bool candidate(double t, double tfar, double scale, double *first, double *second)
{
    if (fabs(t) < T_NEAR * scale || (isfinite(tfar) && fabs(t - tfar) < EPS * tfar))
        return true;
    if (t > 0 && t < tfar) {
        if (t < *first) {
            *second = *first;
            *first = t;
        } else if (t < *second) {
            *second = t;
        }
    }
    return false;
}

/* True when ray o + t d (t in [0, tfar]) passes within EPS of a sphere's silhouette or a triangle's
 * edge, starts on a surface, ends on one, grazes a triangle, or meets two surfaces at nearly the
 * same t: there float rounding may rightly decide either way. Primitive `leaves` (-1: none) is
 * the one an AO ray leaves from outside, away from it: a plane or a convex sphere it cannot meet,
 * so it is not consulted, and a back end that finds it fails the comparison. */
static bool too_close(const struct ao_scene *s, const double o[3], const double d[3], double tfar, long leaves)
{
    double first = INFINITY, second = INFINITY, a = dot(d, d), scale = sqrt(dot(o, o)) + 1e-3;
    for (size_t i = 0; i < s->sphere_count; i++) {
        if ((long)i == leaves)
            continue;
        double c[3], f[3], l[3], r = s->spheres[i].radius;
        from_vec3(s->spheres[i].center, c);
        for (int k = 0; k < 3; k++)
            f[k] = o[k] - c[k];
        double m = -dot(f, d) / a;
        for (int k = 0; k < 3; k++)
            l[k] = f[k] + m * d[k];
        double dist = sqrt(dot(l, l));
        /* A silhouette matters where the ray can reach it. */
        if (fabs(dist - r) < EPS * r && m > -T_NEAR * scale)
            return true;
        if (dist < r) {
            double half = sqrt((r * r - dist * dist) / a);
            if (candidate(m - half, tfar, scale, &first, &second) || candidate(m + half, tfar, scale, &first, &second))
                return true;
        }
    }
    for (size_t i = 0; i < s->triangle_count; i++) {
        if ((long)(s->sphere_count + i) == leaves)
            continue;
        double p[3][3], e1[3], e2[3], n[3], w[3];
        struct ao_vec3 c[3];
        corners(s, i, c);
        for (int v = 0; v < 3; v++)
            from_vec3(c[v], p[v]);
        for (int k = 0; k < 3; k++) {
            e1[k] = p[1][k] - p[0][k];
            e2[k] = p[2][k] - p[0][k];
            w[k] = o[k] - p[0][k];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double den = dot(d, n), cosine = fabs(den) / sqrt(a * dot(n, n));
        double t = -dot(w, n) / den, x[3], nn = dot(n, n), b[3];
        for (int k = 0; k < 3; k++)
            x[k] = w[k] + t * d[k];
        /* Barycentrics of the plane point x (relative to p0) from the areas of the sub-triangles. */
        double c1[3] = {x[1] * e2[2] - x[2] * e2[1], x[2] * e2[0] - x[0] * e2[2], x[0] * e2[1] - x[1] * e2[0]};
        double c2[3] = {e1[1] * x[2] - e1[2] * x[1], e1[2] * x[0] - e1[0] * x[2], e1[0] * x[1] - e1[1] * x[0]};
        b[1] = dot(c1, n) / nn;
        b[2] = dot(c2, n) / nn;
        b[0] = 1 - b[1] - b[2];
        bool in_range = t > -T_NEAR * scale && t < tfar * (1 + EPS);
        bool inside = b[0] > -EPS && b[1] > -EPS && b[2] > -EPS;
        if (in_range && (fabs(b[0]) < EPS || fabs(b[1]) < EPS || fabs(b[2]) < EPS || (inside && cosine < GRAZING)))
            return true;
        if (b[0] > 0 && b[1] > 0 && b[2] > 0 && candidate(t, tfar, scale, &first, &second))
            return true;
    }
    return isfinite(second) && second - first < EPS * first;
}

/* The point p0 + u (p1 - p0) + v (p2 - p0) of triangle `prim` and the triangle's normal; returns
 * the sum of the two edge lengths. */
static double triangle_point(const struct ao_scene *s, uint32_t prim, double u, double v, double x[3], double n[3])
{
    double p[3][3], e1[3], e2[3];
    struct ao_vec3 c[3];
    corners(s, prim, c);
    for (int k = 0; k < 3; k++)
        from_vec3(c[k], p[k]);
    for (int k = 0; k < 3; k++) {
        e1[k] = p[1][k] - p[0][k];
        e2[k] = p[2][k] - p[0][k];
        x[k] = p[0][k] + u * e1[k] + v * e2[k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    return sqrt(dot(e1, e1)) + sqrt(dot(e2, e2));
}

/* ---- rays ---- */

enum ray_kind { RAY_RANDOM, RAY_AIMED, RAY_FROM_SURFACE, RAY_KINDS };

/* A random point on (or, aimed, near) primitive `prim` of the scene (spheres first), with the
 * outward normal of a sphere or the normal of a triangle. */
static void point_on(const struct ao_scene *s, uint64_t *rng, size_t prim, bool near, double x[3], double n[3])
{
    if (prim < s->sphere_count) {
        double c[3], r = s->spheres[prim].radius * (near ? between(rng, 0.5, 1.3) : 1.0);
        from_vec3(s->spheres[prim].center, c);
        unit_vector(rng, n);
        for (int k = 0; k < 3; k++)
            x[k] = c[k] + r * n[k];
        return;
    }
    struct ao_vec3 c[3];
    corners(s, prim - s->sphere_count, c);
    double p[3][3], u = between(rng, 0, 1), v = between(rng, 0, 1);
    if (u + v > 1 && !near) {
        u = 1 - u;
        v = 1 - v;
    }
    if (near) {
        u = u * 1.4 - 0.2;
        v = v * 1.4 - 0.2;
    }
    for (int k = 0; k < 3; k++)
        from_vec3(c[k], p[k]);
    for (int k = 0; k < 3; k++)
        x[k] = p[0][k] + u * (p[1][k] - p[0][k]) + v * (p[2][k] - p[0][k]);
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = p[1][k] - p[0][k];
        e2[k] = p[2][k] - p[0][k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double len = sqrt(dot(n, n)), side = uniform(rng) < 0.5 ? -1 : 1;
    for (int k = 0; k < 3; k++)
        n[k] *= side / len;
}

/* Where aoview starts occlusion rays from x, a point of primitive `prim` with unit normal n: x as
 * aoview computes it (ao_triangle_point at x's barycentrics, ao_sphere_point), lifted past its
 * error bound along n (ao_surface_lift). */
static void lifted_origin(const struct ao_scene *s, size_t prim, const double x[3], const double n[3], double o[3])
{
    struct ao_vec3 p, error, normal = ao_vec3_make((float)n[0], (float)n[1], (float)n[2]);
    if (prim < s->sphere_count) {
        struct ao_vec3 outward;
        p = ao_sphere_point(s->spheres[prim].center, s->spheres[prim].radius,
                            ao_vec3_make((float)x[0], (float)x[1], (float)x[2]), &outward, &error);
    } else {
        struct ao_vec3 v[3];
        corners(s, prim - s->sphere_count, v);
        double p0[3], p1[3], p2[3], e1[3], e2[3], w[3];
        from_vec3(v[0], p0);
        from_vec3(v[1], p1);
        from_vec3(v[2], p2);
        for (int k = 0; k < 3; k++)
            e1[k] = p1[k] - p0[k], e2[k] = p2[k] - p0[k], w[k] = x[k] - p0[k];
        /* Barycentrics from the normal equations of x - p0 = u e1 + v e2. */
        double a = dot(e1, e1), b = dot(e1, e2), c = dot(e2, e2), det = a * c - b * b;
        double u = (c * dot(e1, w) - b * dot(e2, w)) / det, vv = (a * dot(e2, w) - b * dot(e1, w)) / det;
        p = ao_triangle_point(v[0], v[1], v[2], (float)u, (float)vv, &error);
    }
    struct ao_vec3 lifted = ao_surface_lift(p, normal, error);
    from_vec3(lifted, o);
}

/* One random ray of the given kind: origin and direction in double (the float ray is their
 * rounding), tfar infinite or random; *leaves is the primitive an AO ray leaves, else -1. */
static void make_ray(const struct ao_scene *s, uint64_t *rng, enum ray_kind kind, double o[3], double d[3],
                     double *tfar, long *leaves)
{
    *leaves = -1;
    size_t prims = s->sphere_count + s->triangle_count;
    size_t prim = (size_t)(uniform(rng) * (double)prims);
    double x[3], n[3];
    for (int k = 0; k < 3; k++)
        o[k] = between(rng, -3, 3);
    o[1] = between(rng, -1, 3);
    if (kind == RAY_RANDOM) {
        unit_vector(rng, d);
    } else if (kind == RAY_AIMED) {
        point_on(s, rng, prim, true, x, n);
        for (int k = 0; k < 3; k++)
            d[k] = x[k] - o[k];
    } else {
        /* An AO ray: off the surface by aoview's own offset, into the normal's hemisphere. */
        point_on(s, rng, prim, false, x, n);
        lifted_origin(s, prim, x, n, o);
        *leaves = (long)prim;
        unit_vector(rng, d);
        double dn = dot(d, n);
        for (int k = 0; k < 3; k++)
            d[k] -= dn < 0 ? 2 * dn * n[k] : 0;
    }
    /* Directions of any length: both back ends take d as given. */
    double len = sqrt(dot(d, d)) / between(rng, 0.5, 2);
    for (int k = 0; k < 3; k++)
        d[k] /= len;
    *tfar = uniform(rng) < 0.5 ? INFINITY : between(rng, 0.1, 8);
}

/* ---- comparison ---- */

/* open[k] = 1 when the tracer finds ray k of the packet unblocked, traced as a batch of its own. */
static void occluded(const struct ao_tracer *tracer, const struct ao_packet *rays, uint8_t *open)
{
    static struct ao_batch batch; /* static: it is large */
    batch.count = rays->count;
    for (int k = 0; k < rays->count; k++) {
        batch.org_x[k] = rays->org_x[k], batch.org_y[k] = rays->org_y[k], batch.org_z[k] = rays->org_z[k];
        batch.dir_x[k] = rays->dir_x[k], batch.dir_y[k] = rays->dir_y[k], batch.dir_z[k] = rays->dir_z[k];
        batch.tfar[k] = rays->tfar[k];
    }
    ao_tracer_occluded(tracer, &batch);
    for (int k = 0; k < rays->count; k++)
        open[k] = batch.tfar[k] >= 0.0f;
}

struct tally {
    long rays, skipped, hits;
};

/* Traces `packets` packets of random rays of every kind through both back ends and checks that
 * they agree on every ray not too close to call. */
static void compare(const struct ao_scene *scene, uint64_t seed, int packets, struct tally *tally)
{
    struct ao_tracer *embree = ao_tracer_create_with(scene, AO_BACKEND_EMBREE);
    struct ao_tracer *direct = ao_tracer_create_with(scene, AO_BACKEND_DIRECT);
    assert_non_null(embree);
    assert_non_null(direct);
    assert_string_equal(ao_tracer_backend(embree), "embree");
    assert_string_equal(ao_tracer_backend(direct), "direct");
    uint64_t rng = seed;
    for (int p = 0; p < packets; p++) {
        struct ao_packet rays = {.count = AO_PACKET_SIZE - p % 3};
        bool skip[AO_PACKET_SIZE];
        for (int k = 0; k < rays.count; k++) {
            double o[3], d[3], tfar;
            long leaves;
            make_ray(scene, &rng, (enum ray_kind)((p + k) % RAY_KINDS), o, d, &tfar, &leaves);
            rays.org_x[k] = (float)o[0];
            rays.org_y[k] = (float)o[1];
            rays.org_z[k] = (float)o[2];
            rays.dir_x[k] = (float)d[0];
            rays.dir_y[k] = (float)d[1];
            rays.dir_z[k] = (float)d[2];
            rays.tfar[k] = (float)tfar;
            /* Judge the float ray that is actually traced. */
            double of[3] = {rays.org_x[k], rays.org_y[k], rays.org_z[k]};
            double df[3] = {rays.dir_x[k], rays.dir_y[k], rays.dir_z[k]};
            skip[k] = too_close(scene, of, df, rays.tfar[k], leaves);
        }
        struct ao_hit he[AO_PACKET_SIZE], hd[AO_PACKET_SIZE];
        uint8_t oe[AO_PACKET_SIZE], od[AO_PACKET_SIZE];
        ao_tracer_intersect(embree, &rays, he);
        ao_tracer_intersect(direct, &rays, hd);
        occluded(embree, &rays, oe);
        occluded(direct, &rays, od);
        for (int k = 0; k < rays.count; k++) {
            tally->rays++;
            if (skip[k]) {
                tally->skipped++;
                continue;
            }
            if (oe[k] != od[k] || (he[k].t == INFINITY) != (hd[k].t == INFINITY))
                fail_msg("ray (%g %g %g) + t (%g %g %g), tfar %g: embree open %d t %g, direct open %d t %g",
                         rays.org_x[k], rays.org_y[k], rays.org_z[k], rays.dir_x[k], rays.dir_y[k], rays.dir_z[k],
                         rays.tfar[k], oe[k], he[k].t, od[k], hd[k].t);
            /* Closest hits only exist within tfar, so an open ray has none. */
            assert_int_equal(od[k], hd[k].t == INFINITY);
            if (hd[k].t == INFINITY)
                continue;
            tally->hits++;
            assert_int_equal(he[k].sphere, hd[k].sphere);
            assert_int_equal(he[k].prim, hd[k].prim);
            /* t within 1e-4 relative, or within 2^-18 of the origin's magnitude for hits so near that
             * the origin's own rounding dominates. */
            float origin = ao_vec3_max_abs(ao_vec3_make(rays.org_x[k], rays.org_y[k], rays.org_z[k]));
            if (!(fabsf(he[k].t - hd[k].t) <= fmaxf(1e-4f * fmaxf(he[k].t, hd[k].t), 0x1.0p-18f * origin)))
                fail_msg("ray (%a %a %a) + t (%a %a %a), tfar %g: embree t %.9g, direct t %.9g (%s %u)",
                         rays.org_x[k], rays.org_y[k], rays.org_z[k], rays.dir_x[k], rays.dir_y[k], rays.dir_z[k],
                         rays.tfar[k], he[k].t, hd[k].t, hd[k].sphere ? "sphere" : "triangle", hd[k].prim);
            if (!hd[k].sphere) {
                /* Barycentrics: the points they name agree as well as the ray fixes them (1e-4 of the
                 * distances involved, over the cosine of incidence) and as float barycentrics can
                 * name them (1e-6, 16 ulps, of the edges). */
                double pe[3], pd[3], n[3], d[3] = {rays.dir_x[k], rays.dir_y[k], rays.dir_z[k]}, diff[3];
                triangle_point(scene, hd[k].prim, he[k].u, he[k].v, pe, n);
                double size = triangle_point(scene, hd[k].prim, hd[k].u, hd[k].v, pd, n);
                for (int q = 0; q < 3; q++)
                    diff[q] = pe[q] - pd[q];
                double cosine = fabs(dot(d, n)) / sqrt(dot(d, d) * dot(n, n));
                double along = 1e-4 * (origin + hd[k].t * sqrt(dot(d, d)));
                if (!(sqrt(dot(diff, diff)) <= along / cosine + 1e-6 * size))
                    fail_msg("ray (%a %a %a) + t (%a %a %a): embree u %.9g v %.9g, direct u %.9g v %.9g",
                             rays.org_x[k], rays.org_y[k], rays.org_z[k], d[0], d[1], d[2], he[k].u, he[k].v,
                             hd[k].u, hd[k].v);
                /* Both geometric normals are (p1 - p0) x (p2 - p0) up to float rounding: within 1e-5
                 * radians (a few ulps of the edges' products, relative to the normal's length). */
                for (int b = 0; b < 2; b++) {
                    struct ao_vec3 g = b ? hd[k].ng : he[k].ng;
                    double ng[3] = {g.x, g.y, g.z};
                    if (!(dot(ng, n) / sqrt(dot(ng, ng) * dot(n, n)) >= 1.0 - 5e-11))
                        fail_msg("triangle %u: %s normal (%g %g %g), exact (%g %g %g)", hd[k].prim,
                                 b ? "direct" : "embree", ng[0], ng[1], ng[2], n[0], n[1], n[2]);
                }
            }
        }
    }
    ao_tracer_destroy(embree);
    ao_tracer_destroy(direct);
}

/* At most 1% of rays may be too close to call, and enough must hit, or the check says little. */
static void check_tally(const struct tally *t)
{
    assert_true(t->skipped * 100 <= t->rays);
    assert_true(t->hits * 5 >= t->rays);
}

static void load_spheres(struct ao_scene *scene)
{
    const char *root = getenv("AO_SOURCE_ROOT");
    char path[4096];
    assert_non_null(root);
    snprintf(path, sizeof path, "%s/assets/scenes/spheres.scene", root);
    assert_true(ao_scene_load(scene, path, NULL));
}

static void test_spheres_scene_agrees_with_embree(void **state)
{
    (void)state;
    struct ao_scene scene;
    load_spheres(&scene);
    struct tally tally = {0};
    compare(&scene, 1, 20000, &tally);
    check_tally(&tally);
    ao_scene_finish(&scene);
}

static void test_random_scenes_agree_with_embree(void **state)
{
    (void)state;
    uint64_t rng = 99;
    struct tally tally = {0};
    for (int n = 0; n < 40; n++) {
        char text[8192];
        int len = snprintf(text, sizeof text, "camera eye 0 1 5 target 0 0 0\n");
        int spheres = (int)between(&rng, 0, 9), quads = (int)between(&rng, spheres ? 0 : 1, 9);
        for (int i = 0; i < spheres; i++)
            len += snprintf(text + len, sizeof text - (size_t)len, "sphere center %.6f %.6f %.6f radius %.6f\n",
                            between(&rng, -2, 2), between(&rng, -1, 2), between(&rng, -2, 2),
                            between(&rng, 0.05, 1));
        for (int i = 0; i < quads; i++) {
            double e1[3], e2[3];
            unit_vector(&rng, e1);
            unit_vector(&rng, e2);
            double l1 = between(&rng, 0.2, 4), l2 = between(&rng, 0.2, 4);
            len += snprintf(text + len, sizeof text - (size_t)len,
                            "quad corner %.6f %.6f %.6f edge1 %.6f %.6f %.6f edge2 %.6f %.6f %.6f\n",
                            between(&rng, -2, 2), between(&rng, -1, 2), between(&rng, -2, 2), l1 * e1[0],
                            l1 * e1[1], l1 * e1[2], l2 * e2[0], l2 * e2[1], l2 * e2[2]);
        }
        struct ao_scene scene;
        assert_true(ao_scene_parse(&scene, text, "random.scene", NULL));
        compare(&scene, (uint64_t)n + 1000, 1000, &tally);
        ao_scene_finish(&scene);
    }
    check_tally(&tally);
}

/* Occlusion rays leaving a lone sphere or quad outwards, down to grazing angles, at any scale:
 * the surface they leave never blocks them. */
static void test_no_self_occlusion(void **state)
{
    (void)state;
    static const char *const scenes[] = {
        "camera eye 0 0 5 target 0 0 0\nsphere center 0.3 -0.2 0.1 radius 0.7\n",
        "camera eye 0 0 5 target 0 0 0\nsphere center 1000 -2000 500 radius 300\n",
        "camera eye 0 0 5 target 0 0 0\nsphere center 0 0 0 radius 0.001\n",
        "camera eye 0 0 5 target 0 0 0\nquad corner -1 0.2 -1 edge1 0.3 0 2 edge2 2 0.5 0\n",
        "camera eye 0 0 5 target 0 0 0\nquad corner -50 0 -50 edge1 0 0 100 edge2 100 0 0\n",
    };
    uint64_t rng = 7;
    for (size_t i = 0; i < sizeof scenes / sizeof *scenes; i++) {
        struct ao_scene scene;
        assert_true(ao_scene_parse(&scene, scenes[i], "lone.scene", NULL));
        struct ao_tracer *direct = ao_tracer_create_with(&scene, AO_BACKEND_DIRECT);
        for (int p = 0; p < 2000; p++) {
            struct ao_packet rays = {.count = AO_PACKET_SIZE};
            for (int k = 0; k < AO_PACKET_SIZE; k++) {
                double x[3], n[3], d[3];
                double o[3];
                point_on(&scene, &rng, 0, false, x, n);
                lifted_origin(&scene, 0, x, n, o);
                /* Half the rays within a hair of the tangent plane. */
                unit_vector(&rng, d);
                double dn = dot(d, n), lift = k % 2 ? fabs(dn) : 1e-3 * fabs(dn);
                rays.org_x[k] = (float)o[0];
                rays.org_y[k] = (float)o[1];
                rays.org_z[k] = (float)o[2];
                rays.dir_x[k] = (float)(d[0] - dn * n[0] + lift * n[0]);
                rays.dir_y[k] = (float)(d[1] - dn * n[1] + lift * n[1]);
                rays.dir_z[k] = (float)(d[2] - dn * n[2] + lift * n[2]);
                rays.tfar[k] = INFINITY;
            }
            uint8_t open[AO_PACKET_SIZE];
            occluded(direct, &rays, open);
            for (int k = 0; k < AO_PACKET_SIZE; k++)
                assert_int_equal(open[k], 1);
        }
        ao_tracer_destroy(direct);
        ao_scene_finish(&scene);
    }
}

/* ---- images ---- */

enum { WIDTH = 64, HEIGHT = 48, SPP = 64 };

/* The spheres scene at 64x48, 64 passes of one cosine sample each, through the given back end;
 * a malloc'd copy of the final frame. */
static float *render_spheres(enum ao_backend backend, uint64_t seed)
{
    struct ao_scene scene;
    load_spheres(&scene);
    struct ao_tracer *tracer = ao_tracer_create_with(&scene, backend);
    assert_non_null(tracer);
    struct ao_render_config config = {.scene = &scene, .tracer = tracer,
                                      .threads = 2, .seed = seed, .target_spp = SPP,
                                      .ao_distance = scene.ao_distance};
    struct ao_settings settings = {.width = WIDTH, .height = HEIGHT, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .spppp = 1, .camera = scene.camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    assert_non_null(r);
    assert_true(ao_render_wait(r));
    const struct ao_frame *frame = ao_render_take_frame(r);
    assert_non_null(frame);
    float *copy = malloc(sizeof(float) * 3 * WIDTH * HEIGHT);
    assert_non_null(copy);
    for (int k = 0; k < 3 * WIDTH * HEIGHT; k++)
        copy[k] = frame->rgb[k];
    ao_render_destroy(r);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
    return copy;
}

/* Mean over pixels of (a - b) and of |a - b|, each pixel the mean of its three channels. */
static void differences(const float *a, const float *b, double *mean, double *mean_abs)
{
    double sum = 0, sum_abs = 0;
    for (int p = 0; p < WIDTH * HEIGHT; p++) {
        double d = ((double)a[3 * p] + a[3 * p + 1] + a[3 * p + 2] - b[3 * p] - b[3 * p + 1] - b[3 * p + 2]) / 3;
        sum += d;
        sum_abs += fabs(d);
    }
    *mean = sum / (WIDTH * HEIGHT);
    *mean_abs = sum_abs / (WIDTH * HEIGHT);
}

static void test_images_are_statistically_the_same(void **state)
{
    (void)state;
    float *embree = render_spheres(AO_BACKEND_EMBREE, 1);
    float *direct = render_spheres(AO_BACKEND_DIRECT, 2);
    float *direct_same_seed = render_spheres(AO_BACKEND_DIRECT, 1);
    double mean, mean_abs;
    /* Different seeds: independent estimates. With one cosine sample per pass, each of a pixel's 64
     * samples has its own jitter and direction, so the samples are i.i.d.; a sample (channel mean of
     * albedo * visibility, or the background 1) lies in [0, 1], so its variance is at most 1/4 and
     * the pixel's mean has variance <= 1/(4*64). Pixels are independent, so the mean over P = 3072
     * pixels of the difference of two independent images has standard deviation <= sqrt(2/(256 P))
     * = 1.6e-3, and mean 0 when both back ends see the same scene: 5 sigma is 8e-3. */
    differences(embree, direct, &mean, &mean_abs);
    assert_true(fabs(mean) <= 8e-3);
    /* Same seed: the same samples, so only rays that rounding decides differently can differ; each
     * such ray moves a pixel by at most 1/64. Allow one such ray in 100 pixels on average. */
    differences(embree, direct_same_seed, &mean, &mean_abs);
    assert_true(mean_abs <= 1.0 / (64 * 100));
    free(embree);
    free(direct);
    free(direct_same_seed);
}

/* ---- the automatic choice ---- */

/* The back end ao_tracer_create picks for a scene text. */
static void check_choice(const char *text, const char *backend)
{
    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, text, "choice.scene", NULL));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    assert_non_null(tracer);
    assert_string_equal(ao_tracer_backend(tracer), backend);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
}

/* Scene text with a camera, `spheres` spheres and `quads` quads, in a static buffer. */
static const char *scene_text(int spheres, int quads)
{
    static char text[4096];
    int len = snprintf(text, sizeof text, "camera eye 0 1 5 target 0 0 0\n");
    for (int i = 0; i < spheres; i++)
        len += snprintf(text + len, sizeof text - (size_t)len, "sphere center %d 1 0 radius 0.4\n", i);
    for (int i = 0; i < quads; i++)
        len += snprintf(text + len, sizeof text - (size_t)len, "quad corner %d 0 0 edge1 0 0 1 edge2 1 0 0\n", i);
    return text;
}

/* The measured rule (direct.c): up to 16 primitives with a sphere, up to 4 triangles without. */
static void test_small_scenes_choose_direct(void **state)
{
    (void)state;
    struct ao_scene scene;
    load_spheres(&scene);
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    assert_string_equal(ao_tracer_backend(tracer), "direct");
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
    check_choice(scene_text(14, 1), "direct");
    check_choice(scene_text(15, 1), "embree");
    check_choice(scene_text(0, 2), "direct");
    check_choice(scene_text(0, 3), "embree");
}

int main(void)
{
    if (!getenv("AO_SOURCE_ROOT")) {
        fprintf(stderr, "test_direct: AO_SOURCE_ROOT is not set (run it through meson test)\n");
        return 77;
    }
    ao_tracer_thread_init();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spheres_scene_agrees_with_embree),
        cmocka_unit_test(test_random_scenes_agree_with_embree),
        cmocka_unit_test(test_no_self_occlusion),
        cmocka_unit_test(test_images_are_statistically_the_same),
        cmocka_unit_test(test_small_scenes_choose_direct),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
