/* Benchmark: mesh load time (ao_load_model: read, parse, index, normals; a glTF's meshes
 * once each, as scenes load them) of each file named on the
 * command line, runs interleaved round by round so that a busy machine slows every format alike;
 * prints the median of the rounds per file and its ratio to the first file. With --crease, the
 * crease pass alone instead: each file loaded once, then per round the normals it lacks made
 * afresh (ao_mesh_complete_normals on a copy of its mesh without normals) at the default crease
 * angle and at 180 (no crease pass), and their difference: what the crease pass costs. --angle DEG
 * loads at that crease angle instead of the default (under callgrind, the instructions of loads at
 * 40 and 180 differ by the crease pass's). Asserts nothing.
 * Run: build/tests/bench_load [--rounds N] [--angle DEG] [--crease] FIRST.obj OTHER... (docs/formats.md
 *      makes the files; tests/tools/fan.py the fan of random planes). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "load.h"
#include "mesh.h"
#include "program.h"

enum { MAX_FILES = 16, MAX_ROUNDS = 99 };

/* A copy of src's positions and triangles, without normals; exits when memory is short. */
static void copy_without_normals(struct ao_mesh *dst, const struct ao_mesh *src)
{
    *dst = (struct ao_mesh){.vertex_count = src->vertex_count, .triangle_count = src->triangle_count};
    dst->positions = malloc((src->vertex_count + 1) * sizeof *dst->positions);
    dst->indices = malloc((3 * src->triangle_count + 1) * sizeof *dst->indices);
    if (!dst->positions || !dst->indices)
        exit(1);
    memcpy(dst->positions, src->positions, src->vertex_count * sizeof *dst->positions);
    memcpy(dst->indices, src->indices, 3 * src->triangle_count * sizeof *dst->indices);
}

/* The seconds ao_mesh_complete_normals takes on a copy of mesh at crease degrees. */
static double time_normals(const struct ao_mesh *mesh, const char *path, double crease)
{
    struct ao_mesh copy;
    struct ao_budget budget = {.limit = UINT64_MAX / 2};
    copy_without_normals(&copy, mesh);
    double start = bench_now();
    if (!ao_mesh_complete_normals(&copy, path, crease, &budget))
        exit(1);
    double seconds = bench_now() - start;
    ao_mesh_finish(&copy);
    return seconds;
}

/* --crease: per file, the medians of the normals made at the default crease angle and at 180, and
 * of their difference per round. */
static int crease_pass(char **paths, int files, int rounds)
{
    static double creased[MAX_FILES][MAX_ROUNDS], smooth[MAX_FILES][MAX_ROUNDS], pass[MAX_FILES][MAX_ROUNDS];
    static struct ao_model models[MAX_FILES];
    for (int f = 0; f < files; f++) {
        struct ao_budget budget = {.limit = UINT64_MAX / 2};
        if (!ao_load_model(&models[f], paths[f], &budget, 180.0))
            return 1;
    }
    for (int r = 0; r < rounds; r++)
        for (int f = 0; f < files; f++) {
            creased[f][r] = time_normals(&models[f].meshes[0], paths[f], AO_MESH_CREASE_DEFAULT);
            smooth[f][r] = time_normals(&models[f].meshes[0], paths[f], 180.0);
            pass[f][r] = creased[f][r] - smooth[f][r];
        }
    printf("%-40s %12s %12s %12s %12s\n", "file", "triangles", "crease s", "180 s", "pass s");
    for (int f = 0; f < files; f++) {
        printf("%-40s %12zu %12.3f %12.3f %12.3f\n", paths[f], models[f].meshes[0].triangle_count,
               bench_median(creased[f], rounds), bench_median(smooth[f], rounds), bench_median(pass[f], rounds));
        ao_model_finish(&models[f]);
    }
    return 0;
}

int main(int argc, char **argv)
{
    ao_program_init();
    int first = 1, rounds = 5;
    double angle = AO_MESH_CREASE_DEFAULT;
    bool crease = false;
    for (; first < argc; first++) {
        if (strcmp(argv[first], "--rounds") == 0 && first + 1 < argc)
            rounds = atoi(argv[++first]);
        else if (strcmp(argv[first], "--angle") == 0 && first + 1 < argc)
            angle = atof(argv[++first]);
        else if (strcmp(argv[first], "--crease") == 0)
            crease = true;
        else
            break;
    }
    int files = argc - first;
    if (files < 1 || files > MAX_FILES || rounds < 1 || rounds > MAX_ROUNDS) {
        fprintf(stderr, "usage: bench_load [--rounds 1..%d] [--angle DEG] [--crease] MESH... (at most %d)\n", MAX_ROUNDS,
                MAX_FILES);
        return 2;
    }
    if (crease)
        return crease_pass(argv + first, files, rounds);
    static double seconds[MAX_FILES][MAX_ROUNDS];
    size_t triangles[MAX_FILES] = {0};
    for (int r = 0; r < rounds; r++) {
        for (int f = 0; f < files; f++) {
            struct ao_model model;
            struct ao_budget budget = {.limit = UINT64_MAX / 2};
            double start = bench_now();
            if (!ao_load_model(&model, argv[first + f], &budget, angle))
                return 1;
            seconds[f][r] = bench_now() - start;
            triangles[f] = 0;
            for (size_t m = 0; m < model.mesh_count; m++)
                triangles[f] += model.meshes[m].triangle_count;
            ao_model_finish(&model);
        }
    }
    double base = 0.0;
    printf("%-40s %12s %10s %8s\n", "file", "triangles", "median s", "ratio");
    for (int f = 0; f < files; f++) {
        double median = bench_median(seconds[f], rounds);
        if (f == 0)
            base = median;
        printf("%-40s %12zu %10.3f %8.2f\n", argv[first + f], triangles[f], median, median / base);
    }
    return 0;
}
