/* The scene's entry points (scene_load.h): every error of a scene file the contract lists, each one
 * line "FILE:LINE: message" (or "FILE: message" for the scene as a whole) with the scene left
 * empty; the defaults a file may leave out; NULL options the same as zeroed ones; and the BVH and
 * the scene budget chosen alike through every entry path: a scene file, a bare mesh, scene text. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>
#include <unistd.h>

#include "mesh_fixture.h"
#include "scene.h"
#include "scene_load.h"

/* How a scene comes in: a path to a scene file or a mesh (ao_scene_load), or text (ao_scene_parse). */
enum entry { FROM_FILE, FROM_TEXT };

/* Loads (FROM_FILE: path) or parses (FROM_TEXT: text as if from path) with its messages captured in err. */
static bool load_captured_scene(struct ao_scene *scene, enum entry entry, const char *path, const char *text,
                                const struct ao_scene_options *options, char *err, size_t err_size)
{
    struct capture c;
    capture_begin(&c);
    bool ok = entry == FROM_FILE ? ao_scene_load(scene, path, options) : ao_scene_parse(scene, text, path, options);
    capture_end(&c, err, err_size);
    return ok;
}

/* The scene must be all zero, as a failed load leaves it. */
static void assert_scene_empty(const struct ao_scene *scene)
{
    static const struct ao_scene zero;
    assert_memory_equal(scene, &zero, sizeof zero);
}

/* Parsing text as temp_dir/errors.scene must fail with exactly one line: "PATH:LINE: " (line 0:
 * "PATH: ") and then message, at its start (exact) or, with `anywhere`, somewhere in it. */
static void expect_error(const char *text, int line, const char *message, bool anywhere)
{
    char path[4200], err[8192], prefix[4300];
    snprintf(path, sizeof path, "%s/errors.scene", temp_dir);
    if (line)
        snprintf(prefix, sizeof prefix, "%s:%d: ", path, line);
    else
        snprintf(prefix, sizeof prefix, "%s: ", path);
    struct ao_scene scene;
    memset(&scene, 0xab, sizeof scene);
    bool ok = load_captured_scene(&scene, FROM_TEXT, path, text, NULL, err, sizeof err);
    size_t n = strlen(err), p = strlen(prefix);
    bool matches = n > p && strncmp(err, prefix, p) == 0 && strchr(err, '\n') == err + n - 1 &&
                   (anywhere ? strstr(err, message) != NULL : strncmp(err + p, message, strlen(message)) == 0);
    if (ok || !matches)
        fail_msg("\"%.60s\": expected \"%s%s\", got ok=%d \"%s\"", text, prefix, message, ok, err);
    assert_scene_empty(&scene);
}

/* One text per error the contract names (unknown or repeated keys, missing or non-finite values,
 * albedo or background outside [0, 1], a non-positive radius, a degenerate camera or quad), and
 * the parser's others, each at its line. */
static void test_parser_errors(void **state)
{
    (void)state;
    static const char tri[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    temp_file("tri.obj", tri, sizeof tri - 1);
    static const struct {
        const char *text;
        int line;
        const char *message;
    } errors[] = {
        /* Keywords and keys. */
        {"# a comment\n\nteapot 1 2 3\n", 3, "unknown keyword 'teapot'"},
        {"sphere center 0 0 0 radius 1 colour 1\n", 1, "unknown key 'colour' for 'sphere'"},
        {"camera eye 0 0 4 target 0 0 0 eye 0 0 3\n", 1, "'eye' given twice"},
        {"sphere center 0 0 0 radius 1 radius 2\n", 1, "'radius' given twice"},
        {"sphere center 0 0 0 radius 1\ncamera eye 0 0 4\n", 2, "'camera' needs 'target'"},
        {"sphere radius 1\n", 1, "'sphere' needs 'center'"},
        {"sphere center 0 0 0\n", 1, "'sphere' needs 'radius'"},
        {"quad corner 0 0 0 edge1 1 0 0\n", 1, "'quad' needs 'edge2'"},
        {"mesh\n", 1, "'mesh' needs a file name"},
        /* Missing and non-finite values. */
        {"sphere center 0 0 radius 1\n", 1, "'center': expected a number, got 'radius'"},
        {"sphere center 0 0 0 radius\n", 1, "'radius': expected 1 number"},
        {"sphere center 0 0 0 radius 1\ncamera eye 0 0 4 target\n", 2, "'target': expected 3 numbers"},
        {"sphere center 0 0 0 radius inf\n", 1, "'radius': value 'inf' is not a finite number"},
        {"sphere center 0 0 nan radius 1\n", 1, "'center': value 'nan' is not a finite number"},
        {"sphere center 0 0 1e39 radius 1\n", 1, "'center': value '1e39' is not a finite number"},
        {"sphere center 0 0 0 radius 1 albedo 0.5 0.5\n", 1, "'albedo': expected 1 or 3 numbers, got 2"},
        {"mesh tri.obj scale 1 2\n", 1, "'scale': expected 1 or 3 numbers, got 2"},
        {"background 0.5 0.5 0.5 0.5\n", 1, "'background': expected 1 or 3 numbers"},
        {"image 640\n", 1, "'image': expected 2 numbers"},
        /* Values out of their range. */
        {"sphere center 0 0 0 radius 1 albedo 1.5\n", 1, "'albedo': values must lie in [0, 1]"},
        {"quad corner 0 0 0 edge1 1 0 0 edge2 0 0 1 albedo 0.5 -0.1 0.5\n", 1, "'albedo': values must lie in [0, 1]"},
        {"background -0.1\n", 1, "'background': values must lie in [0, 1]"},
        {"background 2 1 1\n", 1, "'background': values must lie in [0, 1]"},
        {"sphere center 0 0 0 radius 0\n", 1, "'radius' must be positive"},
        {"sphere center 0 0 0 radius -1\n", 1, "'radius' must be positive"},
        {"ao-distance 0\n", 1, "'ao-distance' must be positive"},
        {"camera eye 0 0 4 target 0 0 0 fov 180\n", 1, "'fov' must lie strictly between 0 and 180 degrees"},
        {"camera eye 0 0 4 target 0 0 0 fov 0\n", 1, "'fov' must lie strictly between 0 and 180 degrees"},
        {"image 0 480\n", 1, "'image': expected width and height, whole numbers from 1 to 16384"},
        {"image 640.5 480\n", 1, "'image': expected width and height, whole numbers from 1 to 16384"},
        {"mesh tri.obj crease 200\n", 1, "'crease': expected degrees from 0 to 180"},
        {"mesh tri.obj rotate 0 0 0 45\n", 1, "'rotate': the axis must not be zero"},
        {"mesh tri.obj scale 0\n", 1, "'scale' must not be zero"},
        /* A degenerate camera or quad. */
        {"quad corner 0 0 0 edge1 1 0 0 edge2 2 0 0\n", 1, "quad: edge1 and edge2 span no area"},
        {"sphere center 0 0 0 radius 1\n\ncamera eye 0 0 1 target 0 0 1\n", 3,
         "camera: eye equals target or up is parallel to the view direction"},
        {"sphere center 0 0 0 radius 1\ncamera eye 0 0 4 target 0 0 0 up 0 0 1\n", 2,
         "camera: eye equals target or up is parallel to the view direction"},
        {"sphere center 0 0 0 radius 1\ncamera eye 0 0 1e-20 target 0 0 0\n", 2,
         "camera: eye and target are 1e-20 apart, closer than"},
        /* The scene's size, and nothing to see. */
        {"sphere center 0 0 0 radius 1e10\n", 0, "the scene is 2e+10 across; aoview renders scenes from 0.000244 "
                                                 "to 2.15e+09 across"},
        {"sphere center 0 0 0 radius 1e-5\n", 0, "the scene is 2e-05 across"},
        {"sphere center 0 0 0 radius 1\ncamera eye 0 0 3e9 target 0 0 0\n", 2, "camera: with it the scene is 3e+09 across"},
        {"# nothing\n", 0, "no camera and nothing to frame: add a 'camera' line or some geometry"},
    };
    for (size_t k = 0; k < sizeof errors / sizeof errors[0]; k++)
        expect_error(errors[k].text, errors[k].line, errors[k].message, false);
}

/* A scene near the largest size, without a camera line, is framed from outside the range a camera
 * line must keep to: the eye 3.22 half-diagonals from the centre (scene.h's ao_camera_frame_box),
 * beyond AO_SCENE_MAX_EXTENT yet within the 3.3 times it that the fuzz harness checks, and a view. */
static void test_the_largest_scenes_are_framed_from_outside_them(void **state)
{
    (void)state;
    static const char text[] = "quad corner -6.5e8 0 -6.5e8 edge1 0 0 1.3e9 edge2 1.3e9 0 0\n"
                               "sphere center 0 2e8 0 radius 2e8\n";
    struct ao_scene scene;
    char err[1024];
    assert_true(load_captured_scene(&scene, FROM_TEXT, "largest.scene", text, NULL, err, sizeof err));
    struct ao_vec3 eye = scene.camera.eye;
    float far = fmaxf(fabsf(eye.x), fmaxf(fabsf(eye.y), fabsf(eye.z)));
    assert_true(far > AO_SCENE_MAX_EXTENT && far <= 3.3f * AO_SCENE_MAX_EXTENT);
    struct ao_view view;
    assert_true(ao_camera_view(&scene.camera, 64, 48, &view));
    ao_scene_finish(&scene);
}

/* A line of more than 4096 characters, and one of more than 64 words, each refused at its line;
 * a mesh line naming a file that cannot load: that file's own one line. */
static void test_line_limits(void **state)
{
    (void)state;
    char text[8192];
    int n = snprintf(text, sizeof text, "# fine\nsphere center 0 0 0 radius 1 ");
    memset(text + n, ' ', 4100);
    strcpy(text + n + 4100, "\n");
    expect_error(text, 2, "line longer than 4096 characters", false);
    n = snprintf(text, sizeof text, "sphere center 0 0 0 radius 1\nsphere");
    for (int k = 0; k < 70; k++)
        n += snprintf(text + n, sizeof text - (size_t)n, " 1");
    snprintf(text + n, sizeof text - (size_t)n, "\n");
    expect_error(text, 2, "too many words on one line (at most 64)", false);
    char path[4200], err[8192];
    snprintf(path, sizeof path, "%s/errors.scene", temp_dir);
    struct ao_scene scene;
    assert_false(load_captured_scene(&scene, FROM_TEXT, path, "mesh missing.obj\n", NULL, err, sizeof err));
    char want[4300];
    snprintf(want, sizeof want, "%s/missing.obj: cannot open: No such file or directory\n", temp_dir);
    assert_string_equal(err, want);
    assert_scene_empty(&scene);
}

/* Files: missing, or text with a NUL byte. */
static void test_file_errors(void **state)
{
    (void)state;
    char err[8192], want[4500];
    struct ao_scene scene;
    const char *path = temp_file("nul.scene", "sphere center 0 0 0 radius 1\n\0x\n", 32);
    assert_false(load_captured_scene(&scene, FROM_FILE, path, NULL, NULL, err, sizeof err));
    snprintf(want, sizeof want, "%s: not a text file (it contains a NUL byte)\n", path);
    assert_string_equal(err, want);
    assert_scene_empty(&scene);
    path = fixture("missing.scene");
    assert_false(load_captured_scene(&scene, FROM_FILE, path, NULL, NULL, err, sizeof err));
    snprintf(want, sizeof want, "%s: cannot open: No such file or directory\n", path);
    assert_string_equal(err, want);
    /* Only a .scene file (any case) is read as a scene; any other file, a scene's text in it or not,
     * is named by its extension, unread (README.md was parsed: "README.md:3: unknown keyword"). */
    static const char text[] = "camera eye 0 1 4 target 0 0 0\nsphere center 0 0 0 radius 1\n";
    static const char *const others[][2] = {{"notes.md", "extension '.md'"}, {"scene.txt", "extension '.txt'"},
                                            {"scene", "no extension"}, {"dir.scene/scene", "no extension"}};
    for (size_t i = 0; i < sizeof others / sizeof others[0]; i++) {
        path = temp_file(strchr(others[i][0], '/') ? "scene" : others[i][0], text, sizeof text - 1);
        if (strchr(others[i][0], '/')) {   /* a dot in a folder's name is no extension */
            static char folder[4200], file[4300];
            snprintf(folder, sizeof folder, "%.*s/dir.scene", (int)(strrchr(path, '/') - path), path);
            snprintf(file, sizeof file, "%s/scene", folder);
            assert_int_equal(mkdir(folder, 0700) == 0 || errno == EEXIST, 1);
            assert_int_equal(rename(path, file), 0);
            path = file;
        }
        assert_false(load_captured_scene(&scene, FROM_FILE, path, NULL, NULL, err, sizeof err));
        snprintf(want, sizeof want, "%s: %s: aoview reads scenes (.scene) and meshes (.obj, .ply, .stl, .gltf or .glb)\n",
                 path, others[i][1]);
        assert_string_equal(err, want);
        assert_scene_empty(&scene);
        if (strchr(others[i][0], '/')) {
            assert_int_equal(unlink(path), 0);
            *strrchr((char *)path, '/') = '\0';
            assert_int_equal(rmdir(path), 0);
        }
    }
    path = temp_file("UPPER.SCENE", text, sizeof text - 1);
    assert_true(load_captured_scene(&scene, FROM_FILE, path, NULL, NULL, err, sizeof err));
    ao_scene_finish(&scene);
}

/* What a file leaves out: background 1, albedo 0.8, no AO distance, up 0 1 0, fov 40, and a camera
 * framed on the scene's box without a camera line; the same scene with NULL options, zeroed ones,
 * and through either entry. */
static void test_defaults(void **state)
{
    (void)state;
    static const char text[] = "camera eye 0 1 4 target 0 0 0\nsphere center 0 0 0 radius 1\n";
    const char *path = temp_file("defaults.scene", text, sizeof text - 1);
    struct ao_scene a, b, c;
    char err[1024];
    struct ao_scene_options zero = {0};
    assert_true(load_captured_scene(&a, FROM_FILE, path, NULL, NULL, err, sizeof err));
    assert_true(load_captured_scene(&b, FROM_FILE, path, NULL, &zero, err, sizeof err));
    assert_true(load_captured_scene(&c, FROM_TEXT, path, text, &zero, err, sizeof err));
    assert_string_equal(err, "");
    for (const struct ao_scene *s = &a; s; s = s == &a ? &b : s == &b ? &c : NULL) {
        assert_string_equal(s->name, "defaults.scene");
        assert_true(s->background.x == 1.0f && s->background.y == 1.0f && s->background.z == 1.0f);
        assert_true(isinf(s->ao_distance));
        assert_int_equal(s->sphere_count, 1);
        assert_true(s->spheres[0].albedo.x == 0.8f && s->spheres[0].albedo.z == 0.8f);
        assert_true(s->camera.fov == 40.0f && s->camera.up.y == 1.0f && s->camera.up.x == 0.0f);
        assert_int_equal(s->bvh, AO_BVH_MEDIUM);
        assert_int_equal(s->width, 0);
    }
    assert_memory_equal(&a.camera, &b.camera, sizeof a.camera);
    assert_memory_equal(&a.camera, &c.camera, sizeof a.camera);
    ao_scene_finish(&a);
    ao_scene_finish(&b);
    ao_scene_finish(&c);
    assert_true(load_captured_scene(&a, FROM_TEXT, path, "sphere center 0 0 0 radius 1\n", NULL, err, sizeof err));
    struct ao_view view;
    assert_true(ao_camera_view(&a.camera, 1, 1, &view));   /* framed on the sphere */
    ao_scene_finish(&a);
}

/* The entry paths of the BVH and budget test: a scene file naming a mesh, the same text parsed, and
 * the mesh bare (with its ground). */
struct path {
    const char *name;
    enum entry entry;
    const char *path, *text;
};

/* The least budget with which the path loads at options' BVH (found by bisection: loading is
 * monotonic in the budget), and that one byte less is refused in one line. */
static uint64_t least_budget(const struct path *p, struct ao_scene_options options)
{
    uint64_t lo = 1, hi = (uint64_t)1 << 30;
    char err[8192];
    struct ao_scene scene;
    while (lo < hi) {
        options.budget = lo + (hi - lo) / 2;
        if (load_captured_scene(&scene, p->entry, p->path, p->text, &options, err, sizeof err)) {
            hi = options.budget;
            ao_scene_finish(&scene);
        } else {
            lo = options.budget + 1;
        }
    }
    options.budget = lo - 1;
    assert_false(load_captured_scene(&scene, p->entry, p->path, p->text, &options, err, sizeof err));
    assert_non_null(strstr(err, "scene budget"));
    assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    return lo;
}

/* The BVH through every entry path: AUTO (NULL options) builds MEDIUM; a budget where MEDIUM's
 * charges do not fit but COMPACT's do builds COMPACT, with the note that says so; one where
 * neither fits is refused; LOW loads where AUTO does, with compact leaves and the note where AUTO
 * builds COMPACT; asked for, each BVH is built as asked, charged at its own rates, with no note. The same rule on every path (the fault this guards against: the BVH settled in two of four
 * entry points). */
static void test_bvh_through_every_entry(void **state)
{
    (void)state;
    static const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
    const char *mesh = temp_file("square.obj", obj, sizeof obj - 1);
    static const char text[] = "camera eye 0 1 4 target 0 0 0\nmesh square.obj\n";
    const char *file = temp_file("square.scene", text, sizeof text - 1);
    char mesh_path[4200], file_path[4200];
    snprintf(mesh_path, sizeof mesh_path, "%s", mesh);
    snprintf(file_path, sizeof file_path, "%s", file);
    const struct path paths[] = {{"scene file", FROM_FILE, file_path, NULL},
                                 {"scene text", FROM_TEXT, file_path, text},
                                 {"bare mesh", FROM_FILE, mesh_path, NULL}};
    for (size_t k = 0; k < sizeof paths / sizeof paths[0]; k++) {
        const struct path *p = &paths[k];
        struct ao_scene scene;
        char err[8192];
        assert_true(load_captured_scene(&scene, p->entry, p->path, p->text, NULL, err, sizeof err));
        if (scene.bvh != AO_BVH_MEDIUM || scene.notes[0])
            fail_msg("%s: NULL options built BVH %d, notes \"%s\"", p->name, scene.bvh, scene.notes);
        ao_scene_finish(&scene);
        uint64_t medium = least_budget(p, (struct ao_scene_options){.bvh = AO_BVH_MEDIUM});
        uint64_t compact = least_budget(p, (struct ao_scene_options){.bvh = AO_BVH_COMPACT});
        uint64_t low = least_budget(p, (struct ao_scene_options){.bvh = AO_BVH_LOW});
        uint64_t automatic = least_budget(p, (struct ao_scene_options){0});
        if (!(compact < medium && low == compact && automatic == compact))
            fail_msg("%s: least budgets MEDIUM %llu, COMPACT %llu, LOW %llu, AUTO %llu", p->name,
                     (unsigned long long)medium, (unsigned long long)compact, (unsigned long long)low,
                     (unsigned long long)automatic);
        /* AUTO at MEDIUM's least budget builds MEDIUM; a byte less, COMPACT with its note. */
        struct ao_scene_options options = {.budget = medium};
        assert_true(load_captured_scene(&scene, p->entry, p->path, p->text, &options, err, sizeof err));
        assert_int_equal(scene.bvh, AO_BVH_MEDIUM);
        assert_string_equal(scene.notes, "");
        ao_scene_finish(&scene);
        options.budget = medium - 1;
        assert_true(load_captured_scene(&scene, p->entry, p->path, p->text, &options, err, sizeof err));
        assert_int_equal(scene.bvh, AO_BVH_COMPACT);
        if (!strstr(scene.notes, "BVH built compact to fit the scene budget"))
            fail_msg("%s: notes \"%s\"", p->name, scene.notes);
        ao_scene_finish(&scene);
        options.bvh = AO_BVH_LOW;
        assert_true(load_captured_scene(&scene, p->entry, p->path, p->text, &options, err, sizeof err));
        assert_int_equal(scene.bvh, AO_BVH_LOW_COMPACT);
        if (!strstr(scene.notes, "BVH built compact to fit the scene budget"))
            fail_msg("%s: LOW's notes \"%s\"", p->name, scene.notes);
        ao_scene_finish(&scene);
        /* Asked for: as asked, no note. */
        for (enum ao_bvh bvh = AO_BVH_MEDIUM; bvh <= AO_BVH_LOW; bvh++) {
            options = (struct ao_scene_options){.bvh = bvh};
            assert_true(load_captured_scene(&scene, p->entry, p->path, p->text, &options, err, sizeof err));
            assert_int_equal(scene.bvh, bvh);
            assert_string_equal(scene.notes, "");
            ao_scene_finish(&scene);
        }
    }
}

/* The budget through every entry path: the scene file is charged its text and the parsed text is
 * not, so the file needs exactly its size plus one (the NUL) more; the bare mesh is charged the
 * ground's two triangles unless no_ground; an `image` line is charged its buffers unless sized. */
static void test_budget_through_every_entry(void **state)
{
    (void)state;
    static const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
    const char *mesh = temp_file("square.obj", obj, sizeof obj - 1);
    char mesh_path[4200];
    snprintf(mesh_path, sizeof mesh_path, "%s", mesh);
    static const char text[] = "camera eye 0 1 4 target 0 0 0\nmesh square.obj\n";
    const char *file = temp_file("square.scene", text, sizeof text - 1);
    char file_path[4200];
    snprintf(file_path, sizeof file_path, "%s", file);
    struct path from_file = {"scene file", FROM_FILE, file_path, NULL}, from_text = {"scene text", FROM_TEXT, file_path, text};
    struct ao_scene_options medium = {.bvh = AO_BVH_MEDIUM};
    assert_int_equal(least_budget(&from_file, medium), least_budget(&from_text, medium) + sizeof text);
    struct path bare = {"bare mesh", FROM_FILE, mesh_path, NULL};
    struct ao_scene_options bare_only = {.bvh = AO_BVH_MEDIUM, .no_ground = true};
    struct ao_budget rates = {.bvh = AO_BVH_MEDIUM};
    assert_int_equal(least_budget(&bare, medium), least_budget(&bare, bare_only) + ao_budget_charge(&rates, 2, 4, 0));
    /* The ground: there unless no_ground, under a bare mesh only. */
    struct ao_scene scene;
    char err[1024];
    assert_true(load_captured_scene(&scene, FROM_FILE, mesh_path, NULL, NULL, err, sizeof err));
    assert_int_equal(scene.triangle_count, 4);
    ao_scene_finish(&scene);
    assert_true(load_captured_scene(&scene, FROM_FILE, mesh_path, NULL, &bare_only, err, sizeof err));
    assert_int_equal(scene.triangle_count, 2);
    ao_scene_finish(&scene);
    assert_true(load_captured_scene(&scene, FROM_FILE, file_path, NULL, NULL, err, sizeof err));
    assert_int_equal(scene.triangle_count, 2);
    ao_scene_finish(&scene);
    /* An image line of 8192 x 8192 pixels needs its buffers in the budget, unless sized. */
    static const char big[] = "camera eye 0 1 4 target 0 0 0\nmesh square.obj\nimage 8192 8192\n";
    struct ao_scene_options small = {.budget = (uint64_t)1 << 20};
    assert_false(load_captured_scene(&scene, FROM_TEXT, file_path, big, &small, err, sizeof err));
    char want[4400];
    snprintf(want, sizeof want, "%s:3: 'image' 8192x8192: its buffers need about", file_path);
    if (strncmp(err, want, strlen(want)) != 0)
        fail_msg("got \"%s\"", err);
    small.sized = true;
    assert_true(load_captured_scene(&scene, FROM_TEXT, file_path, big, &small, err, sizeof err));
    assert_int_equal(scene.width, 8192);
    ao_scene_finish(&scene);
}

/* One budget covers the whole scene: a mesh file that three lines name is read and charged once,
 * each of its placements once, and each copy of it that flattening makes, its structures too (a one-triangle mesh
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
    /* The scene's text, the mesh (and its structures), three placements and two copies (and theirs),
     * at the MEDIUM BVH's rates. */
    uint64_t need = sizeof text + 3 * medium_charge(1, 3) + AO_BUDGET_MESH + 3 * AO_BUDGET_INSTANCE +
                    2 * AO_BUDGET_COPY;
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
    /* Asked for, each is charged at its own rates, without a note; LOW at AUTO's, so that it loads
     * whatever AUTO loads: with compact leaves where only COMPACT's charges fit. */
    struct ao_scene_options asked = {.budget = compact, .bvh = AO_BVH_COMPACT};
    assert_true(ao_scene_load(&scene, path, &asked));
    assert_int_equal(scene.bvh, AO_BVH_COMPACT);
    assert_string_equal(scene.notes, "");
    ao_scene_finish(&scene);
    asked.bvh = AO_BVH_LOW;
    assert_true(ao_scene_load(&scene, path, &asked));
    assert_int_equal(scene.bvh, AO_BVH_LOW_COMPACT);
    assert_string_equal(scene.notes, "one.scene: BVH built compact to fit the scene budget (slower rays; "
                                     "a larger --scene-budget gets the faster BVH)");
    ao_scene_finish(&scene);
    asked.budget = compact - 1;
    assert_false(ao_scene_load(&scene, path, &asked));
    asked.budget = medium;
    assert_true(ao_scene_load(&scene, path, &asked));
    assert_int_equal(scene.bvh, AO_BVH_LOW);
    assert_string_equal(scene.notes, "");
    ao_scene_finish(&scene);
}

MESH_FIXTURE_MAIN("test_scene", cmocka_unit_test(test_parser_errors), cmocka_unit_test(test_line_limits),
                                cmocka_unit_test(test_file_errors),
                                cmocka_unit_test(test_the_largest_scenes_are_framed_from_outside_them),
                                cmocka_unit_test(test_defaults), cmocka_unit_test(test_bvh_through_every_entry),
                                cmocka_unit_test(test_budget_through_every_entry),
                                cmocka_unit_test(test_scene_budget_covers_every_mesh_line),
                                cmocka_unit_test(test_budget_builds_compact_where_only_that_fits))
