/* glTF and GLB files: node trees and their transforms, meshes loaded once, strips and fans,
 * quantized, sparse and meshopt-compressed data, required extensions, the leniency of exporters,
 * and bad files refused with their one line. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <meshoptimizer.h>

#include "mesh_fixture.h"

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
    load_counted(mesh, temp_file("transformed.gltf", text, (size_t)n), 3, 1);
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

/* nodes.gltf: scene 1 of two; a matrix node (x + 10) over a TRS node (translation y + 1, 90
 * degrees about z, scale 2) holding a triangle without normals; a node mirroring x (scale -1,
 * then z + 5) holding the triangle with NORMAL +z and a point primitive (skipped); a node outside
 * the scene. The buffer is an external file whose name is percent-encoded. */
static void test_gltf_nodes(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_counted(&mesh, fixture("nodes.gltf"), 6, 2);
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
    load_counted(&mesh, temp_file("triangle.gltf", text, sizeof text - 1), 3, 1);
    assert_triangle(&mesh, 0, 0, 1, 2);
    assert_vec3_near(mesh.positions[1], 1, 0, 1);
    assert_vec3_near(mesh.positions[2], 0, 1, 1);
    assert_vec3_near(mesh.normals[0], 0, 0, 0);   /* no NORMAL: flat */
    ao_mesh_finish(&mesh);
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
    load_counted(&mesh, temp_file("huge_matrix.gltf", text, sizeof text - 1), 3, 1);
    ao_mesh_finish(&mesh);
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
        /* 5 + 2 vertices: the fan shares the strip's. */
        load_counted(&mesh, gltf_file("strips.gltf", twice, &data, sizeof data), 5 + 2, 6);
        assert_int_equal(mesh.point_primitives, 1);
        assert_int_equal(mesh.line_primitives, 0);
        static const uint32_t want[6][3] = {{0, 1, 2}, {1, 3, 2}, {2, 3, 4}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}};
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
    load_counted(&mesh, gltf_file("quantized.gltf", json, &data, sizeof data), 9, 3);
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
    load_counted(&mesh, gltf_file("sparse.gltf", json, &data, sizeof data), 6, 2);
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
    load_counted(&mesh, meshopt_gltf("meshopt.gltf", &f, 24), 9 + 9, 8 + 3);
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

MESH_FIXTURE_MAIN("test_gltf", cmocka_unit_test(test_gltf_nodes), cmocka_unit_test(test_gltf_no_scene),
                               cmocka_unit_test(test_gltf_rotation_of_any_length),
                               cmocka_unit_test(test_gltf_huge_matrix_gives_finite_normals),
                               cmocka_unit_test(test_gltf_strips_and_fans),
                               cmocka_unit_test(test_gltf_meshes_load_once), cmocka_unit_test(test_gltf_deep_node_tree),
                               cmocka_unit_test(test_gltf_required_extensions), cmocka_unit_test(test_gltf_leniency),
                               cmocka_unit_test(test_gltf_normals_from_a_later_primitive),
                               cmocka_unit_test(test_gltf_quantized), cmocka_unit_test(test_gltf_sparse),
                               cmocka_unit_test(test_gltf_meshopt), cmocka_unit_test(test_gltf_points_and_lines_only),
                               bad_inputs_test(".gltf"))
