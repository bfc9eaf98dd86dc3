/* What is done to a mesh whatever its file (mesh.c): zero-area triangles dropped and counted,
 * angle-weighted normals (the same bits on any number of threads), the crease angle splitting
 * vertices along sharp edges, given normals that are zero or not finite made as missing ones, and
 * the bunny. */
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
#include "mesh_pass.h"

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

/* A unit cube as OBJ text, its 8 corners shared by 12 triangles, no normals. */
static const char CUBE_OBJ[] = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                               "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";

/* A repeated index, collinear corners and a point are skipped and counted; vertices left
 * without a triangle get a zero normal. */
static void test_degenerate_counted(void **state)
{
    (void)state;
    struct ao_mesh mesh;
    load_counted(&mesh, fixture("degenerate.obj"), 5, 1);
    assert_int_equal(mesh.degenerate_count, 3);
    assert_triangle(&mesh, 0, 0, 1, 2);
    assert_vec3_near(mesh.normals[0], 0, 0, 1);
    assert_vec3_near(mesh.normals[3], 0, 0, 0);
    assert_vec3_near(mesh.normals[4], 0, 0, 0);
    ao_mesh_finish(&mesh);
}

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

/* Triangles that meet at a vertex without sharing an edge there are sides of their own below
 * 180 degrees, however close their normals: two coplanar triangles touching at a corner (a bowtie
 * of two open fans), and two closed fans around one vertex, nearly flat and facing the same way
 * (each seven triangles at 0.01 below the vertex). The crease pass may skip a vertex only where its
 * triangles close into one fan (normals_part's certificate: without its test of the corners'
 * neighbours the first would not split, without its test of the angles' sum the second). */
static void test_crease_fans_without_a_shared_edge(void **state)
{
    (void)state;
    static const char open_fans[] = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv -1 0 0\nv -1 -1 0\nf 1 2 3\nf 1 4 5\n";
    struct ao_mesh mesh;
    const char *path = temp_file("bowtie.obj", open_fans, sizeof open_fans - 1);
    load_at_crease(&mesh, path, 180.0);
    assert_int_equal(mesh.vertex_count, 5);
    ao_mesh_finish(&mesh);
    load_at_crease(&mesh, path, AO_MESH_CREASE_DEFAULT);
    assert_int_equal(mesh.vertex_count, 6);
    assert_int_not_equal(mesh.indices[0], mesh.indices[3]);
    assert_vec3_near(mesh.normals[mesh.indices[0]], 0, 0, 1);
    assert_vec3_near(mesh.normals[mesh.indices[3]], 0, 0, 1);
    ao_mesh_finish(&mesh);

    enum { RIM = 7 };
    char text[2048];
    int n = sprintf(text, "v 0 0 0\n");
    for (int fan = 0; fan < 2; fan++)
        for (int k = 0; k < RIM; k++) {
            double angle = 6.283185307179586 * (k + 0.5 * fan) / RIM;
            n += sprintf(text + n, "v %.9f %.9f %s\n", cos(angle), sin(angle), fan ? "-0.02" : "-0.01");
        }
    for (int fan = 0; fan < 2; fan++)
        for (int k = 0; k < RIM; k++)
            n += sprintf(text + n, "f 1 %d %d\n", 2 + fan * RIM + k, 2 + fan * RIM + (k + 1) % RIM);
    path = temp_file("two_fans.obj", text, (size_t)n);
    load_at_crease(&mesh, path, 180.0);
    assert_int_equal(mesh.vertex_count, 1 + 2 * RIM);
    ao_mesh_finish(&mesh);
    load_at_crease(&mesh, path, AO_MESH_CREASE_DEFAULT);
    assert_int_equal(mesh.vertex_count, 2 + 2 * RIM);
    assert_int_not_equal(mesh.indices[0], mesh.indices[3 * RIM]);
    ao_mesh_finish(&mesh);
}

/* A copy of mesh's positions and triangles, without normals. */
static void copy_without_normals(struct ao_mesh *copy, const struct ao_mesh *mesh)
{
    *copy = (struct ao_mesh){.vertex_count = mesh->vertex_count, .triangle_count = mesh->triangle_count};
    copy->positions = malloc(mesh->vertex_count * sizeof *copy->positions);
    copy->indices = malloc(3 * mesh->triangle_count * sizeof *copy->indices);
    assert_non_null(copy->positions);
    assert_non_null(copy->indices);
    memcpy(copy->positions, mesh->positions, mesh->vertex_count * sizeof *copy->positions);
    memcpy(copy->indices, mesh->indices, 3 * mesh->triangle_count * sizeof *copy->indices);
}

/* Mesh's normals at crease degrees with every vertex that has a triangle looked at edge by edge:
 * the normals pass, then the crease passes with all its vertices marked (none skipped by the
 * cone's certificate). */
static void complete_marking_all(struct ao_mesh *mesh, double crease)
{
    const double degree = 3.14159265358979323846 / 180.0;
    size_t n = mesh->vertex_count, marked = 0;
    struct cone cone = {.cos_half = cos(crease * degree / 2.0), .at = calloc(n, sizeof *cone.at), .marked = malloc(n)};
    mesh->normals = malloc(n * sizeof *mesh->normals);
    assert_non_null(cone.at);
    assert_non_null(cone.marked);
    assert_non_null(mesh->normals);
    ao_mesh_angle_weighted_normals(mesh, mesh->normals, 0, &cone);
    for (size_t v = 0; v < n; v++)
        marked += cone.marked[v] = cone.at[v].angle_sum > 0;
    struct ao_budget budget = {.limit = AO_BUDGET_LEAST};
    assert_true(ao_mesh_split_creases(mesh, "marked", &cone, marked, cos(crease * degree), &budget));
    free(cone.at);
    free(cone.marked);
}

/* The cone's certificate only saves work: at every crease angle tried, the normals made with it
 * are, bit for bit, those made looking at every vertex edge by edge (the same vertices, triangles
 * and normals), on a grid whose heights are jittered so that its folds take every angle near each
 * crease tried, and on the bunny; and on the grid made gentle (its heights a tenth, every
 * triangle's normal within 8 degrees of the vertical) it settles every vertex at once but those on
 * its border (open fans). */
static void test_crease_certificate_only_saves_work(void **state)
{
    (void)state;
    struct ao_mesh grid, bunny;
    shuffled_grid(&grid, 40);
    uint64_t seed = 777;
    for (size_t v = 0; v < grid.vertex_count; v++) {
        seed = seed * 6364136223846793005u + 1442695040888963407u;
        grid.positions[v].z += (float)((double)(seed >> 11) / 9007199254740992.0 - 0.5);
    }
    char path[4200];
    snprintf(path, sizeof path, "%s/assets/bunny.obj", getenv("AO_SOURCE_ROOT"));
    load_at_crease(&bunny, path, 0.0);
    const struct ao_mesh *meshes[2] = {&grid, &bunny};
    const double creases[] = {2.0, 10.0, 25.0, AO_MESH_CREASE_DEFAULT, 70.0, 120.0, 179.0};
    for (int m = 0; m < 2; m++)
        for (size_t c = 0; c < sizeof creases / sizeof *creases; c++) {
            struct ao_mesh fast, all;
            struct ao_budget budget = {.limit = AO_BUDGET_LEAST};
            copy_without_normals(&fast, meshes[m]);
            copy_without_normals(&all, meshes[m]);
            assert_true(ao_mesh_complete_normals(&fast, "fast", creases[c], &budget));
            complete_marking_all(&all, creases[c]);
            assert_int_equal(fast.vertex_count, all.vertex_count);
            assert_memory_equal(fast.indices, all.indices, 3 * all.triangle_count * sizeof *all.indices);
            assert_memory_equal(fast.normals, all.normals, all.vertex_count * sizeof *all.normals);
            ao_mesh_finish(&fast);
            ao_mesh_finish(&all);
        }
    ao_mesh_finish(&grid);
    ao_mesh_finish(&bunny);

    shuffled_grid(&grid, 40);
    size_t n = grid.vertex_count;
    for (size_t v = 0; v < n; v++)
        grid.positions[v].z *= 0.1f;
    struct cone cone = {.cos_half = cos(AO_MESH_CREASE_DEFAULT / 2.0 * 3.14159265358979323846 / 180.0),
                        .at = calloc(n, sizeof *cone.at), .marked = malloc(n)};
    struct ao_vec3 *normals = malloc(n * sizeof *normals);
    assert_non_null(cone.at);
    assert_non_null(cone.marked);
    assert_non_null(normals);
    size_t marked = ao_mesh_angle_weighted_normals(&grid, normals, 0, &cone);
    assert_int_equal(marked, 4 * 40);
    free(cone.at);
    free(cone.marked);
    free(normals);
    ao_mesh_finish(&grid);
}

/* Normals given as NaN, infinite or zero are made as if not given (counted, and noted with the
 * count by the model): an OBJ's from its triangle (smooth up to the crease angle), a glTF's flat. */
static void test_invalid_normals(void **state)
{
    (void)state;
    static const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn nan 0 1\nvn inf 0 0\nvn 0 0 0\nvn 0 0 2\n"
                              "f 1//1 2//2 3//4\nf 1//3 3//4 2//2\n";
    struct ao_budget budget = {.limit = AO_BUDGET_LEAST};
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

MESH_FIXTURE_MAIN("test_mesh", cmocka_unit_test(test_degenerate_counted), cmocka_unit_test(test_compute_normals),
                               cmocka_unit_test(test_normals_any_thread_count), cmocka_unit_test(test_crease_cube),
                               cmocka_unit_test(test_crease_keeps_a_smooth_mesh),
                               cmocka_unit_test(test_crease_many_triangles_at_a_vertex),
                               cmocka_unit_test(test_crease_fans_without_a_shared_edge),
                               cmocka_unit_test(test_crease_certificate_only_saves_work),
                               cmocka_unit_test(test_invalid_normals), cmocka_unit_test(test_bunny))
