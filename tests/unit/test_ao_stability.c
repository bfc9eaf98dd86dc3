/* Stability where the methods could fail: self-intersection at extreme scales and contact occlusion,
 * degenerate meshes, grazing eye rays and silhouettes under AA, long accumulation, and the cost of
 * uniform-sphere sampling. Each test prints its measured figure (docs/stability.md);
 * bounds are derived next to each check; seeds are fixed; random (not Sobol) numbers throughout,
 * so that samples are independent and the standard errors below hold. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "accum.h"
#include "ao.h"
#include "render.h"
#include "render_image.h"
#include "sampling.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

/* A scene and its tracer. */
struct fixture {
    struct ao_scene scene;
    struct ao_tracer *tracer;
};

static void setup_with(struct fixture *f, const char *text, const char *path, enum ao_backend backend)
{
    assert_true(ao_scene_parse(&f->scene, text, path, NULL));
    f->tracer = ao_tracer_create_with(&f->scene, backend);
    assert_non_null(f->tracer);
}

static void setup(struct fixture *f, const char *text, const char *path)
{
    setup_with(f, text, path, AO_BACKEND_AUTO);
}

/* Both back ends, for the tests where rays leave surfaces at their finest: each has its own
 * intersection arithmetic, and the lift must clear both. */
static const enum ao_backend BACKENDS[2] = {AO_BACKEND_DIRECT, AO_BACKEND_EMBREE};

static void teardown(struct fixture *f)
{
    ao_tracer_destroy(f->tracer);
    ao_scene_finish(&f->scene);
}

/* Renders the fixture's scene through the renderer (spppp samples per pass, two threads) and
 * returns a malloc'd copy of the final linear image. */
static float *render_passes(const struct fixture *f, int width, int height, uint32_t spp, uint32_t spppp,
                            enum ao_sampling sampling, bool aa)
{
    struct ao_render_config config = {.scene = &f->scene, .tracer = f->tracer,
                                      .threads = 2, .seed = 9, .target_spp = spp, .ao_distance = INFINITY};
    struct ao_settings settings = {.width = width, .height = height, .sampling = sampling, .aa = aa, .spppp = spppp,
                                   .camera = f->scene.camera};
    float *copy = render_image(&config, &settings);
    return copy;
}

/* render_passes with one sample per pass. */
static float *render(const struct fixture *f, int width, int height, uint32_t spp, enum ao_sampling sampling,
                     bool aa)
{
    return render_passes(f, width, height, spp, 1, sampling, aa);
}

/* The surface aoview shades where the eye ray from `from` towards `to` (local frame) first hits,
 * found and shaded as the renderer does; false on a miss. */
static bool shade(const struct fixture *f, struct ao_vec3 from, struct ao_vec3 to, struct ao_surface *s)
{
    struct ao_vec3 d = ao_vec3_normalize(ao_vec3_sub(to, from));
    struct ao_packet eye = {.org_x = {from.x}, .org_y = {from.y}, .org_z = {from.z}, .dir_x = {d.x},
                            .dir_y = {d.y}, .dir_z = {d.z}, .tfar = {INFINITY}, .count = 1};
    struct ao_hit hit;
    ao_tracer_intersect(f->tracer, &eye, &hit);
    if (hit.t == INFINITY)
        return false;
    ao_surface_from_hit(&f->scene, AO_SHADING_PHONG, from, d, &hit, s);
    return true;
}

/* World point w in the scene's local frame, in double. */
static void to_local(const struct ao_scene *scene, const double w[3], double out[3])
{
    for (int k = 0; k < 3; k++)
        out[k] = w[k] - scene->origin[k];
}

/* A fresh directory for files the scenes load, removed with its files by remove_dir. */
struct temp_dir {
    char path[64];
};

static void make_dir(struct temp_dir *d)
{
    snprintf(d->path, sizeof d->path, "/tmp/aoview-stability-XXXXXX");
    assert_non_null(mkdtemp(d->path));
}

static void write_file(const struct temp_dir *d, const char *name, const char *text)
{
    char path[128];
    snprintf(path, sizeof path, "%s/%s", d->path, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_true(fputs(text, f) >= 0);
    assert_int_equal(fclose(f), 0);
}

static void remove_dir(const struct temp_dir *d, const char *file)
{
    char path[128];
    snprintf(path, sizeof path, "%s/%s", d->path, file);
    assert_int_equal(unlink(path), 0);
    assert_int_equal(rmdir(d->path), 0);
}

/* ------------------------------------------------------------------ self-intersection */

/* One large triangle in a tilted plane through the origin, spanned by U and V (normal U x V). */
static const struct ao_vec3 U = {1.0f, 0.3f, -0.2f}, V = {-0.25f, 1.0f, 0.4f};
static const char TILTED_TRIANGLE[] = "v -7.5 -13 -2\n"       /* -10 U - 10 V */
                                      "v 32.5 -1 -10\n"        /*  30 U - 10 V */
                                      "v -17.5 27 14\n"        /* -10 U + 30 V */
                                      "f 1 2 3\n";

static void test_open_plane_at_any_scale_has_no_acne(void **state)
{
    (void)state;
    /* The tilted triangle, scaled by s and translated by T = (t, t, t), seen obliquely from 5 s
     * above its plane so that it fills the view. Nothing can occlude a lone plane, and cosine
     * sampling weighs every open direction exactly 1, so each pass adds exactly rho to a pixel; the
     * double sums of rho over 256 passes are exact and so is their mean. Any pixel below rho is a
     * self-hit (acne); any at the background (0.25) a miss. Bound: exactly rho everywhere. At
     * t = 0 the plane passes through the origin and stays where it is; translated, it is stored
     * about its own centre (scene.h). The camera is placed in double. */
    struct temp_dir dir;
    make_dir(&dir);
    write_file(&dir, "plane.obj", TILTED_TRIANGLE);
    char path[128];
    snprintf(path, sizeof path, "%s/plane.scene", dir.path);
    const double scales[] = {1e-3, 1.0, 1e3}, shifts[] = {0.0, 1e4, 1e6};
    const float rho = 0.7f;
    struct ao_vec3 n = ao_vec3_normalize(ao_vec3_cross(U, V));
    enum { W = 32, H = 24, SPP = 256 };
    for (int b = 0; b < 6; b++)
        for (int k = 0; k < 3; k++) {
            int j = b % 3;
            double s = scales[k], t = shifts[j], eye[3], target[3];
            const float *nn = &n.x, *u = &U.x, *v = &V.x;
            for (int a = 0; a < 3; a++) {
                eye[a] = t + s * (5.0 * nn[a] + 2.0 * u[a]);
                target[a] = t + s * 0.5 * v[a];
            }
            char text[512];
            snprintf(text, sizeof text,
                     "camera eye %.17g %.17g %.17g target %.17g %.17g %.17g up 0 1 0 fov 40\nbackground 0.25\n"
                     "mesh plane.obj albedo %.9g scale %.17g translate %.17g %.17g %.17g\n",
                     eye[0], eye[1], eye[2], target[0], target[1], target[2], (double)rho, s, t, t, t);
            struct fixture f;
            setup_with(&f, text, path, BACKENDS[b / 3]);
            float *rgb = render(&f, W, H, SPP, AO_SAMPLING_COSINE, true);
            int acne = 0, missed = 0;
            float lowest = rho;
            for (int p = 0; p < W * H; p++) {
                acne += rgb[3 * p] < rho && rgb[3 * p] != 0.25f;
                missed += rgb[3 * p] == 0.25f;
                lowest = fminf(lowest, rgb[3 * p]);
            }
            print_message("plane at %g, scale %g, %s: %d of %d pixels below rho (lowest %.6f, %d missed), %d "
                          "samples each\n", t, s, ao_tracer_backend(f.tracer), acne, W * H, (double)lowest, missed,
                          SPP);
            assert_int_equal(acne, 0);
            assert_int_equal(missed, 0);
            for (int p = 0; p < 3 * W * H; p++)
                assert_true(rgb[p] == rho);
            free(rgb);
            teardown(&f);
        }
    remove_dir(&dir, "plane.obj");
}

static void test_contact_occlusion_is_kept(void **state)
{
    (void)state;
    /* A sphere of radius r resting on a ground quad, placed at the origin and far from it. A ground
     * point at distance x from the contact, d = sqrt(x^2 + r^2) from the centre, has AO rho (1 - F0)
     * with F0 = r^3 / d^3 (the form factor of a sphere wholly above it). The point is found and
     * shaded as the renderer does (an eye ray, grazing at tan = x / r so that it passes under the
     * sphere, which needs tan <= 2 x / r); its occlusion rays start delta above the recomputed
     * point (ao_surface_lift), where the sphere's lower surface is g = r - sqrt(r^2 - x^2) above
     * the ground.
     * - The origin is outside the sphere at every x >= 0.001 r: checked in double.
     * - Contact occlusion is never lost: a point lifted by delta sees the sphere (centre now
     *   u = r - delta above it) at least as much as F(u) = r^2 u / (x^2 + u^2)^(3/2) (the signed
     *   form factor, which counts the part dipping below its horizon negatively), and dF/du < 0
     *   for x^2 < 2 u^2, true for every x <= r here: so the estimate's mean is at most the exact
     *   AO. Bound: mean <= exact + 4 standard errors, where with cosine sampling each sample is rho
     *   with probability q = 1 - F0 and 0 otherwise: standard error rho sqrt(q (1-q) / N).
     * - Nor is it darker than the lift explains: to first order in delta the occlusion grows by
     *   -F'(r) delta = delta r^2 (2 r^2 - x^2) / (x^2 + r^2)^(5/2) <= 2 delta / r; the part below
     *   the horizon is second order. Bound: |mean - exact| <= 4 standard errors + 1.25 rho times
     *   that term. (At x = 0.001 r, q = 1.5e-6: N = 10^6 samples see about 1.5 open rays, so there
     *   the geometric check carries the weight.) */
    enum { N = 1000000 };
    static const struct {
        double radius, shift;
    } cases[] = {{0.5, 0.0}, {500.0, 1e4}, {1.0, 1e4}, {1.0, 1e6}};
    const double fractions[] = {0.001, 0.003, 0.01, 0.03, 0.1, 0.3, 1.0}, rho = 0.8;
    for (int c = 0; c < 8; c++) {
        double r = cases[c % 4].radius, t = cases[c % 4].shift, w = 20 * r;
        char text[1024];
        snprintf(text, sizeof text,
                 "camera eye %.17g %.17g %.17g target %.17g %.17g %.17g\n"
                 "quad corner %.17g %.17g %.17g edge1 0 0 %.17g edge2 %.17g 0 0 albedo 0.8\n"
                 "sphere center %.17g %.17g %.17g radius %.17g albedo 0.8\n",
                 t, t + 6 * r, t + 6 * r, t, t, t, t - w, t, t - w, 2 * w, 2 * w, t, t + r, t, r);
        struct fixture f;
        setup_with(&f, text, "contact.scene", BACKENDS[c / 4]);
        struct ao_context ctx = {.scene = &f.scene, .tracer = f.tracer, .sampling = AO_SAMPLING_COSINE,
                                 .ao_distance = INFINITY, .seed = 17};
        double contact[3], center[3];
        to_local(&f.scene, (const double[3]){t, t, t}, contact);
        to_local(&f.scene, (const double[3]){t, t + r, t}, center);
        for (int k = 0; k < 7; k++) {
            double x0 = fractions[k] * r;
            struct ao_vec3 to = ao_vec3_make((float)(contact[0] + x0), (float)contact[1], (float)contact[2]);
            struct ao_vec3 from = ao_vec3_add(to, ao_vec3_make((float)(2 * r), (float)(2 * x0), 0));
            struct ao_surface surface;
            assert_true(shade(&f, from, to, &surface));
            surface.albedo = ao_vec3_make((float)rho, (float)rho, (float)rho);
            uint64_t rays = 0;
            double mean = ao_estimate_surface(&ctx, &surface, (uint64_t)k, 0, N, &rays).x / N;
            double o[3] = {surface.origin.x - center[0], surface.origin.y - center[1], surface.origin.z - center[2]};
            double x = hypot(surface.position.x - contact[0], surface.position.z - contact[2]);
            double delta = surface.origin.y - contact[1], d2 = x * x + r * r;
            double q = 1.0 - r * r * r / (d2 * sqrt(d2)), expected = rho * q;
            double se = rho * sqrt(q * (1.0 - q) / N), gap = x < r ? r - sqrt(r * r - x * x) : r;
            double first_order = delta * r * r * (2.0 * r * r - x * x) / (d2 * d2 * sqrt(d2));
            bool outside = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] > r * r;
            print_message("contact, r %g at %g, %s: x/r = %.3f AO %.7f, exact %.7f (%+.1f se); lift %.2g r, gap %.2g r%s\n",
                          r, t, ao_tracer_backend(f.tracer), x / r, mean, expected, (mean - expected) / se, delta / r,
                          gap / r, outside ? "" : ": origin in the sphere");
            assert_true(outside);
            assert_true(mean <= expected + 4.0 * se);
            assert_true(fabs(mean - expected) <= 4.0 * se + 1.25 * rho * first_order);
        }
        teardown(&f);
    }
}

/* Probability that a binomial(n, p) count lies at least as far from its mean as k, on k's side
 * (the one-sided tail), summed outward from k until the terms no longer count. */
static double binomial_tail(int n, double p, int k)
{
    if (p <= 0.0 || p >= 1.0)
        return (double)k == n * p ? 1.0 : 0.0;
    int step = k < n * p ? -1 : 1;
    double log_norm = lgamma(n + 1.0), sum = 0.0;
    for (int j = k; j >= 0 && j <= n; j += step) {
        double term = exp(log_norm - lgamma(j + 1.0) - lgamma(n - j + 1.0) + j * log(p) + (n - j) * log1p(-p));
        sum += term;
        if (term < 1e-17 * sum)
            break;
    }
    return fmin(1.0, sum);
}

/* The z of a one-sided normal tail of probability p (bisection on erfc). */
static double tail_z(double p)
{
    double lo = 0.0, hi = 40.0;
    for (int i = 0; i < 100; i++) {
        double mid = 0.5 * (lo + hi);
        if (0.5 * erfc(mid / sqrt(2.0)) > p)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

static void test_sphere_on_ground_matches_the_closed_form_anywhere(void **state)
{
    (void)state;
    /* A sphere of radius 1 resting on a ground quad of +-2e4, placed at the origin, at (1e4, 1e4,
     * 1e4) and at (1e6, 1e6, 1e6); cosine sampling, 2048 samples, no AA, 96x72 pixels. Without AA
     * each pixel shades one point, the one found here as the renderer finds it, and with cosine
     * sampling its value is rho K / N with K ~ binomial(N, q), q the open fraction in closed form
     * (aoview-exact's): on the ground 1 - r^2 h / d^3 (h = r, d the distance to the centre), on
     * the sphere (1 + n.N) / 2 for an infinite ground (this one changes it by less than 6.4e-5,
     * exact.c's bound). Bounds: each pixel's count within its binomial 5-sigma tails (one-sided
     * probability 2.9e-7; over about 6,800 pixels a false alarm has probability 0.004), exact tails
     * rather than a normal approximation since occlusion is rare over most of the ground; and the
     * mean error over the pixels, whose standard error is sqrt(sum of rho^2 q (1-q) / N) / pixels
     * (independent pixels), within 4 of those. */
    enum { W = 96, H = 72, N = 2048 };
    const double shifts[] = {0.0, 1e4, 1e6}, rho = 0.8, r = 1.0;
    for (int c = 0; c < 6; c++) {
        double t = shifts[c % 3];
        char text[1024];
        snprintf(text, sizeof text,
                 "camera eye %.17g %.17g %.17g target %.17g %.17g %.17g fov 40\n"
                 "quad corner %.17g %.17g %.17g edge1 0 0 4e4 edge2 4e4 0 0 albedo 0.8\n"
                 "sphere center %.17g %.17g %.17g radius 1 albedo 0.8\n",
                 t, t + 3.2, t + 6.4, t, t + 0.7, t, t - 2e4, t, t - 2e4, t, t + r, t);
        struct fixture f;
        setup_with(&f, text, "sphere-on-ground.scene", BACKENDS[c / 3]);
        float *rgb = render_passes(&f, W, H, N, 64, AO_SAMPLING_COSINE, false);
        struct ao_view view;
        assert_true(ao_camera_view(&f.scene.camera, W, H, &view));
        double center[3];
        to_local(&f.scene, (const double[3]){t, t + r, t}, center);
        int pixels = 0, worst_i = 0, worst_j = 0;
        double worst_z = 0.0, sum_error = 0.0, sum_variance = 0.0, worst_value = 0.0, worst_exact = 0.0;
        for (int j = 0; j < H; j++)
            for (int i = 0; i < W; i++) {
                struct ao_surface s;
                struct ao_vec3 d = ao_camera_ray(&view, (float)i + 0.5f, (float)j + 0.5f);
                if (!shade(&f, view.eye, ao_vec3_add(view.eye, d), &s))
                    continue;
                double to_c[3] = {center[0] - s.position.x, center[1] - s.position.y, center[2] - s.position.z};
                double q;
                if (s.ng.y > 0.99f && s.position.y < center[1] - 0.5 * r) { /* the ground */
                    double dist = sqrt(to_c[0] * to_c[0] + to_c[1] * to_c[1] + to_c[2] * to_c[2]);
                    q = 1.0 - r * r * r / (dist * dist * dist);
                } else {
                    q = 0.5 * (1.0 + (double)s.ns.y);
                }
                double value = rgb[3 * (j * W + i)], expected = rho * q;
                int k = (int)lround(value * N / rho);
                double z = tail_z(binomial_tail(N, q, k));
                if (z > worst_z)
                    worst_z = z, worst_i = i, worst_j = j, worst_value = value, worst_exact = expected;
                pixels++;
                sum_error += value - expected;
                sum_variance += rho * rho * q * (1.0 - q) / N;
            }
        double bias = sum_error / pixels, tstat = sum_error / sqrt(sum_variance);
        print_message("sphere on ground at %g (local origin %g), %s: %d pixels, worst |z| %.2f at (%d, %d): %.5f "
                      "against %.5f; mean bias %+.7f (t %+.2f)\n", t, f.scene.origin[0], ao_tracer_backend(f.tracer),
                      pixels, worst_z, worst_i, worst_j, worst_value, worst_exact, bias, tstat);
        assert_true(pixels > W * H / 2);
        assert_true(worst_z <= 5.0);
        assert_true(fabs(tstat) < 4.0);
        free(rgb);
        teardown(&f);
    }
}

/* The source tree, where the bunny is; the test is skipped without it. */
static const char *bunny_root(void)
{
    const char *root = getenv("AO_SOURCE_ROOT");
    if (!root) {
        print_message("AO_SOURCE_ROOT is not set (run it through meson test): no bunny to load\n");
        skip();
    }
    return root;
}

static void test_default_scene_renders_the_same_far_from_the_origin(void **state)
{
    (void)state;
    /* The default scene (the bunny on its ground quad) as shipped and moved by (1e6, 1e6, 1e6):
     * camera, mesh translation and quad shifted in the scene text, the same seed. Stored about
     * its own centre, the far scene's local coordinates differ from the near one's only by that
     * centre's offset, so hit points and occlusion rays differ by float rounding, and a sample can
     * change only where a ray passes within rounding of an edge or silhouette: the images must
     * agree but for a few values. Bound: at most 0.1 % of the values differ. (Placed in world
     * floats, where 1e6 is good to 0.06, 62 % of the values differed, by up to 0.68, at 160x120
     * and 256 samples.) */
    const char *root = bunny_root();
    enum { W = 80, H = 60, SPP = 64 };
    float *rgb[2];
    for (int k = 0; k < 2; k++) {
        double t = k ? 1e6 : 0.0;
        char text[4096];
        snprintf(text, sizeof text,
                 "camera eye %.17g %.17g %.17g target %.17g %.17g %.17g up 0 1 0 fov 35\nbackground 1\n"
                 "mesh %s/assets/bunny.obj albedo 0.8 0.75 0.7 scale 0.1 translate %.17g %.17g %.17g\n"
                 "quad corner %.17g %.17g %.17g edge1 0 0 100 edge2 100 0 0 albedo 0.8\n",
                 t + 0.5, t + 1.0, t + 2.5, t, t + 0.42, t, root, t, t + 0.0003, t, t - 50, t, t - 50);
        struct fixture f;
        setup(&f, text, "bunny-far.scene");
        rgb[k] = render_passes(&f, W, H, SPP, 16, AO_SAMPLING_COSINE, true);
        teardown(&f);
    }
    int differ = 0;
    double largest = 0.0;
    for (int p = 0; p < 3 * W * H; p++) {
        differ += rgb[0][p] != rgb[1][p];
        largest = fmax(largest, fabs((double)rgb[0][p] - rgb[1][p]));
    }
    print_message("default scene at 1e6 against the origin: %d of %d values differ (largest %.4f)\n", differ,
                  3 * W * H, largest);
    assert_true(differ * 1000 <= 3 * W * H);
    free(rgb[0]);
    free(rgb[1]);
}

static void test_camera_moves_hold_far_from_the_origin(void **state)
{
    (void)state;
    /* The viewer's moves on a scene at (1e6, 1e6, 1e6), whose camera lives in the scene's local
     * frame: a full orbit in 64 yaw steps, a pan there and back, a zoom in and out. In world
     * floats the eye could not be placed closer than 0.0625 (the spacing of floats at 1e6), 1 % of
     * the eye's distance of 6.3. Here each step rounds at float precision of that distance: the
     * orbit's inverse and forward trigonometry move the eye by a few ulps of it, about 1e-6 of the
     * distance per step, so 64 steps stay within 1e-5 of it even if every error adds up; the pan
     * and the zoom take two steps each. Bound: 1e-5 of the distance. */
    const double t = 1e6;
    char text[512];
    snprintf(text, sizeof text, "camera eye %.17g %.17g %.17g target %.17g %.17g %.17g\n"
             "sphere center %.17g %.17g %.17g radius 1\n", t, t + 3.0, t + 5.8, t, t + 0.5, t, t, t + 1, t);
    struct fixture f;
    setup(&f, text, "far-camera.scene");
    struct ao_camera c = f.scene.camera;
    const struct ao_camera start = c;
    float distance = ao_vec3_length(ao_vec3_sub(c.eye, c.target));
    for (int k = 0; k < 64; k++)
        ao_camera_orbit(&c, 6.283185307179586f / 64.0f, 0.0f);
    float orbit = ao_vec3_length(ao_vec3_sub(c.eye, start.eye));
    c = start;
    ao_camera_pan(&c, 0.3f, -0.2f);
    ao_camera_pan(&c, -0.3f, 0.2f);
    float pan = fmaxf(ao_vec3_length(ao_vec3_sub(c.eye, start.eye)), ao_vec3_length(ao_vec3_sub(c.target, start.target)));
    c = start;
    ao_camera_zoom(&c, 0.5f);
    ao_camera_zoom(&c, 2.0f);
    float zoom = ao_vec3_length(ao_vec3_sub(c.eye, start.eye));
    print_message("camera at 1e6, eye %.2f from the target: full orbit off by %.2g, pan there and back %.2g, "
                  "zoom in and out %.2g (world floats: 0.0625 per coordinate)\n", (double)distance, (double)orbit,
                  (double)pan, (double)zoom);
    assert_true(orbit <= 1e-5f * distance && pan <= 1e-5f * distance && zoom <= 1e-5f * distance);
    teardown(&f);
}

/* ------------------------------------------------------------------ the range of sizes */

/* The scene of test_scenes_at_the_ends_of_the_size_range_render_as_at_size_1, scaled by 2^k:
 * kind 0 a sphere of radius 1 on a ground quad 2^15 wide, kind 1 the default scene (bunny) on a
 * ground quad 2^7 wide; both 2^(15 + k) or 2^(7 + k) across. */
static void scaled_scene(char *text, size_t size, int kind, int k, const char *root)
{
    double s = ldexp(1.0, k);
    if (kind == 0)
        snprintf(text, size, "camera eye 0 %.17g %.17g target 0 %.17g 0 fov 40\n"
                 "quad corner %.17g 0 %.17g edge1 0 0 %.17g edge2 %.17g 0 0 albedo 0.8\n"
                 "sphere center 0 %.17g 0 radius %.17g albedo 0.8\n",
                 3.2 * s, 6.4 * s, 0.7 * s, -16384 * s, -16384 * s, 32768 * s, 32768 * s, s, s);
    else
        snprintf(text, size, "camera eye %.17g %.17g %.17g target 0 %.17g 0 up 0 1 0 fov 35\nbackground 1\n"
                 "mesh %s/assets/bunny.obj albedo 0.8 0.75 0.7 scale %.17g translate 0 %.17g 0\n"
                 "quad corner %.17g 0 %.17g edge1 0 0 %.17g edge2 %.17g 0 0 albedo 0.8\n",
                 0.5 * s, 1.0 * s, 2.5 * s, 0.42 * s, root, 0.1 * s, 0.0003 * s, -64 * s, -64 * s, 128 * s, 128 * s);
}

static void test_scenes_at_the_ends_of_the_size_range_render_as_at_size_1(void **state)
{
    (void)state;
    /* A sphere on a ground quad (both back ends) and the default scene (Embree), scaled by powers
     * of two to the smallest and the largest size scene_place.c accepts (AO_SCENE_MIN_EXTENT and
     * _MAX_EXTENT across), against the same scene at its own size; same seed. Scaling by 2^k
     * multiplies every coordinate, product and comparison of the tracer and the estimator by an
     * exact power of two while nothing over- or underflows, which is what the range is derived to
     * ensure, so the images must agree; the one absolute length in the arithmetic, the lift's floor
     * of 2^-100 on the ground plane, can only change a sample whose ray passes within it of a
     * surface. Bound: at most 0.1 % of the values differ (as test_default_scene_renders_the_same_
     * far_from_the_origin). Measured beyond the range, the scene scaled after loading
     * (docs/stability.md): the sphere's ground, a quarter of the smallest size across, occludes
     * itself (90.6 % of the values differ, mean 0.049 against 0.731); at twice the largest size the
     * normals overflow (90.2 %, mean 0.513). And one step outside the range, the scene is refused. */
    const char *root = bunny_root();
    enum { W = 64, H = 48, SPP = 32 };
    static const struct {
        int kind, log2_size;   /* the scene at 2^log2_size across */
        enum ao_backend backend;
    } cases[] = {{0, 15, AO_BACKEND_DIRECT}, {0, 15, AO_BACKEND_EMBREE}, {1, 7, AO_BACKEND_EMBREE}};
    const int min_log2 = ilogb(AO_SCENE_MIN_EXTENT), max_log2 = ilogb(AO_SCENE_MAX_EXTENT);
    char text[4096];
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        struct fixture f;
        scaled_scene(text, sizeof text, cases[c].kind, 0, root);
        setup_with(&f, text, "sized.scene", cases[c].backend);
        float *at_own_size = render_passes(&f, W, H, SPP, 16, AO_SAMPLING_COSINE, true);
        teardown(&f);
        for (int end = 0; end < 2; end++) {
            int k = (end ? max_log2 : min_log2) - cases[c].log2_size;
            scaled_scene(text, sizeof text, cases[c].kind, k, root);
            setup_with(&f, text, "sized.scene", cases[c].backend);
            float *rgb = render_passes(&f, W, H, SPP, 16, AO_SAMPLING_COSINE, true);
            int differ = 0;
            for (int p = 0; p < 3 * W * H; p++)
                differ += rgb[p] != at_own_size[p];
            print_message("%s, %s, %g across: %d of %d values differ from the scene at its own size\n",
                          cases[c].kind ? "default scene" : "sphere on ground", ao_tracer_backend(f.tracer),
                          ldexp(1.0, cases[c].log2_size + k), differ, 3 * W * H);
            assert_true(differ * 1000 <= 3 * W * H);
            free(rgb);
            teardown(&f);
            /* One step further out: refused. */
            scaled_scene(text, sizeof text, cases[c].kind, end ? k + 1 : k - 1, root);
            struct ao_scene refused;
            assert_false(ao_scene_parse(&refused, text, "sized.scene", NULL));
        }
        free(at_own_size);
    }
}

/* Embree asserts (and aborts) on a ray from beyond 1.844e18. Scenes are refused long before; the
 * viewer's zoom and pan stop at 2^48 from the origin, and an orbit there keeps the eye within 3
 * times that: 20,000 wheel steps out and pans of a hundred views each leave the eye and target
 * within reach, and the eye rays from there trace (the ground still answers). */
static void test_moves_keep_the_eye_within_embrees_range(void **state)
{
    (void)state;
    struct fixture f;
    setup_with(&f, "camera eye 0 1 4 target 0 0 0\nquad corner -1 0 -1 edge1 0 0 2 edge2 2 0 0\n", "far-eye.scene",
               AO_BACKEND_EMBREE);
    struct ao_camera c = f.scene.camera;
    for (int k = 0; k < 20000; k++) {
        ao_camera_zoom(&c, 1.0f / 0.85f);
        ao_camera_pan(&c, 100.0f, -100.0f);
        ao_camera_orbit(&c, 0.3f, 0.1f);
    }
    const float reach = 3.0f * 0x1p48f;
    assert_true(fabsf(c.eye.x) <= reach && fabsf(c.eye.y) <= reach && fabsf(c.eye.z) <= reach);
    assert_true(fabsf(c.target.x) <= 0x1p48f && fabsf(c.target.y) <= 0x1p48f && fabsf(c.target.z) <= 0x1p48f);
    assert_true(ao_vec3_length(ao_vec3_sub(c.eye, c.target)) > 0x1p40f); /* the moves did take it far */
    /* Back towards the quad: an eye ray from high above the origin straight down hits it. */
    struct ao_packet eye = {.org_x = {0}, .org_y = {c.eye.y > 0 ? fabsf(c.eye.y) : 0x1p48f}, .org_z = {0},
                            .dir_x = {0}, .dir_y = {-1}, .dir_z = {0}, .tfar = {INFINITY}, .count = 1};
    struct ao_hit hit;
    ao_tracer_intersect(f.tracer, &eye, &hit);
    assert_true(isfinite(hit.t));
    teardown(&f);
}

/* ------------------------------------------------------------------ degenerate geometry */

/* Zero-area triangles (collinear, repeated index, duplicate vertices), zero-length vertex normals,
 * normals that cancel, and a sliver whose geometric normal underflows in single precision, next to
 * one sound triangle; all on a ground quad. */
static const char DEGENERATE_OBJ[] = "v 0 0 0\n"
                                     "v 1 0 0\n"
                                     "v 0 1 0\n"
                                     "v 1 0 0\n"            /* 4: duplicate of 2 */
                                     "v 2 0 0\n"            /* 5: collinear with 1 and 2 */
                                     "v 0 1 0\n"            /* 6: duplicate of 3 */
                                     "v 0.5 1e-30 0\n"      /* 7: apex of a sliver */
                                     "v 1 1 0\n"
                                     "vn 0 0 0\n"           /* 1: zero length */
                                     "vn 0 0 1\n"
                                     "vn 0 0 -1\n"          /* 3: cancels 2 */
                                     "f 1//1 2//1 3//1\n"   /* zero-length normals on every corner */
                                     "f 2//2 4//2 8//2\n"   /* duplicate vertex: zero area */
                                     "f 1 2 5\n"            /* collinear: zero area */
                                     "f 1 1 3\n"            /* repeated index: zero area */
                                     "f 3//2 6//3 8//2\n"   /* duplicate position: zero area */
                                     "f 1//2 2//3 7//1\n"   /* sliver, normals that cancel */
                                     "f 2//2 8//3 3//2\n";  /* normals that cancel on an edge */

static void test_degenerate_geometry_gives_no_nan(void **state)
{
    (void)state;
    /* Every pixel of every sampler, with and without AA, from the front and edge-on (the eye in
     * the triangles' plane, so eye rays graze them), must be finite and within [0, w rho]: one
     * sample weighs at most w = 4 (uniform sphere), 2 (hemisphere) or 1 (cosine), albedos are at
     * most 1, and so is the background. */
    const float largest[3] = {4.0f, 2.0f, 1.0f};
    struct temp_dir dir;
    make_dir(&dir);
    write_file(&dir, "degenerate.obj", DEGENERATE_OBJ);
    char path[128];
    snprintf(path, sizeof path, "%s/degenerate.scene", dir.path);
    static const char *const cameras[] = {"camera eye 0.6 0.5 2 target 0.5 0.4 0\n",
                                          "camera eye 3 0.4 0 target 0.5 0.4 0\n"};
    enum { W = 24, H = 24 };
    for (int c = 0; c < 2; c++) {
        char text[512];
        snprintf(text, sizeof text, "%smesh degenerate.obj translate 0 0.2 0\n"
                 "quad corner -5 0 -5 edge1 0 0 10 edge2 10 0 0\n", cameras[c]);
        struct fixture f;
        setup(&f, text, path);
        int bad = 0;
        for (int mode = 0; mode < 3; mode++)
            for (int aa = 0; aa < 2; aa++) {
                float *rgb = render(&f, W, H, 16, (enum ao_sampling)mode, aa);
                for (int p = 0; p < 3 * W * H; p++)
                    bad += !(rgb[p] >= 0.0f && rgb[p] <= largest[mode]);
                free(rgb);
            }
        print_message("degenerate mesh, %s: %zu zero-area triangles skipped, %zu kept; %d of %d pixel values "
                      "not finite in [0, w] over 3 samplers x AA on/off\n", c ? "edge-on" : "front",
                      f.scene.degenerate_count, f.scene.triangle_count - 2, bad, 6 * 3 * W * H);
        assert_true(f.scene.degenerate_count >= 4);
        assert_int_equal(bad, 0);
        teardown(&f);
    }
    remove_dir(&dir, "degenerate.obj");
}

/* ------------------------------------------------------------------ silhouettes */

/* Fraction of pixel (i, j) whose eye rays hit the sphere: for each of `rows` sub-rows (midpoints),
 * the rays that hit form an interval of the image-plane coordinate, the roots of a quadratic; its
 * overlap with the pixel is summed. Double precision throughout. */
static double coverage(const struct ao_view *v, const struct ao_sphere *sp, int i, int j, int rows)
{
    double oc[3] = {(double)sp->center.x - v->eye.x, (double)sp->center.y - v->eye.y,
                    (double)sp->center.z - v->eye.z};
    double r2 = (double)sp->radius * sp->radius, k = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - r2;
    double a = v->right.x * oc[0] + v->right.y * oc[1] + v->right.z * oc[2];
    double uo = v->up.x * oc[0] + v->up.y * oc[1] + v->up.z * oc[2];
    double fo = v->forward.x * oc[0] + v->forward.y * oc[1] + v->forward.z * oc[2];
    double tx = (double)v->tan_half_fov * v->aspect, covered = 0.0;
    for (int row = 0; row < rows; row++) {
        /* Direction sx right + sy up + forward hits when (a sx + b)^2 >= (sx^2 + sy^2 + 1) k. */
        double y = j + (row + 0.5) / rows, sy = (1.0 - 2.0 * y / v->height) * v->tan_half_fov;
        double b = sy * uo + fo, qa = a * a - k, qb = 2.0 * a * b, qc = b * b - (sy * sy + 1.0) * k;
        double disc = qb * qb - 4.0 * qa * qc;
        if (disc <= 0.0)
            continue;
        double s0 = (-qb + sqrt(disc)) / (2.0 * qa), s1 = (-qb - sqrt(disc)) / (2.0 * qa);
        double x0 = (fmin(s0, s1) / tx + 1.0) * v->width / 2.0, x1 = (fmax(s0, s1) / tx + 1.0) * v->width / 2.0;
        covered += fmax(0.0, fmin(x1, i + 1.0) - fmax(x0, (double)i));
    }
    return covered / rows;
}

static void test_silhouettes_converge_to_the_box_filter(void **state)
{
    (void)state;
    /* A lone sphere (albedo rho) over a background b: no point of it is occluded, so with cosine
     * sampling each pass gives a pixel exactly rho where its jittered eye ray hits and b where it
     * misses. With AA the mean of P passes estimates rho c + b (1 - c), c the pixel's covered
     * fraction (coverage() above, whose midpoint rule over 4096 rows errs by O(4096^-1.5) ~ 4e-6
     * where a row is tangent), with standard error |rho - b| sqrt(c (1-c) / P). Bounds, over the
     * silhouette pixels (0 < c < 1): each within 5 standard errors where the binomial count is
     * near normal (P c (1-c) >= 25; Bonferroni over < 100 pixels: 100 x 5.7e-7), and the sum of
     * all their errors within 4 standard errors of the sum (independent pixels). Any grazing
     * self-hit or NaN shows as a value off that lattice of rho and b. Without AA the same pixels
     * are all or nothing; their RMS error against the box filter is printed for contrast. */
    static const char SCENE[] = "camera eye 0 0 4 target 0 0 0 fov 30\nbackground 0.2\n"
                                "sphere center 0.13 -0.07 0 radius 0.6 albedo 0.8\n";
    enum { W = 32, H = 32, P = 4096, ROWS = 4096 };
    const double rho = 0.8, b = 0.2;
    struct fixture f;
    setup(&f, SCENE, "silhouette.scene");
    struct ao_view view;
    assert_true(ao_camera_view(&f.scene.camera, W, H, &view));
    float *aa = render(&f, W, H, P, AO_SAMPLING_COSINE, true);
    float *no_aa = render(&f, W, H, 1, AO_SAMPLING_COSINE, false);
    int edge = 0;
    double max_z = 0.0, sum_error = 0.0, sum_variance = 0.0, no_aa_sq = 0.0;
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            int p = j * W + i;
            assert_true(isfinite(aa[3 * p]) && isfinite(no_aa[3 * p]));
            double c = coverage(&view, &f.scene.spheres[0], i, j, ROWS);
            double expected = rho * c + b * (1.0 - c), error = aa[3 * p] - expected;
            if (c <= 0.0 || c >= 1.0) {
                assert_true(fabs(error) < 1e-6);
                continue;
            }
            double variance = (rho - b) * (rho - b) * c * (1.0 - c) / P;
            edge++;
            sum_error += error;
            sum_variance += variance;
            no_aa_sq += (no_aa[3 * p] - expected) * (no_aa[3 * p] - expected);
            if (P * c * (1.0 - c) >= 25.0) {
                max_z = fmax(max_z, fabs(error) / sqrt(variance));
                assert_true(fabs(error) <= 5.0 * sqrt(variance));
            }
        }
    print_message("silhouette: %d edge pixels, AA %d passes: largest |z| %.2f, summed error %+.2f se, RMS "
                  "error %.4f; without AA %.4f\n", edge, P, max_z, sum_error / sqrt(sum_variance),
                  sqrt(sum_variance / edge), sqrt(no_aa_sq / edge));
    assert_true(edge > 40);
    assert_true(fabs(sum_error) <= 4.0 * sqrt(sum_variance));
    free(aa);
    free(no_aa);
    teardown(&f);
}

/* ------------------------------------------------------------------ long accumulation */

static void test_long_accumulation_resolves_exactly(void **state)
{
    (void)state;
    /* 10^6 passes adding the constant c to one pixel. A float c has a 24-bit significand, so every
     * partial sum k c (k <= 10^6 < 2^20) needs at most 44 bits and is exact in a double; the
     * quotient (10^6 c) / 10^6 is then c exactly. Bound: exact equality. A float32 sum is not
     * exact: each addition rounds c to a multiple of the sum's ulp, which grows with the sum (2^-7
     * from 2^16 on, 2^-4 from 2^19), so c is added as a rounded value over long stretches: 0.1f as
     * 13/128 = 0.1016 while the sum is in [2^16, 2^17), 0.7f as 11/16 = 0.6875 in [2^19, 2^20).
     * The mean drifts by about 1 %; the test computes the float32 mean and prints it (+0.96 % for
     * 0.1, -1.00 % for 0.7, +0.15 % for 1/3). */
    enum { PASSES = 1000000 };
    struct ao_accum a;
    assert_true(ao_accum_init(&a, 1, 1));
    struct ao_vec3 c = ao_vec3_make(0.1f, 0.7f, 1.0f / 3.0f);
    float single[3] = {0.0f, 0.0f, 0.0f};
    for (int k = 0; k < PASSES; k++) {
        ao_accum_add(&a, 0, c, 1, false);
        single[0] += c.x;
        single[1] += c.y;
        single[2] += c.z;
    }
    float rgb[3];
    ao_accum_resolve(&a, rgb);
    const float *exact = &c.x;
    for (int k = 0; k < 3; k++) {
        float drift = single[k] / (float)PASSES;
        print_message("accumulation of 10^6 x %.9g: double sums resolve to %.9g; float32 sums give %.9g "
                      "(off by %+.3g, %+.2f %%)\n", (double)exact[k], (double)rgb[k], (double)drift,
                      (double)(drift - exact[k]), 100.0 * (double)(drift - exact[k]) / (double)exact[k]);
        assert_true(rgb[k] == exact[k]);
    }
    ao_accum_finish(&a);
}

/* ------------------------------------------------------------------ uniform-sphere cost */

static void test_uniform_sphere_variance_is_five_times_the_hemisphere(void **state)
{
    (void)state;
    /* On an open plane one sample weighs 4 max(0, cos) (uniform sphere) or 2 cos (hemisphere), with
     * per-sample variances 5/3 and 1/3 (rho = 1): ratio 5, the price of drawing half the
     * directions below the surface. Over N = 10^6 independent samples each (different pixel
     * streams), the variances' standard errors are sqrt((mu4 - sigma^4) / N) = 0.00196 and
     * 0.00030 (moments E X^k = 4^k / (2 (k+1)) and 2^k / (k+1)), relative 1.18e-3 and 0.90e-3, so
     * the ratio's relative standard error is their root sum of squares, 1.48e-3: 4 of those allow
     * |ratio - 5| < 0.030. */
    enum { N = 1000000 };
    struct fixture f;
    setup(&f, "camera eye 0 5 5 target 0 0 0\nquad corner -1e4 0 -1e4 edge1 0 0 2e4 edge2 2e4 0 0 albedo 1\n",
          "open.scene");
    struct ao_context ctx = {.scene = &f.scene, .tracer = f.tracer, .ao_distance = INFINITY, .seed = 23};
    struct ao_vec3 up = ao_vec3_make(0, 1, 0), p = ao_vec3_make(0.3f, 0, -0.2f);
    struct ao_surface s = {.position = p, .ng = up, .ns = up, .albedo = ao_vec3_make(1, 1, 1)};
    s.origin = ao_surface_lift(p, up, ao_vec3_make(0, 0, 0)); /* exact: the plane is y = 0 */
    double variance[2];
    const enum ao_sampling modes[2] = {AO_SAMPLING_UNIFORM, AO_SAMPLING_HEMISPHERE};
    for (int m = 0; m < 2; m++) {
        ctx.sampling = modes[m];
        double sum = 0.0, sum2 = 0.0;
        uint64_t rays = 0;
        for (int k = 0; k < N; k++) {
            double x = ao_estimate_surface(&ctx, &s, (uint64_t)m, (uint64_t)k, 1, &rays).x;
            sum += x;
            sum2 += x * x;
        }
        double mean = sum / N;
        variance[m] = sum2 / N - mean * mean;
        print_message("open plane, %s, 1 spp: mean %.5f, per-sample variance %.5f\n",
                      ao_sampling_name(modes[m]), mean, variance[m]);
    }
    double ratio = variance[0] / variance[1];
    print_message("uniform / hemisphere variance: %.4f (expected 5, bound 0.030)\n", ratio);
    assert_true(fabs(ratio - 5.0) < 0.030);
    teardown(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_open_plane_at_any_scale_has_no_acne),
        cmocka_unit_test(test_contact_occlusion_is_kept),
        cmocka_unit_test(test_sphere_on_ground_matches_the_closed_form_anywhere),
        cmocka_unit_test(test_default_scene_renders_the_same_far_from_the_origin),
        cmocka_unit_test(test_camera_moves_hold_far_from_the_origin),
        cmocka_unit_test(test_scenes_at_the_ends_of_the_size_range_render_as_at_size_1),
        cmocka_unit_test(test_moves_keep_the_eye_within_embrees_range),
        cmocka_unit_test(test_degenerate_geometry_gives_no_nan),
        cmocka_unit_test(test_silhouettes_converge_to_the_box_filter),
        cmocka_unit_test(test_long_accumulation_resolves_exactly),
        cmocka_unit_test(test_uniform_sphere_variance_is_five_times_the_hemisphere),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
