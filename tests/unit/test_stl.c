/* STL files, ASCII and binary: equal positions welded, facet normals ignored for the computed
 * ones, bad files refused with their one line. */
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

/* The unit cube of cube.stl: 36 corners welded into its 8 corners (-0 and 0 as one), then, at the
 * default crease angle, split again along its 90-degree edges: 24 vertices, each face flat with
 * its outward normal. */
static void assert_stl_cube(const struct ao_mesh *mesh)
{
    assert_mesh_valid(mesh);
    assert_int_equal(mesh->vertex_count, 24);
    assert_int_equal(mesh->triangle_count, 12);
    for (size_t t = 0; t < 12; t++) {
        struct ao_vec3 mid = {0, 0, 0};
        for (int k = 0; k < 3; k++)
            mid = ao_vec3_add(mid, ao_vec3_scale(mesh->positions[mesh->indices[3 * t + k]], 1.0f / 3));
        /* The face's outward normal: the axis along which the triangle's middle is farthest out. */
        struct ao_vec3 d = ao_vec3_sub(mid, ao_vec3_make(0.5f, 0.5f, 0.5f)), want = {0, 0, 0};
        if (fabsf(d.x) >= fabsf(d.y) && fabsf(d.x) >= fabsf(d.z))
            want.x = d.x > 0 ? 1.0f : -1.0f;
        else if (fabsf(d.y) >= fabsf(d.z))
            want.y = d.y > 0 ? 1.0f : -1.0f;
        else
            want.z = d.z > 0 ? 1.0f : -1.0f;
        for (int k = 0; k < 3; k++)
            assert_vec3_near(mesh->normals[mesh->indices[3 * t + k]], want.x, want.y, want.z);
    }
}

static void test_stl_ascii(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_ok(&mesh, fixture("cube.stl"));
    assert_stl_cube(&mesh);
    ao_mesh_finish(&mesh);
}

/* The same cube as binary STL, its 80-byte header starting with "solid" as many exporters'
 * do: the size (84 + 50 n) decides. */
static void test_stl_binary(void **state)
{
    (void)state;
    struct ao_mesh ascii;
    load_ok(&ascii, fixture("cube.stl"));
    struct bytes b = {.size = 0};
    char header[81];
    snprintf(header, sizeof header, "%-80s", "solid cube, but binary");
    put_text(&b, header);
    put_int(&b, ascii.triangle_count, 4);
    for (size_t t = 0; t < ascii.triangle_count; t++) {
        for (int k = 0; k < 3; k++)
            put_f32(&b, 0.0f);
        for (int k = 0; k < 3; k++) {
            struct ao_vec3 p = ascii.positions[ascii.indices[3 * t + k]];
            put_f32(&b, p.x);
            put_f32(&b, p.y);
            put_f32(&b, p.z);
        }
        put_int(&b, 0, 2);
    }
    struct ao_mesh mesh;
    load_ok(&mesh, temp_file("cube_binary.stl", b.data, b.size));
    assert_stl_cube(&mesh);
    ao_mesh_finish(&mesh);
    /* One byte more or less: not binary, and not ASCII either (a NUL byte). */
    expect_failure(temp_file("cube_long.stl", b.data, b.size - 1), ": ",
                   "binary STL header declares 12 triangles (684 bytes) but the file has 683");
    ao_mesh_finish(&ascii);
}

/* Each bad STL fixture, where its one error line must point, and what it must say. */
static const struct {
    const char *name, *location, *message;
} bad_inputs[] = {
    {"bad_stl_outside.stl", ":3: ", "'vertex' outside 'outer loop'"},
    {"bad_stl_two.stl", ":6: ", "loop with 2 vertices; at least 3 needed"},
    {"bad_stl_keyword.stl", ":6: ", "unknown STL keyword 'vertx'"},
    {"bad_stl_unended.stl", ":6: ", "file ends inside a facet"},
    {"bad_stl_number.stl", ":4: ", "bad number 'nan'"},
    {"bad_stl_size.stl", ": ", "declares 2 triangles (184 bytes) but the file has 134 bytes"},
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
    if (!mesh_fixture_begin("test_stl"))
        return 77;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stl_ascii),
        cmocka_unit_test(test_stl_binary),
        cmocka_unit_test(test_bad_inputs),
    };
    return cmocka_run_group_tests(tests, mesh_fixture_setup, mesh_fixture_teardown);
}
