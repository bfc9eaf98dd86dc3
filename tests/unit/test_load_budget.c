/* The scene budget: its default from the machine's memory; through the loaders, each format
 * refuses a mesh that would not fit before allocating it, a scene charges every mesh line, and
 * AUTO builds the compact BVH only where nothing else fits. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene.h"
#include "scene_load.h"

#include "mesh_fixture.h"

/* The default budget is a quarter of the machine's memory, at least 1 GiB, and the machine's memory
 * is what the kernel counts (/proc/meminfo's MemTotal, where there is one: the same pages). */
static void test_budget_default_follows_memory(void **state)
{
    (void)state;
    const uint64_t gib = (uint64_t)1 << 30;
    assert_true(ao_budget_default_for(0) == gib);
    assert_true(ao_budget_default_for(2 * gib) == gib);
    assert_true(ao_budget_default_for(4 * gib) == gib);
    assert_true(ao_budget_default_for(4 * gib + 4) == gib + 1);
    assert_true(ao_budget_default_for(24 * gib) == 6 * gib);
    uint64_t memory = ao_budget_machine_memory();
    assert_true(memory > 0);
    assert_true(ao_budget_default() == (memory / 4 > gib ? memory / 4 : gib));
    FILE *info = fopen("/proc/meminfo", "r");
    unsigned long long kib = 0;
    if (info) {
        assert_int_equal(fscanf(info, "MemTotal: %llu kB", &kib), 1);
        fclose(info);
        assert_true(memory == kib * 1024);
    }
}

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

MESH_FIXTURE_MAIN("test_load_budget", cmocka_unit_test(test_budget_default_follows_memory),
                                      cmocka_unit_test(test_loaders_keep_to_the_budget))
