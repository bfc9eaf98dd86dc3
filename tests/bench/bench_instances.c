/* Benchmark: scenes of placed meshes. For each scene, medians of the rounds of: load time, Embree
 * build time, the first 640x480 pass (1 sample a pixel), so the time to the first image; what
 * Embree holds; bytes a unique triangle (peak RSS over unique triangles: one scene per process
 * for that figure); and AO rays a second (512x512, cosine, AA, 2 threads, 16 samples a pixel a
 * pass, 8 passes after one to warm up). Asserts nothing; docs/performance.md has the figures.
 *   bench_instances --generate DIR      writes DIR/once.glb (a 1M-triangle bumpy sphere placed
 *                                       once), DIR/thousand.glb (the same placed 1000 times, framed
 *                                       on the whole) and once.scene, thousand.scene (the same two
 *                                       seen from beside the first sphere)
 *   bench_instances [--rounds N] [--instancing auto|always|never] [--ao-distance D] SCENE...
 *                                       measures (--ao-distance: the occlusion range, default the
 *                                       scene's) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/resource.h>

#include "bench_meshes.h"
#include "bench_util.h"
#include "program.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

enum { SIZE = 512, SPPPP = 16, PASSES = 8, MAX_ROUNDS = 21, MAX_FILES = 8, SPHERE_RINGS = 500 };

/* Mrays/s (eye and AO rays over the render time) of PASSES passes after a first one. */
static double rate(const struct ao_scene *scene, const struct ao_tracer *tracer)
{
    struct ao_frame_info info = bench_render(scene, tracer, SIZE, SIZE, SPPPP, SPPPP * (PASSES + 1));
    return (double)(info.eye_rays + info.shadow_rays) / info.seconds / 1e6;
}

/* Seconds from starting a 640x480 render to its first pass of one sample a pixel. */
static double first_pass(const struct ao_scene *scene, const struct ao_tracer *tracer)
{
    double start = bench_now();
    bench_render(scene, tracer, 640, 480, 1, 1);
    return bench_now() - start;
}

/* Peak resident memory of the process so far, bytes. */
static double peak_rss(void)
{
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss * 1024.0;
}

/* Writes a scene file placing once.glb `copies` times as the GLB does (spacing 3, 10 to a row),
 * seen from beside the first, on a ground quad: the same view for 1 and 1000 copies. */
static bool write_scene(const char *path, int copies)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return false;
    fprintf(f, "camera eye -2.2 1.2 -3 target 0 0 0 up 0 1 0 fov 40\n"
               "quad corner -20 -1.1 -20 edge1 0 0 60 edge2 60 0 0 albedo 0.5\n");
    for (int k = 0; k < copies; k++)
        fprintf(f, "mesh once.glb albedo 0.8 translate %d %d %d\n", 3 * (k % 10), 3 * (k / 100), 3 * (k / 10 % 10));
    return fclose(f) == 0;
}

/* Writes the generated scenes into dir: the sphere placed once and 1000 times, as GLB files
 * (framed on their boxes) and as scene files (one view). */
static int generate(const char *dir)
{
    struct bench_mesh sphere;
    bench_bumpy_sphere(&sphere, SPHERE_RINGS);
    char once[512], thousand[512], once_scene[512], thousand_scene[512];
    snprintf(once, sizeof once, "%s/once.glb", dir);
    snprintf(thousand, sizeof thousand, "%s/thousand.glb", dir);
    snprintf(once_scene, sizeof once_scene, "%s/once.scene", dir);
    snprintf(thousand_scene, sizeof thousand_scene, "%s/thousand.scene", dir);
    bool ok = bench_write_placed_glb(once, &sphere, 1, 1) && bench_write_placed_glb(thousand, &sphere, 1000, 10) &&
              write_scene(once_scene, 1) && write_scene(thousand_scene, 1000);
    printf("%s/{once,thousand}.{glb,scene}: a %zu-triangle sphere placed once and 1000 times\n", dir,
           sphere.triangle_count);
    bench_mesh_free(&sphere);
    if (!ok)
        fprintf(stderr, "bench_instances: could not write into %s\n", dir);
    return ok ? 0 : 1;
}

int main(int argc, char **argv)
{
    ao_program_init();
    if (argc == 3 && strcmp(argv[1], "--generate") == 0)
        return generate(argv[2]);
    int first = 1, rounds = 5;
    double ao_distance = 0.0;   /* 0: the scene's */
    enum ao_instancing mode = AO_INSTANCING_AUTO;
    while (first + 1 < argc && strncmp(argv[first], "--", 2) == 0) {
        if (strcmp(argv[first], "--rounds") == 0)
            rounds = atoi(argv[first + 1]);
        else if (strcmp(argv[first], "--instancing") == 0)
            mode = strcmp(argv[first + 1], "always") == 0  ? AO_INSTANCING_ALWAYS
                   : strcmp(argv[first + 1], "never") == 0 ? AO_INSTANCING_NEVER
                                                            : AO_INSTANCING_AUTO;
        else if (strcmp(argv[first], "--ao-distance") == 0)
            ao_distance = atof(argv[first + 1]);
        else
            break;
        first += 2;
    }
    int files = argc - first;
    if (files < 1 || files > MAX_FILES || rounds < 1 || rounds > MAX_ROUNDS || !(ao_distance >= 0.0)) {
        fprintf(stderr, "usage: bench_instances --generate DIR | [--rounds 1..%d] [--instancing auto|always|never] "
                        "[--ao-distance D] SCENE... (at most %d)\n", MAX_ROUNDS, MAX_FILES);
        return 2;
    }
    static double load[MAX_FILES][MAX_ROUNDS], build[MAX_FILES][MAX_ROUNDS], pass[MAX_FILES][MAX_ROUNDS],
        mrays[MAX_FILES][MAX_ROUNDS], embree[MAX_FILES], embree_peak[MAX_FILES], rss[MAX_FILES];
    static size_t placed[MAX_FILES], unique[MAX_FILES], instances[MAX_FILES];
    for (int r = 0; r < rounds; r++)
        for (int f = 0; f < files; f++) {
            struct ao_scene scene;
            struct ao_scene_options options = {.budget = (uint64_t)1 << 40, .instancing = mode};
            double start = bench_now();
            if (!ao_scene_load(&scene, argv[first + f], &options))
                return 1;
            if (ao_distance > 0.0)
                scene.ao_distance = (float)ao_distance;
            double loaded = bench_now();
            struct ao_tracer *tracer = ao_tracer_create_with(&scene, AO_BACKEND_EMBREE);
            if (!tracer)
                return 1;
            double built = bench_now();
            struct ao_tracer_stats stats;
            ao_tracer_describe(tracer, &stats);
            load[f][r] = loaded - start;
            build[f][r] = built - loaded;
            pass[f][r] = first_pass(&scene, tracer);
            if (r == 0)
                rss[f] = peak_rss();
            mrays[f][r] = rate(&scene, tracer);
            embree[f] = (double)stats.embree_bytes;
            embree_peak[f] = (double)stats.embree_peak_bytes;
            placed[f] = scene.triangle_count;
            unique[f] = 0;
            for (size_t m = 0; m < scene.mesh_count; m++)
                unique[f] += scene.meshes[m].triangle_count;
            instances[f] = stats.instances;
            ao_tracer_destroy(tracer);
            ao_scene_finish(&scene);
        }
    printf("%-28s %13s %10s %9s %7s %7s %7s %7s %10s %8s %9s %8s %8s\n", "scene", "placed tris", "unique", "instances",
           "load s", "build s", "pass s", "first s", "Embree MB", "at most", "peak MB", "B/tri", "Mrays/s");
    for (int f = 0; f < files; f++) {
        double l = bench_median(load[f], rounds), b = bench_median(build[f], rounds), p = bench_median(pass[f], rounds);
        printf("%-28s %13zu %10zu %9zu %7.3f %7.3f %7.3f %7.3f %10.1f %8.1f %9.1f %8.1f %8.2f\n", argv[first + f], placed[f],
               unique[f], instances[f], l, b, p, l + b + p, embree[f] / 1e6, embree_peak[f] / 1e6, rss[f] / 1e6,
               rss[f] / (double)unique[f], bench_median(mrays[f], rounds));
    }
    return 0;
}
