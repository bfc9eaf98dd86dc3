/* Benchmark: mesh load time (ao_load_model: read, parse, index, normals; a glTF's meshes
 * once each, as scenes load them) of each file named on the
 * command line, runs interleaved round by round so that a busy machine slows every format alike;
 * prints the median of the rounds per file and its ratio to the first file. Asserts nothing.
 * Run: build/tests/bench_load [--rounds N] FIRST.obj OTHER... (docs/formats.md makes the files). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "load/load.h"
#include "mesh.h"
#include "program.h"

enum { MAX_FILES = 16, MAX_ROUNDS = 99 };

int main(int argc, char **argv)
{
    ao_program_init();
    int first = 1, rounds = 5;
    if (argc > 2 && strcmp(argv[1], "--rounds") == 0) {
        rounds = atoi(argv[2]);
        first = 3;
    }
    int files = argc - first;
    if (files < 1 || files > MAX_FILES || rounds < 1 || rounds > MAX_ROUNDS) {
        fprintf(stderr, "usage: bench_load [--rounds 1..%d] MESH... (at most %d)\n", MAX_ROUNDS,
                MAX_FILES);
        return 2;
    }
    static double seconds[MAX_FILES][MAX_ROUNDS];
    size_t triangles[MAX_FILES] = {0};
    for (int r = 0; r < rounds; r++) {
        for (int f = 0; f < files; f++) {
            struct ao_model model;
            struct ao_budget budget = {.limit = UINT64_MAX / 2};
            double start = bench_now();
            if (!ao_load_model(&model, argv[first + f], &budget, AO_MESH_CREASE_DEFAULT))
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
