/* OBJ files: vertices, normals, faces fanned, every corner form, negative indices, the statements
 * that are skipped, and each bad file refused with its one line. Fixtures in tests/data/mesh. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_fixture.h"

static void test_obj_triangle(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_counted(&mesh, fixture("tri.obj"), 3, 1);
    assert_int_equal(mesh.degenerate_count, 0);
    assert_triangle(&mesh, 0, 0, 1, 2);
    assert_vec3_near(mesh.positions[1], 1, 0, 0);
    for (int i = 0; i < 3; i++)
        assert_vec3_near(mesh.normals[i], 0, 0, 1);
    ao_mesh_finish(&mesh);
    assert_mesh_empty(&mesh);
}

static void test_obj_polygon_fan(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_counted(&mesh, fixture("fan.obj"), 5, 3);
    assert_triangle(&mesh, 0, 0, 1, 2);
    assert_triangle(&mesh, 1, 0, 2, 3);
    assert_triangle(&mesh, 2, 0, 3, 4);
    for (int i = 0; i < 5; i++)
        assert_vec3_near(mesh.normals[i], 0, 0, 1);
    ao_mesh_finish(&mesh);
}

/* v/vt, v//vn and v/vt/vn; corners with the same position and normal share one vertex. */
static void test_obj_corner_forms(void **state)
{
    (void)state;
    static const char *const names[] = {"forms_vt.obj", "forms_vn.obj", "forms_vtvn.obj"};
    for (size_t f = 0; f < 3; f++) {
        struct ao_mesh mesh;
        load_counted(&mesh, fixture(names[f]), 4, 2);
        for (int i = 0; i < 4; i++)
            assert_vec3_near(mesh.normals[i], 0, 0, 1);
        assert_vec3_near(mesh.positions[mesh.indices[4]], 1, 1, 0);
        ao_mesh_finish(&mesh);
    }
}

/* Negative indices count back from the last v, vt or vn read so far. */
static void test_obj_negative_indices(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_counted(&mesh, fixture("negative.obj"), 6, 2);
    for (int k = 0; k < 3; k++) {
        struct ao_vec3 first = mesh.positions[mesh.indices[k]];
        struct ao_vec3 second = mesh.positions[mesh.indices[3 + k]];
        assert_float_equal(first.z, 0, 0);
        assert_float_equal(second.z, 1, 0);
        assert_vec3_near(mesh.normals[mesh.indices[k]], 0, 0, 1);
        assert_vec3_near(mesh.normals[mesh.indices[3 + k]], 0, 0, -1);
    }
    ao_mesh_finish(&mesh);
}

/* CRLF, comments, blank lines, tabs, w, and statements that do not make triangles. */
static void test_obj_other_statements(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_counted(&mesh, fixture("statements.obj"), 3, 1);
    assert_vec3_near(mesh.positions[2], 0, 1, 0);
    ao_mesh_finish(&mesh);
}

/* Two faces sharing an edge with different normals: the edge's positions split in two. */
static void test_obj_split_vertices(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_counted(&mesh, fixture("split.obj"), 6, 2);
    float h = sqrtf(0.5f);
    for (int k = 0; k < 3; k++) {
        assert_vec3_near(mesh.normals[mesh.indices[k]], 0, 0, 1);
        assert_vec3_near(mesh.normals[mesh.indices[3 + k]], 0, -h, h);
    }
    assert_vec3_near(mesh.positions[mesh.indices[3]], 1, 0, 0);
    assert_vec3_near(mesh.positions[mesh.indices[4]], 1, 1, 1);
    ao_mesh_finish(&mesh);
}

/* Corners without a normal share one vertex per position, whose normal is computed from the
 * triangles using it; the angle weighting shows at (0,1,0), smoothed across every edge (crease
 * 180): 90 degrees of a +z triangle and 45 of a +x one give (1,0,2)/sqrt 5 (area or uniform weights
 * would give (1,0,1)/sqrt 2). At the default crease angle the two triangles, 90 degrees apart, each
 * keep their own normal there, (0,1,0) split in two. */
static void test_obj_mixed_normals(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_at_crease(&mesh, fixture("mixed.obj"), AO_MESH_CREASE_DEFAULT);
    assert_int_equal(mesh.vertex_count, 8);
    size_t plus_z = mesh.indices[5], plus_x = mesh.indices[7];   /* (0,1,0) in the 2nd and 3rd triangles */
    assert_true(plus_z != plus_x);
    assert_vec3_near(mesh.positions[plus_z], 0, 1, 0);
    assert_vec3_near(mesh.positions[plus_x], 0, 1, 0);
    assert_vec3_near(mesh.normals[plus_z], 0, 0, 1);
    assert_vec3_near(mesh.normals[plus_x], 1, 0, 0);
    ao_mesh_finish(&mesh);
    load_at_crease(&mesh, fixture("mixed.obj"), 180.0);
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.vertex_count, 7);
    assert_int_equal(mesh.triangle_count, 3);
    for (int k = 0; k < 3; k++)
        assert_vec3_near(mesh.normals[mesh.indices[k]], 1, 0, 0);
    assert_vec3_near(mesh.normals[mesh.indices[3]], 0, 0, 1);
    assert_vec3_near(mesh.normals[mesh.indices[6]], 1, 0, 0);
    float s = 1.0f / sqrtf(5.0f);
    assert_vec3_near(mesh.normals[vertex_at(&mesh, 0, 1, 0)], s, 0, 2 * s);
    assert_vec3_near(mesh.normals[vertex_at(&mesh, 0, 0, 1)], 1, 0, 0);
    ao_mesh_finish(&mesh);
}

/* A zero normal given is made as if none were: computed from the triangle, and counted. */
static void test_obj_zero_normal(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_ok(&mesh, fixture("zero_normal.obj"));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.invalid_normals, 1);
    for (size_t i = 0; i < mesh.vertex_count; i++)
        assert_vec3_near(mesh.normals[i], 0, 0, 1);
    ao_mesh_finish(&mesh);
}

MESH_FIXTURE_MAIN("test_obj", cmocka_unit_test(test_obj_triangle), cmocka_unit_test(test_obj_polygon_fan),
                              cmocka_unit_test(test_obj_corner_forms), cmocka_unit_test(test_obj_negative_indices),
                              cmocka_unit_test(test_obj_other_statements), cmocka_unit_test(test_obj_split_vertices),
                              cmocka_unit_test(test_obj_mixed_normals), cmocka_unit_test(test_obj_zero_normal),
                              bad_inputs_test(".obj"))
