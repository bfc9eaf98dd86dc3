/* Poison: this header on a folder's include path stops <mpi.h> there (src/meson.build). */
#error "MPI outside src/mpi: the renderer knows no ranks, only a share (share.h); MPI code belongs in src/mpi"
