/* What aoview-mpi's passes cost in MPI on this machine: the latency of the collectives every pass
 * makes (an allreduce of the 1.8 kB tally, one of 8 bytes for the next pass's pixels with adaptive
 * sampling, the 88-byte broadcast of the next pass's start), and an image gather's bandwidth
 * (every rank's share of a 640x480 and a 3840x2160 image, 12 bytes a pixel, into rank 0); medians
 * of RUNS after a warm-up, printed by rank 0 as markdown rows: microseconds, and ms and GB/s.
 * Run: mpirun -np N build/tests/bench_mpi_pass (docs/mpi.md). */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>

enum { RUNS = 201, GATHER_RUNS = 15, TALLY_BYTES = 1800, COUNT_BYTES = 8, START_BYTES = 88 };

static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median over `runs` of the slowest rank's seconds for one call of `what` (0: the tally's
 * allreduce, 1: the count's, 2: the start's broadcast, 3: a gather of `bytes` from each rank). */
static double median(int what, int runs, char *buffer, char *all, int bytes)
{
    double *t = malloc((size_t)runs * sizeof *t);
    int rank;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    for (int k = -1; k < runs; k++) {
        MPI_Barrier(MPI_COMM_WORLD);
        double start = MPI_Wtime();
        if (what == 0)
            MPI_Allreduce(MPI_IN_PLACE, buffer, TALLY_BYTES / 8, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
        else if (what == 1)
            MPI_Allreduce(MPI_IN_PLACE, buffer, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
        else if (what == 2)
            MPI_Bcast(buffer, START_BYTES, MPI_BYTE, 0, MPI_COMM_WORLD);
        else
            MPI_Gather(buffer, bytes, MPI_BYTE, all, bytes, MPI_BYTE, 0, MPI_COMM_WORLD);
        double s = MPI_Wtime() - start;
        MPI_Allreduce(MPI_IN_PLACE, &s, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
        if (k >= 0)
            t[k] = s;
    }
    qsort(t, (size_t)runs, sizeof *t, by_value);
    double m = t[runs / 2];
    free(t);
    return m;
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    int rank, size;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    int most = (int)(12.0 * 3840 * 2160 / size) + 1;
    char *buffer = calloc((size_t)most, 1), *all = rank == 0 ? calloc((size_t)most, (size_t)size) : NULL;
    if (!buffer || (rank == 0 && !all))
        MPI_Abort(MPI_COMM_WORLD, 1);
    double tally = median(0, RUNS, buffer, all, 0), count = median(1, RUNS, buffer, all, 0),
           start = median(2, RUNS, buffer, all, 0);
    if (rank == 0)
        printf("| ranks | tally allreduce us | count allreduce us | start broadcast us | sum us |\n"
               "| %d | %.1f | %.1f | %.1f | %.1f |\n",
               size, 1e6 * tally, 1e6 * count, 1e6 * start, 1e6 * (tally + count + start));
    if (rank == 0)
        printf("| ranks | image | gather ms | GB/s into rank 0 |\n");
    int sizes[2][2] = {{640, 480}, {3840, 2160}};
    for (int k = 0; k < 2; k++) {
        int bytes = (int)(12.0 * sizes[k][0] * sizes[k][1] / size);
        double s = median(3, GATHER_RUNS, buffer, all, bytes);
        if (rank == 0)
            printf("| %d | %dx%d | %.2f | %.2f |\n", size, sizes[k][0], sizes[k][1], 1e3 * s,
                   (double)bytes * (size - 1) / s / 1e9);
    }
    free(buffer);
    free(all);
    MPI_Finalize();
    return 0;
}
