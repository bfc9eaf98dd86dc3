/* Scene files and bare meshes made into scenes (scene.h): the line-based scene format (camera,
 * image, background, ao-distance, sphere, quad and mesh lines; docs/contract.md), or a mesh file
 * placed on a ground quad with a camera framed on it. Three entry points, each with one options
 * struct (NULL or zeroed: the defaults): ao_scene_load for a path, ao_scene_parse for text,
 * ao_scene_from_arrays for a mesh (and spheres) given as arrays in code. Every
 * failure is one "file:line: message" line (text.h's sink), and a scene that would not fit the scene
 * budget is refused before its memory is allocated. */
#ifndef AO_SCENE_LOAD_H
#define AO_SCENE_LOAD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "modes.h"
#include "scene.h"

/* The gap between a bare mesh's lowest point and the ground quad added under it, as a fraction
 * of the mesh's largest side: a flat model never coincides with the ground, and a resting model
 * keeps its contact shadow (both measured in scene_load.c). */
#define AO_SCENE_GROUND_GAP 1e-4

/* How a scene is loaded; every field's zero is its default, so that a zeroed struct (or NULL) is
 * the defaults and callers name only what they change:
 * - budget: the scene budget in bytes (budget.h), which the files read, what the loaders hold,
 *   every element added and an `image` line's buffers are charged to; 0: ao_budget_default();
 * - no_ground: a bare mesh gets no ground quad under it (a .scene file has only the quads it
 *   lists, whatever this says);
 * - instancing: which meshes are instanced (AUTO by default);
 * - bvh: the BVH to build (AUTO: MEDIUM, or COMPACT where only that fits the budget; LOW: LOW, or
 *   LOW_COMPACT where only that fits);
 * - crease, crease_set: the crease angle in degrees for the normals mesh files lack (mesh.h), when
 *   crease_set; else AO_MESH_CREASE_DEFAULT;
 * - sized: the image's size comes from elsewhere (--size), so an `image` line's buffers are not
 *   charged. */
struct ao_scene_options {
    uint64_t budget;
    bool no_ground;
    enum ao_instancing instancing;
    enum ao_bvh bvh;
    double crease;
    bool crease_set;
    bool sized;
};

/* Loads a scene file, or a mesh file (ao_load_is_mesh) placed on a ground quad with a framing
 * camera, with options (NULL: the defaults). On failure reports one "file:line: message" line,
 * leaves scene empty and returns false. Any one thread per scene. */
bool ao_scene_load(struct ao_scene *scene, const char *path, const struct ao_scene_options *options);

/* Parses scene text as if read from path (relative mesh paths resolve against its directory),
 * with options (NULL: the defaults); reports and fails as ao_scene_load. */
bool ao_scene_parse(struct ao_scene *scene, const char *text, const char *path, const struct ao_scene_options *options);

/* A scene made in code from arrays (the Python module's): a mesh as ao_load_model_arrays makes it
 * (load/load.h: what an OBJ file holding the arrays gives), of the given albedo, spheres (world
 * space), and a camera, or none: then the scene is made as of a bare mesh file of those triangles
 * (a camera framed on the mesh and spheres, the ground quad under them unless options->no_ground). */
struct ao_scene_arrays {
    const char *name;                /* the scene's name, in titles and messages */
    const float *positions;          /* vertex_count x 3 */
    size_t vertex_count;
    const uint32_t *indices;         /* triangle_count x 3, each below vertex_count */
    size_t triangle_count;
    const float *normals;            /* vertex_count x 3, or NULL: made as a mesh file's missing ones */
    struct ao_vec3 albedo;           /* the mesh's, in [0, 1] */
    const struct ao_sphere *spheres; /* sphere_count, centres in world space */
    size_t sphere_count;
    const struct ao_camera *camera;  /* world space, or NULL: framed */
};

/* Makes the scene arrays describe, with options (NULL: the defaults); reports and fails as
 * ao_scene_load ("name: message"). Any one thread per scene. */
bool ao_scene_from_arrays(struct ao_scene *scene, const struct ao_scene_arrays *arrays,
                          const struct ao_scene_options *options);

#endif
