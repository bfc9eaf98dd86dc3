/* Triangle meshes: indexed triangles with one normal per vertex, and the models that place them;
 * what is done to a mesh whatever file it came from: zero-area triangles dropped, the normals it
 * lacks made (angle-weighted, across the edges flatter than a crease angle), placed by an affine
 * map, freed. The loaders (src/load/, one file per format) fill meshes and call these. */
#ifndef AO_MESH_H
#define AO_MESH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "affine.h"
#include "budget.h"
#include "vec3.h"

/* The size of ao_mesh's note, terminating NUL included. */
#define AO_MESH_NOTE_SIZE 200

/* The crease angle in degrees (--crease-angle's default): where an OBJ, PLY or STL file gives no
 * normals, they are smoothed across the edges whose triangles' normals lie less than this apart,
 * and the sharper edges stay sharp (chosen by the measurement in docs/formats.md). */
#define AO_MESH_CREASE_DEFAULT 40.0

/* An indexed triangle mesh; the caller owns it (ao_load_mesh fills it, ao_mesh_finish frees it). */
struct ao_mesh {
    struct ao_vec3 *positions;  /* vertex_count positions */
    struct ao_vec3 *normals;    /* vertex_count unit normals (zero where none can be defined, and where
                                   the normal is flat: shading takes the triangle's own there) */
    size_t vertex_count;
    uint32_t *indices;          /* 3 * triangle_count vertex indices */
    size_t triangle_count;
    size_t degenerate_count;    /* zero-area triangles skipped while loading */
    size_t invalid_normals;     /* normals the file gave as zero or not finite, made as if not given */
    size_t point_primitives;    /* glTF primitives of points skipped (one per node placing them) */
    size_t line_primitives;     /* glTF primitives of lines, line loops and line strips skipped */
    char note[AO_MESH_NOTE_SIZE];   /* what the loader ignored that a user should hear of, one line
                                       without the file's name ("materials, textures and lights are
                                       ignored (...)"); "" when nothing */
};

/* Where a model places one of its meshes: model point = to_model (mesh point). */
struct ao_placement {
    size_t mesh;                /* index into the model's meshes */
    struct ao_affine to_model;
};

/* What a mesh file holds: its meshes, each in its own frame, and where it places them. OBJ, PLY and
 * STL hold one mesh placed once by the identity; a glTF file one mesh per glTF mesh that its scene's
 * nodes name (that mesh's triangle primitives together), placed by every node naming it under the
 * node's world matrix. Nothing is flattened: a mesh under a thousand nodes is held once. The caller
 * owns it (ao_load_model fills it, ao_model_finish frees it). */
struct ao_model {
    struct ao_mesh *meshes;
    size_t mesh_count;
    struct ao_placement *placements;
    size_t placement_count;
    size_t degenerate_count;    /* zero-area triangles skipped, all meshes */
    size_t invalid_normals;     /* normals given as zero or not finite, all meshes */
    size_t point_primitives;    /* glTF primitives of points skipped, once per placement */
    size_t line_primitives;     /* glTF primitives of lines skipped, once per placement */
    char note[AO_MESH_NOTE_SIZE];   /* as ao_mesh's */
};

/* Writes src moved by map into dst's arrays from vertex vertex_base and triangle triangle_base on
 * (dst may be src with both bases 0: moved in place): positions in double, narrowed once; normals
 * through ao_affine_normals; a mirroring map's triangles turned round, indices raised by
 * vertex_base. Returns the first vertex whose position is not a finite float, or src's count. */
size_t ao_mesh_place(struct ao_mesh *dst, size_t vertex_base, size_t triangle_base, const struct ao_mesh *src,
                     const struct ao_affine *map);

/* Frees what the mesh holds and zeroes it; accepts an empty mesh. */
void ao_mesh_finish(struct ao_mesh *mesh);

/* Frees what the model holds (its meshes too) and zeroes it; accepts an empty model. */
void ao_model_finish(struct ao_model *model);

/* One past the largest vertex index a mesh's 32-bit indices can use. */
#define AO_MESH_INDEX_LIMIT UINT32_MAX

/* True when a mesh of so many triangles and vertices fits in what budget has left (ao_budget_charge);
 * else reports "path:line: T triangles and V vertices need about ..." ("path: ..." at line 0) and
 * returns false. Any thread. */
bool ao_mesh_fits(const struct ao_budget *budget, uint64_t triangles, uint64_t vertices, const char *path,
                  size_t line);

/* Arrays of at least this many bytes are advised into huge pages (ao_mesh_advise_huge). */
#define AO_MESH_HUGE_ARRAY ((size_t)4 << 20)

/* Asks the system to back the array [data, data + size) (malloc'd, not yet filled) with huge pages
 * when it is AO_MESH_HUGE_ARRAY bytes or more: filling 240 MB of fresh 4 KiB pages costs 0.8 s of
 * page faults in a virtual machine, of 2 MiB pages 0.02 s. Does nothing where the system cannot.
 * For the big arrays of meshes and of the loaders that fill them. */
void ao_mesh_advise_huge(void *data, size_t size);

/* Removes the zero-area triangles (a repeated index included), counting them in
 * mesh->degenerate_count; a mesh may be left with none. Any thread. */
void ao_mesh_drop_degenerate(struct ao_mesh *mesh);

/* The unit vector along (x, y, z) in single precision, or zero when it is zero or not finite;
 * exact-enough for any finite double components (no square overflows or vanishes). */
struct ao_vec3 ao_mesh_unit(double x, double y, double z);

/* A normal that a file does not give (or gives as zero or not finite), as the loaders store it
 * until ao_mesh_complete_normals makes it: NaN. */
struct ao_vec3 ao_mesh_missing_normal(void);

/* True when n is ao_mesh_missing_normal's marker. */
bool ao_mesh_normal_is_missing(struct ao_vec3 n);

/* A normal as a file gives it, as the loaders store it: made unit, or the missing marker when it is
 * zero or not finite (counted in *invalid). */
struct ao_vec3 ao_mesh_given_normal(double x, double y, double z, size_t *invalid);

/* Makes the normals a loaded mesh lacks (mesh->normals NULL: all; else those with the missing
 * marker): with crease 0 or less flat (the zero vector, which shading replaces by the triangle's
 * own normal); from 180 on angle-weighted over every triangle at the vertex; between, angle-weighted
 * over the triangles joined to the vertex's through edges flatter than crease degrees, the vertex
 * split into one per side of the sharper edges (new vertices at the end, charged to budget first).
 * A mesh without such an edge keeps its vertices and gets the normals 180 gives, bit for bit.
 * False (reported, naming path) when memory or the budget runs out. Any thread. */
bool ao_mesh_complete_normals(struct ao_mesh *mesh, const char *path, double crease, const struct ao_budget *budget);

/* Recomputes mesh->normals from the triangles (angle-weighted face normals, smooth across every
 * edge; allocated when NULL), on one thread per core for a big mesh; false (reported) when memory
 * runs out. Any thread. */
bool ao_mesh_compute_normals(struct ao_mesh *mesh);

/* ao_mesh_compute_normals on so many threads (0: its choice); the normals are the same, bit for
 * bit, whatever the number. */
bool ao_mesh_compute_normals_on(struct ao_mesh *mesh, int threads);

#endif
