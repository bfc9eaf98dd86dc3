/* Mesh files: which paths name one, and loading one as what it holds (a model: its meshes and
 * where it places them) or as one mesh with every placement applied. The format is chosen by the
 * extension (any case): OBJ, PLY, STL, glTF and GLB, a loader per format in this folder. The rest
 * of the program sees this header and mesh.h alone. */
#ifndef AO_LOAD_H
#define AO_LOAD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "budget.h"
#include "mesh.h"

/* True when path's extension names a mesh format ao_load_model reads. Pure. */
bool ao_load_is_mesh(const char *path);

/* Writes the mesh formats' extensions for a message, ".obj, .ply, .stl, .gltf or .glb", into out
 * (size bytes, truncated). Pure. */
void ao_load_extensions(char *out, size_t size);

/* Loads a mesh file into model: its unique meshes and their placements (the unique triangles and
 * vertices and every placement charged against what budget has left before they are allocated;
 * nothing stays charged; NULL: a budget of ao_budget_default()). The normals the file lacks, or
 * gives as zero or not finite (noted), are made as its format means them: flat for glTF (its
 * specification's rule), else smooth across the edges flatter than crease degrees (0: flat; 180:
 * smooth across every edge), vertices split along the sharper ones. On failure prints one
 * "path:line: message" (or "path: message") line, leaves model empty and returns false. Any
 * thread. */
bool ao_load_model(struct ao_model *model, const char *path, struct ao_budget *budget, double crease);

/* Loads a mesh file as ao_load_model does at AO_MESH_CREASE_DEFAULT into one mesh, with every
 * placement of a glTF file's meshes applied (positions in float, normals through the inverse
 * transpose, mirrored triangles turned round: the model flattened, for tools and tests; scenes
 * keep models as they are). The file is charged to budget while it is read and parsed (NULL: a
 * budget of ao_budget_default()), and a mesh that does not fit what is left is refused before its
 * arrays are allocated; nothing stays charged: the caller charges the mesh it keeps. Reports and
 * fails as ao_load_model. Any thread. */
bool ao_load_mesh(struct ao_mesh *mesh, const char *path, struct ao_budget *budget);

/* Makes a model of one mesh placed once from arrays, as ao_load_model makes one of an OBJ file
 * holding them (v lines, then f lines; vn lines and v//vn corners when normals are given): vertex_count
 * positions and (unless NULL) normals, 3 floats each, and triangle_count triangles of 3 indices
 * below vertex_count; degenerate triangles dropped, the normals not given (or given as zero or
 * not finite) made smooth up to crease degrees. The arrays are copied and charged to budget as a
 * file's would be (NULL: ao_budget_default()). Reports and fails as ao_load_model, naming `name`. Any
 * thread. */
bool ao_load_model_arrays(struct ao_model *model, const char *name, const float *positions, size_t vertex_count,
                          const uint32_t *indices, size_t triangle_count, const float *normals,
                          struct ao_budget *budget, double crease);

#endif
