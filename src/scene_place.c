/* Scene files and bare meshes; see scene.h and SPEC.md's "Scene file". */
#include "scene.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>

#include "affine.h"
#include "dvec3.h"
#include "file.h"
#include "text.h"
#include "image.h"
#include "load/load.h"
#include "mesh.h"

enum { MAX_TOKENS = 64, MAX_LINE = 4096, MAX_VALUES = 3 };

static const double PI = 3.14159265358979323846;
static const float DEFAULT_ALBEDO = 0.8f;
/* The value of eye rays that miss when the file says nothing: a white sky, as the shipped scenes
 * have it (a bare mesh against black read as a silhouette cut out of the night). */
static const float DEFAULT_BACKGROUND = 1.0f;

/* Where the parser is, for "file:line: message" reports. */
struct cursor {
    const char *path;
    int line;
    char *tokens[MAX_TOKENS];
    int count;
    int next;
};

/* Reports "path:line: message" (or "path: message" at line 0) as one line; returns false. */
static bool fail(const struct cursor *c, const char *fmt, ...)
{
    char message[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(message, sizeof message, fmt, ap);
    va_end(ap);
    if (c->line)
        ao_text_report("%s:%d: %s", c->path, c->line, message);
    else
        ao_text_report("%s: %s", c->path, message);
    return false;
}

/* ---- value parsing ---- */

static bool is_number(const char *s)
{
    char *end;
    strtod(s, &end);
    return end != s && *end == '\0';
}

/* Reads 1 to MAX_VALUES numbers after key into v; returns how many, or 0 after reporting. Every
 * value must also be finite as a float, which the geometry becomes. */
static int numbers(struct cursor *c, const char *key, double *v, int min, int max)
{
    int n = 0;
    while (c->next < c->count && n < max && is_number(c->tokens[c->next])) {
        double d = strtod(c->tokens[c->next++], NULL);
        if (!isfinite(d) || fabs(d) > 3.0e38) {
            fail(c, "'%s': value '%s' is not a finite number", key, c->tokens[c->next - 1]);
            return 0;
        }
        v[n++] = d;
    }
    if (n < min) {
        if (c->next < c->count && !is_number(c->tokens[c->next]))
            fail(c, "'%s': expected a number, got '%s'", key, c->tokens[c->next]);
        else
            fail(c, "'%s': expected %d number%s", key, min, min == 1 ? "" : "s");
        return 0;
    }
    return n;
}

static bool vector(struct cursor *c, const char *key, struct ao_dvec3 *out)
{
    double v[3];
    if (!numbers(c, key, v, 3, 3))
        return false;
    *out = ao_dvec3_make(v[0], v[1], v[2]);
    return true;
}

static bool scalar(struct cursor *c, const char *key, double *out)
{
    return numbers(c, key, out, 1, 1) == 1;
}

/* One number or three: a grey level or an RGB triple. */
static bool triple(struct cursor *c, const char *key, struct ao_dvec3 *out)
{
    double v[3];
    int n = numbers(c, key, v, 1, 3);
    if (n == 2)
        return fail(c, "'%s': expected 1 or 3 numbers, got 2", key);
    if (n == 0)
        return false;
    *out = n == 1 ? ao_dvec3_make(v[0], v[0], v[0]) : ao_dvec3_make(v[0], v[1], v[2]);
    return true;
}

/* triple() narrowed to float, for colours. */
static bool colour(struct cursor *c, const char *key, struct ao_vec3 *out)
{
    struct ao_dvec3 v = {0};
    if (!triple(c, key, &v))
        return false;
    *out = ao_dvec3_narrow(v);
    return true;
}

/* A colour whose values must lie in [0, 1]: an albedo, or the background (brighter than an open
 * white surface it would be no sky, and it would scale the relative error that --target-error stops
 * at, e.g. 3e38 meets 1 % at once; below 0, an error column of inf). */
static bool unit_colour(struct cursor *c, const char *key, struct ao_vec3 *out)
{
    if (!colour(c, key, out))
        return false;
    if (out->x < 0 || out->x > 1 || out->y < 0 || out->y > 1 || out->z < 0 || out->z > 1)
        return fail(c, "'%s': values must lie in [0, 1]", key);
    return true;
}

static bool albedo(struct cursor *c, struct ao_vec3 *out)
{
    return unit_colour(c, "albedo", out);
}

/* A crease angle: degrees from 0 to 180 (mesh.h). */
static bool crease_angle(struct cursor *c, const char *key, double *out)
{
    if (!scalar(c, key, out))
        return false;
    return (*out >= 0.0 && *out <= 180.0) || fail(c, "'%s': expected degrees from 0 to 180", key);
}

/* Takes the next key of a statement; reports duplicates through the seen mask. */
static const char *next_key(struct cursor *c, const char *const *keys, unsigned *seen, int *which)
{
    const char *key = c->tokens[c->next++];
    for (int k = 0; keys[k]; k++) {
        if (strcmp(key, keys[k]) == 0) {
            if (*seen & (1u << k)) {
                fail(c, "'%s' given twice", key);
                return NULL;
            }
            *seen |= 1u << k;
            *which = k;
            return key;
        }
    }
    fail(c, "unknown key '%s' for '%s'", key, c->tokens[0]);
    return NULL;
}

static bool require(const struct cursor *c, unsigned seen, const char *const *keys, unsigned needed)
{
    for (int k = 0; keys[k]; k++)
        if ((needed & (1u << k)) && !(seen & (1u << k)))
            return fail(c, "'%s' needs '%s'", c->tokens[0], keys[k]);
    return true;
}

/* ---- growing the scene's arrays ---- */

/* Resizes *array to count elements of size bytes; false when that overflows or memory is short. */
static bool resize(void *array, size_t count, size_t size)
{
    void **slot = array;
    if (count > SIZE_MAX / size)
        return false;
    void *p = realloc(*slot, count ? count * size : 1);
    if (!p)
        return false;
    *slot = p;
    return true;
}

/* A mesh file that a mesh line loaded: its path and identity, its meshes (scene->meshes[first,
 * first + count)) and its placements of them, kept for further lines naming the same file. */
struct loaded {
    char *path;
    double crease;                /* the crease angle its normals were made with */
    dev_t device;
    ino_t inode;
    bool identified;              /* device and inode known (stat worked) */
    size_t first, count;
    struct ao_placement *placements;
    size_t placement_count;
};

/* A placement of scene->meshes[mesh] waiting for place(), in world space. */
struct pending {
    uint32_t mesh, albedo;
    struct ao_affine to_world;
};

/* A quad waiting for place(): its corners in world space, unit normal and albedo. */
struct quad {
    struct ao_dvec3 p[4];
    struct ao_vec3 n, rho;
};

/* What place() needs to know of each mesh: how often it is placed, whether it is instanced, and
 * the box around its vertices in its own frame (for the boxes of its instances). */
struct mesh_info {
    size_t placements, left;      /* placements in all, and those not yet built into instances */
    bool instanced;
    struct ao_dvec3 lo, hi;
};

/* The scene while it is read, in double precision and world space; ao_scene's meshes and
 * instances, sphere centres and camera are filled from it once the whole scene is known
 * (place()). */
struct world {
    struct ao_dvec3 *sphere_centers;  /* parallel to scene->spheres */
    struct pending *placements;
    size_t placement_count;
    struct quad *quads;
    size_t quad_count;
    struct loaded *files;
    size_t file_count;
    uint32_t *file_slots;         /* hash table of the identified files: index + 1, or 0 (empty) */
    size_t slot_count;            /* a power of two, at least twice file_count; 0 before the first */
    struct mesh_info *info;       /* per mesh, from survey() */
    struct ao_dvec3 eye, target;      /* the camera's, when has_camera */
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
static bool charge(struct cursor *c, struct world *w, uint64_t triangles, uint64_t vertices, const char *what)
{
    uint64_t bytes;
    if (ao_budget_take_mesh(w->budget, triangles, vertices, &bytes))
        return true;
    char why[200];
    ao_budget_explain(w->budget, bytes, why, sizeof why);
    return fail(c, "%s: %llu triangles and %llu vertices %s", what, (unsigned long long)triangles,
                (unsigned long long)vertices, why);
}

/* Takes bytes from the budget for what a line adds beside triangles and vertices; false after
 * reporting "what need about ..." at the cursor's line. */
static bool take(struct cursor *c, struct world *w, uint64_t bytes, const char *what)
{
    if (ao_budget_take(w->budget, bytes))
        return true;
    char why[200];
    ao_budget_explain(w->budget, bytes, why, sizeof why);
    return fail(c, "%s %s", what, why);
}

/* Charges a mesh file's unique meshes their structures' cost (AO_BUDGET_MESH each). */
static bool charge_meshes(struct cursor *c, struct world *w, size_t count, const char *path)
{
    char what[4200];
    snprintf(what, sizeof what, "%s: the structures of %zu mesh%s", path, count, count == 1 ? "" : "es");
    return take(c, w, (uint64_t)count * AO_BUDGET_MESH, what);
}

static bool add_albedo(struct ao_scene *s, struct ao_vec3 rho, uint32_t *index)
{
    if (s->albedo_count >= UINT32_MAX || !resize(&s->albedos, s->albedo_count + 1, sizeof *s->albedos))
        return false;
    s->albedos[s->albedo_count] = rho;
    *index = (uint32_t)s->albedo_count++;
    return true;
}

/* Adds a mesh's note (mesh.h), if any, to the scene's notes as "name: note", after a "; " when
 * there are others; what does not fit is left out. */
static void add_note(struct ao_scene *s, const char *path, const char *note)
{
    if (!note[0])
        return;
    const char *slash = strrchr(path, '/');
    size_t used = strlen(s->notes);
    if (used + 4 < sizeof s->notes &&
        snprintf(s->notes + used, sizeof s->notes - used, "%s%s: %s", used ? "; " : "", slash ? slash + 1 : path,
                 note) < 0)
        s->notes[used] = '\0';
}

/* ---- statements ---- */

/* Scale, then rotation about a unit axis, then translation (SPEC.md's order), in double. */
struct transform {
    struct ao_dvec3 scale, axis, translate;
    double cos_angle, sin_angle;
};

/* Rodrigues' rotation of v about t->axis. */
static struct ao_dvec3 rotate(const struct transform *t, struct ao_dvec3 v)
{
    struct ao_dvec3 k = t->axis;
    struct ao_dvec3 r = ao_dvec3_scale(v, t->cos_angle);
    r = ao_dvec3_add(r, ao_dvec3_scale(ao_dvec3_cross(k, v), t->sin_angle));
    return ao_dvec3_add(r, ao_dvec3_scale(k, ao_dvec3_dot(k, v) * (1.0 - t->cos_angle)));
}

/* The transform as an affine map: column j of L is the rotated axis j scaled by scale j. */
static struct ao_affine affine_of(const struct transform *t)
{
    struct ao_affine a;
    double s[3] = {t->scale.x, t->scale.y, t->scale.z};
    for (int j = 0; j < 3; j++) {
        struct ao_dvec3 e = ao_dvec3_make(j == 0 ? s[0] : 0.0, j == 1 ? s[1] : 0.0, j == 2 ? s[2] : 0.0);
        struct ao_dvec3 column = rotate(t, e);
        a.m[3 * j] = column.x, a.m[3 * j + 1] = column.y, a.m[3 * j + 2] = column.z;
    }
    a.m[9] = t->translate.x, a.m[10] = t->translate.y, a.m[11] = t->translate.z;
    return a;
}

/* Joins a mesh path to the scene file's directory unless it is absolute. */
static bool resolve_path(const struct cursor *c, const char *name, char *out, size_t size)
{
    const char *slash = strrchr(c->path, '/');
    int dir = name[0] == '/' || !slash ? 0 : (int)(slash - c->path + 1);
    if (snprintf(out, size, "%.*s%s", dir, c->path, name) >= (int)size)
        return fail(c, "mesh path too long");
    return true;
}

/* Appends the quad of corners p (triangles p0 p1 p2 and p0 p2 p3) and unit normal n. */
static bool add_quad(struct world *w, const struct ao_dvec3 p[4], struct ao_vec3 n, struct ao_vec3 rho)
{
    if (!resize(&w->quads, w->quad_count + 1, sizeof *w->quads))
        return false;
    struct quad *q = &w->quads[w->quad_count++];
    memcpy(q->p, p, sizeof q->p);
    q->n = n, q->rho = rho;
    return true;
}

/* The slot of file_slots where a file of this identity and crease angle is, or the empty one where
 * it would go. */
static size_t file_slot(const struct world *w, dev_t device, ino_t inode, double crease)
{
    uint64_t bits;
    memcpy(&bits, &crease, sizeof bits);
    uint64_t h = ((uint64_t)device * 0x9E3779B97F4A7C15u) ^ ((uint64_t)inode * 0xC2B2AE3D27D4EB4Fu) ^ bits;
    h ^= h >> 29;
    size_t mask = w->slot_count - 1;
    for (size_t i = (size_t)h & mask;; i = (i + 1) & mask) {
        uint32_t k = w->file_slots[i];
        if (!k || (w->files[k - 1].device == device && w->files[k - 1].inode == inode &&
                   w->files[k - 1].crease == crease))
            return i;
    }
}

/* Enters files[index], identified, into the hash table, doubling it when half full; false when
 * memory is short. */
static bool index_file(struct world *w, size_t index)
{
    if (2 * (index + 1) > w->slot_count) {
        size_t count = w->slot_count ? 2 * w->slot_count : 64;
        uint32_t *slots = calloc(count, sizeof *slots);
        if (!slots)
            return false;
        free(w->file_slots);
        w->file_slots = slots, w->slot_count = count;
        for (size_t i = 0; i < index; i++)
            if (w->files[i].identified)
                w->file_slots[file_slot(w, w->files[i].device, w->files[i].inode, w->files[i].crease)] = (uint32_t)i + 1;
    }
    const struct loaded *f = &w->files[index];
    w->file_slots[file_slot(w, f->device, f->inode, f->crease)] = (uint32_t)index + 1;
    return true;
}

/* The file loaded earlier as path (by device and inode, or by name where stat fails) with this
 * crease angle, or NULL. */
static const struct loaded *find_loaded(const struct world *w, const char *path, double crease)
{
    struct stat st;
    if (stat(path, &st) == 0) {
        if (!w->slot_count)
            return NULL;
        uint32_t k = w->file_slots[file_slot(w, st.st_dev, st.st_ino, crease)];
        return k ? &w->files[k - 1] : NULL;
    }
    for (size_t i = 0; i < w->file_count; i++)
        if (w->files[i].crease == crease && strcmp(w->files[i].path, path) == 0)
            return &w->files[i];
    return NULL;
}

/* Loads the mesh file at path once for every mesh line that names it with one crease angle: its
 * meshes join the scene's, charged to the budget once; returns its entry, or NULL after reporting. */
static const struct loaded *load_file(struct cursor *c, struct ao_scene *s, struct world *w, const char *path,
                                      double crease)
{
    struct ao_model model;
    if (!ao_load_model(&model, path, w->budget, crease))
        return NULL;
    uint64_t triangles = 0, vertices = 0;
    for (size_t i = 0; i < model.mesh_count; i++)
        triangles += model.meshes[i].triangle_count, vertices += model.meshes[i].vertex_count;
    struct stat st;
    char *copy = strdup(path);
    bool ok = charge(c, w, triangles, vertices, path) && charge_meshes(c, w, model.mesh_count, path);
    if (ok && (!copy || s->mesh_count + model.mesh_count >= UINT32_MAX ||
               !resize(&s->meshes, s->mesh_count + model.mesh_count, sizeof *s->meshes) ||
               !resize(&w->files, w->file_count + 1, sizeof *w->files))) {
        ok = fail(c, "out of memory adding '%s'", path);
    }
    if (!ok) {
        free(copy);
        ao_model_finish(&model);
        return NULL;
    }
    struct loaded *f = &w->files[w->file_count++];
    *f = (struct loaded){.path = copy, .crease = crease, .first = s->mesh_count, .count = model.mesh_count,
                         .placements = model.placements, .placement_count = model.placement_count};
    if (stat(path, &st) == 0) {
        f->identified = true, f->device = st.st_dev, f->inode = st.st_ino;
        if (!index_file(w, w->file_count - 1)) {
            w->file_count--;
            free(copy);
            ao_model_finish(&model);
            fail(c, "out of memory adding '%s'", path);
            return NULL;
        }
    }
    memcpy(s->meshes + s->mesh_count, model.meshes, model.mesh_count * sizeof *model.meshes);
    s->mesh_count += model.mesh_count;
    s->degenerate_count += model.degenerate_count;
    s->point_primitives += model.point_primitives;
    s->line_primitives += model.line_primitives;
    add_note(s, path, model.note);
    free(model.meshes);
    return f;
}

/* Places every placement of the loaded file f under the map `line`, with albedo rho: one pending
 * placement each, charged to the budget. */
static bool place_model(struct cursor *c, struct ao_scene *s, struct world *w, const struct loaded *f,
                        const struct ao_affine *line, struct ao_vec3 rho, const char *path)
{
    char what[4200];
    snprintf(what, sizeof what, "%s: %zu placements", path, f->placement_count);
    if (!take(c, w, (uint64_t)f->placement_count * AO_BUDGET_INSTANCE, what))
        return false;
    uint32_t a;
    if (!add_albedo(s, rho, &a) ||
        !resize(&w->placements, w->placement_count + f->placement_count, sizeof *w->placements))
        return fail(c, "out of memory placing '%s'", path);
    for (size_t i = 0; i < f->placement_count; i++)
        w->placements[w->placement_count++] = (struct pending){
            (uint32_t)(f->first + f->placements[i].mesh), a, ao_affine_compose(line, &f->placements[i].to_model)};
    return true;
}

/* A camera line; its eye and target stay in world space until place() checks the camera. */
static bool parse_camera(struct cursor *c, struct ao_scene *s, struct world *w)
{
    static const char *const keys[] = {"eye", "target", "up", "fov", NULL};
    unsigned seen = 0;
    struct ao_dvec3 up = ao_dvec3_make(0, 1, 0);
    double fov = 40.0;
    while (c->next < c->count) {
        int k;
        const char *key = next_key(c, keys, &seen, &k);
        if (!key)
            return false;
        bool ok = k == 0   ? vector(c, key, &w->eye)
                  : k == 1 ? vector(c, key, &w->target)
                  : k == 2 ? vector(c, key, &up)
                           : scalar(c, key, &fov);
        if (!ok)
            return false;
    }
    if (!require(c, seen, keys, 3u))
        return false;
    if (!(fov > 0.0 && fov < 180.0))
        return fail(c, "'fov' must lie strictly between 0 and 180 degrees");
    s->camera.up = ao_dvec3_narrow(up);
    s->camera.fov = (float)fov;
    w->has_camera = true;
    w->camera_line = c->line;
    return true;
}

/* "image W H": the default size, whose buffers (accumulation, frames, a PNG's) the budget is charged
 * for unless the size is set elsewhere (--size): a 13-byte line asked for 3 GB. */
static bool parse_image(struct cursor *c, struct ao_scene *s, struct world *w)
{
    double v[2];
    if (numbers(c, "image", v, 2, 2) != 2)
        return false;
    if (v[0] != floor(v[0]) || v[1] != floor(v[1]) || v[0] < 1 || v[1] < 1 ||
        v[0] > AO_IMAGE_MAX_SIDE || v[1] > AO_IMAGE_MAX_SIDE || v[0] * v[1] > AO_IMAGE_MAX_PIXELS)
        return fail(c, "'image': expected width and height, whole numbers from 1 to %d with at most "
                       "%d pixels", AO_IMAGE_MAX_SIDE, AO_IMAGE_MAX_PIXELS);
    s->width = (int)v[0];
    s->height = (int)v[1];
    if (w->sized)
        return true;
    char what[96];
    snprintf(what, sizeof what, "'image' %dx%d: its buffers", s->width, s->height);
    ao_budget_give(w->budget, w->image_charge);   /* a line before it is replaced */
    w->image_charge = (uint64_t)s->width * (uint64_t)s->height * AO_BUDGET_PIXEL;
    if (take(c, w, w->image_charge, what))
        return true;
    w->image_charge = 0;
    return false;
}

static bool parse_sphere(struct cursor *c, struct ao_scene *s, struct world *w)
{
    static const char *const keys[] = {"center", "radius", "albedo", NULL};
    unsigned seen = 0;
    struct ao_sphere sp = {.albedo = ao_vec3_make(DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO)};
    struct ao_dvec3 center = {0};
    double radius = 0.0;
    while (c->next < c->count) {
        int k;
        const char *key = next_key(c, keys, &seen, &k);
        if (!key)
            return false;
        bool ok = k == 0 ? vector(c, key, &center) : k == 1 ? scalar(c, key, &radius) : albedo(c, &sp.albedo);
        if (!ok)
            return false;
    }
    if (!require(c, seen, keys, 3u))
        return false;
    sp.radius = (float)radius;
    if (!(sp.radius > 0.0f))
        return fail(c, "'radius' must be positive");
    if (!charge(c, w, 1, 0, "sphere"))
        return false;
    if (!resize(&s->spheres, s->sphere_count + 1, sizeof *s->spheres) ||
        !resize(&w->sphere_centers, s->sphere_count + 1, sizeof *w->sphere_centers))
        return fail(c, "out of memory");
    w->sphere_centers[s->sphere_count] = center;
    s->spheres[s->sphere_count++] = sp;
    return true;
}

static bool parse_quad(struct cursor *c, struct ao_scene *s, struct world *w)
{
    static const char *const keys[] = {"corner", "edge1", "edge2", "albedo", NULL};
    unsigned seen = 0;
    struct ao_dvec3 corner = {0}, e1 = {0}, e2 = {0};
    struct ao_vec3 rho = ao_vec3_make(DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO);
    while (c->next < c->count) {
        int k;
        const char *key = next_key(c, keys, &seen, &k);
        if (!key)
            return false;
        bool ok = k == 0   ? vector(c, key, &corner)
                  : k == 1 ? vector(c, key, &e1)
                  : k == 2 ? vector(c, key, &e2)
                           : albedo(c, &rho);
        if (!ok)
            return false;
    }
    if (!require(c, seen, keys, 7u))
        return false;
    struct ao_vec3 n = ao_dvec3_narrow(ao_dvec3_cross(e1, e2));
    if (!(ao_vec3_length(n) > 0.0f) || !ao_vec3_is_finite(n))
        return fail(c, "quad: edge1 and edge2 span no area");
    n = ao_vec3_normalize(n);
    if (!charge(c, w, 2, 4, "quad"))
        return false;
    (void)s;
    struct ao_dvec3 p[4] = {corner, ao_dvec3_add(corner, e1), ao_dvec3_add(ao_dvec3_add(corner, e1), e2), ao_dvec3_add(corner, e2)};
    return add_quad(w, p, n, rho) || fail(c, "out of memory");
}

static bool parse_mesh(struct cursor *c, struct ao_scene *s, struct world *w)
{
    static const char *const keys[] = {"albedo", "scale", "rotate", "translate", "crease", NULL};
    if (c->next >= c->count)
        return fail(c, "'mesh' needs a file name");
    char path[4096];
    if (!resolve_path(c, c->tokens[c->next++], path, sizeof path))
        return false;
    unsigned seen = 0;
    struct ao_vec3 rho = ao_vec3_make(DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO);
    struct transform t = {.scale = ao_dvec3_make(1, 1, 1), .axis = ao_dvec3_make(0, 1, 0), .cos_angle = 1};
    double crease = w->crease;
    while (c->next < c->count) {
        int k;
        double r[4];
        const char *key = next_key(c, keys, &seen, &k);
        if (!key)
            return false;
        if (k == 0 && !albedo(c, &rho))
            return false;
        if (k == 1 && !triple(c, key, &t.scale))
            return false;
        if (k == 2) {
            if (numbers(c, key, r, 4, 4) != 4)
                return false;
            if (!ao_dvec3_unit(ao_dvec3_make(r[0], r[1], r[2]), &t.axis))
                return fail(c, "'rotate': the axis must not be zero");
            t.cos_angle = cos(r[3] * PI / 180.0);
            t.sin_angle = sin(r[3] * PI / 180.0);
        }
        if (k == 3 && !vector(c, key, &t.translate))
            return false;
        if (k == 4 && !crease_angle(c, key, &crease))
            return false;
    }
    if (t.scale.x == 0.0 || t.scale.y == 0.0 || t.scale.z == 0.0)
        return fail(c, "'scale' must not be zero");
    const struct loaded *f = find_loaded(w, path, crease);
    if (!f && !(f = load_file(c, s, w, path, crease)))
        return false;
    struct ao_affine line = affine_of(&t);
    return place_model(c, s, w, f, &line, rho, path);
}

/* ---- whole files ---- */

/* Splits a line into tokens in place, dropping a '#' comment; false when there are too many. */
static bool tokenize(struct cursor *c, char *line)
{
    char *hash = strchr(line, '#');
    if (hash)
        *hash = '\0';
    c->count = 0;
    c->next = 1;
    for (char *p = line; *p;) {
        while (*p == ' ' || *p == '\t' || *p == '\r')
            *p++ = '\0';
        if (!*p)
            break;
        if (c->count == MAX_TOKENS)
            return fail(c, "too many words on one line (at most %d)", MAX_TOKENS);
        c->tokens[c->count++] = p;
        while (*p && *p != ' ' && *p != '\t' && *p != '\r')
            p++;
    }
    return true;
}

static bool parse_statement(struct cursor *c, struct ao_scene *s, struct world *w)
{
    const char *word = c->tokens[0];
    if (strcmp(word, "camera") == 0)
        return parse_camera(c, s, w);
    if (strcmp(word, "image") == 0)
        return parse_image(c, s, w);
    if (strcmp(word, "sphere") == 0)
        return parse_sphere(c, s, w);
    if (strcmp(word, "quad") == 0)
        return parse_quad(c, s, w);
    if (strcmp(word, "mesh") == 0)
        return parse_mesh(c, s, w);
    if (strcmp(word, "background") == 0)
        return unit_colour(c, word, &s->background) &&
               (c->next == c->count || fail(c, "'background': expected 1 or 3 numbers"));
    if (strcmp(word, "ao-distance") == 0) {
        double d;
        if (!scalar(c, word, &d))
            return false;
        s->ao_distance = (float)d;
        return s->ao_distance > 0.0f || fail(c, "'ao-distance' must be positive");
    }
    return fail(c, "unknown keyword '%s'", word);
}

/* ---- instances ---- */

/* gamma(n) of ao.h in double, for the bounds computed here. */
static double gamma_n(int n)
{
    return n * 0x1p-24 / (1.0 - n * 0x1p-24);
}

/* The bound ao.c adds to the error of a point in an instanced mesh's own frame before it lifts an
 * occlusion ray's origin off the surface there: how far the origin o moves when ao.c maps it into
 * the local frame and Embree maps it back, for the instance's float map a (L, t), per axis, as
 * slack[0] max|o| + slack[1]. Those two maps:
 * - ao.c: o_local = L o + t in double, rounded once to float: off by e1, |e1| <= gamma1 |o_local|,
 *   and |o_local| <= (|L| |o| + |t|) (1 + gamma1).
 * - Embree (3.13, instance_intersector): W = L's inverse in float, as the adjoint over the
 *   determinant (each cofactor a b - c d off by gamma2 of |a b| + |c d|, the determinant a dot
 *   product with those, off by gamma5 of the same in absolute values, its reciprocal from rcpss and
 *   one Newton step, 5 ulps, and the product one more), c = -(W t) (off by gamma3 |W| |t|), and the
 *   origin W o_local + c by three multiply-adds (gamma4 (|W| |o_local| + |c|)).
 * With L* the exact inverse, o'' - o = (W - L*) L o + (W t + c) + W e1 + e3, so per axis
 *   |o'' - o| <= (E |L| + gamma6 |W| |L|) |o| + gamma14 |W| |t|,
 * where E = gamma16 (Cabs + |C| Dabs / |D|) / |D| bounds |W - L*| entry by entry (C the cofactors
 * and D the determinant, Cabs and Dabs computed with absolute values) and |W| <= |L*| + E. With
 * |o| <= max|o| on every axis, slack[0] is the largest row sum of the first matrix and slack[1]
 * the largest entry of the second vector; both are raised by 2^-20 of themselves for the rounding
 * of this arithmetic and of ao.c's float evaluation. False, when slack[0] exceeds 2^-8 or L is
 * singular: too ill-conditioned to instance (ao.c's lift assumes slack[0] <= 1/4); the mesh is
 * flattened instead. */
static bool round_trip(const float a[12], float slack[2])
{
    double l[9], cof[9], cabs[9];
    for (int k = 0; k < 9; k++)
        l[k] = a[k];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
            double x = l[3 * c1 + r1] * l[3 * c2 + r2], y = l[3 * c2 + r1] * l[3 * c1 + r2];
            cof[3 * c + r] = x - y;
            cabs[3 * c + r] = fabs(x) + fabs(y);
        }
    double det = l[0] * cof[0] + l[3] * cof[3] + l[6] * cof[6];
    double dabs = fabs(l[0]) * cabs[0] + fabs(l[3]) * cabs[3] + fabs(l[6]) * cabs[6];
    if (!(fabs(det) > 0.0) || !isfinite(det) || !isfinite(dabs))
        return false;
    /* W(r, c) = C(c, r) / D; E and |W| entry by entry, row r, column c at [3 c + r]. */
    double e[9], wabs[9];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            double cc = cof[3 * r + c], ca = cabs[3 * r + c];
            e[3 * c + r] = gamma_n(16) * (ca + fabs(cc) * dabs / fabs(det)) / fabs(det);
            wabs[3 * c + r] = fabs(cc) / fabs(det) + e[3 * c + r];
        }
    double alpha = 0.0, beta = 0.0;
    for (int r = 0; r < 3; r++) {
        double row = 0.0, wt = 0.0;
        for (int j = 0; j < 3; j++) {
            for (int k = 0; k < 3; k++)
                row += (e[3 * k + r] + gamma_n(6) * wabs[3 * k + r]) * fabs(l[3 * j + k]);
            wt += wabs[3 * j + r] * fabs((double)a[9 + j]);
        }
        alpha = fmax(alpha, row);
        beta = fmax(beta, gamma_n(14) * wt);
    }
    alpha *= 1.0 + 0x1p-20, beta *= 1.0 + 0x1p-20;
    if (!(alpha <= 0x1p-8) || !isfinite(beta))
        return false;
    slack[0] = nextafterf((float)alpha, INFINITY);
    slack[1] = nextafterf((float)beta, INFINITY);
    return true;
}

/* The map m narrowed to float, as an instance keeps it. */
static void narrow_affine(const struct ao_affine *m, float out[12])
{
    for (int k = 0; k < 12; k++)
        out[k] = (float)m->m[k];
}

/* The box lo..hi of mesh's positions, in its own frame (float comparisons: the loop stays in
 * registers, and a float's minimum is exact). */
static void box_of(const struct ao_mesh *mesh, struct ao_dvec3 *lo, struct ao_dvec3 *hi)
{
    float l[3] = {INFINITY, INFINITY, INFINITY}, h[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < mesh->vertex_count; v++) {
        const float p[3] = {mesh->positions[v].x, mesh->positions[v].y, mesh->positions[v].z};
        for (int k = 0; k < 3; k++) {
            l[k] = p[k] < l[k] ? p[k] : l[k];
            h[k] = p[k] > h[k] ? p[k] : h[k];
        }
    }
    *lo = ao_dvec3_make(l[0], l[1], l[2]);
    *hi = ao_dvec3_make(h[0], h[1], h[2]);
}

/* Fills w->info: how often each mesh is placed, its box in its own frame, and whether it is
 * instanced (w->instancing's rule; never where a placement's map is too ill-conditioned for
 * round_trip). False when memory is short. */
static bool survey(struct ao_scene *s, struct world *w)
{
    free(w->info);
    if (!(w->info = calloc(s->mesh_count ? s->mesh_count : 1, sizeof *w->info)))
        return false;
    uint64_t reserved = 0;   /* the budget AUTO's flattened copies will take (build_instance) */
    for (size_t i = 0; i < w->placement_count; i++)
        w->info[w->placements[i].mesh].placements++;
    for (size_t m = 0; m < s->mesh_count; m++) {
        struct mesh_info *info = &w->info[m];
        const struct ao_mesh *mesh = &s->meshes[m];
        box_of(mesh, &info->lo, &info->hi);
        info->left = info->placements;
        size_t placed = info->placements * mesh->triangle_count;
        uint64_t copy = ao_budget_charge(w->budget, mesh->triangle_count, mesh->vertex_count, 0), copies = UINT64_MAX;
        if (info->placements > 1 && copy <= (UINT64_MAX - reserved) / (info->placements - 1))
            copies = copy * (info->placements - 1);
        bool flat = info->placements < 2 || (placed / info->placements == mesh->triangle_count &&
                                              placed <= AO_SCENE_FLATTEN_TRIANGLES &&
                                              ao_budget_fits(w->budget, reserved + copies));
        info->instanced = w->instancing == AO_INSTANCING_ALWAYS ? info->placements > 0
                          : w->instancing == AO_INSTANCING_NEVER ? false
                          : !flat;
        if (w->instancing != AO_INSTANCING_ALWAYS && !info->instanced && info->placements > 1)
            reserved += copies;
    }
    for (size_t i = 0; i < w->placement_count; i++) {
        struct mesh_info *info = &w->info[w->placements[i].mesh];
        float a[12], slack[2];
        narrow_affine(&w->placements[i].to_world, a);
        a[9] = a[10] = a[11] = 0.0f;   /* the translation changes slack[1] only */
        if (info->instanced && !round_trip(a, slack))
            info->instanced = false;
    }
    return true;
}

/* The box lo..hi grown to hold p. */
static void grow(struct ao_dvec3 *lo, struct ao_dvec3 *hi, struct ao_dvec3 p)
{
    *lo = ao_dvec3_make(fmin(lo->x, p.x), fmin(lo->y, p.y), fmin(lo->z, p.z));
    *hi = ao_dvec3_make(fmax(hi->x, p.x), fmax(hi->y, p.y), fmax(hi->z, p.z));
}

/* True when m's linear part is diagonal: each world coordinate is then a product and a sum of one
 * mesh coordinate, monotonic in it after rounding too, so the box of the mapped vertices is
 * exactly the box of the mapped corners of the mesh's box. */
static bool diagonal(const struct ao_affine *m)
{
    return m->m[1] == 0.0 && m->m[2] == 0.0 && m->m[3] == 0.0 && m->m[5] == 0.0 && m->m[6] == 0.0 &&
           m->m[7] == 0.0;
}

/* The box lo..hi grown to hold the world positions of placement p: of the corners of its mesh's box
 * when instanced (a box holding the instance) or mapped by a diagonal map (exact); else of its
 * mesh's every vertex (exact). */
static void grow_by_placement(const struct ao_scene *s, const struct world *w, const struct pending *p,
                              struct ao_dvec3 *lo, struct ao_dvec3 *hi)
{
    const struct mesh_info *info = &w->info[p->mesh];
    if (info->instanced || diagonal(&p->to_world)) {
        for (int k = 0; k < 8; k++)
            grow(lo, hi, ao_affine_point(&p->to_world, k & 1 ? info->hi.x : info->lo.x, k & 2 ? info->hi.y : info->lo.y,
                                         k & 4 ? info->hi.z : info->lo.z));
        return;
    }
    const struct ao_mesh *m = &s->meshes[p->mesh];
    for (size_t v = 0; v < m->vertex_count; v++)
        grow(lo, hi, ao_affine_point(&p->to_world, m->positions[v].x, m->positions[v].y, m->positions[v].z));
}

/* World-space bounding box of all geometry (w->info must be current); false for an empty scene. */
static bool bounds(const struct ao_scene *s, const struct world *w, struct ao_dvec3 *lo, struct ao_dvec3 *hi)
{
    *lo = ao_dvec3_make(INFINITY, INFINITY, INFINITY);
    *hi = ao_dvec3_make(-INFINITY, -INFINITY, -INFINITY);
    for (size_t i = 0; i < s->sphere_count; i++) {
        struct ao_dvec3 c = w->sphere_centers[i];
        double r = s->spheres[i].radius;
        grow(lo, hi, ao_dvec3_make(c.x - r, c.y - r, c.z - r));
        grow(lo, hi, ao_dvec3_make(c.x + r, c.y + r, c.z + r));
    }
    for (size_t i = 0; i < w->quad_count; i++)
        for (int k = 0; k < 4; k++)
            grow(lo, hi, w->quads[i].p[k]);
    for (size_t i = 0; i < w->placement_count; i++)
        grow_by_placement(s, w, &w->placements[i], lo, hi);
    return s->sphere_count + w->quad_count + w->placement_count > 0;
}

/* The sizes of scene that the renderer draws as it would the same scene at size 1 (scene.h's
 * AO_SCENE_MIN_EXTENT and AO_SCENE_MAX_EXTENT; measured in docs/stability.md). It traces in single
 * precision with flush-to-zero on, so each product it forms must stay between 2^-126 (below, it
 * becomes 0) and 2^128 (above, infinite). With E the largest side of the box around the geometry,
 * eye and target, every local coordinate is at most E (place()'s origin is in the box), and:
 * - Above. A triangle in the box has edges of at most sqrt(3) E, so the unnormalized normal
 *   Ng = e1 x e2 that either tracer returns is at most 3 E^2 long, and ao.c normalizes it through
 *   |Ng|^2 <= 9 E^4 < 2^128: E < 2^32 / sqrt(3) = 2.48e9. The tracers' distance tests multiply Ng
 *   by one more length (Embree's Pluecker depth 2 (v0 - o).Ng, the direct loops' w.N, at most
 *   2 sqrt(3) E 3 E^2), which needs only E < 3.2e12; Embree's ray validity check (its assertion
 *   `ray.valid()`: |org| and |dir| at most FLT_LARGE = 1.844e18, a tenth of sqrt(2^128)) only
 *   E < 1.8e18. AO_SCENE_MAX_EXTENT = 2^31 = 2.15e9.
 * - Below. Occlusion rays leave a surface lifted past the point's error bound, with a floor of
 *   2^-100 where that bound is 0 (ao.h): on a facet in a coordinate plane through the local
 *   origin, such as the ground y = 0 of most scenes. The same distance tests multiply that lift by
 *   |Ng|; below 2^-126 the product flushes to 0, the ray meets its own facet at t = 0 and the
 *   facet turns black. So |Ng| >= 2^-26, which a facet spanning the scene (|Ng| = E^2 for a
 *   square) reaches at E = 2^-13 = 1.22e-4; AO_SCENE_MIN_EXTENT = 2^-12 = 2.44e-4 keeps a factor 2.
 * The camera's eye and target are ray origins and directions: they belong to the box (Embree's
 * check, and the depth test's o), and ao_camera_view squares their distance, which must therefore
 * stay above 2^-63 (MIN_CAMERA_DISTANCE = 2^-60). Detail finer than the scene is not checked: a
 * triangle whose |Ng| is below 2^-63 (edges of about 3e-10) is shaded with the eye-facing normal
 * that stands in for degenerate ones, and a facet in a coordinate plane through the origin with
 * |Ng| below 2^-26 occludes itself, whatever the scene's size. */
static const double MIN_CAMERA_DISTANCE = 0x1p-60;

/* The largest side of the box lo..hi. */
static double largest_side(struct ao_dvec3 lo, struct ao_dvec3 hi)
{
    return fmax(hi.x - lo.x, fmax(hi.y - lo.y, hi.z - lo.z));
}

/* Refuses a scene whose geometry (the box lo..hi, when any) or camera leaves the range derived
 * above, with one line naming the size; false after reporting. */
static bool check_range(const struct world *w, struct cursor *c, bool any, struct ao_dvec3 lo, struct ao_dvec3 hi)
{
    static const char range[] = "aoview renders scenes from %.3g to %.3g across (docs/stability.md)";
    char message[256];
    double size = any ? largest_side(lo, hi) : 0.0;
    c->line = 0;
    snprintf(message, sizeof message, range, AO_SCENE_MIN_EXTENT, AO_SCENE_MAX_EXTENT);
    if (any && !(size >= AO_SCENE_MIN_EXTENT && size <= AO_SCENE_MAX_EXTENT))
        return fail(c, "the scene is %.3g across%s; %s", size, w->extent_note, message);
    if (!w->has_camera)
        return true;
    c->line = w->camera_line;
    if (!any)
        lo = hi = w->eye;
    grow(&lo, &hi, w->eye);
    grow(&lo, &hi, w->target);
    if (!(largest_side(lo, hi) <= AO_SCENE_MAX_EXTENT))
        return fail(c, "camera: with it the scene is %.3g across; %s", largest_side(lo, hi), message);
    struct ao_dvec3 d = ao_dvec3_sub(w->target, w->eye), along;
    double distance = ao_dvec3_unit(d, &along) ? ao_dvec3_dot(d, along) : 0.0;   /* |d|, no square to vanish */
    if (distance > 0.0 && distance < MIN_CAMERA_DISTANCE)
        return fail(c, "camera: eye and target are %.3g apart, closer than the %.3g aoview can aim by",
                    distance, MIN_CAMERA_DISTANCE);
    return true;
}

/* Writes src (a mesh in its own frame) moved by to_local into dst (the same mesh, moved in place, or
 * an empty one that receives a copy) by ao_mesh_place. False when memory is short. */
static bool flatten(struct ao_mesh *dst, const struct ao_mesh *src, const struct ao_affine *to_local)
{
    if (dst != src) {
        *dst = (struct ao_mesh){.vertex_count = src->vertex_count, .triangle_count = src->triangle_count};
        dst->positions = malloc((src->vertex_count ? src->vertex_count : 1) * sizeof *dst->positions);
        dst->normals = malloc((src->vertex_count ? src->vertex_count : 1) * sizeof *dst->normals);
        dst->indices = malloc((src->triangle_count ? 3 * src->triangle_count : 1) * sizeof *dst->indices);
        if (!dst->positions || !dst->normals || !dst->indices) {
            ao_mesh_finish(dst);
            return false;
        }
    }
    ao_mesh_place(dst, 0, 0, src, to_local);   /* check_range keeps every position finite */
    return true;
}

/* Builds the instance of placement p, whose map into the local frame is to_local: an instanced
 * mesh's map and slack, or the mesh flattened (moved in place at its last placement, copied before:
 * each copy a mesh of its own, charged to the budget). False after reporting. */
static bool build_instance(struct ao_scene *s, struct world *w, struct cursor *c, const struct pending *p,
                           const struct ao_affine *to_local)
{
    struct mesh_info *info = &w->info[p->mesh];
    struct ao_instance *in = &s->instances[s->instance_count];
    *in = (struct ao_instance){.mesh = p->mesh, .albedo = p->albedo, .flat = !info->instanced};
    if (info->instanced) {
        struct ao_affine narrowed;
        double n[9];
        narrow_affine(to_local, in->to_local);
        for (int k = 0; k < 12; k++)
            narrowed.m[k] = in->to_local[k];
        ao_affine_normals(&narrowed, n);
        for (int k = 0; k < 9; k++)
            in->normals[k] = (float)n[k];
        if (!round_trip(in->to_local, in->slack))   /* survey() checked the same L */
            return fail(c, "an instance's transform is too ill-conditioned to trace");
        s->instance_count++;
        return true;
    }
    narrow_affine(&(struct ao_affine){{1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}}, in->to_local);
    in->normals[0] = in->normals[4] = in->normals[8] = 1.0f;
    size_t dst = p->mesh;
    if (--info->left > 0) {   /* a copy: the mesh itself is still needed in its own frame */
        const struct ao_mesh *m = &s->meshes[p->mesh];
        if (!charge(c, w, m->triangle_count, m->vertex_count, "a flattened copy"))
            return false;
        if (s->mesh_count >= UINT32_MAX || !resize(&s->meshes, s->mesh_count + 1, sizeof *s->meshes))
            return fail(c, "out of memory");
        dst = s->mesh_count;
        s->meshes[dst] = (struct ao_mesh){0};
    }
    if (!flatten(&s->meshes[dst], &s->meshes[p->mesh], to_local))
        return fail(c, "out of memory");
    s->mesh_count += dst != p->mesh;
    s->instances[s->instance_count].mesh = (uint32_t)dst;
    s->instance_count++;
    return true;
}

/* The quads from w->quads[*next] on that share its albedo, as one flat mesh in the local frame. */
static bool build_quads(struct ao_scene *s, struct world *w, size_t *next, struct ao_dvec3 origin)
{
    size_t first = *next, n = 1;
    while (first + n < w->quad_count && memcmp(&w->quads[first + n].rho, &w->quads[first].rho,
                                               sizeof w->quads[first].rho) == 0)
        n++;
    *next = first + n;
    uint32_t a;
    if (!add_albedo(s, w->quads[first].rho, &a) || s->mesh_count >= UINT32_MAX ||
        !resize(&s->meshes, s->mesh_count + 1, sizeof *s->meshes))
        return false;
    struct ao_mesh *m = &s->meshes[s->mesh_count];
    *m = (struct ao_mesh){.vertex_count = 4 * n, .triangle_count = 2 * n};
    m->positions = malloc(4 * n * sizeof *m->positions);
    m->normals = malloc(4 * n * sizeof *m->normals);
    m->indices = malloc(6 * n * sizeof *m->indices);
    if (!m->positions || !m->normals || !m->indices) {
        ao_mesh_finish(m);
        return false;
    }
    static const uint32_t tris[6] = {0, 1, 2, 0, 2, 3};
    for (size_t q = 0; q < n; q++) {
        for (int k = 0; k < 4; k++) {
            m->positions[4 * q + (size_t)k] = ao_dvec3_narrow(ao_dvec3_sub(w->quads[first + q].p[k], origin));
            m->normals[4 * q + (size_t)k] = w->quads[first + q].n;
        }
        for (int k = 0; k < 6; k++)
            m->indices[6 * q + (size_t)k] = (uint32_t)(4 * q) + tris[k];
    }
    s->instances[s->instance_count++] = (struct ao_instance){
        .mesh = (uint32_t)s->mesh_count++, .albedo = a, .flat = true,
        .to_local = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, .normals = {1, 0, 0, 0, 1, 0, 0, 0, 1}};
    return true;
}

/* Gives the mesh's positions the spare entry scene.h promises (realloc: no copy for big arrays,
 * which the C library maps and remaps); false when memory is short. */
static bool pad(struct ao_mesh *m)
{
    struct ao_vec3 *p = realloc(m->positions, (m->vertex_count + 1) * sizeof *p);
    if (!p)
        return false;
    p[m->vertex_count] = ao_vec3_make(0.0f, 0.0f, 0.0f);
    m->positions = p;
    return true;
}

/* Moves the scene from world space into its local frame and narrows it to float: every mesh
 * placement (moved into the frame, or instanced with its map into it), quad, sphere centre and the
 * camera become world - origin, with the origin at the bounding box's centre, so that float
 * precision follows the scene's size rather than its distance from (0, 0, 0). Where the box holds
 * (0, 0, 0) its coordinates are at most its size already (one bit worse than from the centre) and
 * the origin stays there, leaving such scenes exactly as written. A scene without a camera line
 * gets one framed on its box. False after reporting (the camera's line) or on short memory. */
static bool place(struct ao_scene *s, struct world *w, struct cursor *c)
{
    struct ao_dvec3 lo, hi, origin = {0};
    c->line = 0;
    if (!survey(s, w))
        return fail(c, "out of memory");
    bool any = bounds(s, w, &lo, &hi);
    if (!check_range(w, c, any, lo, hi))
        return false;
    if (any && !(lo.x <= 0.0 && hi.x >= 0.0 && lo.y <= 0.0 && hi.y >= 0.0 && lo.z <= 0.0 && hi.z >= 0.0))
        origin = ao_dvec3_scale(ao_dvec3_add(lo, hi), 0.5);
    s->origin[0] = origin.x, s->origin[1] = origin.y, s->origin[2] = origin.z;
    c->line = 0;
    if (!resize(&s->instances, w->placement_count + w->quad_count, sizeof *s->instances))
        return fail(c, "out of memory");
    struct ao_affine shift = ao_affine_identity();
    shift.m[9] = -origin.x, shift.m[10] = -origin.y, shift.m[11] = -origin.z;
    for (size_t i = 0; i < w->placement_count; i++) {
        struct ao_affine to_local = ao_affine_compose(&shift, &w->placements[i].to_world);
        if (!build_instance(s, w, c, &w->placements[i], &to_local))
            return false;
    }
    for (size_t next = 0; next < w->quad_count;)
        if (!build_quads(s, w, &next, origin))
            return fail(c, "out of memory");
    for (size_t i = 0; i < s->mesh_count; i++)
        if (!pad(&s->meshes[i]))
            return fail(c, "out of memory");
    for (size_t i = 0; i < s->instance_count; i++)
        s->triangle_count += s->meshes[s->instances[i].mesh].triangle_count;
    for (size_t i = 0; i < s->sphere_count; i++)
        s->spheres[i].center = ao_dvec3_narrow(ao_dvec3_sub(w->sphere_centers[i], origin));
    if (w->has_camera) {
        s->camera.eye = ao_dvec3_narrow(ao_dvec3_sub(w->eye, origin));
        s->camera.target = ao_dvec3_narrow(ao_dvec3_sub(w->target, origin));
        struct ao_view view;
        c->line = w->camera_line;
        if (!ao_camera_view(&s->camera, 1, 1, &view))
            return fail(c, "camera: eye equals target or up is parallel to the view direction");
        return true;
    }
    c->line = 0;
    if (!any)
        return fail(c, "no camera and nothing to frame: add a 'camera' line or some geometry");
    ao_camera_frame_box(&s->camera, ao_dvec3_narrow(ao_dvec3_sub(lo, origin)), ao_dvec3_narrow(ao_dvec3_sub(hi, origin)));
    return true;
}

/* Records in a placed scene the BVH its budget gives it (ao_budget_bvh: every charge is made by
 * now), with a note when AUTO gave COMPACT. */
static void settle_bvh(struct ao_scene *s, const struct ao_budget *budget)
{
    s->bvh = ao_budget_bvh(budget);
    if (budget->bvh == AO_BVH_AUTO && s->bvh == AO_BVH_COMPACT)
        add_note(s, s->name, "BVH built compact to fit the scene budget (slower rays; a larger "
                             "--scene-budget gets the faster BVH)");
}

/* Frees what the world holds while a scene is read. */
static void world_finish(struct world *w)
{
    for (size_t i = 0; i < w->file_count; i++) {
        free(w->files[i].path);
        free(w->files[i].placements);
    }
    free(w->files);
    free(w->file_slots);
    free(w->placements);
    free(w->quads);
    free(w->info);
    free(w->sphere_centers);
}

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

/* ao_scene_parse charging budget, with options' instancing and crease angle. */
static bool parse_text(struct ao_scene *scene, const char *text, const char *path, struct ao_budget *budget,
                       const struct ao_scene_options *options)
{
    begin(scene, path);
    struct cursor c = {.path = path};
    struct world w = {.extent_note = "", .budget = budget, .instancing = options->instancing,
                      .crease = crease_of(options), .sized = options->sized};
    bool ok = true;
    char line[MAX_LINE + 2];
    for (const char *p = text; ok && *p;) {
        size_t len = strcspn(p, "\n");
        c.line++;
        if (len > MAX_LINE) {
            ok = fail(&c, "line longer than %d characters", MAX_LINE);
            break;
        }
        memcpy(line, p, len);
        line[len] = '\0';
        p += len + (p[len] == '\n');
        ok = tokenize(&c, line) && (c.count == 0 || parse_statement(&c, scene, &w));
    }
    ok = ok && place(scene, &w, &c);
    if (ok)
        settle_bvh(scene, budget);
    world_finish(&w);
    if (!ok)
        ao_scene_finish(scene);
    return ok;
}

bool ao_scene_parse(struct ao_scene *scene, const char *text, const char *path)
{
    struct ao_scene_options options = {.budget = AO_BUDGET_DEFAULT};
    return ao_scene_parse_with(scene, text, path, &options);
}

bool ao_scene_parse_with(struct ao_scene *scene, const char *text, const char *path,
                         const struct ao_scene_options *options)
{
    struct ao_budget budget = {.limit = options->budget, .bvh = options->bvh};
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
static bool add_ground(struct world *w, struct ao_dvec3 lo, struct ao_dvec3 hi)
{
    struct ao_dvec3 mid = ao_dvec3_scale(ao_dvec3_add(lo, hi), 0.5);
    double extent = largest_side(lo, hi), size = 25.0 * extent, y = lo.y - AO_SCENE_GROUND_GAP * extent;
    struct ao_dvec3 p[4] = {ao_dvec3_make(mid.x - size, y, mid.z - size), ao_dvec3_make(mid.x - size, y, mid.z + size),
                        ao_dvec3_make(mid.x + size, y, mid.z + size), ao_dvec3_make(mid.x + size, y, mid.z - size)};
    return add_quad(w, p, ao_vec3_make(0, 1, 0), ao_vec3_make(0.5f, 0.5f, 0.5f));
}

/* A bare mesh: the mesh file's model, with ground a large ground quad under it, a camera framed on
 * it. */
static bool load_bare_mesh(struct ao_scene *s, const char *path, struct ao_budget *budget,
                           const struct ao_scene_options *options)
{
    begin(s, path);
    bool ground = options->ground;
    struct world w = {.extent_note = ground ? " (the mesh with its ground quad, 50 times as wide as the mesh)" : "",
                      .budget = budget, .instancing = options->instancing, .crease = crease_of(options)};
    struct cursor c = {.path = path};
    struct ao_affine identity = ao_affine_identity();
    const struct loaded *f = load_file(&c, s, &w, path, w.crease);
    bool ok = f && (!ground || charge(&c, &w, 2, 4, "the ground")) &&
              place_model(&c, s, &w, f, &identity, ao_vec3_make(DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO), path);
    struct ao_dvec3 lo, hi;
    if (ok && !survey(s, &w))
        ok = fail(&c, "out of memory");
    if (ok && bounds(s, &w, &lo, &hi)) {
        /* The camera framed on the mesh about its centre, then kept in world space. */
        struct ao_dvec3 mid = ao_dvec3_scale(ao_dvec3_add(lo, hi), 0.5);
        ao_camera_frame_box(&s->camera, ao_dvec3_narrow(ao_dvec3_sub(lo, mid)), ao_dvec3_narrow(ao_dvec3_sub(hi, mid)));
        w.eye = ao_dvec3_add(mid, ao_dvec3_of(s->camera.eye));
        w.target = ao_dvec3_add(mid, ao_dvec3_of(s->camera.target));
        w.has_camera = true;
        if (ground && !add_ground(&w, lo, hi))
            ok = fail(&c, "out of memory");
    }
    ok = ok && place(s, &w, &c);
    if (ok)
        settle_bvh(s, budget);
    world_finish(&w);
    if (!ok)
        ao_scene_finish(s);
    return ok;
}

bool ao_scene_load(struct ao_scene *scene, const char *path)
{
    return ao_scene_load_budget(scene, path, AO_BUDGET_DEFAULT);
}

bool ao_scene_load_budget(struct ao_scene *scene, const char *path, uint64_t budget_bytes)
{
    struct ao_scene_options options = {.budget = budget_bytes, .ground = true};
    return ao_scene_load_with(scene, path, &options);
}

bool ao_scene_load_with(struct ao_scene *scene, const char *path, const struct ao_scene_options *options)
{
    struct ao_budget budget = {.limit = options->budget, .bvh = options->bvh};
    memset(scene, 0, sizeof *scene);
    if (ao_load_is_mesh(path))
        return load_bare_mesh(scene, path, &budget, options);
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

void ao_scene_finish(struct ao_scene *scene)
{
    for (size_t i = 0; scene->meshes && i < scene->mesh_count; i++)
        ao_mesh_finish(&scene->meshes[i]);
    free(scene->meshes);
    free(scene->instances);
    free(scene->spheres);
    free(scene->albedos);
    memset(scene, 0, sizeof *scene);
}

bool ao_scene_add_flat_mesh(struct ao_scene *scene, struct ao_mesh *mesh, struct ao_vec3 albedo)
{
    uint32_t a;
    bool ok = scene->mesh_count < UINT32_MAX && scene->instance_count < UINT32_MAX && pad(mesh) &&
              resize(&scene->meshes, scene->mesh_count + 1, sizeof *scene->meshes) &&
              resize(&scene->instances, scene->instance_count + 1, sizeof *scene->instances) &&
              add_albedo(scene, albedo, &a);
    if (!ok) {
        ao_mesh_finish(mesh);
        return false;
    }
    scene->instances[scene->instance_count++] = (struct ao_instance){
        .mesh = (uint32_t)scene->mesh_count, .albedo = a, .flat = true,
        .to_local = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, .normals = {1, 0, 0, 0, 1, 0, 0, 0, 1}};
    scene->meshes[scene->mesh_count++] = *mesh;
    scene->triangle_count += mesh->triangle_count;
    *mesh = (struct ao_mesh){0};
    return true;
}

void ao_scene_triangle(const struct ao_scene *scene, size_t instance, size_t prim, struct ao_vec3 corners[3])
{
    const struct ao_instance *in = &scene->instances[instance];
    const struct ao_mesh *m = &scene->meshes[in->mesh];
    for (int k = 0; k < 3; k++) {
        struct ao_vec3 p = m->positions[m->indices[3 * prim + (size_t)k]];
        if (in->flat) {
            corners[k] = p;
            continue;
        }
        const float *a = in->to_local;
        double q[3];
        for (int r = 0; r < 3; r++)
            q[r] = (double)a[r] * p.x + (double)a[3 + r] * p.y + (double)a[6 + r] * p.z + (double)a[9 + r];
        corners[k] = ao_vec3_make((float)q[0], (float)q[1], (float)q[2]);
    }
}
