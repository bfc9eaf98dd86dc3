/* The cost of aoview-mpi's merge on this machine: MPI_Allreduce (in place, float sum, as
 * src/cluster.c does) and MPI_Reduce of buffers from 64 KB to 64 MB, median of 15 after a warm-up,
 * printed by rank 0 as a markdown table of milliseconds and GB/s (buffer bytes / time).
 * Run: mpirun -np N build/tests/bench_mpi_merge (docs/mpi.md). */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>

enum { RUNS = 15 };

static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    int rank, size;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    size_t most = (size_t)64 << 20;
    float *buffer = calloc(most / sizeof(float), sizeof(float));
    if (!buffer)
        MPI_Abort(MPI_COMM_WORLD, 1);
    if (rank == 0)
        printf("| bytes | ranks | Allreduce ms | Allreduce GB/s | Reduce ms | Reduce GB/s |\n|---|---|---|---|---|---|\n");
    for (size_t bytes = (size_t)64 << 10; bytes <= most; bytes *= 4) {
        int count = (int)(bytes / sizeof(float));
        double ms[2][RUNS];
        for (int op = 0; op < 2; op++)
            for (int k = -1; k < RUNS; k++) {
                MPI_Barrier(MPI_COMM_WORLD);
                double start = MPI_Wtime();
                if (op == 0)
                    MPI_Allreduce(MPI_IN_PLACE, buffer, count, MPI_FLOAT, MPI_SUM, MPI_COMM_WORLD);
                else
                    MPI_Reduce(rank == 0 ? MPI_IN_PLACE : buffer, buffer, count, MPI_FLOAT, MPI_SUM, 0, MPI_COMM_WORLD);
                double t = 1e3 * (MPI_Wtime() - start);
                MPI_Allreduce(MPI_IN_PLACE, &t, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
                if (k >= 0)
                    ms[op][k] = t;
            }
        qsort(ms[0], RUNS, sizeof(double), by_value);
        qsort(ms[1], RUNS, sizeof(double), by_value);
        if (rank == 0)
            printf("| %zu | %d | %.3f | %.2f | %.3f | %.2f |\n", bytes, size, ms[0][RUNS / 2],
                   (double)bytes / ms[0][RUNS / 2] / 1e6, ms[1][RUNS / 2], (double)bytes / ms[1][RUNS / 2] / 1e6);
    }
    free(buffer);
    MPI_Finalize();
    return 0;
}
