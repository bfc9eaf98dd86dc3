/* Scenes from arrays (ao_scene_from_arrays, the Python module's Scene.from_arrays) against the
 * scene aoview makes of an OBJ file holding the same arrays: the same meshes, normals, placements and
 * camera, bit for bit; spheres, a given camera and bad arrays; and ao_tracer_intersect_arrays'
 * rays against the mesh, scaled, moved far off and leaving its surface. */
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

#include "scene.h"
#include "scene_load.h"
#include "tracer_arrays.h"

/* A bent strip: two triangles meeting at 90 degrees (sharper than the crease angle), a third
 * flatter one, a degenerate one (dropped by both routes) and a vertex no triangle uses. */
static const float POSITIONS[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 1, 0, 1, 2, 0.2f, 1, 5, 5, 5};
static const uint32_t INDICES[] = {2, 1, 0, 0, 2, 3, 1, 4, 2, 4, 5, 2, 0, 0, 1};
enum { VERTICES = 7, TRIANGLES = 5 };

static void write_obj(const char *path, const float *normals)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    for (int i = 0; i < VERTICES; i++)
        fprintf(f, "v %.9g %.9g %.9g\n", POSITIONS[3 * i], POSITIONS[3 * i + 1], POSITIONS[3 * i + 2]);
    for (int i = 0; normals && i < VERTICES; i++)
        fprintf(f, "vn %.9g %.9g %.9g\n", normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]);
    for (int t = 0; t < TRIANGLES; t++) {
        const uint32_t *v = &INDICES[3 * t];
        if (normals)
            fprintf(f, "f %u//%u %u//%u %u//%u\n", v[0] + 1, v[0] + 1, v[1] + 1, v[1] + 1, v[2] + 1, v[2] + 1);
        else
            fprintf(f, "f %u %u %u\n", v[0] + 1, v[1] + 1, v[2] + 1);
    }
    assert_int_equal(fclose(f), 0);
}

/* The placed triangles' corners and shading normals of both scenes, and their cameras, equal bit for bit. */
static void assert_same_scene(const struct ao_scene *a, const struct ao_scene *b)
{
    assert_int_equal(a->instance_count, b->instance_count);
    assert_int_equal(a->triangle_count, b->triangle_count);
    assert_memory_equal(&a->camera, &b->camera, sizeof a->camera);
    assert_memory_equal(a->origin, b->origin, sizeof a->origin);
    for (size_t i = 0; i < a->instance_count; i++) {
        const struct ao_mesh *ma = &a->meshes[a->instances[i].mesh], *mb = &b->meshes[b->instances[i].mesh];
        assert_int_equal(ma->triangle_count, mb->triangle_count);
        for (size_t t = 0; t < ma->triangle_count; t++) {
            struct ao_vec3 ca[3], cb[3];
            ao_scene_triangle(a, i, t, ca);
            ao_scene_triangle(b, i, t, cb);
            assert_memory_equal(ca, cb, sizeof ca);
            for (int k = 0; k < 3; k++) {
                struct ao_vec3 na = ma->normals[ma->indices[3 * t + k]], nb = mb->normals[mb->indices[3 * t + k]];
                assert_memory_equal(&na, &nb, sizeof na);
            }
        }
        assert_memory_equal(&a->albedos[a->instances[i].albedo], &b->albedos[b->instances[i].albedo],
                            sizeof(struct ao_vec3));
    }
}

static void compare_with_obj(const float *normals)
{
    char dir[] = "/tmp/aoview-arrays-XXXXXX", path[64];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/strip.obj", dir);
    write_obj(path, normals);
    struct ao_scene from_file, from_arrays;
    assert_true(ao_scene_load(&from_file, path, NULL));
    struct ao_scene_arrays arrays = {.name = "strip", .positions = POSITIONS, .vertex_count = VERTICES,
                                     .indices = INDICES, .triangle_count = TRIANGLES, .normals = normals,
                                     .albedo = {0.8f, 0.8f, 0.8f}};
    assert_true(ao_scene_from_arrays(&from_arrays, &arrays, NULL));
    assert_int_equal(from_arrays.degenerate_count, 1);
    assert_same_scene(&from_file, &from_arrays);
    ao_scene_finish(&from_file);
    ao_scene_finish(&from_arrays);
    unlink(path);
    rmdir(dir);
}

static void test_as_obj_without_normals(void **state)
{
    (void)state;
    compare_with_obj(NULL);
}

static void test_as_obj_with_normals(void **state)
{
    (void)state;
    float normals[3 * VERTICES];
    for (int i = 0; i < VERTICES; i++)
        normals[3 * i] = 0.6f, normals[3 * i + 1] = 0.0f, normals[3 * i + 2] = 0.8f;
    normals[3] = NAN;   /* made as if not given, by both routes */
    compare_with_obj(normals);
}

static void test_spheres_and_camera(void **state)
{
    (void)state;
    struct ao_sphere sphere = {.center = {0.5f, 0.5f, 2.0f}, .radius = 0.25f, .albedo = {0.5f, 0.6f, 0.7f}};
    struct ao_camera camera = {.eye = {0.5f, 0.5f, 6.0f}, .target = {0.5f, 0.5f, 0.0f}, .up = {0, 1, 0}, .fov = 30};
    struct ao_scene_arrays arrays = {.name = "strip", .positions = POSITIONS, .vertex_count = VERTICES,
                                     .indices = INDICES, .triangle_count = TRIANGLES, .albedo = {1, 1, 1},
                                     .spheres = &sphere, .sphere_count = 1, .camera = &camera};
    struct ao_scene s;
    assert_true(ao_scene_from_arrays(&s, &arrays, &(struct ao_scene_options){.no_ground = true}));
    assert_int_equal(s.sphere_count, 1);
    assert_int_equal(s.instance_count, 1);   /* no ground */
    assert_float_equal(s.spheres[0].center.x + (float)s.origin[0], 0.5f, 1e-6);
    assert_float_equal(s.spheres[0].albedo.z, 0.7f, 0);
    assert_float_equal(s.camera.eye.z + (float)s.origin[2], 6.0f, 1e-6);
    assert_float_equal(s.camera.fov, 30.0f, 0);
    ao_scene_finish(&s);
}

static void test_bad_arrays(void **state)
{
    (void)state;
    uint32_t out_of_range[] = {0, 1, 7};
    float not_finite[3 * VERTICES];
    memcpy(not_finite, POSITIONS, sizeof not_finite);
    not_finite[4] = INFINITY;
    struct ao_sphere flat = {.center = {0, 0, 0}, .radius = 0.0f, .albedo = {1, 1, 1}};
    struct ao_camera blind = {.eye = {0, 0, 1}, .target = {0, 0, 1}, .up = {0, 1, 0}, .fov = 40};
    struct ao_scene_arrays good = {.name = "strip", .positions = POSITIONS, .vertex_count = VERTICES,
                                   .indices = INDICES, .triangle_count = TRIANGLES, .albedo = {1, 1, 1}};
    struct ao_scene_arrays bad[6];
    for (int i = 0; i < 6; i++)
        bad[i] = good;
    bad[0].indices = out_of_range, bad[0].triangle_count = 1;
    bad[1].positions = not_finite;
    bad[2].spheres = &flat, bad[2].sphere_count = 1;
    bad[3].camera = &blind;
    bad[4].triangle_count = 0;
    bad[5].indices = INDICES + 12, bad[5].triangle_count = 1;   /* only a degenerate triangle */
    for (int i = 0; i < 6; i++) {
        struct ao_scene s;
        assert_false(ao_scene_from_arrays(&s, &bad[i], NULL));
        assert_int_equal(s.instance_count, 0);
    }
}

/* ao_tracer_intersect_arrays on the same mesh: each hit's point from its weights lies on its ray
 * at t, misses as gpytoolbox has them; the same rays with their directions scaled by 2^40 or 2^-40
 * give the same triangles and weights and t scaled back exactly (tracer_arrays.c scales directions by
 * powers of two); rays from 10^15 away (brought to the mesh) the same triangles as from nearby, at
 * t within the mesh's rounding, not 10^15's; nothing nearer than tnear. */
static void test_intersect_arrays(void **state)
{
    (void)state;
    enum { RAYS = 4000 };
    float *origins = malloc(sizeof(float) * 3 * RAYS), *directions = malloc(sizeof(float) * 3 * RAYS);
    float *moved = malloc(sizeof(float) * 3 * RAYS);
    double *t = malloc(sizeof(double) * 2 * RAYS), *barys = malloc(sizeof(double) * 6 * RAYS);
    int32_t *ids = malloc(sizeof(int32_t) * 2 * RAYS);
    assert_true(origins && directions && moved && t && barys && ids);
    srand(7);
    for (int i = 0; i < RAYS; i++) {
        origins[3 * i] = 0.5f, origins[3 * i + 1] = 0.5f, origins[3 * i + 2] = 3.0f;
        directions[3 * i] = 2.0f * ((float)rand() / (float)RAND_MAX) - 0.8f;
        directions[3 * i + 1] = 2.0f * ((float)rand() / (float)RAND_MAX) - 1.0f;
        directions[3 * i + 2] = -2.0f;   /* not unit: t in its units */
    }
    struct ao_tracer_arrays *mesh = ao_tracer_arrays_create(POSITIONS, VERTICES, INDICES, TRIANGLES);
    assert_non_null(mesh);
    assert_true(ao_tracer_intersect_arrays(mesh, origins, directions, RAYS, 0.0f, 2, t, ids, barys));
    int hits = 0;
    for (int i = 0; i < RAYS; i++) {
        if (ids[i] < 0) {
            assert_true(isinf(t[i]));
            assert_true(barys[3 * i] == 0.0 && barys[3 * i + 1] == 0.0 && barys[3 * i + 2] == 0.0);
            continue;
        }
        hits++;
        assert_true(ids[i] < 4);   /* never the degenerate one */
        const uint32_t *v = &INDICES[3 * ids[i]];
        for (int k = 0; k < 3; k++) {   /* the hit point from the weights is on the ray at t */
            double p = barys[3 * i] * POSITIONS[3 * v[0] + k] + barys[3 * i + 1] * POSITIONS[3 * v[1] + k] +
                       barys[3 * i + 2] * POSITIONS[3 * v[2] + k];
            assert_float_equal(p, origins[3 * i + k] + t[i] * directions[3 * i + k], 1e-5);
        }
        assert_float_equal(barys[3 * i] + barys[3 * i + 1] + barys[3 * i + 2], 1.0, 1e-6);
    }
    printf("%d of %d rays hit\n", hits, RAYS);
    assert_true(hits > RAYS / 20 && hits < RAYS / 2);
    for (int e = -40; e <= 40; e += 80) {
        float *scaled = moved;
        for (int i = 0; i < 3 * RAYS; i++)
            scaled[i] = ldexpf(directions[i], e);
        assert_true(ao_tracer_intersect_arrays(mesh, origins, scaled, RAYS, 0.0f, 1, t + RAYS, ids + RAYS,
                                               barys + 3 * RAYS));
        for (int i = 0; i < RAYS; i++) {
            assert_int_equal(ids[RAYS + i], ids[i]);
            assert_true(ldexp(t[RAYS + i], e) == t[i]);
            assert_memory_equal(&barys[3 * (RAYS + i)], &barys[3 * i], 3 * sizeof(double));
        }
    }
    /* Straight down from z = 3 and from z = 10^15 (exact in float), over the strip. */
    for (int i = 0; i < RAYS; i++) {
        origins[3 * i] = moved[3 * i] = 2.2f * ((float)rand() / (float)RAND_MAX) - 0.1f;
        origins[3 * i + 1] = moved[3 * i + 1] = 1.2f * ((float)rand() / (float)RAND_MAX) - 0.1f;
        origins[3 * i + 2] = 3.0f, moved[3 * i + 2] = 1e15f;
        directions[3 * i] = directions[3 * i + 1] = 0.0f, directions[3 * i + 2] = -2.0f;
    }
    assert_true(ao_tracer_intersect_arrays(mesh, origins, directions, RAYS, 0.0f, 2, t, ids, barys));
    assert_true(ao_tracer_intersect_arrays(mesh, moved, directions, RAYS, 0.0f, 2, t + RAYS, ids + RAYS,
                                           barys + 3 * RAYS));
    hits = 0;
    for (int i = 0; i < RAYS; i++) {
        assert_int_equal(ids[RAYS + i], ids[i]);
        hits += ids[i] >= 0;
        if (ids[i] >= 0)   /* t within the float rounding of the mesh's box, not of 10^15 */
            assert_float_equal(t[RAYS + i] - t[i], (1e15f - 3.0) / 2.0, 1e-3);
    }
    assert_true(hits > RAYS / 2);
    /* From points of the square z = 0 (triangles 0 and 1) up and towards the wall x = 1: with
     * tnear 0 some meet their own triangle at t = 0 (as the rays of gpytoolbox's course code,
     * which leave surface points unmoved), with tnear 1e-4 none is nearer. */
    for (int i = 0; i < RAYS; i++) {
        moved[3 * i] = (float)rand() / (float)RAND_MAX, moved[3 * i + 1] = (float)rand() / (float)RAND_MAX;
        moved[3 * i + 2] = 0.0f;
        directions[3 * i] = 1.0f, directions[3 * i + 1] = 0.1f, directions[3 * i + 2] = 0.5f;
    }
    int near = 0;
    for (int pass = 0; pass < 2; pass++) {
        float tnear = pass ? 1e-4f : 0.0f;
        assert_true(ao_tracer_intersect_arrays(mesh, moved, directions, RAYS, tnear, 2, t, ids, barys));
        for (int i = 0; i < RAYS; i++) {
            assert_true(ids[i] < 0 || t[i] >= tnear);
            near += ids[i] >= 0 && t[i] < 1e-4;
        }
        assert_true(pass ? near == 0 : near > RAYS / 10);
        near = 0;
    }
    ao_tracer_arrays_destroy(mesh);
    free(origins), free(directions), free(moved), free(t), free(barys), free(ids);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_as_obj_without_normals), cmocka_unit_test(test_as_obj_with_normals),
        cmocka_unit_test(test_spheres_and_camera), cmocka_unit_test(test_bad_arrays),
        cmocka_unit_test(test_intersect_arrays),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
