/* The scene budget through the loaders: each format refuses a mesh that would not fit before
 * allocating it, a scene charges every mesh line, and AUTO builds the compact BVH only where
 * nothing else fits. */
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

int main(void)
{
    if (!mesh_fixture_begin("test_load_budget"))
        return 77;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_loaders_keep_to_the_budget),
        cmocka_unit_test(test_scene_budget_covers_every_mesh_line),
        cmocka_unit_test(test_budget_builds_compact_where_only_that_fits),
    };
    return cmocka_run_group_tests(tests, mesh_fixture_setup, mesh_fixture_teardown);
}
