/* Benchmark: a big mesh from file to first image. Writes a bumpy sphere (bench_meshes.h) of
 * 9,991,920 triangles and 4,995,962 vertices, without normals (so the loader computes them; the
 * GLB's are flat, as glTF says, and computed no more), into
 * DIR as binary PLY, ASCII PLY, OBJ and GLB; then loads each as a bare mesh (ground added, as
 * `aoview FILE` does) in a process of its own per round, rounds interleaved across the files, and
 * prints the medians of: load (read, parse, normals, the scene's setup), normals alone (recomputed
 * on the loaded mesh), Embree's build (ao_tracer_create), the first pass at 640x480 with 1 sample a
 * pixel (2 threads, cosine, AA), their sum (time to first image), AO Mrays/s over 4 more passes of
 * 4 samples, peak RSS (getrusage) and peak RSS per triangle. Asserts nothing; docs/formats.md has
 * the figures.
 * With --builds, the binary PLY alone under each build, interleaved per round: `default` (what
 * headless aoview does with its defaults under the machine's default budget: where the budget holds
 * both BVHs a big scene's one-pass run, the first image, on LOW alone, a longer one, the time to 1 %,
 * on MEDIUM alone), `progressive` (the window's way: LOW first, MEDIUM built beside it and switched
 * to between passes), then medium, compact and low alone; it prints the medians of first image,
 * Mrays/s (after the first image, on the same tracer) and peak RSS as above, and of the time to 1 %
 * estimated error at GOAL_WIDTH x GOAL_HEIGHT with aoview's defaults (Sobol numbers, auto passes,
 * adaptive sampling), from the start of loading, in a process of its own.
 * Run: build/tests/bench_scale [--rounds N] [--reuse] [--bvh B] [--builds] DIR   (writes about 1 GB
 *      into DIR; --reuse keeps files written by an earlier run; --bvh as aoview's, low-compact,
 *      progressive (auto under a budget that holds everything, the window's way) or default
 *      (headless aoview's defaults);
 *      default medium)
 *      build/tests/bench_scale [--bvh B] [--goal [--error E]] --one FILE   (one measurement, one line:
 *      what each round runs; --goal: the seconds to 1 % alone, or to E: a relative error, as 0.03) */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench_meshes.h"
#include "budget.h"
#include "bench_util.h"
#include "program.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

/* The sphere: bench_bumpy_sphere of RINGS rings, 4 RINGS (RINGS - 1) = 9,991,920 triangles. */
enum { RINGS = 1581 };
enum { WIDTH = 640, HEIGHT = 480, RATE_SPPPP = 4, RATE_PASSES = 4, MAX_ROUNDS = 21, FILES = 4, PHASES = 8 };
enum { GOAL_WIDTH = 1280, GOAL_HEIGHT = 960, GOAL_SPP = 100000 };

static const char *const names[FILES] = {"sphere.ply", "sphere_ascii.ply", "sphere.obj", "sphere.glb"};
/* --bvh's names, in modes.h's order, then PROGRESSIVE (AUTO under a budget that holds everything:
 * LOW first where the scene is big) and DEFAULT (headless aoview's defaults: AUTO under the
 * machine's default budget, progressive only for a one-pass run), and the one asked for. */
enum { PROGRESSIVE = AO_BVH_LOW_COMPACT + 1, DEFAULT, BUILDS = 5 };
static const char *const bvh_names[] = {"auto", "medium", "compact", "low", "low-compact", "progressive", "default"};
static int bvh = AO_BVH_MEDIUM;
/* The estimated error --goal runs to: --error's, or 1 %. */
static double goal_error = 0.01;
static const int builds[BUILDS] = {DEFAULT, PROGRESSIVE, AO_BVH_MEDIUM, AO_BVH_COMPACT, AO_BVH_LOW};

static const char *const phase_names[PHASES] = {"load s", "normals s", "build s", "first s", "total s",
                                                "Mrays/s", "peak MB", "B/tri"};

/* fopen for writing with a big buffer, or exit. */
static FILE *create(const char *dir, const char *name)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f || setvbuf(f, NULL, _IOFBF, 1 << 22) != 0) {
        fprintf(stderr, "bench_scale: cannot write %s: %s\n", path, strerror(errno));
        exit(1);
    }
    return f;
}

/* fclose, or exit. */
static void close_file(FILE *f)
{
    if (ferror(f) | fclose(f)) {
        fprintf(stderr, "bench_scale: write error\n");
        exit(1);
    }
}

/* Writes the four files of m into dir. */
static void write_files(const char *dir, const struct bench_mesh *m)
{
    const float *p = m->positions;
    FILE *ply = create(dir, names[0]), *ascii = create(dir, names[1]), *obj = create(dir, names[2]);
    for (int k = 0; k < 2; k++)
        fprintf(k ? ascii : ply,
                "ply\nformat %s 1.0\nelement vertex %zu\nproperty float x\nproperty float y\nproperty float z\n"
                "element face %zu\nproperty list uchar int vertex_indices\nend_header\n",
                k ? "ascii" : "binary_little_endian", m->vertex_count, m->triangle_count);
    fwrite(p, sizeof *p, m->vertex_count * 3, ply);
    for (size_t v = 0; v < m->vertex_count; v++) {
        char line[80];
        int n = snprintf(line, sizeof line, "%.9g %.9g %.9g\n", p[3 * v], p[3 * v + 1], p[3 * v + 2]);
        fwrite(line, 1, (size_t)n, ascii);
        fputs("v ", obj);
        fwrite(line, 1, (size_t)n, obj);
    }
    for (size_t k = 0; k < m->triangle_count; k++) {
        const uint32_t *c = m->indices + 3 * k;
        unsigned char three = 3;
        fwrite(&three, 1, 1, ply);
        fwrite(c, sizeof *c, 3, ply);
        fprintf(ascii, "3 %u %u %u\n", c[0], c[1], c[2]);
        fprintf(obj, "f %u %u %u\n", c[0] + 1, c[1] + 1, c[2] + 1);
    }
    close_file(ply), close_file(ascii), close_file(obj);
    char glb[4096];
    snprintf(glb, sizeof glb, "%s/%s", dir, names[3]);
    if (!bench_write_placed_glb(glb, m, 1, 1)) {
        fprintf(stderr, "bench_scale: cannot write %s\n", glb);
        exit(1);
    }
}

/* One measurement of path in this process; prints the PHASES figures on one line, or with `goal`
 * the seconds from the start of loading to goal_error. */
static int measure(const char *path, bool goal)
{
    struct ao_scene scene;
    bool automatic = bvh == PROGRESSIVE || bvh == DEFAULT;
    struct ao_scene_options options = {.budget = bvh == DEFAULT ? 0 : (uint64_t)1 << 40,
                                       .bvh = automatic ? AO_BVH_AUTO : (enum ao_bvh)bvh};
    double start = bench_now();
    if (!ao_scene_load(&scene, path, &options))
        return 1;
    double loaded = bench_now();
    bool progressive = (bvh == PROGRESSIVE || (bvh == DEFAULT && !goal)) && scene.progressive;
    struct ao_tracer *tracer = progressive ? ao_tracer_create_progressive(&scene) : ao_tracer_create(&scene);
    if (!tracer)
        return 1;
    struct ao_tracer *upgrade = progressive ? tracer : NULL;
    double built = bench_now();
    if (goal) {
        bench_render_until(&scene, tracer, upgrade, GOAL_WIDTH, GOAL_HEIGHT, 0, true, AO_SEQUENCE_SOBOL, GOAL_SPP,
                           goal_error);
        printf("%.6f\n", bench_now() - start);
        ao_tracer_destroy(tracer);
        ao_scene_finish(&scene);
        return 0;
    }
    bench_render_until(&scene, tracer, upgrade, WIDTH, HEIGHT, 1, false, AO_SEQUENCE_SOBOL, 1, 0.0);
    double first = bench_now();
    struct ao_frame_info info = bench_render_until(&scene, tracer, upgrade, WIDTH, HEIGHT, RATE_SPPPP, false,
                                                   AO_SEQUENCE_SOBOL, RATE_SPPPP * RATE_PASSES, 0.0);
    struct ao_mesh *big = &scene.meshes[0];
    for (size_t m = 1; m < scene.mesh_count; m++)
        big = scene.meshes[m].triangle_count > big->triangle_count ? &scene.meshes[m] : big;
    double before = bench_now();
    if (!ao_mesh_compute_normals(big))
        return 1;
    double normals = bench_now() - before;
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    double peak = (double)usage.ru_maxrss * 1024.0;
    printf("%.6f %.6f %.6f %.6f %.6f %.3f %.1f %.1f\n", loaded - start, normals, built - loaded, first - built,
           first - start, (double)(info.eye_rays + info.shadow_rays) / info.seconds / 1e6, peak / 1e6,
           peak / (double)big->triangle_count);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
    return 0;
}

/* Runs `--one path` (with --goal: `count` is 1) in a child process (this program, exec'd afresh)
 * and reads its `count` figures. */
static void run_child(const char *path, double *out, int count)
{
    int fds[2];
    if (pipe(fds) != 0)
        exit(1);
    pid_t pid = fork();
    if (pid == 0) {
        dup2(fds[1], 1);
        close(fds[0]);
        close(fds[1]);
        if (count == 1)
            execl("/proc/self/exe", "bench_scale", "--bvh", bvh_names[bvh], "--goal", "--one", path, (char *)NULL);
        else
            execl("/proc/self/exe", "bench_scale", "--bvh", bvh_names[bvh], "--one", path, (char *)NULL);
        _exit(127);
    }
    close(fds[1]);
    FILE *in = fdopen(fds[0], "r");
    int status, got = 0;
    for (int k = 0; in && k < count; k++)
        got += fscanf(in, "%lf", &out[k]) == 1;
    if (in)
        fclose(in);
    if (pid < 0 || waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0 ||
        got != count) {
        fprintf(stderr, "bench_scale: measuring %s failed\n", path);
        exit(1);
    }
}

/* The index of --bvh's name, or -1. */
static int bvh_of(const char *name)
{
    for (int k = 0; k < (int)(sizeof bvh_names / sizeof bvh_names[0]); k++)
        if (strcmp(name, bvh_names[k]) == 0)
            return k;
    return -1;
}

/* --builds: the binary PLY under each build, interleaved per round; prints the medians. */
static int compare_builds(const char *dir, int rounds)
{
    static double figures[BUILDS][PHASES + 1][MAX_ROUNDS];
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, names[0]);
    for (int r = 0; r < rounds; r++)
        for (int b = 0; b < BUILDS; b++) {
            double one[PHASES + 1];
            bvh = builds[b];
            run_child(path, one, PHASES);
            run_child(path, one + PHASES, 1);
            for (int k = 0; k <= PHASES; k++)
                figures[b][k][r] = one[k];
        }
    printf("%s, medians of %d rounds, one process per build and figure per round; to 1 %%: %dx%d from the "
           "start of loading; the default budget %.1f GiB\n%-12s %10s %10s %10s %10s %10s\n", names[0], rounds,
           GOAL_WIDTH, GOAL_HEIGHT, (double)ao_budget_default() / (1 << 30), "build",
           "build s", "first s", "Mrays/s", "peak MB", "to 1 % s");
    static const int shown[] = {2, 4, 5, 6, PHASES};
    for (int b = 0; b < BUILDS; b++) {
        printf("%-12s", bvh_names[builds[b]]);
        for (int k = 0; k < 5; k++)
            printf(" %10.3f", bench_median(figures[b][shown[k]], rounds));
        printf("\n");
    }
    return 0;
}

int main(int argc, char **argv)
{
    ao_program_init();
    int first = 1, rounds = 5;
    bool reuse = false, one = false, goal = false, by_build = false;
    for (; first < argc - 1; first++) {
        if (strcmp(argv[first], "--rounds") == 0 && first + 2 < argc)
            rounds = atoi(argv[++first]);
        else if (strcmp(argv[first], "--reuse") == 0)
            reuse = true;
        else if (strcmp(argv[first], "--bvh") == 0 && first + 2 < argc)
            bvh = bvh_of(argv[++first]);
        else if (strcmp(argv[first], "--one") == 0)
            one = true;
        else if (strcmp(argv[first], "--goal") == 0)
            goal = true;
        else if (strcmp(argv[first], "--error") == 0 && first + 2 < argc)
            goal_error = atof(argv[++first]);
        else if (strcmp(argv[first], "--builds") == 0)
            by_build = true;
        else
            break;
    }
    if (first != argc - 1 || rounds < 1 || rounds > MAX_ROUNDS || bvh < 0 || !(goal_error > 0.0)) {
        fprintf(stderr, "usage: bench_scale [--rounds 1..%d] [--reuse] [--bvh auto|medium|compact|low|low-compact|"
                        "progressive|default] [--builds] DIR | bench_scale [--bvh B] [--goal [--error E]] --one FILE\n",
                MAX_ROUNDS);
        return 2;
    }
    if (one)
        return measure(argv[first], goal);
    const char *dir = argv[first];
    if (!reuse) {
        double start = bench_now();
        struct bench_mesh sphere;
        bench_bumpy_sphere(&sphere, RINGS);
        write_files(dir, &sphere);
        printf("wrote %zu triangles, %zu vertices in %.1f s\n", sphere.triangle_count, sphere.vertex_count,
               bench_now() - start);
        bench_mesh_free(&sphere);
    }
    if (by_build)
        return compare_builds(dir, rounds);
    static double figures[FILES][PHASES][MAX_ROUNDS];
    for (int r = 0; r < rounds; r++)
        for (int f = 0; f < FILES; f++) {
            char path[4096];
            double one[PHASES];
            snprintf(path, sizeof path, "%s/%s", dir, names[f]);
            run_child(path, one, PHASES);
            for (int k = 0; k < PHASES; k++)
                figures[f][k][r] = one[k];
        }
    printf("medians of %d rounds, one process per file per round\n%-18s", rounds, "file");
    for (int k = 0; k < PHASES; k++)
        printf(" %10s", phase_names[k]);
    printf("\n");
    for (int f = 0; f < FILES; f++) {
        printf("%-18s", names[f]);
        for (int k = 0; k < PHASES; k++)
            printf(" %10.3f", bench_median(figures[f][k], rounds));
        printf("\n");
    }
    return 0;
}
