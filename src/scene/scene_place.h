/* The scene while it is read (struct ao_world): everything a scene file's lines or a bare mesh add,
 * in world space and double precision, the mesh files loaded once each, every element charged to
 * the scene budget as it comes; and placing it all, once the whole scene is known, into the
 * scene's local frame in float (ao_world_place). Private to the scene's readers: scene_parse.c
 * and scene_load.c. */
#ifndef AO_SCENE_PLACE_H
#define AO_SCENE_PLACE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <sys/types.h>

#include "affine.h"
#include "budget.h"
#include "mesh.h"
#include "scene.h"

/* The most words a scene file's line may have. */
enum { AO_CURSOR_TOKENS = 64 };

/* The albedo of what a scene file gives none, and of a bare mesh. */
#define AO_WORLD_ALBEDO 0.8f

/* Where the reader is, for "file:line: message" reports: the file, the line (0: none), and the
 * tokens of that line while the parser reads it, the next one to take at `next`. */
struct ao_cursor {
    const char *path;
    int line;
    char *tokens[AO_CURSOR_TOKENS];
    int count;
    int next;
};

/* Reports "path:line: message" (or "path: message" at line 0) as one line; returns false. */
bool ao_cursor_fail(const struct ao_cursor *c, const char *fmt, ...);

/* A mesh file that a mesh line loaded: its path and identity, its meshes (scene->meshes[first,
 * first + count)) and its placements of them, kept for further lines naming the same file. */
struct ao_world_file {
    char *path;
    double crease;                /* the crease angle its normals were made with */
    dev_t device;
    ino_t inode;
    bool identified;              /* device and inode known (stat worked) */
    size_t first, count;
    struct ao_placement *placements;
    size_t placement_count;
};

/* A placement of scene->meshes[mesh] waiting for ao_world_place(), in world space. */
struct ao_world_placement {
    uint32_t mesh, albedo;
    struct ao_affine to_world;
};

/* A quad waiting for ao_world_place(): its corners in world space, unit normal and albedo. */
struct ao_world_quad {
    struct ao_dvec3 p[4];
    struct ao_vec3 n, rho;
};

/* What ao_world_place() needs to know of each mesh: how often it is placed, whether it is
 * instanced, and the box around its vertices in its own frame (for the boxes of its instances). */
struct ao_world_mesh {
    size_t placements, left;      /* placements in all, and those not yet built into instances */
    bool instanced;
    struct ao_dvec3 lo, hi;
};

/* The scene while it is read, in double precision and world space; ao_scene's meshes and
 * instances, sphere centres and camera are filled from it once the whole scene is known
 * (ao_world_place()). */
struct ao_world {
    struct ao_dvec3 *sphere_centers; /* parallel to scene->spheres */
    struct ao_world_placement *placements;
    size_t placement_count;
    struct ao_world_quad *quads;
    size_t quad_count;
    struct ao_world_file *files;
    size_t file_count;
    uint32_t *file_slots;         /* hash table of the identified files: index + 1, or 0 (empty) */
    size_t slot_count;            /* a power of two, at least twice file_count; 0 before the first */
    struct ao_world_mesh *info;   /* per mesh, from ao_world_survey() */
    struct ao_dvec3 eye, target;  /* the camera's, when has_camera */
    bool has_camera;
    int camera_line;
    const char *extent_note;      /* what makes up the extent, for its message ("" in scene files) */
    struct ao_budget *budget;     /* charged for every element as it is added */
    enum ao_instancing instancing;
    double crease;                /* mesh files' crease angle, degrees (mesh.h) */
    bool sized;                   /* the image's size is set elsewhere: an `image` line's is not charged */
    uint64_t image_charge;        /* what the `image` line took from the budget */
};

/* Charges an element of so many triangles (a sphere counts as one) and vertices to the budget;
 * false after reporting at the cursor's line. */
bool ao_world_charge(struct ao_cursor *c, struct ao_world *w, uint64_t triangles, uint64_t vertices, const char *what);

/* Takes bytes from the budget for what a line adds beside triangles and vertices; false after
 * reporting "what need about ..." at the cursor's line. */
bool ao_world_take(struct ao_cursor *c, struct ao_world *w, uint64_t bytes, const char *what);

/* Appends the quad of corners p (triangles p0 p1 p2 and p0 p2 p3) and unit normal n; false when
 * memory is short. */
bool ao_world_add_quad(struct ao_world *w, const struct ao_dvec3 p[4], struct ao_vec3 n, struct ao_vec3 rho);

/* The file loaded earlier as path (by device and inode, or by name where stat fails) with this
 * crease angle, or NULL. */
const struct ao_world_file *ao_world_find_file(const struct ao_world *w, const char *path, double crease);

/* Loads the mesh file at path once for every mesh line that names it with one crease angle: its
 * meshes join the scene's, charged to the budget once; returns its entry, or NULL after reporting. */
const struct ao_world_file *ao_world_load_file(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w,
                                              const char *path, double crease);

/* ao_world_load_file's second half, for a model loaded otherwise (taken: emptied, freed on failure):
 * its meshes join the scene's as the file `path`'s, charged to the budget; its entry, or NULL after
 * reporting. */
const struct ao_world_file *ao_world_add_model(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w,
                                              struct ao_model *taken, const char *path, double crease);

/* Places every placement of the loaded file f under the map `line`, with albedo rho: one pending
 * placement each, charged to the budget; false after reporting. */
bool ao_world_place_model(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w,
                          const struct ao_world_file *f, const struct ao_affine *line, struct ao_vec3 rho,
                          const char *path);

/* Fills w->info: how often each mesh is placed, its box in its own frame, and whether it is
 * instanced (w->instancing's rule; never where a placement's map is too ill-conditioned to trace).
 * False when memory is short. */
bool ao_world_survey(struct ao_scene *s, struct ao_world *w);

/* World-space bounding box of all geometry (w->info must be current); false for an empty scene. */
bool ao_world_bounds(const struct ao_scene *s, const struct ao_world *w, struct ao_dvec3 *lo, struct ao_dvec3 *hi);

/* The largest side of the box lo..hi. */
double ao_world_largest_side(struct ao_dvec3 lo, struct ao_dvec3 hi);

/* Moves the scene from world space into its local frame and narrows it to float (the rule and its
 * reasons in scene_place.c); a scene without a camera line gets one framed on its box. False after
 * reporting (the camera's line) or on short memory. */
bool ao_world_place(struct ao_scene *s, struct ao_world *w, struct ao_cursor *c);

/* Frees what the world holds while a scene is read. */
void ao_world_finish(struct ao_world *w);

#endif
