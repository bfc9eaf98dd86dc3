/* Scenes: the .scene file format of SPEC.md (or a bare mesh on a ground quad) turned into a camera,
 * analytic spheres and one triangle soup for every mesh and quad, all in the scene's local frame:
 * read and transformed in double precision, then stored in float relative to an origin near the
 * scene (scene.c's place()), so that float precision follows the scene's size, not its distance
 * from (0, 0, 0). Everything downstream (camera moves, tracer, estimator) works in that frame. */
#ifndef AO_SCENE_H
#define AO_SCENE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "camera.h"
#include "vec3.h"

/* The smallest and largest scene, as the largest side of the box around its geometry (and its
 * camera, for the largest), that the renderer draws as the same scene at size 1; ao_scene_load
 * and ao_scene_parse refuse others (derived in scene.c, measured in docs/stability.md). */
#define AO_SCENE_MIN_EXTENT 0x1p-12
#define AO_SCENE_MAX_EXTENT 0x1p31

/* An analytic sphere with its diffuse albedo. */
struct ao_sphere {
    struct ao_vec3 center;
    float radius;
    struct ao_vec3 albedo;
};

/* A whole scene; the caller owns it (ao_scene_load fills it, ao_scene_finish frees it). */
struct ao_scene {
    char name[64];                /* file name without directory, for titles */
    double origin[3];             /* world position of the local frame's (0, 0, 0) */
    struct ao_camera camera;      /* local frame */
    int width, height;            /* the file's `image` size, 0 when not given */
    struct ao_vec3 background;    /* value of eye rays that miss */
    float ao_distance;            /* occlusion range; INFINITY when not given */
    struct ao_sphere *spheres;    /* centres in the local frame */
    size_t sphere_count;
    struct ao_vec3 *positions;    /* all triangles of all meshes and quads, local frame */
    struct ao_vec3 *normals;      /* per vertex, unit or zero */
    size_t vertex_count;
    uint32_t *indices;            /* 3 per triangle */
    uint32_t *triangle_albedo;    /* per triangle, index into albedos */
    size_t triangle_count;
    struct ao_vec3 *albedos;
    size_t albedo_count;
    size_t degenerate_count;      /* zero-area triangles skipped by the mesh loaders */
    size_t point_primitives;      /* glTF primitives of points skipped (mesh.h) */
    size_t line_primitives;       /* glTF primitives of lines skipped */
    char notes[512];              /* the meshes' notes (mesh.h), "name: note; name: note", or "" */
};

/* Loads a .scene file, or a mesh file placed on a ground quad with a framing camera.
 * On failure prints one "file:line: message" line to stderr, leaves scene empty, returns false. */
bool ao_scene_load(struct ao_scene *scene, const char *path);

/* ao_scene_load within a scene budget of budget_bytes (ao_scene_load's is AO_BUDGET_DEFAULT): the
 * files read, what the loaders hold and every element added are charged to it (budget.h), and a
 * scene that does not fit is refused, before its memory is allocated, in one line naming what
 * needs how much. */
bool ao_scene_load_budget(struct ao_scene *scene, const char *path, uint64_t budget_bytes);

/* How ao_scene_load_with loads: the scene budget in bytes (budget.h) and, for a bare mesh, whether
 * the ground quad is added under it (a .scene file has only the quads it lists). */
struct ao_scene_options {
    uint64_t budget;
    bool ground;
};

/* The gap between a bare mesh's lowest point and the ground quad added under it, as a fraction
 * of the mesh's largest side: a flat model never coincides with the ground, and a resting model
 * keeps its contact shadow (both measured in scene.c). */
#define AO_SCENE_GROUND_GAP 1e-4

/* ao_scene_load_budget with options: ao_scene_load_budget's budget is options->budget, and a bare
 * mesh gets the ground quad only with options->ground. */
bool ao_scene_load_with(struct ao_scene *scene, const char *path, const struct ao_scene_options *options);

/* Parses scene text as if read from path (relative mesh paths resolve against its directory);
 * same reporting and budget as ao_scene_load. */
bool ao_scene_parse(struct ao_scene *scene, const char *text, const char *path);

/* Frees everything the scene owns and zeroes it; accepts an empty scene. */
void ao_scene_finish(struct ao_scene *scene);

#endif
