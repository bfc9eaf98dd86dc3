/* The AO estimator against closed forms, for all three samplers, through both tracer back ends
 * (Embree and the direct loops). Statistical bounds are derived next to each check; seeds are
 * fixed. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>

#include "ao.h"
#include "sampling.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

/* A ground plane (2e4 across: infinite as seen from |x| < 3), optionally a sphere of radius R
 * centred at height H above the origin. */
static const float RHO = 0.7f, R = 0.5f, H = 1.0f;

/* The back end the current group of tests traces with. */
static enum ao_backend backend;

struct fixture {
    struct ao_scene scene;
    struct ao_tracer *tracer;
    struct ao_context ctx;
};

static void setup(struct fixture *f, const char *text)
{
    assert_true(ao_scene_parse(&f->scene, text, "estimator.scene", NULL));
    f->tracer = ao_tracer_create_with(&f->scene, backend);
    assert_non_null(f->tracer);
    f->ctx = (struct ao_context){.scene = &f->scene, .tracer = f->tracer, .ao_distance = INFINITY, .seed = 42};
}

static void teardown(struct fixture *f)
{
    ao_tracer_destroy(f->tracer);
    ao_scene_finish(&f->scene);
}

static const char PLANE[] = "camera eye 0 5 5 target 0 0 0\n"
                            "quad corner -1e4 0 -1e4 edge1 0 0 2e4 edge2 2e4 0 0 albedo 0.7\n";
static const char PLANE_AND_SPHERE[] = "camera eye 0 5 5 target 0 0 0\n"
                                       "quad corner -1e4 0 -1e4 edge1 0 0 2e4 edge2 2e4 0 0 albedo 0.7\n"
                                       "sphere center 0 1 0 radius 0.5 albedo 0.3\n";

static struct ao_surface ground_point(float x)
{
    struct ao_vec3 up = ao_vec3_make(0, 1, 0), p = ao_vec3_make(x, 0, 0);
    struct ao_surface s = {.position = p, .ng = up, .ns = up, .albedo = ao_vec3_make(RHO, RHO, RHO)};
    s.origin = ao_surface_lift(p, up, ao_vec3_make(0, 0, 0)); /* exact: the plane is y = 0 */
    return s;
}

/* Mean and variance of n single-sample estimates (red channel) at s. */
static void moments(struct fixture *f, const struct ao_surface *s, int n, double *mean, double *var)
{
    double sum = 0, sum2 = 0;
    uint64_t rays = 0;
    for (int k = 0; k < n; k++) {
        double x = ao_estimate_surface(&f->ctx, s, 0, (uint64_t)k, 1, &rays).x;
        sum += x;
        sum2 += x * x;
    }
    *mean = sum / n;
    *var = sum2 / n - *mean * *mean;
}

static void test_open_plane_gives_rho(void **state)
{
    (void)state;
    struct fixture f;
    setup(&f, PLANE);
    /* Cosine: every sample is exactly rho (weight 1, nothing occludes). */
    f.ctx.sampling = AO_SAMPLING_COSINE;
    struct ao_surface s = ground_point(0.3f);
    uint64_t rays = 0;
    for (int k = 0; k < 10000; k++)
        assert_true(ao_estimate_surface(&f.ctx, &s, 1, (uint64_t)k, 1, &rays).x == RHO);
    /* Uniform and hemisphere: mean rho, per-sample variance 5 rho^2/3 and rho^2/3.
     * Standard errors over N = 10^6 samples (rho = 1 scale): mean sqrt(5/3/N) = 0.0013 and
     * sqrt(1/3/N) = 0.00058; sample variance sqrt((mu4 - sigma^4)/N) with mu4 = 6.6 and 0.2 (from
     * the moments E X^k = 4^k/(2(k+1)) and 2^k/(k+1)): 0.00196 and 0.00030. Bounds are 4 sigma,
     * scaled by rho and rho^2. */
    enum { N = 1000000 };
    double rho2 = (double)RHO * RHO, mean, var;
    f.ctx.sampling = AO_SAMPLING_UNIFORM;
    moments(&f, &s, N, &mean, &var);
    assert_true(fabs(mean - RHO) < 4 * 0.0013 * RHO);
    assert_true(fabs(var - 5.0 / 3.0 * rho2) < 4 * 0.00196 * rho2);
    f.ctx.sampling = AO_SAMPLING_HEMISPHERE;
    moments(&f, &s, N, &mean, &var);
    assert_true(fabs(mean - RHO) < 4 * 0.00058 * RHO);
    assert_true(fabs(var - 1.0 / 3.0 * rho2) < 4 * 0.00030 * rho2);
    f.ctx.sampling = AO_SAMPLING_COSINE;
    moments(&f, &s, N, &mean, &var);
    assert_true(mean == RHO && var < 1e-12);
    teardown(&f);
}

static void test_ground_under_sphere_matches_closed_form(void **state)
{
    (void)state;
    /* A sphere of radius r centred at height h hides, from a ground point at distance d from its
     * centre, a cap of cosine-weighted solid angle r^2 h / d^3 (the projected disc): AO = rho (1 -
     * r^2 h / d^3). Each point uses 10^6 samples and is checked to 4 standard errors, the standard
     * error estimated from the same samples (per-sample variance is below 5/3 rho^2, so that is
     * at most 4 * 0.0013 rho); the geometry is exact enough that no bias term is needed. */
    enum { N = 1000000 };
    struct fixture f;
    setup(&f, PLANE_AND_SPHERE);
    const float xs[] = {0.0f, 0.4f, 1.0f, 2.5f};
    for (int mode = 0; mode < 3; mode++) {
        f.ctx.sampling = (enum ao_sampling)mode;
        for (int i = 0; i < 4; i++) {
            double d = sqrt((double)xs[i] * xs[i] + (double)H * H);
            double expected = RHO * (1.0 - R * R * H / (d * d * d));
            double mean, var;
            struct ao_surface s = ground_point(xs[i]);
            moments(&f, &s, N, &mean, &var);
            double se = sqrt(var / N);
            print_message("%-10s x=%.1f expected %.5f got %.5f (%.1f se)\n",
                          ao_sampling_name((enum ao_sampling)mode), xs[i], expected, mean, (mean - expected) / se);
            assert_true(fabs(mean - expected) < 4 * se + 1e-7);
        }
    }
    teardown(&f);
}

static void test_inside_closed_sphere_gives_zero(void **state)
{
    (void)state;
    struct fixture f;
    setup(&f, "camera eye 0 0 0.5 target 0 0 0\nsphere center 0 0 0 radius 2\n");
    for (int mode = 0; mode < 3; mode++) {
        f.ctx.sampling = (enum ao_sampling)mode;
        /* A point on the inside of the shell, normal pointing inwards, as an eye ray finds it. */
        struct ao_vec3 n, error, p = ao_sphere_point(ao_vec3_make(0, 0, 0), 2, ao_vec3_make(0, 0, -2), &n, &error);
        n = ao_vec3_scale(n, -1.0f);
        struct ao_surface s = {.position = p, .ng = n, .ns = n, .albedo = ao_vec3_make(1, 1, 1)};
        s.origin = ao_surface_lift(p, n, error);
        uint64_t rays = 0;
        struct ao_vec3 sum = ao_estimate_surface(&f.ctx, &s, 3, 0, 100000, &rays);
        assert_true(sum.x == 0.0f && sum.y == 0.0f && sum.z == 0.0f);
        assert_true(rays > 0);
    }
    teardown(&f);
}

static void test_ao_distance_limits_occlusion(void **state)
{
    (void)state;
    /* With an AO distance shorter than the gap (the sphere's bottom is at h - r = 0.5 above the
     * ground), nothing occludes: cosine sampling gives exactly rho. */
    struct fixture f;
    setup(&f, PLANE_AND_SPHERE);
    f.ctx.sampling = AO_SAMPLING_COSINE;
    f.ctx.ao_distance = 0.45f;
    struct ao_surface s = ground_point(0.0f);
    uint64_t rays = 0;
    struct ao_vec3 sum = ao_estimate_surface(&f.ctx, &s, 0, 0, 1000, &rays);
    assert_true(sum.x == 1000 * RHO);
    teardown(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_open_plane_gives_rho),
        cmocka_unit_test(test_ground_under_sphere_matches_closed_form),
        cmocka_unit_test(test_inside_closed_sphere_gives_zero),
        cmocka_unit_test(test_ao_distance_limits_occlusion),
    };
    backend = AO_BACKEND_EMBREE;
    int failures = cmocka_run_group_tests_name("embree", tests, NULL, NULL);
    backend = AO_BACKEND_DIRECT;
    return failures + cmocka_run_group_tests_name("direct", tests, NULL, NULL);
}
