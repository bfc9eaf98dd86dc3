/* What the loader tests share; see mesh_fixture.h. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "mesh_fixture.h"

char data_dir[4096];
char temp_dir[4096];

static int make_temp_dir(void **state)
{
    (void)state;
    const char *tmp = getenv("TMPDIR");
    snprintf(temp_dir, sizeof temp_dir, "%s/test_load.XXXXXX", tmp && *tmp ? tmp : "/tmp");
    return mkdtemp(temp_dir) ? 0 : -1;
}

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

int mesh_fixture_run(const char *name, const struct CMUnitTest *tests, size_t count)
{
    const char *root = getenv("AO_SOURCE_ROOT");
    if (!root) {
        fprintf(stderr, "%s: AO_SOURCE_ROOT is not set (run it through meson test)\n", name);
        return 77;
    }
    snprintf(data_dir, sizeof data_dir, "%s/tests/data/mesh", root);
    return _cmocka_run_group_tests(name, tests, count, make_temp_dir, remove_temp_dir);
}

char *path_buffer(void)
{
    static char buffers[4][4200];
    static int next;
    next = (next + 1) % 4;
    return buffers[next];
}

const char *fixture(const char *name)
{
    char *path = path_buffer();
    snprintf(path, 4200, "%s/%s", data_dir, name);
    return path;
}

const char *temp_file(const char *name, const void *bytes, size_t size)
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

unsigned char *slurp(const char *path, size_t *size)
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

bool load_captured(struct ao_mesh *mesh, const char *path, char *err, size_t err_size)
{
    struct capture c;
    capture_begin(&c);
    bool ok = ao_load_mesh(mesh, path, NULL);
    capture_end(&c, err, err_size);
    return ok;
}

uint64_t medium_model(uint64_t triangles, uint64_t vertices, uint64_t placements)
{
    return ao_budget_charge(&(struct ao_budget){.bvh = AO_BVH_MEDIUM}, triangles, vertices, placements);
}

uint64_t medium_charge(uint64_t triangles, uint64_t vertices)
{
    return medium_model(triangles, vertices, 0);
}

bool load_within(struct ao_mesh *mesh, const char *path, uint64_t limit, char *err, size_t err_size)
{
    struct ao_budget budget = {.limit = limit, .bvh = AO_BVH_MEDIUM};
    struct capture c;
    capture_begin(&c);
    bool ok = ao_load_mesh(mesh, path, &budget);
    capture_end(&c, err, err_size);
    assert_true(budget.used == 0);
    return ok;
}

void load_ok(struct ao_mesh *mesh, const char *path)
{
    char err[1024];
    bool ok = load_captured(mesh, path, err, sizeof err);
    if (!ok || err[0])
        print_error("loading %s printed: %s\n", path, err);
    assert_true(ok);
    assert_string_equal(err, "");
}

void load_counted(struct ao_mesh *mesh, const char *path, size_t vertices, size_t triangles)
{
    load_ok(mesh, path);
    assert_mesh_valid(mesh);
    assert_int_equal(mesh->vertex_count, vertices);
    assert_int_equal(mesh->triangle_count, triangles);
}

void assert_mesh_empty(const struct ao_mesh *mesh)
{
    assert_null(mesh->positions);
    assert_null(mesh->normals);
    assert_null(mesh->indices);
    assert_int_equal(mesh->vertex_count, 0);
    assert_int_equal(mesh->triangle_count, 0);
    assert_int_equal(mesh->degenerate_count, 0);
}

void expect_failure(const char *path, const char *location, const char *message)
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

void assert_vec3_near(struct ao_vec3 a, float x, float y, float z)
{
    assert_float_equal(a.x, x, 1e-5f);
    assert_float_equal(a.y, y, 1e-5f);
    assert_float_equal(a.z, z, 1e-5f);
}

void assert_triangle(const struct ao_mesh *mesh, size_t t, uint32_t a, uint32_t b, uint32_t c)
{
    assert_int_equal(mesh->indices[3 * t], a);
    assert_int_equal(mesh->indices[3 * t + 1], b);
    assert_int_equal(mesh->indices[3 * t + 2], c);
}

void assert_mesh_valid(const struct ao_mesh *mesh)
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

size_t vertex_at(const struct ao_mesh *mesh, float x, float y, float z)
{
    for (size_t i = 0; i < mesh->vertex_count; i++) {
        struct ao_vec3 p = mesh->positions[i];
        if (p.x == x && p.y == y && p.z == z)
            return i;
    }
    fail();
    return 0;
}

void put_text(struct bytes *b, const char *text)
{
    size_t n = strlen(text);
    assert_true(b->size + n <= sizeof b->data);
    memcpy(b->data + b->size, text, n);
    b->size += n;
}

void put_int(struct bytes *b, uint64_t value, size_t n)
{
    assert_true(b->size + n <= sizeof b->data);
    for (size_t i = 0; i < n; i++)
        b->data[b->size++] = (unsigned char)(i < 8 ? value >> (8 * i) : 0);
}

void put_f32(struct bytes *b, float f)
{
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    put_int(b, bits, 4);
}

void put_f64(struct bytes *b, double d)
{
    uint64_t bits;
    memcpy(&bits, &d, sizeof bits);
    put_int(b, bits, 8);
}

struct bytes binary_square(void)
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

void load_at_crease(struct ao_mesh *mesh, const char *path, double crease)
{
    struct ao_budget budget = {.limit = AO_BUDGET_LEAST};
    struct ao_model model;
    assert_true(ao_load_model(&model, path, &budget, crease));
    assert_int_equal(model.mesh_count, 1);
    *mesh = model.meshes[0];
    model.meshes[0] = (struct ao_mesh){0};
    ao_model_finish(&model);
}

uint64_t file_size(const char *path)
{
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    return (uint64_t)st.st_size;
}

void base64(const unsigned char *in, size_t size, char *out)
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

const char *gltf_file(const char *name, const char *json, const void *data, size_t size)
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
