/* Triangle meshes from OBJ, PLY, STL and glTF files: indexed triangles with one normal per vertex.
 * The loaders live in src/load/, one file per format. */
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

/* An indexed triangle mesh; the caller owns it (ao_mesh_load fills it, ao_mesh_finish frees it). */
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
 * owns it (ao_model_load_budget fills it, ao_model_finish frees it). */
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

/* True when path's extension names a mesh format ao_mesh_load reads. */
bool ao_mesh_is_mesh_path(const char *path);

/* Loads an .obj, .ply, .stl, .gltf or .glb file (chosen by extension, any case) into mesh, with
 * every placement of a glTF file's meshes applied (positions in float, normals through the inverse
 * transpose, mirrored triangles turned round: the model flattened, for tools and tests; scenes keep
 * models as they are, scene.h); makes the normals the file lacks as ao_model_load_budget does at
 * AO_MESH_CREASE_DEFAULT. On failure prints one "path:line: message" (or "path: message") line to
 * stderr, leaves mesh empty and returns false. Any thread. */
bool ao_mesh_load(struct ao_mesh *mesh, const char *path);

/* ao_mesh_load within budget (ao_mesh_load's is AO_BUDGET_DEFAULT): the file is charged while it is
 * read and parsed, and a mesh whose ao_budget_charge does not fit what is left is refused
 * before its arrays are allocated. Nothing stays charged: the caller charges the mesh it keeps. */
bool ao_mesh_load_budget(struct ao_mesh *mesh, const char *path, struct ao_budget *budget);

/* Loads a mesh file as ao_mesh_load_budget does, into model: its unique meshes and their placements
 * (the unique triangles and vertices and every placement charged against what budget has left
 * before they are allocated; nothing stays charged). The normals the file lacks, or gives as zero
 * or not finite (noted), are made as its format means them: flat for glTF (its specification's
 * rule), else smooth across the edges flatter than crease degrees (0: flat; 180: smooth across
 * every edge), vertices split along the sharper ones. On failure prints one line, leaves model
 * empty and returns false. Any thread. */
bool ao_model_load_budget(struct ao_model *model, const char *path, struct ao_budget *budget, double crease);

/* Frees what ao_model_load_budget allocated and zeroes model; accepts an empty model. */
void ao_model_finish(struct ao_model *model);

/* Writes src moved by map into dst's arrays from vertex vertex_base and triangle triangle_base on
 * (dst may be src with both bases 0: moved in place): positions in double, narrowed once; normals
 * through ao_affine_normals; a mirroring map's triangles turned round, indices raised by
 * vertex_base. Returns the first vertex whose position is not a finite float, or src's count. */
size_t ao_mesh_place(struct ao_mesh *dst, size_t vertex_base, size_t triangle_base, const struct ao_mesh *src,
                     const struct ao_affine *map);

/* Recomputes mesh->normals from the triangles (angle-weighted face normals, smooth across every
 * edge), on one thread per core for a big mesh; false (reported) when memory runs out. Any thread. */
bool ao_mesh_compute_normals(struct ao_mesh *mesh);

/* ao_mesh_compute_normals on so many threads (0: its choice); the normals are the same, bit for
 * bit, whatever the number. */
bool ao_mesh_compute_normals_on(struct ao_mesh *mesh, int threads);

/* Frees what ao_mesh_load allocated and zeroes mesh; accepts an empty mesh. */
void ao_mesh_finish(struct ao_mesh *mesh);

#endif
