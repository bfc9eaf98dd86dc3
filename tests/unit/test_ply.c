/* PLY files, ASCII and binary little endian: every scalar type, lists and elements skipped,
 * normals given or not, the layouts agreeing, truncated and bad files refused with their one line. */
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

/* One triangle (0,0,0) (1,0,0) (0,1,0); its face row is a list of the given types ("uchar int")
 * with count written as the count and the three index values after it. */
static struct bytes binary_triangle(const char *list_types, size_t count_size, uint64_t count,
                                    size_t index_size, const uint64_t index[3])
{
    struct bytes b = {.size = 0};
    char header[400];
    snprintf(header, sizeof header, "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
             "property float x\nproperty float y\nproperty float z\nelement face 1\n"
             "property list %s vertex_indices\nend_header\n", list_types);
    put_text(&b, header);
    for (int i = 0; i < 3; i++) {
        put_f32(&b, i == 1);
        put_f32(&b, i == 2);
        put_f32(&b, 0.0f);
    }
    put_int(&b, count, count_size);
    for (int i = 0; i < 3; i++)
        put_int(&b, index[i], index_size);
    return b;
}

/* The layouts of write_ply: the common binary one (floats and a list of uchar and int, read
 * straight from the bytes), with an extra vertex property (read so too), others read value by
 * value (a double x, a list of ushort and uint beside another face property; ascii). */
enum ply_layout { PLY_PLAIN, PLY_EXTRA_VERTEX, PLY_GENERAL, PLY_ASCII };

/* Writes mesh (positions and triangles) as a PLY file of the given layout; returns its path. */
static const char *write_ply(const struct ao_mesh *mesh, const char *name, enum ply_layout layout)
{
    char *path = path_buffer();
    snprintf(path, 4200, "%s/%s", temp_dir, name);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "ply\nformat %s 1.0\nelement vertex %zu\nproperty %s x\n%sproperty float y\nproperty float z\n"
               "element face %zu\n%sproperty list %s vertex_indices\nend_header\n",
            layout == PLY_ASCII ? "ascii" : "binary_little_endian", mesh->vertex_count,
            layout == PLY_GENERAL ? "double" : "float", layout == PLY_EXTRA_VERTEX ? "property uchar red\n" : "",
            mesh->triangle_count, layout == PLY_GENERAL ? "property uchar flags\n" : "",
            layout == PLY_GENERAL ? "ushort uint" : "uchar int");
    for (size_t i = 0; i < mesh->vertex_count; i++) {
        struct ao_vec3 p = mesh->positions[i];
        double x = p.x;
        unsigned char red = 7;
        if (layout == PLY_ASCII)
            fprintf(f, "%.9g %.9g %.9g\n", p.x, p.y, p.z);
        else if (layout == PLY_GENERAL)
            fwrite(&x, 8, 1, f);
        else
            fwrite(&p.x, 4, 1, f);
        if (layout == PLY_EXTRA_VERTEX)
            fwrite(&red, 1, 1, f);
        if (layout != PLY_ASCII)
            fwrite(&p.y, 4, 2, f);
    }
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *v = mesh->indices + 3 * t;
        unsigned char three[2] = {3, 0}, flags = 1;
        if (layout == PLY_ASCII)
            fprintf(f, "3 %u %u %u\n", v[0], v[1], v[2]);
        else if (layout == PLY_GENERAL)
            fwrite(&flags, 1, 1, f), fwrite(three, 1, 2, f);
        else
            fwrite(three, 1, 1, f);
        if (layout != PLY_ASCII)
            fwrite(v, 4, 3, f);
    }
    assert_int_equal(fclose(f), 0);
    return path;
}

/* Quads fanned, extra properties and elements (lists too) skipped, and angle-weighted normals:
 * every cube corner gets 90 degrees of each of its three faces, however the quads were split,
 * so its normal points away from the centre. */
static void test_ply_ascii_cube(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    /* At the default crease angle every corner splits in three, one per face, each face flat. */
    load_counted(&mesh, fixture("cube.ply"), 24, 12);
    for (size_t t = 0; t < 12; t++) {
        struct ao_vec3 p[3], n = mesh.normals[mesh.indices[3 * t]];
        for (int k = 0; k < 3; k++)
            p[k] = mesh.positions[mesh.indices[3 * t + k]];
        struct ao_vec3 face = ao_vec3_normalize(ao_vec3_cross(ao_vec3_sub(p[1], p[0]), ao_vec3_sub(p[2], p[0])));
        for (int k = 0; k < 3; k++)
            assert_vec3_near(mesh.normals[mesh.indices[3 * t + k]], face.x, face.y, face.z);
        assert_float_equal(fabsf(n.x) + fabsf(n.y) + fabsf(n.z), 1.0f, 0.0f);
    }
    ao_mesh_finish(&mesh);
    load_at_crease(&mesh, fixture("cube.ply"), 180.0);   /* smooth everywhere: 8 vertices */
    assert_int_equal(mesh.vertex_count, 8);
    assert_triangle(&mesh, 0, 0, 3, 2);
    assert_triangle(&mesh, 1, 0, 2, 1);
    assert_vec3_near(mesh.positions[6], 1, 1, 1);
    float s = 1.0f / sqrtf(3.0f);
    for (size_t i = 0; i < 8; i++) {
        struct ao_vec3 p = mesh.positions[i];
        assert_vec3_near(mesh.normals[i], p.x > 0.5f ? s : -s, p.y > 0.5f ? s : -s,
                         p.z > 0.5f ? s : -s);
    }
    ao_mesh_finish(&mesh);
}

/* File normals (mixed types, CRLF, vertex_index) are normalized; a zero one is made as if not
 * given (from its two triangles, facing +z) and counted. */
static void test_ply_ascii_normals(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_counted(&mesh, fixture("normals.ply"), 4, 2);
    assert_int_equal(mesh.degenerate_count, 1);
    assert_triangle(&mesh, 1, 1, 3, 2);
    assert_vec3_near(mesh.normals[0], 0, 0, 1);
    assert_vec3_near(mesh.normals[1], 0, 0, 1);
    assert_vec3_near(mesh.normals[2], 0, 0, 1);
    assert_vec3_near(mesh.normals[3], 0, 0, -1);
    assert_int_equal(mesh.invalid_normals, 1);
    ao_mesh_finish(&mesh);
}

static void test_ply_binary(void **state)
{
    (void)state;
    struct bytes b = binary_square();
    struct ao_mesh mesh;
    load_counted(&mesh, temp_file("square.ply", b.data, b.size), 4, 2);
    assert_int_equal(mesh.degenerate_count, 1);
    assert_triangle(&mesh, 0, 0, 1, 2);
    assert_triangle(&mesh, 1, 0, 2, 3);
    assert_vec3_near(mesh.positions[2], 1, 1, -2);
    assert_vec3_near(mesh.positions[3], 0, 1, -2);
    for (int i = 0; i < 4; i++)
        assert_vec3_near(mesh.normals[i], 0, 0, 1);
    ao_mesh_finish(&mesh);
}

/* Claimed sizes are checked against the file before anything is allocated for them; list
 * counts against the bytes left; signed and unsigned indices against the vertex count. */
static void test_ply_binary_errors(void **state)
{
    (void)state;
    static const uint64_t good[3] = {0, 1, 2}, negative[3] = {0, 0xffffffff, 2},
                          huge[3] = {0, 4294967295u, 2}, range[3] = {0, 3, 2};
    struct bytes b = binary_triangle("uchar int", 1, 3, 4, good);
    struct ao_mesh mesh;
    load_ok(&mesh, temp_file("good.ply", b.data, b.size));
    ao_mesh_finish(&mesh);

    b = binary_triangle("uchar int", 1, 3, 4, negative);
    expect_failure(temp_file("negative.ply", b.data, b.size), ": face 0: ", "vertex index -1");
    b = binary_triangle("uchar uint", 1, 3, 4, huge);
    expect_failure(temp_file("huge.ply", b.data, b.size), ": face 0: ", "4294967295");
    b = binary_triangle("uint8 ushort", 1, 3, 2, range);
    expect_failure(temp_file("range.ply", b.data, b.size), ": face 0: ", "vertex index 3");
    b = binary_triangle("uchar uint", 1, 3, 4, range);
    expect_failure(temp_file("range_uint.ply", b.data, b.size), ": face 0: ", "vertex index 3");

    b = binary_triangle("uchar int", 1, 3, 4, good);
    put_int(&b, 0, 3);
    expect_failure(temp_file("trailing.ply", b.data, b.size), ": ", "3 bytes after the last");

    b = binary_triangle("uchar int", 1, 3, 4, good);
    memcpy(b.data + b.size - 13 - 36 + 12, "\x00\x00\xc0\x7f", 4);  /* x of vertex 1: NaN */
    expect_failure(temp_file("nan.ply", b.data, b.size), ": vertex 1: ", "not a finite float");

    b = binary_triangle("uchar int", 1, 255, 4, good);
    expect_failure(temp_file("list.ply", b.data, b.size), ": face 0: ",
                   "list of 255 items runs past the end");
    b = binary_triangle("uint int", 4, 4000000000u, 4, good);
    expect_failure(temp_file("list4g.ply", b.data, b.size), ": face 0: ",
                   "list of 4000000000 items runs past the end");

    b = (struct bytes){.size = 0};
    put_text(&b, "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
                 "property float x\nproperty float y\nproperty float z\nelement face 1\n"
                 "property list uchar int vertex_indices\nend_header\n");
    put_int(&b, 0, 12);
    expect_failure(temp_file("claims.ply", b.data, b.size), ":3: ", "declares 4000000000 rows");

    /* 2^62 + 1 rows of 8 bytes: the product overflows 64 bits. */
    b = (struct bytes){.size = 0};
    put_text(&b, "ply\nformat binary_little_endian 1.0\nelement vertex 0\n"
                 "property float x\nproperty float y\nproperty float z\n"
                 "element junk 4611686018427387905\nproperty double d\nelement face 1\n"
                 "property list uchar int vertex_indices\nend_header\n");
    expect_failure(temp_file("overflow.ply", b.data, b.size), ":7: ", "declares");
}

/* Every proper prefix of a binary file fails cleanly. */
static void test_ply_binary_truncated(void **state)
{
    (void)state;
    struct bytes b = binary_square();
    for (size_t size = 0; size < b.size; size++) {
        struct ao_mesh mesh;
        char err[1024];
        assert_false(load_captured(&mesh, temp_file("cut.ply", b.data, size), err, sizeof err));
        assert_mesh_empty(&mesh);
        assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    }
}

/* Binary rows read straight from the bytes give the mesh that reading value by value gives, bit
 * for bit: the bunny in every layout of write_ply. Big-endian files are still refused. */
static void test_ply_layouts_agree(void **state)
{
    (void)state;
    char path[4200];
    snprintf(path, sizeof path, "%s/assets/bunny.obj", getenv("AO_SOURCE_ROOT"));
    struct ao_mesh bunny, mesh;
    load_ok(&bunny, path);
    static const char *const names[] = {"plain.ply", "extra.ply", "general.ply", "ascii.ply"};
    for (int layout = PLY_PLAIN; layout <= PLY_ASCII; layout++) {
        load_ok(&mesh, write_ply(&bunny, names[layout], (enum ply_layout)layout));
        assert_int_equal(mesh.vertex_count, bunny.vertex_count);
        assert_int_equal(mesh.triangle_count, bunny.triangle_count);
        assert_memory_equal(mesh.positions, bunny.positions, bunny.vertex_count * sizeof *bunny.positions);
        assert_memory_equal(mesh.normals, bunny.normals, bunny.vertex_count * sizeof *bunny.normals);
        assert_memory_equal(mesh.indices, bunny.indices, 3 * bunny.triangle_count * sizeof *bunny.indices);
        ao_mesh_finish(&mesh);
    }
    expect_failure(fixture("bad_big_endian.ply"), ":2: ", "big-endian binary PLY is not supported");
    /* Every proper prefix of the plain file fails cleanly, in one line. */
    const char *plain = write_ply(&bunny, "plain.ply", PLY_PLAIN);
    FILE *f = fopen(plain, "rb");
    assert_non_null(f);
    static unsigned char bytes[1 << 17];
    size_t size = fread(bytes, 1, sizeof bytes, f);
    assert_true(size < sizeof bytes);
    fclose(f);
    for (size_t cut = 0; cut < size; cut += cut < 300 ? 1 : 997) {
        char err[1024];
        assert_false(load_captured(&mesh, temp_file("cut.ply", bytes, cut), err, sizeof err));
        assert_mesh_empty(&mesh);
        assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    }
    ao_mesh_finish(&bunny);
}

MESH_FIXTURE_MAIN("test_ply", cmocka_unit_test(test_ply_ascii_cube), cmocka_unit_test(test_ply_ascii_normals),
                              cmocka_unit_test(test_ply_binary), cmocka_unit_test(test_ply_binary_errors),
                              cmocka_unit_test(test_ply_binary_truncated), cmocka_unit_test(test_ply_layouts_agree),
                              bad_inputs_test(".ply"))
