/* Scene files and bare meshes made into scenes; see scene_load.h. */
#include "scene_load.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "file.h"
#include "load.h"
#include "scene_parse.h"
#include "scene_place.h"
#include "text.h"

/* The value of eye rays that miss when the file says nothing: a white sky, as the shipped scenes
 * have it (a bare mesh against black read as a silhouette cut out of the night). */
static const float DEFAULT_BACKGROUND = 1.0f;

/* Scenes of at least PROGRESSIVE_TRIANGLES trace a LOW BVH while the MEDIUM one is built, when
 * the budget also holds the LOW one beside MEDIUM's build: LOW_TRIANGLE bytes a triangle more
 * (peak RSS of the 10M-triangle PLY, 2110 against 1215 MB: 92; docs/formats.md, "Which BVH").
 * Smaller scenes build MEDIUM in a fraction of a second. */
enum { PROGRESSIVE_TRIANGLES = 1 << 20, LOW_TRIANGLE = 96 };

/* Records in a placed scene the BVH its budget gives it (ao_budget_bvh: every charge is made by
 * now), with a note when AUTO or LOW gave a compact one, and whether a LOW BVH traces first (with a note when
 * the budget has no room for it). */
static void settle_bvh(struct ao_scene *s, const struct ao_budget *budget)
{
    s->bvh = ao_budget_bvh(budget);
    if ((budget->bvh == AO_BVH_AUTO && s->bvh == AO_BVH_COMPACT) || s->bvh == AO_BVH_LOW_COMPACT)
        ao_scene_add_note(s, s->name, "BVH built compact to fit the scene budget (slower rays; a larger "
                                      "--scene-budget gets the faster BVH)");
    if (budget->bvh != AO_BVH_AUTO || s->bvh != AO_BVH_MEDIUM || s->triangle_count < PROGRESSIVE_TRIANGLES)
        return;
    uint64_t both = (uint64_t)s->triangle_count * LOW_TRIANGLE;
    s->progressive = budget->surplus <= UINT64_MAX - both && ao_budget_fits(budget, budget->surplus + both);
    if (!s->progressive)
        ao_scene_add_note(s, s->name, "first image after the full BVH build: no room in the scene budget for "
                                      "a quick BVH beside it (a larger --scene-budget renders sooner)");
}

/* An empty scene named after path's last part, with the defaults a file may change. */
static void begin(struct ao_scene *s, const char *path)
{
    memset(s, 0, sizeof *s);
    const char *slash = strrchr(path, '/');
    snprintf(s->name, sizeof s->name, "%s", slash ? slash + 1 : path);
    s->ao_distance = INFINITY;
    s->background = ao_vec3_make(DEFAULT_BACKGROUND, DEFAULT_BACKGROUND, DEFAULT_BACKGROUND);
}

/* The crease angle options ask for. */
static double crease_of(const struct ao_scene_options *options)
{
    return options->crease_set ? options->crease : AO_MESH_CREASE_DEFAULT;
}

/* The budget options ask for, at their BVH's rates. */
static struct ao_budget budget_of(const struct ao_scene_options *options)
{
    struct ao_budget budget = {.limit = options->budget ? options->budget : ao_budget_default(), .bvh = options->bvh};
    return budget;
}

/* Scene text read into scene, charging budget, with options' instancing and crease angle. */
static bool parse_text(struct ao_scene *scene, const char *text, const char *path, struct ao_budget *budget,
                       const struct ao_scene_options *options)
{
    begin(scene, path);
    struct ao_cursor c = {.path = path};
    struct ao_world w = {.extent_note = "", .budget = budget, .instancing = options->instancing,
                         .crease = crease_of(options), .sized = options->sized};
    bool ok = ao_scene_parse_lines(&c, scene, &w, text) && ao_world_place(scene, &w, &c);
    if (ok)
        settle_bvh(scene, budget);
    ao_world_finish(&w);
    if (!ok)
        ao_scene_finish(scene);
    return ok;
}

bool ao_scene_parse(struct ao_scene *scene, const char *text, const char *path, const struct ao_scene_options *options)
{
    static const struct ao_scene_options defaults;
    options = options ? options : &defaults;
    struct ao_budget budget = budget_of(options);
    return parse_text(scene, text, path, &budget, options);
}

/* The ground quad added under a bare mesh whose box is lo..hi: 50 times as wide as the mesh's
 * largest side E, AO_SCENE_GROUND_GAP E below its lowest point. At the lowest point itself (as
 * before) a flat model (a floor, a terrain tile, a sheet) lay within rounding of the ground, and
 * eye rays hit one or the other at random: speckle from 0.5 to 0.8 over the whole model. The gap
 * must clear the rounding of hit points (about 2^-23 of the camera distance, a few E) and stay
 * below what a contact shadow shows. Measured (docs/formats.md): the flat 2 x 2 square at 160x120,
 * 64 spp, still speckled at a gap of 1e-7 E (585 of its 1859 pixels below 0.9 rho) and was clean
 * from 1e-6 E up, on both tracers; the bare bunny at 640x480, 256 spp, against the gap 0, darkened
 * its contact shadow (the ground pixels below 0.9 rho) by 0.03 % at 1e-4 E, within the noise of that
 * mean, and by 0.3 % at 1e-3 E, 3 % at 1e-2 E. 1e-4 E keeps a factor 100 on either side. */
static bool add_ground(struct ao_world *w, struct ao_dvec3 lo, struct ao_dvec3 hi)
{
    struct ao_dvec3 mid = ao_dvec3_scale(ao_dvec3_add(lo, hi), 0.5);
    double extent = ao_world_largest_side(lo, hi), size = 25.0 * extent, y = lo.y - AO_SCENE_GROUND_GAP * extent;
    struct ao_dvec3 p[4] = {ao_dvec3_make(mid.x - size, y, mid.z - size), ao_dvec3_make(mid.x - size, y, mid.z + size),
                            ao_dvec3_make(mid.x + size, y, mid.z + size), ao_dvec3_make(mid.x + size, y, mid.z - size)};
    return ao_world_add_quad(w, p, ao_vec3_make(0, 1, 0), ao_vec3_make(0.5f, 0.5f, 0.5f));
}

/* Adds the arrays' spheres (in world space) to the scene being read; false after reporting one that
 * is not a sphere. */
static bool add_spheres(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w, const struct ao_scene_arrays *a)
{
    for (size_t i = 0; i < a->sphere_count; i++) {
        struct ao_sphere sp = a->spheres[i];
        struct ao_vec3 rho = sp.albedo;
        if (!(isfinite(sp.center.x) && isfinite(sp.center.y) && isfinite(sp.center.z) && sp.radius > 0.0f &&
              isfinite(sp.radius)))
            return ao_cursor_fail(c, "sphere %zu: the centre must be finite and the radius positive", i);
        if (!(rho.x >= 0.0f && rho.x <= 1.0f && rho.y >= 0.0f && rho.y <= 1.0f && rho.z >= 0.0f && rho.z <= 1.0f))
            return ao_cursor_fail(c, "sphere %zu: albedo must lie in [0,1]", i);
        if (!ao_world_charge(c, w, 1, 0, "sphere"))
            return false;
        if (!ao_scene_grow(&s->spheres, s->sphere_count, s->sphere_count + 1, sizeof *s->spheres) ||
            !ao_scene_grow(&w->sphere_centers, s->sphere_count, s->sphere_count + 1, sizeof *w->sphere_centers))
            return ao_cursor_fail(c, "out of memory");
        w->sphere_centers[s->sphere_count] = ao_dvec3_of(sp.center);
        s->spheres[s->sphere_count++] = sp;
    }
    return true;
}

/* A bare mesh: the mesh file's model (or, with arrays, theirs: its albedo and spheres beside it),
 * a large ground quad under it unless options->no_ground, a camera framed on it (or the arrays'). */
static bool load_bare_mesh(struct ao_scene *s, const char *path, const struct ao_scene_arrays *arrays,
                           struct ao_budget *budget, const struct ao_scene_options *options)
{
    begin(s, path);
    bool ground = !options->no_ground;
    struct ao_world w = {.extent_note = ground ? " (the mesh with its ground quad, 50 times as wide as the mesh)" : "",
                         .budget = budget, .instancing = options->instancing, .crease = crease_of(options)};
    struct ao_cursor c = {.path = path};
    struct ao_affine identity = ao_affine_identity();
    struct ao_vec3 rho = ao_vec3_make(AO_WORLD_ALBEDO, AO_WORLD_ALBEDO, AO_WORLD_ALBEDO);
    const struct ao_world_file *f = NULL;
    if (arrays) {
        struct ao_model model;
        rho = arrays->albedo;
        if (ao_load_model_arrays(&model, path, arrays->positions, arrays->vertex_count, arrays->indices,
                                 arrays->triangle_count, arrays->normals, budget, w.crease))
            f = ao_world_add_model(&c, s, &w, &model, path, w.crease);
    } else {
        f = ao_world_load_file(&c, s, &w, path, w.crease);
    }
    bool ok = f && (!arrays || add_spheres(&c, s, &w, arrays)) &&
              (!ground || ao_world_charge(&c, &w, 2, 4, "the ground")) &&
              ao_world_place_model(&c, s, &w, f, &identity, rho, path);
    struct ao_dvec3 lo, hi;
    if (ok && !ao_world_survey(s, &w))
        ok = ao_cursor_fail(&c, "out of memory");
    if (ok && ao_world_bounds(s, &w, &lo, &hi)) {
        struct ao_dvec3 mid = ao_dvec3_scale(ao_dvec3_add(lo, hi), 0.5);
        if (arrays && arrays->camera) {
            /* The arrays' camera, in world space as a scene file's. */
            w.eye = ao_dvec3_of(arrays->camera->eye);
            w.target = ao_dvec3_of(arrays->camera->target);
            s->camera.up = arrays->camera->up;
            s->camera.fov = arrays->camera->fov;
        } else {
            /* The camera framed on the mesh about its centre, then kept in world space. */
            ao_camera_frame_box(&s->camera, ao_dvec3_narrow(ao_dvec3_sub(lo, mid)),
                                ao_dvec3_narrow(ao_dvec3_sub(hi, mid)));
            w.eye = ao_dvec3_add(mid, ao_dvec3_of(s->camera.eye));
            w.target = ao_dvec3_add(mid, ao_dvec3_of(s->camera.target));
        }
        w.has_camera = true;
        if (ground && !add_ground(&w, lo, hi))
            ok = ao_cursor_fail(&c, "out of memory");
    }
    ok = ok && ao_world_place(s, &w, &c);
    if (ok)
        settle_bvh(s, budget);
    ao_world_finish(&w);
    if (!ok)
        ao_scene_finish(s);
    return ok;
}

bool ao_scene_from_arrays(struct ao_scene *scene, const struct ao_scene_arrays *arrays,
                          const struct ao_scene_options *options)
{
    static const struct ao_scene_options defaults;
    options = options ? options : &defaults;
    struct ao_budget budget = budget_of(options);
    if (arrays->camera && !(arrays->camera->fov > 0.0f && arrays->camera->fov < 180.0f)) {
        ao_text_report("%s: camera: 'fov' must lie strictly between 0 and 180 degrees", arrays->name);
        memset(scene, 0, sizeof *scene);
        return false;
    }
    return load_bare_mesh(scene, arrays->name, arrays, &budget, options);
}

/* True when path names a scene file: its extension is .scene (any case). Else (not a mesh either)
 * reports the extension and what aoview reads, so that a README is not parsed as a scene. */
static bool is_scene_file(const char *path)
{
    const char *slash = strrchr(path, '/'), *dot = strrchr(slash ? slash : path, '.');
    if (dot && strcasecmp(dot, ".scene") == 0)
        return true;
    char extensions[64];
    ao_load_extensions(extensions, sizeof extensions);
    ao_text_report("%s: %s%s%s: aoview reads scenes (.scene) and meshes (%s)", path, dot ? "extension '" : "no extension",
                   dot ? dot : "", dot ? "'" : "", extensions);
    return false;
}

bool ao_scene_load(struct ao_scene *scene, const char *path, const struct ao_scene_options *options)
{
    static const struct ao_scene_options defaults;
    options = options ? options : &defaults;
    struct ao_budget budget = budget_of(options);
    memset(scene, 0, sizeof *scene);
    if (ao_load_is_mesh(path))
        return load_bare_mesh(scene, path, NULL, &budget, options);
    if (!is_scene_file(path))
        return false;
    char *text;
    size_t got;
    if (!ao_file_read_budget(path, &budget, &text, &got))
        return false;
    bool ok = strlen(text) == got;
    if (!ok)
        ao_text_report("%s: not a text file (it contains a NUL byte)", path);
    ok = ok && parse_text(scene, text, path, &budget, options);
    free(text);
    return ok;
}
