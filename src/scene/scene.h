/* A scene as the renderer sees it: a camera, analytic spheres, a table of unique triangle meshes and
 * the instances that place them, with their albedos, all in the scene's local frame: stored in
 * float relative to an origin near the scene (scene_place.c), so that float precision follows the
 * scene's size, not its distance from (0, 0, 0). A mesh placed once (or small and placed a few
 * times) is flattened: moved into the local frame; one placed more is instanced. Everything
 * downstream (camera moves, tracer, estimator) works in that frame. Scene files and bare meshes
 * become scenes through scene_load.h; code builds one with ao_scene_add_flat_mesh. */
#ifndef AO_SCENE_H
#define AO_SCENE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "camera.h"
#include "mesh.h"
#include "modes.h"
#include "vec3.h"

/* The smallest and largest scene, as the largest side of the box around its geometry (and its
 * camera, for the largest), that the renderer draws as the same scene at size 1; ao_scene_load
 * and ao_scene_parse (scene_load.h) refuse others (derived in scene_place.c, measured in
 * docs/stability.md). */
#define AO_SCENE_MIN_EXTENT 0x1p-12
#define AO_SCENE_MAX_EXTENT 0x1p31

/* Which meshes the scene instances: AUTO those placed more than once with more than
 * AO_SCENE_FLATTEN_TRIANGLES triangles placed (the rule measured in docs/performance.md) or whose
 * flattened copies would not fit in the scene budget; ALWAYS every mesh file's mesh (the quads
 * stay flat), NEVER none (every placement flattened, as copies), for tests and benchmarks. A
 * transform too ill-conditioned for the tracer's error bound is flattened whatever this says. */
enum ao_instancing { AO_INSTANCING_AUTO, AO_INSTANCING_ALWAYS, AO_INSTANCING_NEVER };

/* The most triangles that AUTO flattens of a mesh placed several times (all its copies together):
 * up to about 4M placed triangles one flat BVH traces 13-28 % faster than instances (2.5x for a
 * 528-triangle mesh placed 1000 times), at 8M instances trace 1.7x faster (docs/performance.md). */
#define AO_SCENE_FLATTEN_TRIANGLES (1u << 22)

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
                                 moves by at most slack[0] max|o| + slack[1] per axis
                                 (scene_place.c) */
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
    bool progressive;             /* big enough, and room in the budget, to trace a LOW BVH first while
                                   * the MEDIUM one is built (ao_tracer_create_progressive) */
};

/* Adds mesh (taken: the scene frees it; zeroed here), whose positions are in the scene's local frame
 * already, as a flat instance of the given albedo: for scenes built in code (benchmarks, tests).
 * False when memory is short (the mesh is then freed). */
bool ao_scene_add_flat_mesh(struct ao_scene *scene, struct ao_mesh *mesh, struct ao_vec3 albedo);

/* The corners of triangle prim of the given instance in the local frame: a flat instance's as
 * stored, another's mapped by its to_local in double and narrowed. Any thread. */
void ao_scene_triangle(const struct ao_scene *scene, size_t instance, size_t prim, struct ao_vec3 corners[3]);

/* Frees everything the scene owns and zeroes it; accepts an empty scene. */
void ao_scene_finish(struct ao_scene *scene);

/* For the scene's builders (scene_place.c and its callers): makes room in *array, a malloc'd array
 * of had elements of size bytes (or NULL), for count; false when that overflows or memory is short
 * (the array is then left as it was). */
bool ao_scene_grow(void *array, size_t had, size_t count, size_t size);

/* Appends an albedo to the scene's table, its index in *index; false when memory or 32-bit indices
 * run out. */
bool ao_scene_add_albedo(struct ao_scene *scene, struct ao_vec3 rho, uint32_t *index);

/* Adds a note (mesh.h's), if not empty, to the scene's notes as "name: note" (name: path's last
 * part), after a "; " when there are others; what does not fit is left out. */
void ao_scene_add_note(struct ao_scene *scene, const char *path, const char *note);

/* Says what a load left out or changed as note lines (text.h) to this thread's sink: the skipped
 * primitives ("aoview: skipped 2 degenerate triangles and 1 point primitive") and the meshes'
 * notes ("aoview: name: note; ..."); nothing when there are none. Any thread. */
void ao_scene_say_notes(const struct ao_scene *scene);

/* Gives the mesh's positions the spare zero entry struct ao_scene promises (realloc: no copy for
 * big arrays, which the C library maps and remaps); false when memory is short. */
bool ao_scene_pad(struct ao_mesh *mesh);

#endif
