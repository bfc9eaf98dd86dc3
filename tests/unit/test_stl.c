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

MESH_FIXTURE_MAIN("test_stl", cmocka_unit_test(test_stl_ascii), cmocka_unit_test(test_stl_binary),
                              bad_inputs_test(".stl"))
