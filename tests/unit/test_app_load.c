/* The front ends' loading (app_load.c): the files checked before loading (an output that is the
 * scene, --reference or another output, also through a link, refused in one line) and after (an
 * output that is a mesh the scene read); a load that fills in the renderer's config and says what
 * it built; failures that leave nothing to release but what ao_app_finish releases; a failed
 * --stats write turning a clean exit into a failure. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "app_fixture.h"
#include "app_load.h"
#include "app_report.h"
#include "tracer.h"

/* A scene of the ground and a mesh read from tri.obj beside it: the path of scene.scene in the
 * scratch folder (a static buffer). */
static const char *mesh_scene(void)
{
    assert_true(write_text(scratch_path("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
    assert_true(write_text(scratch_path("scene.scene"), "camera eye 0 1 3 target 0 0 0 fov 40\n"
                                                        "mesh tri.obj\n"
                                                        "quad corner -5 0 -5 edge1 0 0 10 edge2 10 0 0\n"));
    static char path[8192];
    snprintf(path, sizeof path, "%s", scratch_path("scene.scene"));
    return path;
}

/* ao_app_check_files on opts, with `outputs` -o's; what it said into said. */
static bool check(const struct ao_options *opts, const char *const *outputs, size_t count, char *said, size_t size)
{
    stderr_begin();
    bool ok = ao_app_check_files(opts, outputs, count);
    snprintf(said, size, "%s", stderr_end());
    return ok;
}

/* An output that is the scene, directly or through a link; --stats that is --reference; the two
 * outputs of --compare that are one file. Distinct files pass, in silence. */
static void test_check_files(void **state)
{
    (void)state;
    const char *scene = mesh_scene();
    struct ao_options opts = {.scene_path = scene};
    char said[8192], expected[8192];
    const char *output = scene;
    assert_false(check(&opts, &output, 1, said, sizeof said));
    snprintf(expected, sizeof expected, "-o: %s is also the scene (%s): aoview does not overwrite its inputs\n",
             scene, scene);
    assert_string_equal(said, expected);

    const char *link = scratch_path("link.png");
    unlink(link);
    assert_int_equal(symlink(scene, link), 0);
    assert_false(check(&opts, &link, 1, said, sizeof said));
    assert_non_null(strstr(said, "is also the scene"));

    const char *reference = scratch_path("reference.pfm");
    assert_true(write_text(reference, "PF\n1 1\n-1\n"));
    opts.reference_path = reference;
    opts.stats_path = reference;
    output = scratch_path("out.pfm");
    assert_false(check(&opts, &output, 1, said, sizeof said));
    snprintf(expected, sizeof expected,
             "--stats: %s is also --reference (%s): aoview does not overwrite its inputs\n", reference, reference);
    assert_string_equal(said, expected);

    opts.stats_path = scratch_path("stats.csv");
    const char *two[] = {scratch_path("a.pfm"), scratch_path("a.pfm")};
    assert_false(check(&opts, two, 2, said, sizeof said));
    assert_non_null(strstr(said, "each output needs a file of its own"));

    two[1] = scratch_path("b.pfm");
    assert_true(check(&opts, two, 2, said, sizeof said));
    assert_string_equal(said, "");
}

/* The scene's mesh is a file the checks before loading could not know of: --stats naming it is
 * refused once the scene is loaded, and the mesh left as it was; -o, whose name ends in an image's
 * extension, naming a glTF buffer likewise. */
static void test_output_is_a_mesh(void **state)
{
    (void)state;
    struct loaded l = {0};
    const char *obj = scratch_path("tri.obj");
    char expected[8192];
    snprintf(expected, sizeof expected,
             "--stats: %s is a file the scene reads (%s): aoview does not overwrite its inputs\n", obj, obj);
    stderr_begin();
    int status = load_line(&l, "aoview --headless --quiet --size 16x12 --stats %s %s", obj, mesh_scene());
    assert_string_equal(stderr_end(), expected);
    assert_int_equal(status, AO_EXIT_RUNTIME);
    assert_null(l.app.tracer);
    assert_int_equal(ao_app_finish(&l.app, status), AO_EXIT_RUNTIME);
    char *text = read_file(obj, NULL);
    assert_string_equal(text, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    free(text);

    /* A glTF buffer named as an image: -o naming it is refused the same way. */
    const float triangle[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const char *buffer = scratch_path("tri.pfm");
    FILE *f = fopen(buffer, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(triangle, sizeof triangle, 1, f), 1);
    assert_int_equal(fclose(f), 0);
    assert_true(write_text(scratch_path("tri.gltf"),
                           "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
                           "\"nodes\":[{\"mesh\":0}],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                           "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
                           "\"min\":[0,0,0],\"max\":[1,1,0]}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
                           "\"buffers\":[{\"uri\":\"tri.pfm\",\"byteLength\":36}]}"));
    const char *scene = scratch_path("gltf.scene");
    assert_true(write_text(scene, "camera eye 0 1 3 target 0 0 0 fov 40\nmesh tri.gltf\n"));
    struct loaded gltf = {0};
    snprintf(expected, sizeof expected,
             "-o: %s is a file the scene reads (tri.pfm): aoview does not overwrite its inputs\n", buffer);
    stderr_begin();
    status = load_line(&gltf, "aoview --headless --quiet --size 16x12 -o %s %s", buffer, scene);
    assert_string_equal(stderr_end(), expected);
    assert_int_equal(status, AO_EXIT_RUNTIME);
    assert_int_equal(ao_app_finish(&gltf.app, status), AO_EXIT_RUNTIME);
}

/* A load: one line saying what was built, the config reporting to the app's reporter, --stats
 * open (and removed by ao_app_finish, having no row), -o named for the signal lines. */
static void test_load(void **state)
{
    (void)state;
    struct loaded l = {0};
    struct ao_app *app = &l.app;
    const char *stats = scratch_path("load.csv");
    stderr_begin();
    int status = load_line(&l, "aoview --headless --size 16x12 --spp 4 --seed 9 --stats %s %s", stats, mesh_scene());
    const char *said = stderr_end();
    assert_int_equal(status, 0);
    assert_memory_equal(said, "aoview: scene.scene: 3 triangles, 0 spheres, traced by ",
                        strlen("aoview: scene.scene: 3 triangles, 0 spheres, traced by "));
    assert_int_equal(strchr(said, '\n') - said, strlen(said) - 1);   /* one line */
    assert_ptr_equal(l.config.on_pass, ao_app_on_pass);
    assert_ptr_equal(l.config.on_preview, ao_app_on_preview);
    assert_ptr_equal(l.config.user, &app->reporter);
    assert_ptr_equal(l.config.scene, &app->scene);
    assert_ptr_equal(l.config.tracer, app->tracer);
    assert_int_equal(l.config.target_spp, 4);
    assert_int_equal(l.config.seed, 9);
    assert_null(l.config.reference);
    assert_int_equal(l.settings.width, 16);
    assert_int_equal(l.settings.height, 12);
    assert_ptr_equal(app->reporter.stats, &app->stats);
    assert_false(app->reporter.progress);
    assert_string_equal(app->interrupt.output, "aoview.png");
    assert_int_equal(access(stats, F_OK), 0);
    assert_int_equal(ao_app_finish(app, 0), 0);
    assert_int_not_equal(access(stats, F_OK), 0);
}

/* A binary PLY grid of GRID x GRID squares, 1,051,250 triangles (over 2^20, a big scene for
 * `--bvh auto`), in the scratch folder; its path (a static buffer). */
static const char *big_grid(void)
{
    enum { GRID = 725, SIDE = GRID + 1 };
    static char path[8192];
    snprintf(path, sizeof path, "%s", scratch_path("grid.ply"));
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
               "property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n",
            SIDE * SIDE, 2 * GRID * GRID);
    for (int z = 0; z < SIDE; z++)
        for (int x = 0; x < SIDE; x++) {
            float v[3] = {(float)x / GRID - 0.5f, 0.0f, (float)z / GRID - 0.5f};
            assert_int_equal(fwrite(v, sizeof v, 1, f), 1);
        }
    for (int z = 0; z < GRID; z++)
        for (int x = 0; x < GRID; x++) {
            int32_t a = z * SIDE + x, corners[2][3] = {{a, a + SIDE, a + 1}, {a + 1, a + SIDE, a + SIDE + 1}};
            for (int t = 0; t < 2; t++) {
                unsigned char three = 3;
                assert_int_equal(fwrite(&three, 1, 1, f), 1);
                assert_int_equal(fwrite(corners[t], sizeof corners[t], 1, f), 1);
            }
        }
    assert_int_equal(fclose(f), 0);
    return path;
}

/* A big scene starts on a LOW BVH (the tracer's MEDIUM build still to come, config.upgrade set)
 * where that is sooner: in the window and in a one-pass headless run (--spp at most the first
 * pass's samples: --spppp's, or auto passes' 8); a longer headless run builds MEDIUM alone. */
static void test_big_scene_bvh_by_run(void **state)
{
    (void)state;
    const char *grid = big_grid();
    static const struct {
        const char *options;
        bool low_first;
    } cases[] = {
        {"--size 16x12", true},
        {"--headless --size 16x12 --spp 8", true},
        {"--headless --size 16x12 --spp 4 --spppp 4", true},
        {"--headless --size 16x12 --spp 9", false},
        {"--headless --size 16x12 --spp 8 --spppp 4", false},
        {"--headless --size 16x12", false},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        struct loaded l = {0};
        int status = load_line(&l, "aoview --quiet --scene-budget 1G %s %s", cases[k].options, grid);
        print_message("%s: %s\n", cases[k].options, l.config.upgrade ? "LOW first" : "MEDIUM alone");
        assert_int_equal(status, 0);
        assert_true(l.app.scene.progressive);   /* the budget holds both BVHs */
        assert_int_equal(l.config.upgrade != NULL, cases[k].low_first);
        assert_int_equal(ao_tracer_upgrading(l.app.tracer), cases[k].low_first);
        assert_int_equal(ao_app_finish(&l.app, 0), 0);
    }
}

/* A scene that is not there, and a --reference of another size: one line each, AO_EXIT_RUNTIME,
 * and ao_app_finish releases what was made. */
static void test_load_refused(void **state)
{
    (void)state;
    struct loaded missing = {0};
    stderr_begin();
    int status = load_line(&missing, "aoview --headless --quiet --size 16x12 %s", scratch_path("missing.scene"));
    const char *said = stderr_end();
    assert_int_equal(status, AO_EXIT_RUNTIME);
    assert_non_null(strstr(said, "missing.scene"));
    assert_int_equal(strchr(said, '\n') - said, strlen(said) - 1);
    assert_int_equal(ao_app_finish(&missing.app, status), AO_EXIT_RUNTIME);

    const char *reference = scratch_path("small.pfm");
    float pixel[3] = {0.5f, 0.5f, 0.5f};
    FILE *f = fopen(reference, "wb");
    assert_non_null(f);
    fputs("PF\n1 1\n-1\n", f);
    fwrite(pixel, sizeof pixel, 1, f);
    fclose(f);
    struct loaded sized = {0};
    stderr_begin();
    status = load_line(&sized, "aoview --headless --quiet --size 16x12 --reference %s %s", reference, mesh_scene());
    said = stderr_end();
    assert_int_equal(status, AO_EXIT_RUNTIME);
    assert_non_null(strstr(said, "small.pfm"));
    assert_null(sized.app.reference);
    assert_int_equal(ao_app_finish(&sized.app, status), AO_EXIT_RUNTIME);
}

/* A --stats row that could not be written turns a clean exit into AO_EXIT_RUNTIME, once said;
 * another status stays. */
static void test_finish_after_failed_stats(void **state)
{
    (void)state;
    if (access("/dev/full", W_OK) != 0)
        skip();
    for (int status = 0; status <= 130; status += 130) {
        struct loaded l = {0};
        assert_int_equal(load_line(&l, "aoview --headless --quiet --size 16x12 --stats /dev/full %s", mesh_scene()), 0);
        struct ao_frame_info info = {.pass = 1, .spp = 1, .error = NAN, .converged = NAN, .rmse = NAN};
        stderr_begin();
        l.config.on_pass(&info, l.config.user);
        int finished = ao_app_finish(&l.app, status);
        assert_string_equal(stderr_end(), "/dev/full: write failed\n");
        assert_int_equal(finished, status ? status : AO_EXIT_RUNTIME);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_check_files),
        cmocka_unit_test(test_output_is_a_mesh),
        cmocka_unit_test(test_load),
        cmocka_unit_test(test_load_refused),
        cmocka_unit_test(test_big_scene_bvh_by_run),
        cmocka_unit_test(test_finish_after_failed_stats),
    };
    return cmocka_run_group_tests(tests, app_fixture_setup, app_fixture_teardown);
}
