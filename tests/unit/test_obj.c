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
    load_ok(&mesh, fixture("tri.obj"));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.vertex_count, 3);
    assert_int_equal(mesh.triangle_count, 1);
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
    load_ok(&mesh, fixture("fan.obj"));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.vertex_count, 5);
    assert_int_equal(mesh.triangle_count, 3);
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
        load_ok(&mesh, fixture(names[f]));
        assert_mesh_valid(&mesh);
        assert_int_equal(mesh.vertex_count, 4);
        assert_int_equal(mesh.triangle_count, 2);
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
    load_ok(&mesh, fixture("negative.obj"));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.vertex_count, 6);
    assert_int_equal(mesh.triangle_count, 2);
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
    load_ok(&mesh, fixture("statements.obj"));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.vertex_count, 3);
    assert_int_equal(mesh.triangle_count, 1);
    assert_vec3_near(mesh.positions[2], 0, 1, 0);
    ao_mesh_finish(&mesh);
}

/* Two faces sharing an edge with different normals: the edge's positions split in two. */
static void test_obj_split_vertices(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_ok(&mesh, fixture("split.obj"));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.vertex_count, 6);
    assert_int_equal(mesh.triangle_count, 2);
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

/* Each bad OBJ fixture, where its one error line must point, and what it must say. */
static const struct {
    const char *name, *location, *message;
} bad_inputs[] = {
    {"bad_number.obj", ":2: ", "bad number 'x'"},
    {"bad_nan.obj", ":1: ", "bad number 'nan'"},
    {"bad_inf.obj", ":3: ", "bad number '1e999'"},
    {"bad_v_few.obj", ":2: ", "found 2 numbers"},
    {"bad_v_many.obj", ":1: ", "too many numbers"},
    {"bad_vn_count.obj", ":4: ", "expected 'vn x y z'"},
    {"bad_index_range.obj", ":4: ", "'4': vertex index out of range (3 defined"},
    {"bad_index_negative.obj", ":4: ", "'-4': vertex index out of range"},
    {"bad_index_zero.obj", ":4: ", "bad face corner '0'"},
    {"bad_index_huge.obj", ":4: ", "vertex index out of range"},
    {"bad_forward_ref.obj", ":1: ", "(0 defined so far)"},
    {"bad_normal_range.obj", ":5: ", "'2//2': normal index out of range"},
    {"bad_texcoord_range.obj", ":5: ", "'3/2': texture coordinate index out of range"},
    {"bad_corner_slash.obj", ":4: ", "bad face corner '1/'"},
    {"bad_corner_fields.obj", ":6: ", "bad face corner '1/1/1/1'"},
    {"bad_corner_text.obj", ":4: ", "bad face corner 'a'"},
    {"bad_face_two.obj", ":4: ", "face with 2 vertices"},
    {"bad_empty.obj", ": ", "no triangles"},
    {"bad_no_faces.obj", ": ", "no triangles"},
    {"bad_all_degenerate.obj", ": ", "no triangles (2 degenerate"},
};

/* Every bad fixture fails with its one line and an empty mesh. */
static void test_bad_inputs(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof bad_inputs / sizeof bad_inputs[0]; i++)
        expect_failure(fixture(bad_inputs[i].name), bad_inputs[i].location, bad_inputs[i].message);
}

int main(void)
{
    if (!mesh_fixture_begin("test_obj"))
        return 77;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_obj_triangle),
        cmocka_unit_test(test_obj_polygon_fan),
        cmocka_unit_test(test_obj_corner_forms),
        cmocka_unit_test(test_obj_negative_indices),
        cmocka_unit_test(test_obj_other_statements),
        cmocka_unit_test(test_obj_split_vertices),
        cmocka_unit_test(test_obj_mixed_normals),
        cmocka_unit_test(test_obj_zero_normal),
        cmocka_unit_test(test_bad_inputs),
    };
    return cmocka_run_group_tests(tests, mesh_fixture_setup, mesh_fixture_teardown);
}
