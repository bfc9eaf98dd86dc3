/* Scenes: the .scene file format of SPEC.md (or a bare mesh on a ground quad) turned into a camera,
 * analytic spheres, a table of unique triangle meshes and the instances that place them, all in the
 * scene's local frame: read and transformed in double precision, then stored in float relative to
 * an origin near the scene (scene.c's place()), so that float precision follows the scene's size,
 * not its distance from (0, 0, 0). A mesh file that several mesh lines name is loaded once, a glTF
 * mesh under several nodes once; a mesh placed once (or small and placed a few times) is
 * flattened: moved into the local frame. Everything downstream (camera moves, tracer, estimator)
 * works in that frame. */
#ifndef AO_SCENE_H
#define AO_SCENE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "camera.h"
#include "mesh.h"
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

/* A mesh placed in the scene: scene->meshes[mesh] with an albedo. A flat instance's mesh lies in the
 * local frame already (flattened; its transform is the identity); any other's lies in its own frame,
 * which to_local maps into the local frame, and is traced through Embree's instancing. */
struct ao_instance {
    uint32_t mesh;            /* index into meshes */
    uint32_t albedo;          /* index into albedos */
    bool flat;
    float to_local[12];       /* local = L p + t, column major (affine.h's layout) */
    float normals[9];         /* maps the mesh's normals into the local frame (ao_affine_normals) */
    float slack[2];           /* a ray origin o mapped into the local frame and back by the tracer
                                 moves by at most slack[0] max|o| + slack[1] per axis (scene.c) */
};

/* A whole scene; the caller owns it (ao_scene_load fills it, ao_scene_finish frees it). */
struct ao_scene {
    char name[64];                /* file name without directory, for titles */
    double origin[3];             /* world position of the local frame's (0, 0, 0) */
    struct ao_camera camera;      /* local frame */
    int width, height;            /* the file's `image` size, 0 when not given */
    struct ao_vec3 background;    /* value of eye rays that miss, in [0, 1]; 1 unless the file says */
    float ao_distance;            /* occlusion range; INFINITY when not given */
    struct ao_sphere *spheres;    /* centres in the local frame */
    size_t sphere_count;
    struct ao_mesh *meshes;       /* unique meshes (mesh.h); the quads are meshes too; each one's
                                     positions have a spare zero entry after the last vertex, so
                                     that the tracer can share them with Embree (which reads 16
                                     bytes at a time) */
    size_t mesh_count;
    struct ao_instance *instances;
    size_t instance_count;
    size_t triangle_count;        /* triangles placed, all instances */
    struct ao_vec3 *albedos;
    size_t albedo_count;
    size_t degenerate_count;      /* zero-area triangles skipped by the mesh loaders */
    size_t point_primitives;      /* glTF primitives of points skipped (mesh.h) */
    size_t line_primitives;       /* glTF primitives of lines skipped */
    char notes[512];              /* the meshes' notes (mesh.h), "name: note; name: note", or "" */
    enum ao_bvh bvh;              /* how the tracer builds its BVHs (budget.h); AUTO counts as MEDIUM */
};

/* Loads a .scene file, or a mesh file placed on a ground quad with a framing camera.
 * On failure prints one "file:line: message" line to stderr, leaves scene empty, returns false. */
bool ao_scene_load(struct ao_scene *scene, const char *path);

/* ao_scene_load within a scene budget of budget_bytes (ao_scene_load's is AO_BUDGET_DEFAULT): the
 * files read, what the loaders hold and every element added are charged to it (budget.h), and a
 * scene that does not fit is refused, before its memory is allocated, in one line naming what
 * needs how much. */
bool ao_scene_load_budget(struct ao_scene *scene, const char *path, uint64_t budget_bytes);

/* Which meshes the scene instances: AUTO those placed more than once with more than
 * AO_SCENE_FLATTEN_TRIANGLES triangles placed (the rule measured in docs/performance.md) or whose
 * flattened copies would not fit in the scene budget; ALWAYS every mesh file's mesh (the quads
 * stay flat), NEVER none (every placement flattened, as copies), for tests and benchmarks. A transform too ill-conditioned for the tracer's error bound is
 * flattened whatever this says. */
enum ao_instancing { AO_INSTANCING_AUTO, AO_INSTANCING_ALWAYS, AO_INSTANCING_NEVER };

/* The most triangles that AUTO flattens of a mesh placed several times (all its copies together):
 * up to about 4M placed triangles one flat BVH traces 13-28 % faster than instances (2.5x for a
 * 528-triangle mesh placed 1000 times), at 8M instances trace 1.7x faster (docs/performance.md). */
#define AO_SCENE_FLATTEN_TRIANGLES (1u << 22)

/* How ao_scene_load_with loads: the scene budget in bytes (budget.h), which an `image` line's
 * buffers are charged to unless sized (the size comes from elsewhere, --size); for a bare mesh,
 * whether the ground quad is added under it (a .scene file has only the quads it lists); which
 * meshes it instances; the BVH to build (AUTO: MEDIUM, or COMPACT where only that fits the budget);
 * the crease angle in degrees for the normals mesh files lack (mesh.h), when crease_set (else
 * AO_MESH_CREASE_DEFAULT, so that options set field by field keep the default). */
struct ao_scene_options {
    uint64_t budget;
    bool ground;
    enum ao_instancing instancing;
    enum ao_bvh bvh;
    double crease;
    bool crease_set;
    bool sized;
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

/* ao_scene_parse with options (their ground is not used: scene text has only the quads it lists). */
bool ao_scene_parse_with(struct ao_scene *scene, const char *text, const char *path,
                         const struct ao_scene_options *options);

/* Adds mesh (taken: the scene frees it; zeroed here), whose positions are in the scene's local frame
 * already, as a flat instance of the given albedo: for scenes built in code (benchmarks, tests).
 * False when memory is short (the mesh is then freed). */
bool ao_scene_add_flat_mesh(struct ao_scene *scene, struct ao_mesh *mesh, struct ao_vec3 albedo);

/* The corners of triangle prim of the given instance in the local frame: a flat instance's as
 * stored, another's mapped by its to_local in double and narrowed. Any thread. */
void ao_scene_triangle(const struct ao_scene *scene, size_t instance, size_t prim, struct ao_vec3 corners[3]);

/* Frees everything the scene owns and zeroes it; accepts an empty scene. */
void ao_scene_finish(struct ao_scene *scene);

#endif
