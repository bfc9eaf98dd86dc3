/* Tests of the mesh loaders (OBJ, PLY, STL, glTF): every supported form, the computed normals,
 * degenerate triangles, and that each bad input fails with one "path:line: message" line and an empty mesh.
 * Fixtures live in tests/data/mesh; binary PLY files are generated into a temporary directory. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <meshoptimizer.h>

#include "file.h"
#include "load/load.h"
#include "load/loader.h"
#include "mesh.h"
#include "scene.h"
#include "scene_load.h"

/* Where the committed fixtures are, and a scratch directory for generated files. */
static char data_dir[4096];
static char temp_dir[4096];

/* ------------------------------------------------------------------ helpers */

/* A path in one of a few rotating buffers, so a test can hold several at once. */
static char *path_buffer(void)
{
    static char buffers[4][4200];
    static int next;
    next = (next + 1) % 4;
    return buffers[next];
}

/* The path of a committed fixture. */
static const char *fixture(const char *name)
{
    char *path = path_buffer();
    snprintf(path, 4200, "%s/%s", data_dir, name);
    return path;
}

/* Writes bytes to a new file of the temporary directory and returns its path. An old file of
 * that name is removed first: ext4 flushes a file truncated and rewritten to disk on close,
 * which made the many rewrites below take seconds. */
static const char *temp_file(const char *name, const void *bytes, size_t size)
{
    char *path = path_buffer();
    snprintf(path, 4200, "%s/%s", temp_dir, name);
    assert_true(unlink(path) == 0 || errno == ENOENT);
    FILE *file = fopen(path, "wb");
    assert_non_null(file);
    assert_int_equal(fwrite(bytes, 1, size, file), size);
    assert_int_equal(fclose(file), 0);
    return path;
}

/* Reads a whole file into a malloc'd buffer. */
static unsigned char *slurp(const char *path, size_t *size)
{
    FILE *file = fopen(path, "rb");
    assert_non_null(file);
    assert_int_equal(fseek(file, 0, SEEK_END), 0);
    long length = ftell(file);
    assert_true(length >= 0);
    rewind(file);
    unsigned char *data = malloc((size_t)length + 1);
    assert_non_null(data);
    assert_int_equal(fread(data, 1, (size_t)length, file), (size_t)length);
    fclose(file);
    *size = (size_t)length;
    return data;
}

/* Runs ao_load_mesh with stderr redirected, returning what it printed in err. */
static bool load_captured(struct ao_mesh *mesh, const char *path, char *err, size_t err_size)
{
    FILE *capture = tmpfile();
    assert_non_null(capture);
    fflush(stderr);
    int saved = dup(STDERR_FILENO);
    assert_true(saved >= 0);
    assert_true(dup2(fileno(capture), STDERR_FILENO) >= 0);
    bool ok = ao_load_mesh(mesh, path, NULL);
    fflush(stderr);
    assert_true(dup2(saved, STDERR_FILENO) >= 0);
    close(saved);
    rewind(capture);
    size_t n = fread(err, 1, err_size - 1, capture);
    err[n] = '\0';
    fclose(capture);
    return ok;
}

/* The budget's charges at the MEDIUM BVH's rates: a mesh, and meshes with their placements. */
static uint64_t medium_model(uint64_t triangles, uint64_t vertices, uint64_t placements)
{
    return ao_budget_charge(&(struct ao_budget){.bvh = AO_BVH_MEDIUM}, triangles, vertices, placements);
}

static uint64_t medium_charge(uint64_t triangles, uint64_t vertices)
{
    return medium_model(triangles, vertices, 0);
}

/* Runs ao_load_mesh within a budget of `limit` bytes at the MEDIUM BVH's rates, stderr
 * captured in err; the budget must come back empty, whatever happened. */
static bool load_within(struct ao_mesh *mesh, const char *path, uint64_t limit, char *err, size_t err_size)
{
    struct ao_budget budget = {.limit = limit, .bvh = AO_BVH_MEDIUM};
    FILE *capture = tmpfile();
    assert_non_null(capture);
    fflush(stderr);
    int saved = dup(STDERR_FILENO);
    assert_true(saved >= 0);
    assert_true(dup2(fileno(capture), STDERR_FILENO) >= 0);
    bool ok = ao_load_mesh(mesh, path, &budget);
    fflush(stderr);
    assert_true(dup2(saved, STDERR_FILENO) >= 0);
    close(saved);
    rewind(capture);
    size_t n = fread(err, 1, err_size - 1, capture);
    err[n] = '\0';
    fclose(capture);
    assert_true(budget.used == 0);
    return ok;
}

/* Loads a file that must load, and prints nothing. */
static void load_ok(struct ao_mesh *mesh, const char *path)
{
    char err[1024];
    bool ok = load_captured(mesh, path, err, sizeof err);
    if (!ok || err[0])
        print_error("loading %s printed: %s\n", path, err);
    assert_true(ok);
    assert_string_equal(err, "");
}

/* The mesh must be all zero, as a failed load leaves it. */
static void assert_mesh_empty(const struct ao_mesh *mesh)
{
    assert_null(mesh->positions);
    assert_null(mesh->normals);
    assert_null(mesh->indices);
    assert_int_equal(mesh->vertex_count, 0);
    assert_int_equal(mesh->triangle_count, 0);
    assert_int_equal(mesh->degenerate_count, 0);
}

/* Loading path must fail, leave the mesh empty and print exactly one line that starts with
 * the path followed by location (":LINE: " or ": ") and contains message. */
static void expect_failure(const char *path, const char *location, const char *message)
{
    struct ao_mesh mesh;
    char err[1024], prefix[4300];
    memset(&mesh, 0xab, sizeof mesh);
    bool ok = load_captured(&mesh, path, err, sizeof err);
    snprintf(prefix, sizeof prefix, "%s%s", path, location);
    if (ok || strncmp(err, prefix, strlen(prefix)) != 0 || !strstr(err, message))
        print_error("%s: expected \"%s...%s\", got ok=%d \"%s\"\n", path, prefix, message, ok,
                    err);
    assert_false(ok);
    assert_mesh_empty(&mesh);
    size_t n = strlen(err);
    assert_true(n > 0 && strchr(err, '\n') == err + n - 1);
    assert_memory_equal(err, prefix, strlen(prefix));
    assert_non_null(strstr(err, message));
}

/* a must be within 1e-5 of (x, y, z). */
static void assert_vec3_near(struct ao_vec3 a, float x, float y, float z)
{
    assert_float_equal(a.x, x, 1e-5f);
    assert_float_equal(a.y, y, 1e-5f);
    assert_float_equal(a.z, z, 1e-5f);
}

/* Triangle t must be (a, b, c). */
static void assert_triangle(const struct ao_mesh *mesh, size_t t, uint32_t a, uint32_t b,
                            uint32_t c)
{
    assert_int_equal(mesh->indices[3 * t], a);
    assert_int_equal(mesh->indices[3 * t + 1], b);
    assert_int_equal(mesh->indices[3 * t + 2], c);
}

/* What every loaded mesh must satisfy: triangles, indices in range, finite positions, and
 * normals that are unit length or zero. */
static void assert_mesh_valid(const struct ao_mesh *mesh)
{
    assert_true(mesh->triangle_count > 0);
    assert_non_null(mesh->positions);
    assert_non_null(mesh->normals);
    assert_non_null(mesh->indices);
    for (size_t i = 0; i < 3 * mesh->triangle_count; i++)
        assert_true(mesh->indices[i] < mesh->vertex_count);
    for (size_t i = 0; i < mesh->vertex_count; i++) {
        float length = ao_vec3_length(mesh->normals[i]);
        assert_true(ao_vec3_is_finite(mesh->positions[i]));
        assert_true(length == 0.0f || fabsf(length - 1.0f) < 1e-5f);
    }
}

/* The one vertex at position p (the test meshes have a single one there). */
static size_t vertex_at(const struct ao_mesh *mesh, float x, float y, float z)
{
    for (size_t i = 0; i < mesh->vertex_count; i++) {
        struct ao_vec3 p = mesh->positions[i];
        if (p.x == x && p.y == y && p.z == z)
            return i;
    }
    fail();
    return 0;
}

/* ------------------------------------------------------------------ binary PLY writer */

/* A binary PLY file under construction. */
struct bytes {
    unsigned char data[4096];
    size_t size;
};

/* Appends text (the header). */
static void put_text(struct bytes *b, const char *text)
{
    size_t n = strlen(text);
    assert_true(b->size + n <= sizeof b->data);
    memcpy(b->data + b->size, text, n);
    b->size += n;
}

/* Appends value as n bytes, little endian (zero-extended past 8). */
static void put_int(struct bytes *b, uint64_t value, size_t n)
{
    assert_true(b->size + n <= sizeof b->data);
    for (size_t i = 0; i < n; i++)
        b->data[b->size++] = (unsigned char)(i < 8 ? value >> (8 * i) : 0);
}

/* Appends a float32, little endian. */
static void put_f32(struct bytes *b, float f)
{
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    put_int(b, bits, 4);
}

/* Appends a float64, little endian. */
static void put_f64(struct bytes *b, double d)
{
    uint64_t bits;
    memcpy(&bits, &d, sizeof bits);
    put_int(b, bits, 8);
}

/* A square of 4 vertices (z = -2, normals +z) as one quad plus a degenerate triangle, with every
 * scalar type, list properties and elements the loader must skip. */
static struct bytes binary_square(void)
{
    static const float corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    struct bytes b = {.size = 0};
    put_text(&b, "ply\nformat binary_little_endian 1.0\n"
                 "comment every scalar type, and lists and elements to skip\n"
                 "element vertex 4\nproperty char a\nproperty uchar b\nproperty short c\n"
                 "property ushort d\nproperty int e\nproperty uint f\nproperty float x\n"
                 "property double y\nproperty int16 z\nproperty float64 nx\n"
                 "property float32 ny\nproperty int8 nz\n"
                 "element extra 2\nproperty list int uint32 stuff\nproperty double w\n"
                 "element face 2\nproperty uchar flags\n"
                 "property list int32 uint32 vertex_indices\nproperty list uchar double other\n"
                 "element tail 2\nproperty list ushort short values\nend_header\n");
    for (int i = 0; i < 4; i++) {
        put_int(&b, (uint64_t)-5, 1);
        put_int(&b, 200, 1);
        put_int(&b, (uint64_t)-300, 2);
        put_int(&b, 60000, 2);
        put_int(&b, (uint64_t)-70000, 4);
        put_int(&b, 4000000000u, 4);
        put_f32(&b, corners[i][0]);
        put_f64(&b, corners[i][1]);
        put_int(&b, (uint64_t)-2, 2);
        put_f64(&b, 0.0);
        put_f32(&b, 0.0f);
        put_int(&b, 3, 1);
    }
    /* extra: stuff [1 2], w 0.5; stuff [], w 0.25 */
    put_int(&b, 2, 4);
    put_int(&b, 1, 4);
    put_int(&b, 2, 4);
    put_f64(&b, 0.5);
    put_int(&b, 0, 4);
    put_f64(&b, 0.25);
    /* face: flags 1, the quad 0 1 2 3, other [9.0]; flags 0, the degenerate 3 1 1, other [] */
    put_int(&b, 1, 1);
    put_int(&b, 4, 4);
    for (uint64_t i = 0; i < 4; i++)
        put_int(&b, i, 4);
    put_int(&b, 1, 1);
    put_f64(&b, 9.0);
    put_int(&b, 0, 1);
    put_int(&b, 3, 4);
    put_int(&b, 3, 4);
    put_int(&b, 1, 4);
    put_int(&b, 1, 4);
    put_int(&b, 0, 1);
    /* tail: values [-1 -2]; values [] */
    put_int(&b, 2, 2);
    put_int(&b, (uint64_t)-1, 2);
    put_int(&b, (uint64_t)-2, 2);
    put_int(&b, 0, 2);
    return b;
}

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

/* ------------------------------------------------------------------ numbers */

/* Checks one token against strtod and strtof: the same bits, and the same verdict. */
static void assert_number_as_libc(const char *token)
{
    struct ao_load_span s = {token, token + strlen(token)};
    char *stop;
    double want = strtod(token, &stop), got = 0.0;
    bool ok = ao_load_parse_number(s, &got);
    assert_int_equal(ok, stop == s.end);
    if (ok && memcmp(&want, &got, sizeof want) != 0)
        fail_msg("'%s': strtod %.17g, parsed %.17g", token, want, got);
    float want_f = strtof(token, &stop), got_f = 0.0f;
    ok = ao_load_parse_float(s, &got_f);
    assert_int_equal(ok, stop == s.end && isfinite(want_f));
    if (ok && memcmp(&want_f, &got_f, sizeof want_f) != 0)
        fail_msg("'%s': strtof %.9g, parsed %.9g", token, want_f, got_f);
}

/* The numbers of text files parse as strtod and strtof parse them, bit for bit, the fast path for
 * short decimals included: random values in every notation and precision, the halfway points
 * between adjacent floats (where rounding twice would go wrong), extremes and malformed tokens. */
static void test_numbers_as_libc(void **state)
{
    (void)state;
    static const char *const fixed[] = {"0", "-0", "+1", "1.", ".5", "-.5", "1e5", "1E-5", "1e+5", "007", "0.000",
                                        "3.4028235e38", "3.4028236e38", "1e39", "-1e39", "1e-38", "1.17549435e-38",
                                        "1e-40", "1e-46", "9007199254740993", "123456789012345678901",
                                        "0.1234567890123456789", "1e22", "1e23", "1e-22", "1e-23", "inf", "nan",
                                        "0x1p3", "1e", "1e+", ".", "-", "1.2.3", "1e5.5", "12a", "1e99999", ""};
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        assert_number_as_libc(fixed[i]);
    uint64_t seed = 99;
    char token[64];
    for (int i = 0; i < 200000; i++) {
        seed = seed * 6364136223846793005u + 1442695040888963407u;
        uint32_t bits = (uint32_t)(seed >> 32);
        float f;
        memcpy(&f, &bits, sizeof f);
        if (!isfinite(f))
            continue;
        static const char *const formats[] = {"%.9g", "%.6g", "%.17g", "%.3f", "%.9e", "%g"};
        snprintf(token, sizeof token, formats[i % 6], f);
        assert_number_as_libc(token);
        float next = nextafterf(f, INFINITY);
        snprintf(token, sizeof token, "%.17g", ((double)f + (double)next) / 2);
        assert_number_as_libc(token);
        snprintf(token, sizeof token, "%.9g", (double)(bits % 2000000) / 1000.0 - 1000.0);
        assert_number_as_libc(token);
    }
}

/* ------------------------------------------------------------------ OBJ */

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

/* Loads path as one mesh (OBJ, PLY, STL), the normals it lacks made at the crease angle. */
static void load_at_crease(struct ao_mesh *mesh, const char *path, double crease)
{
    struct ao_budget budget = {.limit = AO_BUDGET_DEFAULT};
    struct ao_model model;
    assert_true(ao_load_model(&model, path, &budget, crease));
    assert_int_equal(model.mesh_count, 1);
    *mesh = model.meshes[0];
    model.meshes[0] = (struct ao_mesh){0};
    ao_model_finish(&model);
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

/* A repeated index, collinear corners and a point are skipped and counted; vertices left
 * without a triangle get a zero normal. */
static void test_degenerate_counted(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_ok(&mesh, fixture("degenerate.obj"));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.vertex_count, 5);
    assert_int_equal(mesh.triangle_count, 1);
    assert_int_equal(mesh.degenerate_count, 3);
    assert_triangle(&mesh, 0, 0, 1, 2);
    assert_vec3_near(mesh.normals[0], 0, 0, 1);
    assert_vec3_near(mesh.normals[3], 0, 0, 0);
    assert_vec3_near(mesh.normals[4], 0, 0, 0);
    ao_mesh_finish(&mesh);
}

/* The extension decides the format, in any case. */
static void test_extension_case(void **state)
{
    (void)state;
    static const char *const pairs[][2] = {{"tri.obj", "UPPER.OBJ"}, {"cube.ply", "Mixed.Ply"}};
    for (int i = 0; i < 2; i++) {
        size_t size;
        unsigned char *text = slurp(fixture(pairs[i][0]), &size);
        struct ao_mesh mesh;
        load_ok(&mesh, temp_file(pairs[i][1], text, size));
        assert_mesh_valid(&mesh);
        ao_mesh_finish(&mesh);
        free(text);
    }
}

/* ------------------------------------------------------------------ PLY */

/* Quads fanned, extra properties and elements (lists too) skipped, and angle-weighted normals:
 * every cube corner gets 90 degrees of each of its three faces, however the quads were split,
 * so its normal points away from the centre. */
static void test_ply_ascii_cube(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_ok(&mesh, fixture("cube.ply"));
    assert_mesh_valid(&mesh);
    /* At the default crease angle every corner splits in three, one per face, each face flat. */
    assert_int_equal(mesh.vertex_count, 24);
    assert_int_equal(mesh.triangle_count, 12);
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
    load_ok(&mesh, fixture("normals.ply"));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.vertex_count, 4);
    assert_int_equal(mesh.triangle_count, 2);
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
    load_ok(&mesh, temp_file("square.ply", b.data, b.size));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.vertex_count, 4);
    assert_int_equal(mesh.triangle_count, 2);
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

/* ------------------------------------------------------------------ STL */

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

/* ------------------------------------------------------------------ glTF */

/* nodes.gltf: scene 1 of two; a matrix node (x + 10) over a TRS node (translation y + 1, 90
 * degrees about z, scale 2) holding a triangle without normals; a node mirroring x (scale -1,
 * then z + 5) holding the triangle with NORMAL +z and a point primitive (skipped); a node outside
 * the scene. The buffer is an external file whose name is percent-encoded. */
static void test_gltf_nodes(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_ok(&mesh, fixture("nodes.gltf"));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.vertex_count, 6);
    assert_int_equal(mesh.triangle_count, 2);
    /* (0,0,0) (1,0,0) (0,1,0) scaled by 2, turned (x, y) -> (-y, x), moved by (10, 1, 0). */
    size_t a = vertex_at(&mesh, 10, 1, 0), b = vertex_at(&mesh, 10, 3, 0);
    size_t c = vertex_at(&mesh, 8, 1, 0);
    assert_triangle(&mesh, 0, (uint32_t)a, (uint32_t)b, (uint32_t)c);
    /* Mirrored: the winding turns round so that the file's normal +z still agrees with it. */
    size_t d = vertex_at(&mesh, 0, 0, 5), e = vertex_at(&mesh, -1, 0, 5);
    size_t f = vertex_at(&mesh, 0, 1, 5);
    assert_triangle(&mesh, 1, (uint32_t)d, (uint32_t)f, (uint32_t)e);
    /* The first mesh has no NORMAL: flat (zero), as glTF says; the mirrored one keeps its +z. */
    for (size_t i = 0; i < 3; i++) {
        assert_vec3_near(mesh.normals[(size_t[]){a, b, c}[i]], 0, 0, 0);
        assert_vec3_near(mesh.normals[(size_t[]){d, e, f}[i]], 0, 0, 1);
    }
    assert_int_equal(mesh.point_primitives, 1);
    ao_mesh_finish(&mesh);
}

/* No scene: every root node; a non-indexed primitive with an embedded buffer (a triangle). */
static void test_gltf_no_scene(void **state)
{
    (void)state;
    static const char text[] =
        "{\"asset\": {\"version\": \"2.0\"},\n"
        " \"nodes\": [{\"mesh\": 0, \"translation\": [0, 0, 1]}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3,\n"
        "                \"type\": \"VEC3\"}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}],\n"
        " \"buffers\": [{\"byteLength\": 36, \"uri\": \"data:application/gltf-buffer;base64,"
        "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}]}\n";
    struct ao_mesh mesh;
    load_ok(&mesh, temp_file("triangle.gltf", text, sizeof text - 1));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.triangle_count, 1);
    assert_triangle(&mesh, 0, 0, 1, 2);
    assert_vec3_near(mesh.positions[1], 1, 0, 1);
    assert_vec3_near(mesh.positions[2], 0, 1, 1);
    assert_vec3_near(mesh.normals[0], 0, 0, 0);   /* no NORMAL: flat */
    ao_mesh_finish(&mesh);
}

/* A one-triangle glTF, (0,0,0) (1,0,0) (0,1,0), under one node with the given transform members. */
static void load_transformed_triangle(struct ao_mesh *mesh, const char *transform)
{
    char text[1024];
    int n = snprintf(text, sizeof text,
                     "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 0, %s}],\n"
                     " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}],\n"
                     " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3,"
                     " \"type\": \"VEC3\"}], \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}],\n"
                     " \"buffers\": [{\"byteLength\": 36, \"uri\": \"data:application/gltf-buffer;base64,"
                     "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}]}\n", transform);
    load_ok(mesh, temp_file("transformed.gltf", text, (size_t)n));
    assert_mesh_valid(mesh);
    assert_int_equal(mesh->triangle_count, 1);
}

/* Quaternions of any nonzero length are normalized, also where their squares would overflow or
 * vanish (1e200 gave an infinite length and a silent identity, 1e-200 a "zero quaternion"). */
static void test_gltf_rotation_of_any_length(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_transformed_triangle(&mesh, "\"rotation\": [1e200, 0, 0, 0]");   /* 180 degrees about x */
    assert_vec3_near(mesh.positions[1], 1, 0, 0);
    assert_vec3_near(mesh.positions[2], 0, -1, 0);
    ao_mesh_finish(&mesh);
    load_transformed_triangle(&mesh, "\"rotation\": [0, 0, 0, 1e-200]");  /* the identity */
    assert_vec3_near(mesh.positions[2], 0, 1, 0);
    ao_mesh_finish(&mesh);
    load_transformed_triangle(&mesh, "\"rotation\": [0, 0, 3, 3]");       /* 90 degrees about z */
    assert_vec3_near(mesh.positions[1], 0, 1, 0);
    assert_vec3_near(mesh.positions[2], -1, 0, 0);
    ao_mesh_finish(&mesh);
}

/* A finite but huge matrix whose entries cancel on the triangle's plane: the triangle (0,0,0)
 * (1,1,0) (0,0,1) with NORMAL along (1,-1,0) under rows (1, 0, 0), (H, 1 - H, 0), (H, -H, 1),
 * H = 1e160. The positions stay finite, but the products of two entries overflow, and the normal
 * transform came out NaN (inf - inf); assert_mesh_valid wants every normal finite, unit or zero. */
static void test_gltf_huge_matrix_gives_finite_normals(void **state)
{
    (void)state;
    static const char text[] =
        "{\"asset\": {\"version\": \"2.0\"},\n"
        " \"nodes\": [{\"mesh\": 0, \"matrix\": [1, 1e160, 1e160, 0, 0, -1e160, -1e160, 0, 0, 0, 1, 0,"
        " 0, 0, 0, 1]}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1}}]}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"},\n"
        "                {\"bufferView\": 0, \"byteOffset\": 36, \"componentType\": 5126, \"count\": 3,"
        " \"type\": \"VEC3\"}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 72}],\n"
        " \"buffers\": [{\"byteLength\": 72, \"uri\": \"data:application/gltf-buffer;base64,"
        "AAAAAAAAAAAAAAAAAACAPwAAgD8AAAAAAAAAAAAAAAAAAIA/8wQ1P/MENb8AAAAA8wQ1P/MENb8AAAAA8wQ1P/MENb8AAAAA\"}]}\n";
    struct ao_mesh mesh;
    load_ok(&mesh, temp_file("huge_matrix.gltf", text, sizeof text - 1));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.triangle_count, 1);
    ao_mesh_finish(&mesh);
}

/* The size of the file at path. */
static uint64_t file_size(const char *path)
{
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    return (uint64_t)st.st_size;
}

/* base64 of size bytes into out, which holds 4 (size + 2) / 3 + 1 characters. */
static void base64(const unsigned char *in, size_t size, char *out)
{
    static const char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (size_t i = 0; i < size; i += 3) {
        uint32_t bits = (uint32_t)in[i] << 16 | (i + 1 < size ? (uint32_t)in[i + 1] << 8 : 0) |
                        (i + 2 < size ? in[i + 2] : 0);
        for (int k = 0; k < 4; k++)
            *out++ = k <= (int)(size - i) ? digits[bits >> (18 - 6 * k) & 63] : '=';
    }
    *out = '\0';
}

/* A glTF file made of json, a printf format whose one %s becomes a base64 data URI of the bytes
 * data (and whose %zu, before it, their count); returns its path. */
static const char *gltf_file(const char *name, const char *json, const void *data, size_t size)
{
    char *uri = malloc(64 + 4 * (size + 2) / 3 + 1), *text = malloc(strlen(json) + 96 + 4 * (size + 2) / 3);
    assert_non_null(uri);
    assert_non_null(text);
    strcpy(uri, "data:application/gltf-buffer;base64,");
    base64(data, size, uri + strlen(uri));
    int n = sprintf(text, json, size, uri);
    const char *path = temp_file(name, text, (size_t)n);
    free(uri);
    free(text);
    return path;
}

/* Triangle strips and fans (modes 5 and 6) load as triangles in glTF's winding. A strip of five
 * vertices zigzagging in z = 0 makes (0 1 2), (1 3 2), (2 3 4): every one faces -z, so the odd one
 * is turned round; an indexed fan 4 0 1 2 3 makes (0 1 4), (1 2 4), (2 3 4); a strip of two
 * vertices makes none. The fan names the strip's POSITION accessor, so the two share its vertices.
 * Under a mirroring node (scale -1 in x), each triangle turns round.
 * The primitive of points beside them is skipped and counted. */
static void test_gltf_strips_and_fans(void **state)
{
    (void)state;
    struct {
        float p[5][3];
        unsigned char index[5], pad[3];
    } data = {{{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}, {2, 0, 0}}, {4, 0, 1, 2, 3}, {0}};
    static const char json[] =
        "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 0, \"scale\": [%s, 1, 1]}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"mode\": 5},\n"
        "                {\"attributes\": {\"POSITION\": 0}, \"indices\": 1, \"mode\": 6},\n"
        "                {\"attributes\": {\"POSITION\": 2}, \"mode\": 5}, {\"attributes\": {\"POSITION\": 0}, \"mode\": 0}]}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 5, \"type\": \"VEC3\"},\n"
        "               {\"bufferView\": 0, \"byteOffset\": 60, \"componentType\": 5121, \"count\": 5, \"type\": \"SCALAR\"},\n"
        "               {\"bufferView\": 0, \"componentType\": 5126, \"count\": 2, \"type\": \"VEC3\"}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": %%zu}], \"buffers\": [{\"byteLength\": %%zu, \"uri\": \"%%s\"}]}\n";
    for (int mirror = 0; mirror < 2; mirror++) {
        char format[2048];
        snprintf(format, sizeof format, json, mirror ? "-1" : "1");
        /* The view and the buffer share the size: print it twice through one %zu each. */
        char twice[2048];
        char *at = strstr(format, "%zu}]");
        assert_non_null(at);
        snprintf(twice, sizeof twice, "%.*s%zu%s", (int)(at - format), format, sizeof data, at + 3);
        struct ao_mesh mesh;
        load_ok(&mesh, gltf_file("strips.gltf", twice, &data, sizeof data));
        assert_mesh_valid(&mesh);
        assert_int_equal(mesh.triangle_count, 6);
        assert_int_equal(mesh.point_primitives, 1);
        assert_int_equal(mesh.line_primitives, 0);
        static const uint32_t want[6][3] = {{0, 1, 2}, {1, 3, 2}, {2, 3, 4}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}};
        assert_int_equal(mesh.vertex_count, 5 + 2);   /* the fan shares the strip's vertices */
        for (size_t t = 0; t < 6; t++) {
            if (mirror)
                assert_triangle(&mesh, t, want[t][0], want[t][2], want[t][1]);
            else
                assert_triangle(&mesh, t, want[t][0], want[t][1], want[t][2]);
        }
        /* Without NORMAL the normals are flat, as glTF says: zero, which shading replaces by the
         * triangle's own. */
        for (size_t i = 0; i < 5; i++)
            assert_vec3_near(mesh.normals[i], 0, 0, 0);
        ao_mesh_finish(&mesh);
    }
}

/* A glTF whose mesh 0 (a strip of 202 vertices (i / 2, i % 2, 0) making 200 triangles) is named
 * by `copies` nodes, node k translated by (2k, 0, 0), and whose mesh 1 (the same accessor) by one
 * more node, scaled by -1 in x; returns its path. */
static const char *placed_gltf(const char *name, int copies)
{
    static float p[202][3];
    for (int i = 0; i < 202; i++)
        p[i][0] = (float)(i / 2), p[i][1] = (float)(i % 2), p[i][2] = 0.0f;
    size_t size = (size_t)copies * 64 + 1024;
    char *json = malloc(size), *at = json;
    assert_non_null(json);
    at += sprintf(at, "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [");
    for (int k = 0; k < copies; k++)
        at += sprintf(at, "{\"mesh\": 0, \"translation\": [%d, 0, 0]}, ", 2 * k);
    sprintf(at, "{\"mesh\": 1, \"scale\": [-1, 1, 1]}],\n"
                " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"mode\": 5}]},"
                " {\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"mode\": 5}]}],\n"
                " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 202, \"type\": \"VEC3\"}],\n"
                " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 2424}], \"buffers\": [{\"byteLength\": %%zu, \"uri\": \"%%s\"}]}\n");
    const char *path = gltf_file(name, json, p, sizeof p);
    free(json);
    return path;
}

/* A mesh that several nodes name loads once, in its own frame, with one placement per node: the
 * model holds 2 meshes (each glTF mesh once) and 1001 placements, and loads within a budget that
 * holds those (what a scene keeps) where the flattened 200,200 triangles would not fit. */
static void test_gltf_meshes_load_once(void **state)
{
    (void)state;
    const char *path = placed_gltf("placed.gltf", 1000);
    struct ao_model model;
    struct ao_budget budget = {.limit = UINT64_MAX / 2};
    assert_true(ao_load_model(&model, path, &budget, AO_MESH_CREASE_DEFAULT));
    assert_int_equal(budget.used, 0);
    assert_int_equal(model.mesh_count, 2);
    assert_int_equal(model.placement_count, 1001);
    for (size_t m = 0; m < 2; m++) {
        assert_int_equal(model.meshes[m].triangle_count, 200);
        assert_int_equal(model.meshes[m].vertex_count, 202);
        assert_vec3_near(model.meshes[m].positions[3], 1, 1, 0);   /* untransformed */
        assert_vec3_near(model.meshes[m].normals[0], 0, 0, 0);   /* no NORMAL: flat */
    }
    for (size_t k = 0; k < 1000; k++) {
        struct ao_affine want = ao_affine_identity();
        want.m[9] = 2.0 * (double)k;
        assert_int_equal(model.placements[k].mesh, 0);
        assert_memory_equal(&model.placements[k].to_model, &want, sizeof want);
    }
    assert_int_equal(model.placements[1000].mesh, 1);
    assert_true(model.placements[1000].to_model.m[0] == -1.0);
    ao_model_finish(&model);

    /* The budget: the file, its JSON (4 MiB hold both), 400 triangles, 404 vertices and 1001 placements fit; the
     * 200,200 triangles and 202,202 vertices flattened would need more. */
    uint64_t unique = medium_model(400, 404, 1001), flat = medium_charge(200200, 202202);
    assert_true(flat > unique + (4 << 20));
    budget = (struct ao_budget){.limit = unique + (4 << 20), .bvh = AO_BVH_MEDIUM};
    assert_true(ao_load_model(&model, path, &budget, AO_MESH_CREASE_DEFAULT));
    ao_model_finish(&model);
    char err[1024];
    struct ao_mesh mesh;
    assert_false(load_within(&mesh, path, unique + (4 << 20), err, sizeof err));
    assert_non_null(strstr(err, "placed.gltf: 200200 triangles and 202202 vertices need about"));

    /* A model placed once is refused in a line that names its triangles, not "placed 1 times". */
    path = placed_gltf("once.gltf", 0);
    assert_false(load_within(&mesh, path, 40 << 10, err, sizeof err));
    assert_non_null(strstr(err, "once.gltf: 200 triangles and 202 vertices need about"));
    assert_null(strstr(err, "placed"));
}

/* A node tree deeper than AO_GLTF_MAX_NODE_DEPTH (1024) is refused in one line naming the limit,
 * without recursion (10^5 levels); one of 1024 levels loads. */
static void test_gltf_deep_node_tree(void **state)
{
    (void)state;
    float p[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    static const int depths[2] = {1024, 100000};
    for (int d = 0; d < 2; d++) {
        int n = depths[d];
        char *json = malloc((size_t)n * 40 + 1024), *at = json;
        assert_non_null(json);
        at += sprintf(at, "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [");
        for (int k = 0; k + 1 < n; k++)
            at += sprintf(at, "{\"children\": [%d]}, ", k + 1);
        sprintf(at, "{\"mesh\": 0}],\n"
                    " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}],\n"
                    " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"}],\n"
                    " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}], \"buffers\": [{\"byteLength\": %%zu, \"uri\": \"%%s\"}]}\n");
        const char *path = gltf_file(d ? "deep.gltf" : "deep_enough.gltf", json, p, sizeof p);
        free(json);
        if (d) {
            expect_failure(path, ": ", "node 1024 lies more than 1024 nodes deep, the deepest node tree aoview reads");
        } else {
            struct ao_mesh mesh;
            load_ok(&mesh, path);
            assert_int_equal(mesh.triangle_count, 1);
            ao_mesh_finish(&mesh);
        }
    }
}

/* A one-triangle glTF whose top level also holds members (e.g. "\"extensionsRequired\": [...]"). */
static const char *triangle_gltf(const char *name, const char *members)
{
    float p[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    char json[1024];
    snprintf(json, sizeof json,
             "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 0}], %s,\n"
             " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}],\n"
             " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"}],\n"
             " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}], \"buffers\": [{\"byteLength\": %%zu, \"uri\": \"%%s\"}]}\n",
             members);
    return gltf_file(name, json, p, sizeof p);
}

/* Required extensions that change only how surfaces look load, with one note naming them (printed
 * by the front end); one that changes the geometry and is not read, or one aoview does not know,
 * is refused naming it. */
static void test_gltf_required_extensions(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_ok(&mesh, triangle_gltf("looks.gltf", "\"extensionsRequired\": [\"KHR_texture_basisu\", "
                                 "\"KHR_materials_transmission\", \"KHR_texture_transform\", \"KHR_lights_punctual\"]"));
    assert_int_equal(mesh.triangle_count, 1);
    assert_string_equal(mesh.note, "materials, textures and lights are ignored (it requires KHR_texture_basisu, "
                                   "KHR_materials_transmission, KHR_texture_transform, KHR_lights_punctual)");
    ao_mesh_finish(&mesh);
    load_ok(&mesh, triangle_gltf("plain.gltf", "\"extensionsUsed\": [\"FOO_anything\"]"));
    assert_string_equal(mesh.note, "");
    ao_mesh_finish(&mesh);
    expect_failure(triangle_gltf("instancing.gltf", "\"extensionsRequired\": [\"KHR_materials_unlit\", "
                                 "\"EXT_mesh_gpu_instancing\"]"), ": ",
                   "requires extension 'EXT_mesh_gpu_instancing', which places meshes many times");
    expect_failure(triangle_gltf("unknown.gltf", "\"extensionsRequired\": [\"FOO_geometry\"]"), ": ",
                   "requires extension 'FOO_geometry', which aoview does not know (it may change the geometry)");
    expect_failure(triangle_gltf("number.gltf", "\"extensionsRequired\": [7]"), ": ",
                   "extensionsRequired: entry 0 is not a string");
}

/* A GLB of the JSON text and the BIN chunk bin (both padded to 4 bytes), with extra bytes after it
 * that its header does not count; returns its path. */
static const char *glb_file(const char *name, const char *json, const void *bin, size_t bin_size, size_t extra)
{
    size_t json_size = (strlen(json) + 3) / 4 * 4, padded = (bin_size + 3) / 4 * 4;
    size_t total = 12 + 8 + json_size + 8 + padded;
    unsigned char *data = calloc(1, total + extra);
    assert_non_null(data);
    uint32_t words[5] = {0x46546C67, 2, (uint32_t)total, (uint32_t)json_size, 0x4E4F534A};
    for (int k = 0; k < 5; k++)
        for (int b = 0; b < 4; b++)
            data[4 * k + b] = (unsigned char)(words[k] >> (8 * b));
    memset(data + 20, ' ', json_size);
    memcpy(data + 20, json, strlen(json));
    uint32_t bin_words[2] = {(uint32_t)padded, 0x004E4942};
    for (int k = 0; k < 2; k++)
        for (int b = 0; b < 4; b++)
            data[20 + json_size + 4 * k + b] = (unsigned char)(bin_words[k] >> (8 * b));
    memcpy(data + 28 + json_size, bin, bin_size);
    memset(data + total, 0x5a, extra);
    const char *path = temp_file(name, data, total + extra);
    free(data);
    return path;
}

/* Where the glTF validator only warns, files load: bytes after a GLB's stated length (ignored, and
 * said in the note), a data URI that is not base64 (percent-encoded bytes), a buffer without a
 * uri that nothing reads. A buffer without data that a view reads, and a bad escape, are refused. */
static void test_gltf_leniency(void **state)
{
    (void)state;
    float p[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    static const char glb_json[] =
        "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 0}],"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}],"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"}],"
        " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}], \"buffers\": [{\"byteLength\": 36},"
        " {\"byteLength\": 1000}]}";
    struct ao_mesh mesh;
    const char *path = glb_file("trailing.glb", glb_json, p, sizeof p, 13);
    load_ok(&mesh, path);
    assert_int_equal(mesh.triangle_count, 1);
    char want[160];
    snprintf(want, sizeof want, "13 bytes after the GLB's stated length of %llu are ignored",
             (unsigned long long)file_size(path) - 13);
    assert_string_equal(mesh.note, want);
    ao_mesh_finish(&mesh);
    load_ok(&mesh, glb_file("exact.glb", glb_json, p, sizeof p, 0));
    assert_string_equal(mesh.note, "");
    ao_mesh_finish(&mesh);

    /* The triangle's 36 bytes percent-encoded: %00 for zero bytes, %3F and the letter '?' alike. */
    static const char text[] =
        "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 0}],"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}],"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"}],"
        " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}],"
        " \"buffers\": [{\"byteLength\": 36, \"uri\": \"data:application/octet-stream,"
        "%00%00%00%00%00%00%00%00%00%00%00%00%00%00%80%3F%00%00%00%00%00%00%00%00%00%00%00%00%00%00%80?"
        "%00%00%00%00\"}, {\"byteLength\": 8}]}";
    load_ok(&mesh, temp_file("percent.gltf", text, sizeof text - 1));
    assert_int_equal(mesh.triangle_count, 1);
    assert_vec3_near(mesh.positions[1], 1, 0, 0);
    assert_vec3_near(mesh.positions[2], 0, 1, 0);
    ao_mesh_finish(&mesh);
    char bad[sizeof text];
    strcpy(bad, text);
    memcpy(strstr(bad, "%80%3F"), "%80%G0", 6);
    expect_failure(temp_file("bad_percent.gltf", bad, sizeof text - 1), ": ",
                   "buffer 0: bad percent-encoding at byte 45 of its data URI's data");
    strcpy(bad, text);
    memcpy(strstr(bad, "\"buffer\": 0"), "\"buffer\": 1", 11);
    memcpy(strstr(bad, "{\"byteLength\": 8}"), "{\"byteLength\":36}", 17);
    expect_failure(temp_file("no_data.gltf", bad, sizeof text - 1), ": ",
                   "buffer 1 has no 'uri' and is not a GLB's BIN chunk: it has no data");
}

/* A mesh whose first primitive has no normals and whose second has: the first's vertices are flat
 * (zero: glTF's rule), the second's keep the file's (kept from the first primitive that has some). */
static void test_gltf_normals_from_a_later_primitive(void **state)
{
    (void)state;
    static const float data[3][3][3] = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}},
                                         {{1, 0, 0}, {1, 0, 0}, {1, 0, 0}}};
    static const char json[] =
        "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 0}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}},"
        " {\"attributes\": {\"POSITION\": 1, \"NORMAL\": 2}}]}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"},\n"
        "   {\"bufferView\": 1, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"},\n"
        "   {\"bufferView\": 2, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}, {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 36},"
        " {\"buffer\": 0, \"byteOffset\": 72, \"byteLength\": 36}],\n"
        " \"buffers\": [{\"byteLength\": %zu, \"uri\": \"%s\"}]}\n";
    struct ao_mesh mesh;
    load_ok(&mesh, gltf_file("later_normals.gltf", json, &data, sizeof data));
    assert_int_equal(mesh.vertex_count, 6);
    for (int i = 0; i < 3; i++) {
        assert_vec3_near(mesh.normals[i], 0, 0, 0);
        assert_vec3_near(mesh.normals[3 + i], 1, 0, 0);
    }
    ao_mesh_finish(&mesh);
}

/* KHR_mesh_quantization: positions and normals as 8- and 16-bit integers, normalized or not, in
 * 4-byte aligned strides, under the node transform that gives them their size (as exporters write
 * them). Normalized signed values map to c / 127 or c / 32767, at least -1 (so -32768 is -1, as
 * -32767 is); unsigned ones to c / 255 or c / 65535; others are their integer values. */
static void test_gltf_quantized(void **state)
{
    (void)state;
    struct {
        int16_t p[3][4];        /* SHORT normalized, stride 8 */
        int8_t n[3][4];         /* BYTE normalized, stride 4 */
        uint8_t q[3][4];        /* UNSIGNED_BYTE, stride 4 */
        uint16_t r[3][4];       /* UNSIGNED_SHORT normalized, stride 8 */
    } data = {{{0, 0, 0, 0}, {32767, 0, 0, 0}, {0, -32768, 0, 0}},
              {{0, 0, -127, 0}, {0, 0, -127, 0}, {0, 0, -128, 0}},
              {{1, 1, 1, 0}, {3, 1, 1, 0}, {1, 3, 1, 0}},
              {{0, 0, 65535, 0}, {65535, 0, 65535, 0}, {0, 65535, 65535, 0}}};
    static const char json[] =
        "{\"asset\": {\"version\": \"2.0\"}, \"extensionsUsed\": [\"KHR_mesh_quantization\"],"
        " \"extensionsRequired\": [\"KHR_mesh_quantization\"], \"nodes\": [{\"mesh\": 0, \"scale\": [2, 2, 2]}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1}},"
        " {\"attributes\": {\"POSITION\": 2}}, {\"attributes\": {\"POSITION\": 3}}]}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5122, \"normalized\": true, \"count\": 3, \"type\": \"VEC3\"},\n"
        "   {\"bufferView\": 1, \"componentType\": 5120, \"normalized\": true, \"count\": 3, \"type\": \"VEC3\"},\n"
        "   {\"bufferView\": 2, \"componentType\": 5121, \"count\": 3, \"type\": \"VEC3\"},\n"
        "   {\"bufferView\": 3, \"componentType\": 5123, \"normalized\": true, \"count\": 3, \"type\": \"VEC3\"}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 24, \"byteStride\": 8},"
        " {\"buffer\": 0, \"byteOffset\": 24, \"byteLength\": 12, \"byteStride\": 4},"
        " {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 12, \"byteStride\": 4},"
        " {\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": 24, \"byteStride\": 8}],\n"
        " \"buffers\": [{\"byteLength\": %zu, \"uri\": \"%s\"}]}\n";
    struct ao_mesh mesh;
    load_ok(&mesh, gltf_file("quantized.gltf", json, &data, sizeof data));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.triangle_count, 3);
    assert_string_equal(mesh.note, "");
    static const float want[9][3] = {{0, 0, 0}, {2, 0, 0}, {0, -2, 0}, {2, 2, 2}, {6, 2, 2}, {2, 6, 2},
                                     {0, 0, 2}, {2, 0, 2}, {0, 2, 2}};
    for (size_t i = 0; i < 9; i++)
        assert_true(mesh.positions[i].x == want[i][0] && mesh.positions[i].y == want[i][1] &&
                    mesh.positions[i].z == want[i][2]);
    for (size_t i = 0; i < 3; i++)
        assert_vec3_near(mesh.normals[i], 0, 0, -1);
    ao_mesh_finish(&mesh);
}

/* Sparse accessors: entries written over the bufferView's elements, or over zeros without one; an
 * accessor without a bufferView or sparse entries is zeros. Positions: the triangle (0,0,0) (1,0,0)
 * (0,1,0) with its last vertex moved to (0,2,0) by a sparse entry; then the same triangle from zeros
 * and two entries (unsigned short indices); indices 0 0 0 with entries making them 0 1 2; NORMAL
 * all zeros. A sparse index past the count is refused. */
static void test_gltf_sparse(void **state)
{
    (void)state;
    struct {
        float p[3][3];
        float moved[3];
        uint16_t at[2];
        float two[2][3];
        uint8_t index_at[2], index_value[2];
    } data = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 2, 0}, {1, 2}, {{1, 0, 0}, {0, 1, 0}}, {1, 2}, {1, 2}};
    static const char json[] =
        "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 0}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 2}},"
        " {\"attributes\": {\"POSITION\": 1}, \"indices\": 3}]}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\",\n"
        "    \"sparse\": {\"count\": 1, \"indices\": {\"bufferView\": 0, \"byteOffset\": 50, \"componentType\": 5123},"
        " \"values\": {\"bufferView\": 0, \"byteOffset\": 36}}},\n"
        "   {\"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\", \"sparse\": {\"count\": 2,"
        " \"indices\": {\"bufferView\": 0, \"byteOffset\": 48, \"componentType\": 5123}, \"values\": {\"bufferView\": 0,"
        " \"byteOffset\": 52}}},\n"
        "   {\"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"},\n"
        "   {\"componentType\": 5121, \"count\": 3, \"type\": \"SCALAR\", \"sparse\": {\"count\": 2, \"indices\":"
        " {\"bufferView\": 0, \"byteOffset\": 76, \"componentType\": 5121}, \"values\": {\"bufferView\": 0,"
        " \"byteOffset\": 78}}}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 80}],\n"
        " \"buffers\": [{\"byteLength\": %zu, \"uri\": \"%s\"}]}\n";
    struct ao_mesh mesh;
    load_ok(&mesh, gltf_file("sparse.gltf", json, &data, sizeof data));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.triangle_count, 2);
    assert_vec3_near(mesh.positions[2], 0, 2, 0);
    assert_vec3_near(mesh.positions[3], 0, 0, 0);
    assert_vec3_near(mesh.positions[4], 1, 0, 0);
    assert_vec3_near(mesh.positions[5], 0, 1, 0);
    assert_vec3_near(mesh.normals[0], 0, 0, 0);     /* the file's normals, zeros: as if not given */
    assert_int_equal(mesh.invalid_normals, 3);
    assert_vec3_near(mesh.normals[3], 0, 0, 0);     /* none given: flat */
    assert_triangle(&mesh, 1, 3, 4, 5);
    ao_mesh_finish(&mesh);
    data.at[1] = 3;
    expect_failure(gltf_file("sparse_range.gltf", json, &data, sizeof data), ": ",
                   "accessor 0 (POSITION) sparse: index 3 at 0 is out of range (3 elements)");
}

/* A glTF of one mesh, every view of it compressed with EXT_meshopt_compression by the library's
 * own encoders, in buffer 0, and the fallback buffer 1 without data (as gltfpack writes them):
 * positions (float, or with quantized shorts), normals octahedral-filtered into bytes, and the
 * indices as a triangle list (TRIANGLES) and as a strip (INDICES, mode 5). */
struct meshopt_file {
    unsigned char data[4096];
    size_t size;
    char views[2048];
    size_t view_count;
};

/* Encodes count elements of stride bytes as mode into f's buffer and adds its bufferView. */
static void meshopt_add(struct meshopt_file *f, const char *mode, const char *filter, const void *elements,
                        size_t count, size_t stride)
{
    size_t room = sizeof f->data - f->size, n;
    if (strcmp(mode, "ATTRIBUTES") == 0)
        n = meshopt_encodeVertexBuffer(f->data + f->size, room, elements, count, stride);
    else if (strcmp(mode, "TRIANGLES") == 0)
        n = meshopt_encodeIndexBuffer(f->data + f->size, room, elements, count);
    else
        n = meshopt_encodeIndexSequence(f->data + f->size, room, elements, count);
    assert_true(n > 0);
    size_t used = strlen(f->views);
    snprintf(f->views + used, sizeof f->views - used,
             "%s{\"buffer\": 1, \"byteLength\": %zu%s, \"extensions\": {\"EXT_meshopt_compression\": {\"buffer\": 0,"
             " \"byteOffset\": %zu, \"byteLength\": %zu, \"byteStride\": %zu, \"count\": %zu, \"mode\": \"%s\"%s%s%s}}}",
             f->view_count ? ", " : "", count * stride, strcmp(mode, "ATTRIBUTES") ? "" : ", \"byteStride\": 0",
             f->size, n, stride, count, mode, filter ? ", \"filter\": \"" : "", filter ? filter : "", filter ? "\"" : "");
    if (strcmp(mode, "ATTRIBUTES") == 0) {   /* the view's byteStride is the extension's */
        char *zero = strstr(f->views + used, "\"byteStride\": 0");
        char stride_text[32];
        int k = snprintf(stride_text, sizeof stride_text, "\"byteStride\": %zu", stride);
        memmove(zero + k, zero + 15, strlen(zero + 15) + 1);
        memcpy(zero, stride_text, (size_t)k);
    }
    f->size += (n + 3) / 4 * 4;
    f->view_count++;
}

/* The test's file: accessors over views 0 (positions), 1 (normals), 2 (indices), 3 (quantized
 * positions, under a node scaling by 2), 4 (strip indices, 32 bits). */
static const char *meshopt_gltf(const char *name, const struct meshopt_file *f, size_t index_count)
{
    char *json = malloc(16384);
    assert_non_null(json);
    int n = snprintf(json, 16384,
        "{\"asset\": {\"version\": \"2.0\"}, \"extensionsUsed\": [\"EXT_meshopt_compression\", \"KHR_mesh_quantization\"],"
        " \"extensionsRequired\": [\"EXT_meshopt_compression\", \"KHR_mesh_quantization\"],\n"
        " \"nodes\": [{\"mesh\": 0}, {\"mesh\": 1, \"scale\": [2, 2, 2]}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1}, \"indices\": 2}]},\n"
        "   {\"primitives\": [{\"attributes\": {\"POSITION\": 3}, \"indices\": 4, \"mode\": 5}]}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 9, \"type\": \"VEC3\"},\n"
        "   {\"bufferView\": 1, \"componentType\": 5120, \"normalized\": true, \"count\": 9, \"type\": \"VEC3\"},\n"
        "   {\"bufferView\": 2, \"componentType\": 5123, \"count\": %zu, \"type\": \"SCALAR\"},\n"
        "   {\"bufferView\": 3, \"componentType\": 5122, \"normalized\": true, \"count\": 9, \"type\": \"VEC3\"},\n"
        "   {\"bufferView\": 4, \"componentType\": 5125, \"count\": 5, \"type\": \"SCALAR\"}],\n"
        " \"bufferViews\": [%s],\n"
        " \"buffers\": [{\"byteLength\": %%zu, \"uri\": \"%%s\"}, {\"byteLength\": 4096,"
        " \"extensions\": {\"EXT_meshopt_compression\": {\"fallback\": true}}}]}\n", index_count, f->views);
    assert_true(n > 0 && n < 16384);
    const char *path = gltf_file(name, json, f->data, f->size);
    free(json);
    return path;
}

/* EXT_meshopt_compression decodes to exactly what was encoded: the float positions of a 3 x 3
 * grid, its 8 triangles, its quantized positions (exactly, under the node's scale) and a strip; the
 * octahedral normals within their 8 bits; the triangle codec may rotate a triangle's corners, not
 * its winding. Then what the library or the extension refuses: a
 * triangle index past the vertices, a stream cut short, a codec version 0.18 cannot decode, a
 * stride the attribute codec does not take, a view length that is not count * stride. */
static void test_gltf_meshopt(void **state)
{
    (void)state;
    float p[9][3];
    int8_t normal[9][4];
    int16_t q[9][4];
    float up[9][4];
    for (int i = 0; i < 9; i++) {
        p[i][0] = (float)(i % 3), p[i][1] = (float)(i / 3), p[i][2] = 0.25f * (float)(i % 2);
        q[i][0] = (int16_t)(i % 3 * 16383), q[i][1] = (int16_t)(i / 3 * 16383), q[i][2] = 0, q[i][3] = 0;
        up[i][0] = 0, up[i][1] = 0, up[i][2] = 1, up[i][3] = 0;
    }
    meshopt_encodeFilterOct(normal, 9, 4, 8, &up[0][0]);
    uint16_t triangles[24];
    for (int c = 0, k = 0; c < 4; c++) {
        uint16_t a = (uint16_t)(c / 2 * 3 + c % 2);   /* the cell's lower left corner */
        uint16_t t[6] = {a, (uint16_t)(a + 1), (uint16_t)(a + 3), (uint16_t)(a + 1), (uint16_t)(a + 4), (uint16_t)(a + 3)};
        memcpy(triangles + k, t, sizeof t);
        k += 6;
    }
    unsigned int triangles32[24], strip[5] = {0, 3, 1, 4, 2};
    for (int k = 0; k < 24; k++)
        triangles32[k] = triangles[k];
    meshopt_encodeIndexVersion(1);   /* the version EXT_meshopt_compression names (0xe1) */
    struct meshopt_file f = {.size = 0};
    meshopt_add(&f, "ATTRIBUTES", NULL, p, 9, 12);
    meshopt_add(&f, "ATTRIBUTES", "OCTAHEDRAL", normal, 9, 4);
    meshopt_add(&f, "TRIANGLES", NULL, triangles32, 24, 2);
    meshopt_add(&f, "ATTRIBUTES", NULL, q, 9, 8);
    meshopt_add(&f, "INDICES", NULL, strip, 5, 4);
    struct ao_mesh mesh;
    load_ok(&mesh, meshopt_gltf("meshopt.gltf", &f, 24));
    assert_mesh_valid(&mesh);
    assert_int_equal(mesh.triangle_count, 8 + 3);
    for (size_t i = 0; i < 9; i++) {
        assert_true(mesh.positions[i].x == p[i][0] && mesh.positions[i].y == p[i][1] &&
                    mesh.positions[i].z == p[i][2]);
        assert_vec3_near(mesh.normals[i], 0, 0, 1);
        /* q / 32767 * 2: 16383 / 32767 * 2 rounds to 0.99996948 in single precision. */
        assert_float_equal(mesh.positions[9 + i].x, (float)(q[i][0] / 32767.0 * 2.0), 0.0f);
        assert_float_equal(mesh.positions[9 + i].y, (float)(q[i][1] / 32767.0 * 2.0), 0.0f);
    }
    /* The triangle codec keeps the triangles' order and winding but may rotate their corners. */
    for (size_t t = 0; t < 8; t++) {
        const uint32_t *got = mesh.indices + 3 * t;
        int r = got[0] == triangles[3 * t] ? 0 : got[1] == triangles[3 * t] ? 2 : 1;
        for (int k = 0; k < 3; k++)
            assert_int_equal(got[(k + 3 - r) % 3], triangles[3 * t + k]);
    }
    assert_triangle(&mesh, 8, 9 + 0, 9 + 3, 9 + 1);
    assert_triangle(&mesh, 9, 9 + 3, 9 + 4, 9 + 1);
    assert_triangle(&mesh, 10, 9 + 1, 9 + 4, 9 + 2);
    ao_mesh_finish(&mesh);

    /* A triangle index past the 9 vertices: the codec carries any index; the loader refuses it. */
    struct meshopt_file bad = {.size = 0};
    triangles32[23] = 9;
    meshopt_add(&bad, "ATTRIBUTES", NULL, p, 9, 12);
    meshopt_add(&bad, "ATTRIBUTES", "OCTAHEDRAL", normal, 9, 4);
    meshopt_add(&bad, "TRIANGLES", NULL, triangles32, 24, 2);
    meshopt_add(&bad, "ATTRIBUTES", NULL, q, 9, 8);
    meshopt_add(&bad, "INDICES", NULL, strip, 5, 4);
    expect_failure(meshopt_gltf("meshopt_range.gltf", &bad, 24), ": ",
                   "mesh 0 primitive 0: index 9 at 23 is out of range (9 vertices)");
    /* The positions' stream cut short by 8 bytes. */
    char *at = strstr(f.views, "\"byteLength\": ");
    at = strstr(at + 14, "\"byteLength\": ") + 14;   /* the extension's length of view 0 */
    size_t length = strtoul(at, NULL, 10);
    struct meshopt_file cut = f;
    snprintf(cut.views, sizeof cut.views, "%.*s%zu%s", (int)(at - f.views), f.views, length - 8,
             at + strspn(at, "0123456789"));
    expect_failure(meshopt_gltf("meshopt_cut.gltf", &cut, 24), ": ",
                   "bufferView 0 (EXT_meshopt_compression): its ");
    /* Vertex codec version 1 (meshoptimizer 0.23's, and KHR_meshopt_compression's). */
    struct meshopt_file v1 = f;
    v1.data[0] = 0xa1;
    expect_failure(meshopt_gltf("meshopt_v1.gltf", &v1, 24), ": ",
                   "bufferView 0 (EXT_meshopt_compression): its data is of codec version 1, and libmeshoptimizer "
                   "0.18 decodes up to version 0");
    /* The indices' view says 46 bytes where the extension decodes 24 of 2 bytes. */
    struct meshopt_file lying = f;
    char *length48 = strstr(lying.views, "{\"buffer\": 1, \"byteLength\": 48,");
    assert_non_null(length48);
    memcpy(length48 + 28, "46", 2);
    expect_failure(meshopt_gltf("meshopt_count.gltf", &lying, 24), ": ",
                   "bufferView 2 (EXT_meshopt_compression): the view's byteLength 46 is not byteStride 2 times count 24");
    /* A stride the attribute codec does not take. */
    struct meshopt_file odd = f;
    char *stride12 = strstr(odd.views, "\"byteStride\": 12, \"count\": 9");
    assert_non_null(stride12);
    memcpy(stride12 + 14, "10", 2);
    expect_failure(meshopt_gltf("meshopt_stride.gltf", &odd, 24), ": ",
                   "bufferView 0 (EXT_meshopt_compression): attributes need a byteStride that is a multiple of 4");
}

/* A file of points and lines only has nothing to render: one line names the modes found. */
static void test_gltf_points_and_lines_only(void **state)
{
    (void)state;
    float p[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    static const char json[] =
        "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 0}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"mode\": 0},"
        " {\"attributes\": {\"POSITION\": 0}, \"mode\": 3}]}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}], \"buffers\": [{\"byteLength\": %zu, \"uri\": \"%s\"}]}\n";
    expect_failure(gltf_file("lines.gltf", json, p, sizeof p), ": ",
                   "no triangles to render: its primitives have the modes 0 (points), 3 (line strip), and aoview "
                   "draws only triangles");
}

/* ------------------------------------------------------------------ the scene budget */

/* The loaders refuse, at the right place, a mesh whose charge (ao_budget_mesh) does not fit beside
 * the file (charged while it is read): OBJ and ASCII formats as the counts grow, binary PLY and STL
 * from their headers' counts, glTF before parsing its JSON. What fits loads, and the budget comes
 * back empty. */
static void test_loaders_keep_to_the_budget(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    char err[1024];
    /* OBJ: one triangle fits exactly; the fourth vertex, one line later, does not. */
    static const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 0 0 1\n";
    const char *path = temp_file("budget.obj", obj, sizeof obj - 1);
    uint64_t file = file_size(path) + 1;
    assert_false(load_within(&mesh, path, file + medium_charge(1, 3), err, sizeof err));
    assert_non_null(strstr(err, "budget.obj:5: 1 triangles and 4 vertices need 360 bytes, more than the "
                                "300 bytes left of the scene budget (raise it with --scene-budget)"));
    path = temp_file("budget.obj", obj, sizeof obj - 9);   /* without the last line */
    file = file_size(path) + 1;
    assert_true(load_within(&mesh, path, file + medium_charge(1, 3), err, sizeof err));
    assert_int_equal(mesh.triangle_count, 1);
    ao_mesh_finish(&mesh);
    /* A file larger than the budget is not read. */
    assert_false(load_within(&mesh, path, file - 1, err, sizeof err));
    assert_non_null(strstr(err, "budget.obj: 32 bytes need 33 bytes, more than the 32 bytes left"));
    /* Binary PLY: 2 faces (at least 2 triangles) and 4 vertices, from the header; the quad then
     * fans into 2 triangles, so the mesh has 3. */
    struct bytes b = binary_square();
    path = temp_file("budget.ply", b.data, b.size);
    file = file_size(path) + 1;
    assert_false(load_within(&mesh, path, file + medium_charge(2, 4) - 1, err, sizeof err));
    assert_non_null(strstr(err, "budget.ply: 2 triangles and 4 vertices need 480 bytes"));
    assert_false(load_within(&mesh, path, file + medium_charge(3, 4) - 1, err, sizeof err));
    assert_non_null(strstr(err, "budget.ply: face 1: 3 triangles and 4 vertices need 600 bytes"));
    assert_true(load_within(&mesh, path, file + medium_charge(3, 4), err, sizeof err));
    ao_mesh_finish(&mesh);
    /* Binary STL: the header's 1000 triangles, before any is read. */
    static unsigned char stl[84 + 50 * 1000];
    stl[80] = 1000 & 0xff, stl[81] = 1000 >> 8;
    path = temp_file("budget.stl", stl, sizeof stl);
    assert_false(load_within(&mesh, path, sizeof stl + 1 + medium_charge(999, 0), err, sizeof err));
    assert_non_null(strstr(err, "budget.stl: 1000 triangles and 0 vertices need about 117.2 KiB"));
    /* glTF: its JSON tree, estimated before parsing. */
    assert_false(load_within(&mesh, fixture("nodes.gltf"), file_size(fixture("nodes.gltf")) + 1000, err, sizeof err));
    assert_non_null(strstr(err, "nodes.gltf: parsing its JSON would need about"));
    assert_true(load_within(&mesh, fixture("nodes.gltf"), 1 << 20, err, sizeof err));
    ao_mesh_finish(&mesh);
}

/* One budget covers the whole scene: a mesh file that three lines name is read and charged once,
 * each of its placements once, and each copy of it that flattening makes (a one-triangle mesh
 * placed three times is flattened: the mesh moved for the last placement, copied for the others);
 * with one byte less it is instanced, and below the mesh and its placements refused. */
static void test_scene_budget_covers_every_mesh_line(void **state)
{
    (void)state;
    static const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    temp_file("tri.obj", obj, sizeof obj - 1);
    static const char text[] = "camera eye 0 1 4 target 0 0 0\nmesh tri.obj\nmesh tri.obj translate 1 0 0\n"
                               "mesh tri.obj translate 2 0 0\n";
    const char *path = temp_file("three.scene", text, sizeof text - 1);
    /* The scene's text, the mesh (and its structures), three placements and two copies, at the MEDIUM
     * BVH's rates. */
    uint64_t need = sizeof text + 3 * medium_charge(1, 3) + AO_BUDGET_MESH + 3 * AO_BUDGET_INSTANCE;
    struct ao_scene_options medium = {.budget = need, .bvh = AO_BVH_MEDIUM};
    struct ao_scene scene;
    assert_true(ao_scene_load(&scene, path, &medium));
    assert_int_equal(scene.triangle_count, 3);
    assert_int_equal(scene.mesh_count, 3);
    assert_int_equal(scene.instance_count, 3);
    ao_scene_finish(&scene);
    /* One byte less: the copies do not fit, so the mesh is instanced instead (scene.h's AUTO). */
    medium.budget = need - 1;
    assert_true(ao_scene_load(&scene, path, &medium));
    assert_int_equal(scene.mesh_count, 1);
    assert_false(scene.instances[0].flat);
    ao_scene_finish(&scene);
    /* Without room for the copies' rule, the mesh and its placements alone: one byte less refused. */
    uint64_t least = sizeof text + medium_charge(1, 3) + AO_BUDGET_MESH + 3 * AO_BUDGET_INSTANCE;
    medium.budget = least;
    assert_true(ao_scene_load(&scene, path, &medium));
    assert_int_equal(scene.bvh, AO_BVH_MEDIUM);
    ao_scene_finish(&scene);
    medium.budget = least - 1;
    assert_false(ao_scene_load(&scene, path, &medium));
}

/* An AUTO budget charges the compact rates and builds the MEDIUM BVH when MEDIUM's charges would
 * fit too, else COMPACT with a note; below the compact charges the scene is refused. The budget
 * decides for the whole scene: the placement charged after the mesh counts alike. */
static void test_budget_builds_compact_where_only_that_fits(void **state)
{
    (void)state;
    static const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    temp_file("tri.obj", obj, sizeof obj - 1);
    static const char text[] = "camera eye 0 1 4 target 0 0 0\nmesh tri.obj\n";
    const char *path = temp_file("one.scene", text, sizeof text - 1);
    uint64_t medium = sizeof text + medium_charge(1, 3) + AO_BUDGET_MESH + AO_BUDGET_INSTANCE;
    uint64_t compact = medium - (AO_BUDGET_TRIANGLE - AO_BUDGET_TRIANGLE_COMPACT);
    struct ao_scene scene;
    assert_true(ao_scene_load(&scene, path, &(struct ao_scene_options){.budget = medium}));
    assert_int_equal(scene.bvh, AO_BVH_MEDIUM);
    assert_string_equal(scene.notes, "");
    ao_scene_finish(&scene);
    assert_true(ao_scene_load(&scene, path, &(struct ao_scene_options){.budget = medium - 1}));
    assert_int_equal(scene.bvh, AO_BVH_COMPACT);
    assert_string_equal(scene.notes, "one.scene: BVH built compact to fit the scene budget (slower rays; "
                                     "a larger --scene-budget gets the faster BVH)");
    ao_scene_finish(&scene);
    assert_true(ao_scene_load(&scene, path, &(struct ao_scene_options){.budget = compact}));
    assert_int_equal(scene.bvh, AO_BVH_COMPACT);
    ao_scene_finish(&scene);
    assert_false(ao_scene_load(&scene, path, &(struct ao_scene_options){.budget = compact - 1}));
    /* Asked for, each is charged at its own rates, without a note. */
    struct ao_scene_options asked = {.budget = compact, .bvh = AO_BVH_COMPACT};
    assert_true(ao_scene_load(&scene, path, &asked));
    assert_int_equal(scene.bvh, AO_BVH_COMPACT);
    assert_string_equal(scene.notes, "");
    ao_scene_finish(&scene);
    asked.bvh = AO_BVH_LOW;
    assert_false(ao_scene_load(&scene, path, &asked));
    asked.budget = medium;
    assert_true(ao_scene_load(&scene, path, &asked));
    assert_int_equal(scene.bvh, AO_BVH_LOW);
    ao_scene_finish(&scene);
}

/* ------------------------------------------------------------------ bad input */

/* Each bad fixture, where its one error line must point, and what it must say. */
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
    {"bad_empty.ply", ": ", "empty file"},
    {"bad_magic.ply", ":1: ", "not a PLY file"},
    {"bad_big_endian.ply", ":2: ", "big-endian binary PLY is not supported"},
    {"bad_format.ply", ":2: ", "unknown PLY format 'binary'"},
    {"bad_version.ply", ":2: ", "unsupported PLY version '2.0'"},
    {"bad_no_format.ply", ":3: ", "no format line"},
    {"bad_no_end_header.ply", ":3: ", "without end_header"},
    {"bad_property_first.ply", ":3: ", "property before any element"},
    {"bad_type.ply", ":4: ", "unknown property type 'float128'"},
    {"bad_keyword.ply", ":3: ", "unknown header keyword 'elemnt'"},
    {"bad_count.ply", ":3: ", "bad element count '-3'"},
    {"bad_count_overflow.ply", ":3: ", "bad element count"},
    {"bad_no_z.ply", ":3: ", "needs x, y and z"},
    {"bad_partial_normals.ply", ":3: ", "nx, ny and nz"},
    {"bad_no_face.ply", ": ", "no 'face' element"},
    {"bad_indices_scalar.ply", ":7: ", "'vertex_indices' must be a list"},
    {"bad_few_values.ply", ":11: ", "too few values for a 'vertex' row"},
    {"bad_many_values.ply", ":11: ", "more values than the header declares"},
    {"bad_few_rows.ply", ":13: ", "'face' declares 2 rows, found 1"},
    {"bad_extra_rows.ply", ":15: ", "data after the last element"},
    {"bad_ply_index_range.ply", ":13: ", "vertex index 3 is not an integer in [0, 3)"},
    {"bad_ply_index_negative.ply", ":13: ", "vertex index -1"},
    {"bad_ply_index_fraction.ply", ":13: ", "vertex index 1.5"},
    {"bad_ply_face_two.ply", ":13: ", "face with 2 vertices"},
    {"bad_ply_list_count.ply", ":13: ", "bad list count -1"},
    {"bad_ply_nan.ply", ":11: ", "not a finite float"},
    {"bad_ply_number.ply", ":11: ", "bad number 'abc'"},
    {"bad_ply_float_range.ply", ":11: ", "not a finite float"},
    {"bad_ply_claims.ply", ":12: ", "'vertex' declares 4000000000 rows, found 3"},
    {"bad_stl_outside.stl", ":3: ", "'vertex' outside 'outer loop'"},
    {"bad_stl_two.stl", ":6: ", "loop with 2 vertices; at least 3 needed"},
    {"bad_stl_keyword.stl", ":6: ", "unknown STL keyword 'vertx'"},
    {"bad_stl_unended.stl", ":6: ", "file ends inside a facet"},
    {"bad_stl_number.stl", ":4: ", "bad number 'nan'"},
    {"bad_stl_size.stl", ": ", "declares 2 triangles (184 bytes) but the file has 134 bytes"},
    {"bad_gltf_json.gltf", ":3: ", "JSON: unexpected character"},
    {"bad_gltf_asset.gltf", ": ", "no asset.version"},
    {"bad_gltf_version.gltf", ": ", "glTF version '1.0'; only 2.x is supported"},
    {"bad_gltf_extension.gltf", ": ", "requires extension 'EXT_mesh_gpu_instancing', which places meshes many times "
                                      "and which aoview does not read"},
    {"bad_gltf_sparse.gltf", ": ", "accessor 0 (POSITION) sparse: no 'indices' and 'values' objects"},
    {"bad_gltf_position_type.gltf", ": ", "componentType 5125; positions and normals must be float (5126), or byte"},
    {"bad_gltf_index_count.gltf", ": ", "2 indices, not a whole number of triangles"},
    {"bad_gltf_mesh_index.gltf", ": ", "node 1: 'mesh' 7 is out of range (2 defined)"},
    {"bad_gltf_uri.gltf", ": ", "buffer 0 ('http://example.com/x.bin'): the URI scheme 'http:' is not supported"},
    {"bad_gltf_base64.gltf", ": ", "buffer 0: bad base64 data"},
};

static void test_bad_inputs(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof bad_inputs / sizeof bad_inputs[0]; i++)
        expect_failure(fixture(bad_inputs[i].name), bad_inputs[i].location,
                       bad_inputs[i].message);
}

/* A missing file, a directory, an unknown or absent extension. */
static void test_file_errors(void **state)
{
    (void)state;
    char *dir = path_buffer();
    snprintf(dir, 4200, "%s/dir.obj", temp_dir);
    assert_int_equal(mkdir(dir, 0700), 0);
    expect_failure(fixture("missing.obj"), ": ", "cannot open: No such file");
    expect_failure(dir, ": ", "is a directory");
    expect_failure(fixture("tri.3ds"), ": ", "unknown mesh format");
    expect_failure(data_dir, ": ", "unknown mesh format");
    expect_failure("dir.obj/file", ": ", "unknown mesh format");
}

/* A file without read permission (not testable as root, who may read anything). */
static void test_unreadable_file(void **state)
{
    (void)state;
    const char *path = temp_file("locked.obj", "v 0 0 0\n", 8);
    assert_int_equal(chmod(path, 0), 0);
    FILE *probe = fopen(path, "rb");
    if (probe) {
        fclose(probe);
        skip();
    }
    expect_failure(path, ": ", "cannot open: Permission denied");
}

/* A mapped file that another process shrinks under the parser: reading past its new end ends the
 * process with the file's one line and status 1, not a crash (run in a child, which it ends). */
static void test_file_shrunk_while_mapped(void **state)
{
    (void)state;
    static char bytes[3 * 4096 + 100];
    memset(bytes, '#', sizeof bytes);
    const char *path = temp_file("shrinks.obj", bytes, sizeof bytes);
    int err[2];
    assert_int_equal(pipe(err), 0);
    pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) {
        dup2(err[1], STDERR_FILENO);
        const char *text;
        size_t size;
        bool mapped;
        if (!ao_file_map_budget(path, NULL, &text, &size, &mapped) || !mapped || truncate(path, 10) != 0)
            _exit(3);
        volatile char last = text[size - 1]; /* on a page past the new end */
        (void)last;
        _exit(0);
    }
    close(err[1]);
    char line[256] = "";
    ssize_t got = read(err[0], line, sizeof line - 1);
    close(err[0]);
    int status;
    assert_int_equal(waitpid(child, &status, 0), child);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 1);
    assert_true(got > 0);
    if (!strstr(line, "shrinks.obj: the file shrank while it was being read\n"))
        fail_msg("stderr: %s", line);
}

/* Random byte changes to valid files (fixed seed) load or fail cleanly, never anything else. */
static void test_mutations(void **state)
{
    (void)state;
    static const char *const names[] = {"cube.ply", "normals.ply", "mixed.obj", "negative.obj"};
    static const char alphabet[] = "0123456789-+./ \n#eExvfn\r";
    const size_t letters = sizeof alphabet - 1;
    uint64_t rng = 0x2545f4914f6cdd1dULL;
    struct bytes binary = binary_square();
    for (int f = 0; f < 5; f++) {
        size_t size = binary.size;
        unsigned char *original = f < 4 ? slurp(fixture(names[f]), &size) : binary.data;
        unsigned char *text = malloc(size);
        assert_non_null(text);
        for (int m = 0; m < 400; m++) {
            memcpy(text, original, size);
            for (int k = 0; k < 1 + m % 3; k++) {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                text[(rng >> 8) % size] = (rng & 1) ? (unsigned char)(rng >> 40)
                                                    : (unsigned char)alphabet[(rng >> 40) % letters];
            }
            struct ao_mesh mesh;
            char err[1024];
            const char *path = temp_file(f < 4 ? names[f] : "square.ply", text, size);
            if (load_captured(&mesh, path, err, sizeof err)) {
                assert_string_equal(err, "");
                assert_mesh_valid(&mesh);
                ao_mesh_finish(&mesh);
            } else {
                assert_mesh_empty(&mesh);
                assert_true(strchr(err, '\n') == err + strlen(err) - 1);
            }
        }
        free(text);
        if (f < 4)
            free(original);
    }
}

/* ------------------------------------------------------------------ normals and the bunny */

/* The public recomputation, from scratch and over existing normals; an empty mesh is fine. */
static void test_compute_normals(void **state)
{
    (void)state;
    struct ao_mesh mesh = {0};
    assert_true(ao_mesh_compute_normals(&mesh));
    ao_mesh_finish(&mesh);
    mesh.vertex_count = 3;
    mesh.triangle_count = 1;
    mesh.positions = malloc(3 * sizeof *mesh.positions);
    mesh.indices = malloc(3 * sizeof *mesh.indices);
    assert_non_null(mesh.positions);
    assert_non_null(mesh.indices);
    mesh.positions[0] = ao_vec3_make(0, 0, 0);
    mesh.positions[1] = ao_vec3_make(0, 1, 0);
    mesh.positions[2] = ao_vec3_make(1, 0, 0);
    for (uint32_t i = 0; i < 3; i++)
        mesh.indices[i] = i;
    assert_true(ao_mesh_compute_normals(&mesh));
    assert_vec3_near(mesh.normals[1], 0, 0, -1);
    mesh.positions[2] = ao_vec3_make(0, 0, 1);
    assert_true(ao_mesh_compute_normals(&mesh));
    assert_vec3_near(mesh.normals[1], 1, 0, 0);
    ao_mesh_finish(&mesh);
    assert_mesh_empty(&mesh);
}

/* A bumpy grid of 2 n^2 triangles whose vertices are numbered in a shuffled order, so that every
 * part of a parallel normals pass meets triangles that it shares with the others. */
static void shuffled_grid(struct ao_mesh *mesh, uint32_t n)
{
    uint32_t side = n + 1, *order = malloc((size_t)side * side * sizeof *order);
    *mesh = (struct ao_mesh){.vertex_count = (size_t)side * side, .triangle_count = 2 * (size_t)n * n};
    mesh->positions = malloc(mesh->vertex_count * sizeof *mesh->positions);
    mesh->indices = malloc(3 * mesh->triangle_count * sizeof *mesh->indices);
    assert_non_null(order);
    assert_non_null(mesh->positions);
    assert_non_null(mesh->indices);
    for (uint32_t i = 0; i < side * side; i++)
        order[i] = i;
    uint64_t seed = 12345;
    for (uint32_t i = side * side - 1; i > 0; i--) {
        seed = seed * 6364136223846793005u + 1442695040888963407u;
        uint32_t j = (uint32_t)((seed >> 33) % (i + 1)), swap = order[i];
        order[i] = order[j], order[j] = swap;
    }
    for (uint32_t y = 0; y < side; y++)
        for (uint32_t x = 0; x < side; x++)
            mesh->positions[order[y * side + x]] = ao_vec3_make((float)x, (float)y, 3.0f * sinf(0.37f * (float)x) *
                                                                                    cosf(0.23f * (float)y));
    uint32_t *t = mesh->indices;
    for (uint32_t y = 0; y < n; y++)
        for (uint32_t x = 0; x < n; x++, t += 6) {
            uint32_t a = order[y * side + x], b = order[y * side + x + 1], c = order[(y + 1) * side + x],
                     d = order[(y + 1) * side + x + 1];
            uint32_t two[6] = {a, b, d, a, d, c};
            memcpy(t, two, sizeof two);
        }
    free(order);
}

/* Normals are computed in parallel: the same bits on any number of threads, and within float
 * rounding of the angle-weighted sum taken with libm's atan2, triangle by triangle, as defined. */
static void test_normals_any_thread_count(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    shuffled_grid(&mesh, 300);
    assert_true(ao_mesh_compute_normals_on(&mesh, 1));
    struct ao_vec3 *one = malloc(mesh.vertex_count * sizeof *one);
    assert_non_null(one);
    memcpy(one, mesh.normals, mesh.vertex_count * sizeof *one);
    static const int counts[] = {2, 3, 7, 0};
    for (size_t k = 0; k < sizeof counts / sizeof counts[0]; k++) {
        memset(mesh.normals, 0xff, mesh.vertex_count * sizeof *mesh.normals);
        assert_true(ao_mesh_compute_normals_on(&mesh, counts[k]));
        assert_memory_equal(one, mesh.normals, mesh.vertex_count * sizeof *one);
    }
    double (*sum)[3] = calloc(mesh.vertex_count, sizeof *sum);
    assert_non_null(sum);
    for (size_t t = 0; t < mesh.triangle_count; t++) {
        const uint32_t *v = mesh.indices + 3 * t;
        double p[3][3];
        for (int c = 0; c < 3; c++)
            p[c][0] = mesh.positions[v[c]].x, p[c][1] = mesh.positions[v[c]].y, p[c][2] = mesh.positions[v[c]].z;
        double a[3], b[3], n[3];
        for (int i = 0; i < 3; i++)
            a[i] = p[1][i] - p[0][i], b[i] = p[2][i] - p[0][i];
        n[0] = a[1] * b[2] - a[2] * b[1], n[1] = a[2] * b[0] - a[0] * b[2], n[2] = a[0] * b[1] - a[1] * b[0];
        double area = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int c = 0; c < 3; c++) {
            double e[3], f[3];
            for (int i = 0; i < 3; i++)
                e[i] = p[(c + 1) % 3][i] - p[c][i], f[i] = p[(c + 2) % 3][i] - p[c][i];
            double angle = atan2(area, e[0] * f[0] + e[1] * f[1] + e[2] * f[2]);
            for (int i = 0; i < 3; i++)
                sum[v[c]][i] += n[i] / area * angle;
        }
    }
    for (size_t i = 0; i < mesh.vertex_count; i++) {
        double length = sqrt(sum[i][0] * sum[i][0] + sum[i][1] * sum[i][1] + sum[i][2] * sum[i][2]);
        assert_float_equal(one[i].x, sum[i][0] / length, 1e-6);
        assert_float_equal(one[i].y, sum[i][1] / length, 1e-6);
        assert_float_equal(one[i].z, sum[i][2] / length, 1e-6);
    }
    free(sum);
    free(one);
    ao_mesh_finish(&mesh);
}

/* ------------------------------------------------------------------ normals a file lacks */

/* A unit cube as OBJ text, its 8 corners shared by 12 triangles, no normals. */
static const char CUBE_OBJ[] = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                               "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";

/* The crease angle on a cube, whose faces meet at 90 degrees: at 0 every vertex is flat (the zero
 * normal: shading takes the triangle's own); below 90 each corner splits into one vertex per face,
 * with that face's normal; from 90 on (the edges no longer sharper) the 8 corners stay, smooth, as
 * ao_mesh_compute_normals makes them. */
static void test_crease_cube(void **state)
{
    (void)state;
    const char *path = temp_file("cube.obj", CUBE_OBJ, sizeof CUBE_OBJ - 1);
    struct ao_mesh mesh;
    load_at_crease(&mesh, path, 0.0);
    assert_int_equal(mesh.vertex_count, 8);
    for (size_t i = 0; i < 8; i++)
        assert_vec3_near(mesh.normals[i], 0, 0, 0);
    ao_mesh_finish(&mesh);
    for (double crease = 1.0; crease < 90.0; crease += 22.0) {
        load_at_crease(&mesh, path, crease);
        assert_int_equal(mesh.vertex_count, 24);
        for (size_t i = 0; i < 24; i++) {
            struct ao_vec3 n = mesh.normals[i];
            assert_float_equal(fabsf(n.x) + fabsf(n.y) + fabsf(n.z), 1.0f, 0.0f);   /* an axis, exactly */
        }
        ao_mesh_finish(&mesh);
    }
    for (double crease = 90.5; crease <= 180.0; crease += 44.75) {
        load_at_crease(&mesh, path, crease);
        assert_int_equal(mesh.vertex_count, 8);
        struct ao_mesh again = mesh;
        again.normals = NULL;
        struct ao_vec3 *given = mesh.normals;
        assert_true(ao_mesh_compute_normals(&again));
        assert_memory_equal(given, again.normals, 8 * sizeof *given);
        free(again.normals);
        ao_mesh_finish(&mesh);
    }
}

/* A smooth mesh (a 32 x 16 UV sphere, 11.25 degrees between facets) keeps its vertices at the
 * default crease angle and gets the normals of smoothing everywhere, bit for bit. */
static void test_crease_keeps_a_smooth_mesh(void **state)
{
    (void)state;
    char *text = malloc(1 << 16);
    assert_non_null(text);
    int n = 0, segments = 32, rings = 16;
    const double pi = 3.14159265358979323846;
    n += sprintf(text + n, "v 0 -1 0\nv 0 1 0\n");
    for (int r = 1; r < rings; r++)
        for (int k = 0; k < segments; k++) {
            double lat = pi * ((double)r / rings - 0.5), lon = 2 * pi * k / segments;
            n += sprintf(text + n, "v %.9f %.9f %.9f\n", cos(lat) * cos(lon), sin(lat), cos(lat) * sin(lon));
        }
    for (int r = 0; r < rings; r++)
        for (int k = 0; k < segments; k++) {
            int k1 = (k + 1) % segments, a = 3 + (r - 1) * segments + k, b = 3 + (r - 1) * segments + k1;
            if (r == 0)
                n += sprintf(text + n, "f 1 %d %d\n", 3 + k1, 3 + k);
            else if (r == rings - 1)
                n += sprintf(text + n, "f %d %d 2\n", a, b);
            else
                n += sprintf(text + n, "f %d %d %d %d\n", a, b, b + segments, a + segments);
        }
    const char *path = temp_file("sphere.obj", text, (size_t)n);
    free(text);
    struct ao_mesh smooth, creased;
    load_at_crease(&smooth, path, 180.0);
    load_at_crease(&creased, path, AO_MESH_CREASE_DEFAULT);
    assert_int_equal(creased.vertex_count, smooth.vertex_count);
    assert_int_equal(creased.vertex_count, 2 + 15 * 32);
    assert_memory_equal(creased.normals, smooth.normals, smooth.vertex_count * sizeof *smooth.normals);
    assert_memory_equal(creased.indices, smooth.indices, 3 * smooth.triangle_count * sizeof *smooth.indices);
    ao_mesh_finish(&smooth);
    ao_mesh_finish(&creased);
}

/* A vertex a hundred thousand triangles share, folded back and forth at every edge (a fan whose
 * rim zigzags up and down): each triangle its own side, split in linear time, and one whose folds
 * all lie flatter than the crease, one side. */
static void test_crease_many_triangles_at_a_vertex(void **state)
{
    (void)state;
    enum { FAN = 100000 };
    for (int folded = 0; folded < 2; folded++) {
        size_t size = 64 + (size_t)FAN * 80;
        char *text = malloc(size);
        assert_non_null(text);
        int n = sprintf(text, "v 0 0 0\n");
        for (int k = 0; k <= FAN; k++) {
            double angle = 6.283185307179586 * k / (FAN + 1);
            n += sprintf(text + n, "v %.9f %.9f %s\n", cos(angle), sin(angle), folded && k % 2 ? "0.5" : "0");
        }
        for (int k = 0; k < FAN; k++)
            n += sprintf(text + n, "f 1 %d %d\n", k + 2, k + 3);
        const char *path = temp_file("fan.obj", text, (size_t)n);
        free(text);
        struct ao_mesh mesh;
        load_at_crease(&mesh, path, AO_MESH_CREASE_DEFAULT);
        assert_int_equal(mesh.triangle_count, FAN);
        /* Folded: the centre splits into one vertex per triangle (each fold about 90 degrees); the
         * rim's vertices, each between two triangles, into two. Flat: nothing splits. */
        assert_int_equal(mesh.vertex_count, folded ? (size_t)FAN + 2 * (FAN + 1) - 2 : (size_t)FAN + 2);
        for (size_t i = 0; i < mesh.vertex_count; i++)
            assert_float_equal(ao_vec3_length(mesh.normals[i]), 1.0f, 1e-5f);
        ao_mesh_finish(&mesh);
    }
}

/* Normals given as NaN, infinite or zero are made as if not given (counted, and noted with the
 * count by the model): an OBJ's from its triangle (smooth up to the crease angle), a glTF's flat. */
static void test_invalid_normals(void **state)
{
    (void)state;
    static const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn nan 0 1\nvn inf 0 0\nvn 0 0 0\nvn 0 0 2\n"
                              "f 1//1 2//2 3//4\nf 1//3 3//4 2//2\n";
    struct ao_budget budget = {.limit = AO_BUDGET_DEFAULT};
    struct ao_model model;
    assert_true(ao_load_model(&model, temp_file("nan.obj", obj, sizeof obj - 1), &budget, 40.0));
    assert_int_equal(model.invalid_normals, 3);
    assert_non_null(strstr(model.note, "3 of its normals are zero or not finite: made as for a file without "
                                       "normals (smooth up to the crease angle)"));
    const struct ao_mesh *m = &model.meshes[0];
    assert_int_equal(m->triangle_count, 2);
    /* (0,0,0) and (1,0,0), whose normals are missing in both triangles, split between them (the
     * second winds the other way: 180 degrees apart); (0,1,0) keeps the normal given. */
    assert_vec3_near(m->normals[m->indices[0]], 0, 0, 1);
    assert_vec3_near(m->normals[m->indices[1]], 0, 0, 1);
    assert_vec3_near(m->normals[m->indices[3]], 0, 0, -1);
    assert_vec3_near(m->normals[m->indices[5]], 0, 0, -1);
    assert_vec3_near(m->normals[m->indices[2]], 0, 0, 1);
    assert_int_equal(m->indices[2], m->indices[4]);
    ao_model_finish(&model);

    struct {
        float p[3][3], n[3][3];
    } data = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{NAN, 0, 0}, {0, 0, 1}, {0, 0, 0}}};
    static const char json[] =
        "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 0}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1}}]}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"},\n"
        "   {\"bufferView\": 0, \"byteOffset\": 36, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 72}],\n"
        " \"buffers\": [{\"byteLength\": %zu, \"uri\": \"%s\"}]}\n";
    assert_true(ao_load_model(&model, gltf_file("nan.gltf", json, &data, sizeof data), &budget, 40.0));
    assert_int_equal(model.invalid_normals, 2);
    assert_non_null(strstr(model.note, "2 of its normals are zero or not finite: made as for a file without "
                                       "normals (flat)"));
    assert_vec3_near(model.meshes[0].normals[0], 0, 0, 0);
    assert_vec3_near(model.meshes[0].normals[1], 0, 0, 1);
    assert_vec3_near(model.meshes[0].normals[2], 0, 0, 0);
    ao_model_finish(&model);
}

/* The shipped bunny: its counts, y up, finite unit normals, and outward orientation. Its file has no
 * normals: at the default crease angle (40 degrees) the 129 vertices on its sharper edges split,
 * 1968 vertices for 1839 positions; at 180 every vertex is smooth. */
static void test_bunny(void **state)
{
    (void)state;
    char path[4200];
    snprintf(path, sizeof path, "%s/assets/bunny.obj", getenv("AO_SOURCE_ROOT"));
    struct ao_mesh mesh;
    load_at_crease(&mesh, path, 180.0);
    assert_int_equal(mesh.vertex_count, 1839);
    ao_mesh_finish(&mesh);
    load_ok(&mesh, path);
    assert_int_equal(mesh.vertex_count, 1968);
    assert_int_equal(mesh.triangle_count, 3674);
    assert_int_equal(mesh.degenerate_count, 0);
    struct ao_vec3 lo = mesh.positions[0], hi = lo, sum = {0, 0, 0};
    for (size_t i = 0; i < mesh.vertex_count; i++) {
        struct ao_vec3 p = mesh.positions[i];
        lo = ao_vec3_make(fminf(lo.x, p.x), fminf(lo.y, p.y), fminf(lo.z, p.z));
        hi = ao_vec3_make(fmaxf(hi.x, p.x), fmaxf(hi.y, p.y), fmaxf(hi.z, p.z));
        sum = ao_vec3_add(sum, p);
        assert_true(ao_vec3_is_finite(mesh.normals[i]));
        assert_float_equal(ao_vec3_length(mesh.normals[i]), 1.0f, 1e-5f);
    }
    assert_float_equal(lo.y, -0.003149f, 1e-6f);
    assert_float_equal(hi.y, 9.654748f, 1e-5f);
    struct ao_vec3 centre = ao_vec3_scale(sum, 1.0f / (float)mesh.vertex_count);
    size_t outward = 0;
    for (size_t i = 0; i < mesh.vertex_count; i++)
        outward += ao_vec3_dot(mesh.normals[i], ao_vec3_sub(mesh.positions[i], centre)) > 0.0f;
    assert_true(outward > mesh.vertex_count * 9 / 10);
    ao_mesh_finish(&mesh);
}

/* ------------------------------------------------------------------ main */

/* Makes the scratch directory. */
static int make_temp_dir(void **state)
{
    (void)state;
    const char *tmp = getenv("TMPDIR");
    snprintf(temp_dir, sizeof temp_dir, "%s/test_mesh.XXXXXX", tmp && *tmp ? tmp : "/tmp");
    return mkdtemp(temp_dir) ? 0 : -1;
}

/* Removes the scratch directory and what the tests left in it. */
static int remove_temp_dir(void **state)
{
    (void)state;
    DIR *dir = opendir(temp_dir);
    struct dirent *entry;
    char path[8300];
    while (dir && (entry = readdir(dir))) {
        snprintf(path, sizeof path, "%s/%s", temp_dir, entry->d_name);
        if (strcmp(entry->d_name, ".") != 0 && strcmp(entry->d_name, "..") != 0 &&
            unlink(path) != 0)
            rmdir(path);
    }
    if (dir)
        closedir(dir);
    return rmdir(temp_dir);
}

int main(void)
{
    const char *root = getenv("AO_SOURCE_ROOT");
    if (!root) {
        fprintf(stderr, "test_mesh: AO_SOURCE_ROOT is not set (run it through meson test)\n");
        return 77;
    }
    snprintf(data_dir, sizeof data_dir, "%s/tests/data/mesh", root);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_numbers_as_libc),
        cmocka_unit_test(test_obj_triangle),
        cmocka_unit_test(test_obj_polygon_fan),
        cmocka_unit_test(test_obj_corner_forms),
        cmocka_unit_test(test_obj_negative_indices),
        cmocka_unit_test(test_obj_other_statements),
        cmocka_unit_test(test_obj_split_vertices),
        cmocka_unit_test(test_obj_mixed_normals),
        cmocka_unit_test(test_obj_zero_normal),
        cmocka_unit_test(test_degenerate_counted),
        cmocka_unit_test(test_extension_case),
        cmocka_unit_test(test_ply_ascii_cube),
        cmocka_unit_test(test_ply_ascii_normals),
        cmocka_unit_test(test_ply_binary),
        cmocka_unit_test(test_ply_binary_errors),
        cmocka_unit_test(test_ply_binary_truncated),
        cmocka_unit_test(test_ply_layouts_agree),
        cmocka_unit_test(test_stl_ascii),
        cmocka_unit_test(test_stl_binary),
        cmocka_unit_test(test_gltf_nodes),
        cmocka_unit_test(test_gltf_meshes_load_once),
        cmocka_unit_test(test_gltf_deep_node_tree),
        cmocka_unit_test(test_gltf_no_scene),
        cmocka_unit_test(test_gltf_rotation_of_any_length),
        cmocka_unit_test(test_gltf_huge_matrix_gives_finite_normals),
        cmocka_unit_test(test_gltf_strips_and_fans),
        cmocka_unit_test(test_gltf_points_and_lines_only),
        cmocka_unit_test(test_gltf_required_extensions),
        cmocka_unit_test(test_gltf_leniency),
        cmocka_unit_test(test_gltf_quantized),
        cmocka_unit_test(test_gltf_normals_from_a_later_primitive),
        cmocka_unit_test(test_gltf_sparse),
        cmocka_unit_test(test_gltf_meshopt),
        cmocka_unit_test(test_loaders_keep_to_the_budget),
        cmocka_unit_test(test_scene_budget_covers_every_mesh_line),
        cmocka_unit_test(test_budget_builds_compact_where_only_that_fits),
        cmocka_unit_test(test_bad_inputs),
        cmocka_unit_test(test_file_errors),
        cmocka_unit_test(test_unreadable_file),
        cmocka_unit_test(test_file_shrunk_while_mapped),
        cmocka_unit_test(test_mutations),
        cmocka_unit_test(test_compute_normals),
        cmocka_unit_test(test_normals_any_thread_count),
        cmocka_unit_test(test_crease_cube),
        cmocka_unit_test(test_crease_keeps_a_smooth_mesh),
        cmocka_unit_test(test_crease_many_triangles_at_a_vertex),
        cmocka_unit_test(test_invalid_normals),
        cmocka_unit_test(test_bunny),
    };
    return cmocka_run_group_tests(tests, make_temp_dir, remove_temp_dir);
}
