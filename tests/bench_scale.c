/* Benchmark: a big mesh from file to first image. Writes a bumpy sphere of 10,000,000 triangles
 * and 5,000,002 vertices, without normals (so the loader computes them), into DIR as binary PLY,
 * ASCII PLY, OBJ and GLB; then loads each as a bare mesh (ground added, as `aoview FILE` does) in a
 * process of its own per round, rounds interleaved across the files, and prints the medians of:
 * load (read, parse, normals, the scene's setup), normals alone (recomputed on the loaded mesh),
 * Embree's build (ao_tracer_create), the first pass at 640x480 with 1 sample a pixel (2 threads,
 * cosine, AA), their sum (time to first image), AO Mrays/s over 4 more passes of 4 samples, peak
 * RSS (getrusage) and peak RSS per triangle. Asserts nothing; docs/formats.md has the figures.
 * Run: build/tests/bench_scale [--rounds N] [--reuse] DIR   (writes about 1 GB into DIR; --reuse
 *      keeps files written by an earlier run)
 *      build/tests/bench_scale --one FILE   (one measurement, one line: what each round runs) */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench_util.h"
#include "render.h"
#include "scene.h"
#include "tracer.h"

/* The sphere: RINGS - 1 rings of COLUMNS vertices and two poles, 2 COLUMNS (RINGS - 1) triangles. */
enum { RINGS = 1601, COLUMNS = 3125, VERTICES = (RINGS - 1) * COLUMNS + 2, TRIANGLES = 2 * COLUMNS * (RINGS - 1) };
enum { WIDTH = 640, HEIGHT = 480, RATE_SPPPP = 4, RATE_PASSES = 4, MAX_ROUNDS = 21, FILES = 4, PHASES = 8 };

static const char *const names[FILES] = {"sphere.ply", "sphere_ascii.ply", "sphere.obj", "sphere.glb"};
static const char *const phase_names[PHASES] = {"load s", "normals s", "build s", "first s", "total s",
                                                "Mrays/s", "peak MB", "B/tri"};

/* The vertex index of ring i (1..RINGS-1), column j (any, taken modulo COLUMNS). */
static uint32_t vertex(int i, int j)
{
    return 1 + (uint32_t)(i - 1) * COLUMNS + (uint32_t)(j % COLUMNS);
}

/* The bumpy sphere: positions (VERTICES) and outward-wound triangles (TRIANGLES). */
static void make_sphere(float *p, uint32_t *t)
{
    const double pi = 3.14159265358979323846;
    for (size_t v = 0; v < VERTICES; v++) {
        int i = v == 0 ? 0 : v == VERTICES - 1 ? RINGS : 1 + (int)((v - 1) / COLUMNS);
        int j = v == 0 || v == VERTICES - 1 ? 0 : (int)((v - 1) % COLUMNS);
        double theta = pi * i / RINGS, phi = 2.0 * pi * j / COLUMNS;
        double r = 1.0 + 0.03 * sin(17.0 * theta) * cos(23.0 * phi);
        p[3 * v] = (float)(r * sin(theta) * cos(phi));
        p[3 * v + 1] = (float)(r * cos(theta));
        p[3 * v + 2] = (float)(r * sin(theta) * sin(phi));
    }
    /* One corner on the upper ring (or pole): (upper, lower j+1, lower j); two: (upper j, upper j+1, lower). */
    for (int j = 0; j < COLUMNS; j++, t += 6) {
        uint32_t a[6] = {0, vertex(1, j + 1), vertex(1, j), vertex(RINGS - 1, j), vertex(RINGS - 1, j + 1),
                         VERTICES - 1};
        memcpy(t, a, sizeof a);
    }
    for (int i = 1; i + 1 < RINGS; i++)
        for (int j = 0; j < COLUMNS; j++, t += 6) {
            uint32_t a[6] = {vertex(i, j), vertex(i + 1, j + 1), vertex(i + 1, j),
                             vertex(i, j), vertex(i, j + 1), vertex(i + 1, j + 1)};
            memcpy(t, a, sizeof a);
        }
}

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

/* Writes the four files into dir. */
static void write_files(const char *dir)
{
    float *p = malloc((size_t)VERTICES * 3 * sizeof *p);
    uint32_t *t = malloc((size_t)TRIANGLES * 3 * sizeof *t);
    if (!p || !t)
        exit(1);
    make_sphere(p, t);
    FILE *ply = create(dir, names[0]), *ascii = create(dir, names[1]), *obj = create(dir, names[2]);
    FILE *glb = create(dir, names[3]);
    for (int k = 0; k < 2; k++)
        fprintf(k ? ascii : ply,
                "ply\nformat %s 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
                "element face %d\nproperty list uchar int vertex_indices\nend_header\n",
                k ? "ascii" : "binary_little_endian", VERTICES, TRIANGLES);
    fwrite(p, sizeof *p, (size_t)VERTICES * 3, ply);
    for (size_t v = 0; v < VERTICES; v++) {
        char line[80];
        int n = snprintf(line, sizeof line, "%.9g %.9g %.9g\n", p[3 * v], p[3 * v + 1], p[3 * v + 2]);
        fwrite(line, 1, (size_t)n, ascii);
        fputs("v ", obj);
        fwrite(line, 1, (size_t)n, obj);
    }
    for (size_t k = 0; k < TRIANGLES; k++) {
        const uint32_t *c = t + 3 * k;
        unsigned char three = 3;
        fwrite(&three, 1, 1, ply);
        fwrite(c, sizeof *c, 3, ply);
        fprintf(ascii, "3 %u %u %u\n", c[0], c[1], c[2]);
        fprintf(obj, "f %u %u %u\n", c[0] + 1, c[1] + 1, c[2] + 1);
    }
    /* GLB: a JSON chunk (padded with spaces) and a BIN chunk of positions, then indices. */
    uint32_t positions = VERTICES * 12u, indices = TRIANGLES * 12u;
    char json[1024];
    int n = snprintf(json, sizeof json,
                     "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
                     "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
                     "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\","
                     "\"min\":[-1.03,-1.03,-1.03],\"max\":[1.03,1.03,1.03]},"
                     "{\"bufferView\":1,\"componentType\":5125,\"count\":%d,\"type\":\"SCALAR\"}],"
                     "\"bufferViews\":[{\"buffer\":0,\"byteLength\":%u},{\"buffer\":0,\"byteOffset\":%u,\"byteLength\":%u}],"
                     "\"buffers\":[{\"byteLength\":%u}]}",
                     VERTICES, 3 * TRIANGLES, positions, positions, indices, positions + indices);
    while (n % 4)
        json[n++] = ' ';
    uint32_t header[5] = {0x46546C67u, 2, 12 + 8 + (uint32_t)n + 8 + positions + indices, (uint32_t)n, 0x4E4F534Au};
    uint32_t bin[2] = {positions + indices, 0x004E4942u};
    fwrite(header, sizeof header, 1, glb);
    fwrite(json, 1, (size_t)n, glb);
    fwrite(bin, sizeof bin, 1, glb);
    fwrite(p, sizeof *p, (size_t)VERTICES * 3, glb);
    fwrite(t, sizeof *t, (size_t)TRIANGLES * 3, glb);
    close_file(ply), close_file(ascii), close_file(obj), close_file(glb);
    free(p);
    free(t);
}

/* Renders passes of spppp samples until target_spp; the last frame's facts. */
static struct ao_frame_info render(const struct ao_scene *scene, const struct ao_tracer *tracer, int spppp,
                                   uint32_t target_spp)
{
    struct ao_render_config config = {.scene = scene, .tracer = tracer, .threads = 2, .seed = 1,
                                      .target_spp = target_spp, .ao_distance = scene->ao_distance};
    struct ao_settings settings = {.width = WIDTH, .height = HEIGHT, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .spppp = spppp, .camera = scene->camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    if (!r || !ao_render_wait(r))
        exit(1);
    struct ao_frame_info info = ao_render_take_frame(r)->info;
    ao_render_destroy(r);
    return info;
}

/* One measurement of path in this process; prints the PHASES figures on one line. */
static int measure(const char *path)
{
    struct ao_scene scene;
    struct ao_scene_options options = {.budget = (uint64_t)1 << 40, .ground = true};
    double start = bench_now();
    if (!ao_scene_load_with(&scene, path, &options))
        return 1;
    double loaded = bench_now();
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    if (!tracer)
        return 1;
    double built = bench_now();
    render(&scene, tracer, 1, 1);
    double first = bench_now();
    struct ao_frame_info info = render(&scene, tracer, RATE_SPPPP, RATE_SPPPP * RATE_PASSES);
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

/* Runs `--one path` in a child process (this program, exec'd afresh) and reads its figures. */
static void run_child(const char *path, double out[PHASES])
{
    int fds[2];
    if (pipe(fds) != 0)
        exit(1);
    pid_t pid = fork();
    if (pid == 0) {
        dup2(fds[1], 1);
        close(fds[0]);
        close(fds[1]);
        execl("/proc/self/exe", "bench_scale", "--one", path, (char *)NULL);
        _exit(127);
    }
    close(fds[1]);
    FILE *in = fdopen(fds[0], "r");
    int status, got = 0;
    for (int k = 0; in && k < PHASES; k++)
        got += fscanf(in, "%lf", &out[k]) == 1;
    if (in)
        fclose(in);
    if (pid < 0 || waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0 ||
        got != PHASES) {
        fprintf(stderr, "bench_scale: measuring %s failed\n", path);
        exit(1);
    }
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--one") == 0)
        return measure(argv[2]);
    int first = 1, rounds = 5;
    bool reuse = false;
    for (; first < argc - 1; first++) {
        if (strcmp(argv[first], "--rounds") == 0 && first + 2 < argc)
            rounds = atoi(argv[++first]);
        else if (strcmp(argv[first], "--reuse") == 0)
            reuse = true;
        else
            break;
    }
    if (first != argc - 1 || rounds < 1 || rounds > MAX_ROUNDS) {
        fprintf(stderr, "usage: bench_scale [--rounds 1..%d] [--reuse] DIR | bench_scale --one FILE\n", MAX_ROUNDS);
        return 2;
    }
    const char *dir = argv[first];
    if (!reuse) {
        double start = bench_now();
        write_files(dir);
        printf("wrote %d triangles, %d vertices in %.1f s\n", TRIANGLES, VERTICES, bench_now() - start);
    }
    static double figures[FILES][PHASES][MAX_ROUNDS];
    for (int r = 0; r < rounds; r++)
        for (int f = 0; f < FILES; f++) {
            char path[4096];
            double one[PHASES];
            snprintf(path, sizeof path, "%s/%s", dir, names[f]);
            run_child(path, one);
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
