/* What the loader tests share (test_obj.c, test_ply.c, test_stl.c, test_gltf.c, test_load_files.c,
 * test_load_budget.c, test_mesh.c, test_scene.c): their main (the fixtures' folder,
 * tests/data/mesh, and a scratch folder for generated files), loads that capture the one error line,
 * assertions every loaded mesh must meet, the test of a format's bad fixtures, and writers of binary
 * PLY and glTF files. Include after cmocka.h. */
#ifndef AO_TEST_MESH_FIXTURE_H
#define AO_TEST_MESH_FIXTURE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "budget.h"
#include "capture.h"
#include "load.h"
#include "mesh.h"

/* Where the committed fixtures are, and the scratch folder of this run. */
extern char data_dir[4096];
extern char temp_dir[4096];

/* A loader test's main: sets data_dir from AO_SOURCE_ROOT and runs the count tests as the group
 * `name` in a scratch folder made for them and removed after them; returns main's exit status, 77
 * (said on stderr as `name: ...`) without AO_SOURCE_ROOT. */
int mesh_fixture_run(const char *name, const struct CMUnitTest *tests, size_t count);

/* Defines a loader test's main: mesh_fixture_run over the tests listed (cmocka_unit_test entries). */
#define MESH_FIXTURE_MAIN(name, ...)                                                                                   \
    int main(void)                                                                                                     \
    {                                                                                                                  \
        const struct CMUnitTest tests[] = {__VA_ARGS__};                                                               \
        return mesh_fixture_run(name, tests, sizeof tests / sizeof tests[0]);                                          \
    }

/* A binary file (PLY, STL) under construction. */
struct bytes {
    unsigned char data[4096];
    size_t size;
};

/* A path in one of a few rotating buffers, so a test can hold several at once. */
char *path_buffer(void);

/* The path of a committed fixture. */
const char *fixture(const char *name);

/* Writes bytes to a new file of the temporary directory and returns its path. An old file of
 * that name is removed first: ext4 flushes a file truncated and rewritten to disk on close,
 * which made the tests' many rewrites take seconds. */
const char *temp_file(const char *name, const void *bytes, size_t size);

/* Reads a whole file into a malloc'd buffer. */
unsigned char *slurp(const char *path, size_t *size);

/* Runs ao_load_mesh with its messages captured (capture.h), returning them in err. */
bool load_captured(struct ao_mesh *mesh, const char *path, char *err, size_t err_size);

/* The budget's charges at the MEDIUM BVH's rates: a mesh, and meshes with their placements. */
uint64_t medium_model(uint64_t triangles, uint64_t vertices, uint64_t placements);

/* medium_model's charge of one mesh and no placements. */
uint64_t medium_charge(uint64_t triangles, uint64_t vertices);

/* Runs ao_load_mesh within a budget of `limit` bytes at the MEDIUM BVH's rates, its messages
 * captured in err; the budget must come back empty, whatever happened. */
bool load_within(struct ao_mesh *mesh, const char *path, uint64_t limit, char *err, size_t err_size);

/* Loads a file that must load, and prints nothing. */
void load_ok(struct ao_mesh *mesh, const char *path);

/* load_ok, then the mesh must be valid (assert_mesh_valid) with these counts of vertices and
 * triangles. */
void load_counted(struct ao_mesh *mesh, const char *path, size_t vertices, size_t triangles);

/* The mesh must be all zero, as a failed load leaves it. */
void assert_mesh_empty(const struct ao_mesh *mesh);

/* Loading path must fail, leave the mesh empty and print exactly one line that starts with
 * the path followed by location (":LINE: " or ": ") and contains message. */
void expect_failure(const char *path, const char *location, const char *message);

/* cmocka test (bad_meshes.c): every bad fixture whose name ends in the extension *state (".obj")
 * fails with its one line and an empty mesh (expect_failure). */
void test_bad_inputs(void **state);

/* test_bad_inputs over the bad fixtures of extension ext, as an entry of a test list. */
#define bad_inputs_test(ext) cmocka_unit_test_prestate(test_bad_inputs, (void *)(ext))

/* a must be within 1e-5 of (x, y, z). */
void assert_vec3_near(struct ao_vec3 a, float x, float y, float z);

/* Triangle t must be (a, b, c). */
void assert_triangle(const struct ao_mesh *mesh, size_t t, uint32_t a, uint32_t b, uint32_t c);

/* What every loaded mesh must satisfy: triangles, indices in range, finite positions, and
 * normals that are unit length or zero. */
void assert_mesh_valid(const struct ao_mesh *mesh);

/* The one vertex at position p (the test meshes have a single one there). */
size_t vertex_at(const struct ao_mesh *mesh, float x, float y, float z);

/* Appends text (the header). */
void put_text(struct bytes *b, const char *text);

/* Appends value as n bytes, little endian (zero-extended past 8). */
void put_int(struct bytes *b, uint64_t value, size_t n);

/* Appends a float32, little endian. */
void put_f32(struct bytes *b, float f);

/* Appends a float64, little endian. */
void put_f64(struct bytes *b, double d);

/* A square of 4 vertices (z = -2, normals +z) as one quad plus a degenerate triangle, with every
 * scalar type, list properties and elements the loader must skip. */
struct bytes binary_square(void);

/* Loads path as one mesh (OBJ, PLY, STL), the normals it lacks made at the crease angle. */
void load_at_crease(struct ao_mesh *mesh, const char *path, double crease);

/* The size of the file at path. */
uint64_t file_size(const char *path);

/* base64 of size bytes into out, which holds 4 (size + 2) / 3 + 1 characters. */
void base64(const unsigned char *in, size_t size, char *out);

/* A glTF file made of json, a printf format whose one %s becomes a base64 data URI of the bytes
 * data (and whose %zu, before it, their count); returns its path. */
const char *gltf_file(const char *name, const char *json, const void *data, size_t size);

#endif
