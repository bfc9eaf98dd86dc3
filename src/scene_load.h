/* Scene files and bare meshes made into scenes (scene.h): the line-based scene format (camera,
 * image, background, ao-distance, sphere, quad and mesh lines; docs/contract.md), or a mesh file
 * placed on a ground quad with a camera framed on it. Two entry points, each with one options
 * struct (NULL or zeroed: the defaults): ao_scene_load for a path, ao_scene_parse for text. Every
 * failure is one "file:line: message" line on stderr, and a scene that would not fit the scene
 * budget is refused before its memory is allocated. */
#ifndef AO_SCENE_LOAD_H
#define AO_SCENE_LOAD_H

#include <stdbool.h>
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
 *   every element added and an `image` line's buffers are charged to; 0: AO_BUDGET_DEFAULT;
 * - no_ground: a bare mesh gets no ground quad under it (a .scene file has only the quads it
 *   lists, whatever this says);
 * - instancing: which meshes are instanced (AUTO by default);
 * - bvh: the BVH to build (AUTO: MEDIUM, or COMPACT where only that fits the budget);
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
 * camera, with options (NULL: the defaults). On failure prints one "file:line: message" line to
 * stderr, leaves scene empty and returns false. Any one thread per scene. */
bool ao_scene_load(struct ao_scene *scene, const char *path, const struct ao_scene_options *options);

/* Parses scene text as if read from path (relative mesh paths resolve against its directory),
 * with options (NULL: the defaults); reports and fails as ao_scene_load. */
bool ao_scene_parse(struct ao_scene *scene, const char *text, const char *path, const struct ao_scene_options *options);

#endif
