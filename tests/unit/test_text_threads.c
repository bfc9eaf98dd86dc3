/* The core's entry points that may run at once (docs/architecture.md#threads) on four threads
 * together, good and bad inputs, each thread routed to its own sink: scenes from a path, a mesh,
 * text and arrays; tracers (Embree) and ray batches (ao_tracer_arrays_create and
 * ao_tracer_intersect_arrays), with their own thread teams; renders on separate scenes, whose
 * render threads report. Each thread must receive exactly the messages it received running alone,
 * and nothing else; the process's sink nothing. In the threads suite, run under ThreadSanitizer by CI. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "capture.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"
#include "tracer_arrays.h"

enum { THREADS = 4, ROUNDS = 20 };

/* The fixtures' folder and this run's scratch folder. */
static char source_root[4096], temp_dir[4096];

/* A bent strip of two triangles (tests/unit/test_scene_load_arrays.c's start). */
static const float POSITIONS[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
static const uint32_t INDICES[] = {2, 1, 0, 0, 2, 3};

/* One thread's run: its number, what it received and how its calls went. */
struct worker {
    int index;
    struct capture capture;
    int failures;            /* calls that failed where they should not have, or succeeded where not */
};

/* The render thread's note after each pass, which must reach the renderer's creator's sink. */
static void note_pass(const struct ao_frame_info *info, void *user)
{
    ao_text_note("worker %d: pass %u", *(const int *)user, info->pass);
}

/* A render of the arrays' scene to 16 spp in 2 passes of 8 on 2 threads (the render thread and a
 * worker), each pass noted by the render thread; false when it did not finish. */
static bool render_scene(const struct ao_scene *scene, const struct ao_tracer *tracer, const int *index)
{
    struct ao_render_config config = {.scene = scene, .tracer = tracer, .threads = 2, .seed = 1, .target_spp = 16,
                                      .ao_distance = INFINITY, .on_pass = note_pass, .user = (void *)index};
    struct ao_settings settings = {.width = 16, .height = 12, .sampling = AO_SAMPLING_COSINE, .aa = true, .spppp = 8,
                                   .camera = scene->camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    bool done = r && ao_render_wait(r) && ao_render_take_frame(r);
    ao_render_destroy(r);
    return done;
}

/* Counts a call that went the wrong way. */
static void expect(struct worker *w, bool ok, bool wanted)
{
    w->failures += ok != wanted;
}

/* One round of every entry point, good and bad, each input naming the worker and the round. */
static void round_of_calls(struct worker *w, int round)
{
    char path[4400], name[64];
    struct ao_scene scene;

    /* A scene file and a mesh from their paths; a missing file; a bad scene file. */
    snprintf(path, sizeof path, "%s/assets/scenes/sphere-on-plane.scene", source_root);
    expect(w, ao_scene_load(&scene, path, NULL), true);
    ao_scene_finish(&scene);
    snprintf(path, sizeof path, "%s/tests/data/mesh/cube.ply", source_root);
    expect(w, ao_scene_load(&scene, path, NULL), true);
    ao_scene_finish(&scene);
    snprintf(path, sizeof path, "%s/missing-%d-%d.obj", temp_dir, w->index, round);
    expect(w, ao_scene_load(&scene, path, NULL), false);
    snprintf(path, sizeof path, "%s/bad-%d.scene", temp_dir, w->index);
    expect(w, ao_scene_load(&scene, path, NULL), false);

    /* Scene text, bad. */
    snprintf(name, sizeof name, "text-%d-%d.scene", w->index, round);
    expect(w, ao_scene_parse(&scene, "sphere center 0 0 0 radius -1\n", name, NULL), false);

    /* Arrays: a bad camera, then the strip, its tracer, a render of it. */
    struct ao_camera camera = {.eye = {0, 0, 3}, .target = {0, 0, 0}, .up = {0, 1, 0}, .fov = 200};
    snprintf(name, sizeof name, "arrays-%d-%d", w->index, round);
    struct ao_scene_arrays arrays = {.name = name, .positions = POSITIONS, .vertex_count = 4, .indices = INDICES,
                                     .triangle_count = 2, .albedo = {0.8f, 0.8f, 0.8f}, .camera = &camera};
    expect(w, ao_scene_from_arrays(&scene, &arrays, NULL), false);
    arrays.camera = NULL;
    bool loaded = ao_scene_from_arrays(&scene, &arrays, NULL);
    expect(w, loaded, true);
    struct ao_tracer *tracer = loaded ? ao_tracer_create_with(&scene, AO_BACKEND_EMBREE) : NULL;
    expect(w, tracer != NULL, true);
    if (tracer)
        expect(w, render_scene(&scene, tracer, &w->index), true);
    ao_tracer_destroy(tracer);
    if (loaded)
        ao_scene_finish(&scene);

    /* Ray batches on a team of 2: one that hits, and a mesh Embree refuses (a buffer too large: its
     * error, kept from Embree's callback, then the failure, both on this thread). */
    const float origins[] = {0.2f, 0.5f, 1.0f}, directions[] = {0, 0, -1};
    double t, barys[3];
    int32_t id;
    struct ao_tracer_arrays *mesh = ao_tracer_arrays_create(POSITIONS, 4, INDICES, 2);
    expect(w, mesh != NULL, true);
    if (mesh)
        expect(w, ao_tracer_intersect_arrays(mesh, origins, directions, 1, 0.0f, 2, &t, &id, barys), true);
    w->failures += !(mesh && t == 1.0 && id >= 0);
    ao_tracer_arrays_destroy(mesh);
    expect(w, ao_tracer_arrays_create(POSITIONS, 4, INDICES, (size_t)1 << 40) != NULL, false);
}

/* A worker's thread: every round, routed to its own capture. */
static void *work(void *arg)
{
    struct worker *w = arg;
    capture_begin(&w->capture);
    for (int round = 0; round < ROUNDS; round++)
        round_of_calls(w, round);
    capture_end(&w->capture, NULL, 0);
    return NULL;
}

/* Whether text holds "worker K" or a path of worker K's ("-K-", "bad-K.") for a K other than own. */
static bool names_another(const char *text, int own)
{
    for (int k = 0; k < THREADS; k++) {
        char marks[3][32];
        snprintf(marks[0], sizeof marks[0], "worker %d:", k);
        snprintf(marks[1], sizeof marks[1], "-%d-", k);
        snprintf(marks[2], sizeof marks[2], "bad-%d.", k);
        for (int m = 0; k != own && m < 3; m++)
            if (strstr(text, marks[m]))
                return true;
    }
    return false;
}

/* Occurrences of line in text. */
static int count_of(const char *text, const char *line)
{
    int n = 0;
    for (const char *p = text; (p = strstr(p, line)); p += strlen(line))
        n++;
    return n;
}

static void test_entry_points_at_once(void **state)
{
    (void)state;
    atomic_int process_lines = 0;
    const struct ao_text_sink process = {.write = capture_count, .user = &process_lines};
    ao_text_set_sink(&process);
    static struct worker alone[THREADS], together[THREADS];
    pthread_t ids[THREADS];
    /* Each worker alone, one after another: what it must receive. */
    for (int k = 0; k < THREADS; k++) {
        alone[k] = (struct worker){.index = k};
        assert_int_equal(pthread_create(&ids[k], NULL, work, &alone[k]), 0);
        pthread_join(ids[k], NULL);
    }
    /* All four at once. */
    for (int k = 0; k < THREADS; k++) {
        together[k] = (struct worker){.index = k};
        assert_int_equal(pthread_create(&ids[k], NULL, work, &together[k]), 0);
    }
    for (int k = 0; k < THREADS; k++)
        pthread_join(ids[k], NULL);
    ao_text_set_sink(NULL);
    for (int k = 0; k < THREADS; k++) {
        const struct capture *a = &alone[k].capture, *t = &together[k].capture;
        if (strcmp(a->text, t->text) != 0)
            fail_msg("worker %d alone:\n%s\ntogether:\n%s", k, a->text, t->text);
        assert_int_equal(alone[k].failures, 0);
        assert_int_equal(together[k].failures, 0);
        /* per round: 4 bad scenes and 2 Embree lines are errors; 2 passes are notes */
        assert_int_equal(t->errors, ROUNDS * 6);
        assert_int_equal(t->notes, ROUNDS * 2);
        assert_false(names_another(t->text, k));
        char line[64];
        snprintf(line, sizeof line, "worker %d: pass 2\n", k);
        assert_int_equal(count_of(t->text, line), ROUNDS);
        assert_int_equal(count_of(t->text, "aoview: Embree error "), ROUNDS);
    }
    assert_int_equal(atomic_load(&process_lines), 0);
}

/* The scratch folder with each worker's bad scene file (a line that names the worker's file). */
static int setup(void **state)
{
    (void)state;
    const char *tmp = getenv("TMPDIR");
    snprintf(temp_dir, sizeof temp_dir, "%s/test_text_threads.XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(temp_dir))
        return -1;
    for (int k = 0; k < THREADS; k++) {
        char path[4400];
        snprintf(path, sizeof path, "%s/bad-%d.scene", temp_dir, k);
        FILE *f = fopen(path, "w");
        if (!f)
            return -1;
        fprintf(f, "camera eye 0 1 4 target 0 0.5 0\nsphere center 0 0 0 radius %d\n", -k);
        if (fclose(f) != 0)
            return -1;
    }
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    for (int k = 0; k < THREADS; k++) {
        char path[4400];
        snprintf(path, sizeof path, "%s/bad-%d.scene", temp_dir, k);
        unlink(path);
    }
    return rmdir(temp_dir);
}

int main(void)
{
    const char *root = getenv("AO_SOURCE_ROOT");
    if (!root) {
        fprintf(stderr, "test_text_threads: AO_SOURCE_ROOT is not set (run it through meson test)\n");
        return 77;
    }
    snprintf(source_root, sizeof source_root, "%s", root);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_entry_points_at_once),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
